//! Maximum likelihood for equation systems linear in the measured numbers
//! (the Gauss–Helmert model): the one estimation engine of Plinth. Per speed
//! s an equation residual e_s(p) (real, length r) that is zero for the true
//! measured numbers, linear in them with B_s(p) = ∂e_s/∂(measured), and
//! independent noise of variance D_s per measured real number. Then e_s is
//! zero-mean with covariance Σ_s(p) = B_s·D_s·B_sᵀ, and the ML estimate
//! minimises J(p) = Σ_s e_sᵀ Σ_s(p)⁻¹ e_s.
//!
//! The models: one pedestal on rigid ground ([`super::ml`], analytic
//! derivatives), on a measured base and a group on an unmeasured base
//! ([`super::base`], central differences).
//!
//! [`minimise`] (and [`fit`]) minimises J by Levenberg–Marquardt on the
//! whitened residuals ([`Equations::whiten`]: its Jacobian includes Σ's
//! dependence on p) or, with `frozen` weights, a fixed Σ (cheap, for
//! profiling a grid); [`fisher`] is F = Σ Aᵀ Σ⁻¹ A with A = ∂e/∂p, whose
//! inverse ([`inverse_psd`]) is the Cramér–Rao bound at p.

use nalgebra::{DMatrix, DVector};

mod factor;

use factor::Workspace;

/// A system of equations per speed, linear in the measured numbers.
pub trait Equations {
    /// Speeds (independent blocks of equations).
    fn speeds(&self) -> usize;
    /// Residual e_s(p) and B_s = ∂e_s/∂(measured numbers) at speed `s` for
    /// parameters `p` (model units).
    fn residual(&self, s: usize, p: &[f64]) -> (DVector<f64>, DMatrix<f64>);
    /// The residual e_s(p) alone (what frozen weights need).
    fn error(&self, s: usize, p: &[f64]) -> DVector<f64> {
        self.residual(s, p).0
    }
    /// Noise variance of each measured number of speed `s` (order of B's columns).
    fn variance(&self, s: usize) -> &[f64];
    /// Whitened residuals L_s⁻¹e_s of every speed stacked (Σ at `p`), and,
    /// when `jacobian` is given, their derivatives with respect to the
    /// parameters it names (model units). `None` when some Σ is singular or
    /// a number is not finite. The default works from [`Equations::residual`]
    /// with central differences (they include Σ's dependence on p); a model
    /// with analytic derivatives overrides it (and does its per-speed work
    /// once, not per call).
    fn whiten(&self, p: &[f64], jacobian: Option<JacobianRequest<'_>>) -> Option<DVector<f64>> {
        let mut ws = Workspace::new();
        let r = whitened_generic(self, p, None, &mut ws)?;
        if let Some(j) = jacobian {
            *j.out = DMatrix::zeros(r.len(), j.free.len());
            let mut at = p.to_vec();
            for (c, (&k, &h)) in j.free.iter().zip(j.step).enumerate() {
                at[k] = p[k] + h;
                let up = whitened_generic(self, &at, None, &mut ws)?;
                at[k] = p[k] - h;
                let dn = whitened_generic(self, &at, None, &mut ws)?;
                at[k] = p[k];
                for (row, (a, b)) in up.iter().zip(dn.iter()).enumerate() {
                    j.out[(row, c)] = (a - b) / (2.0 * h);
                }
            }
        }
        Some(r)
    }
    /// J(p) = Σ eᵀΣ⁻¹e [-] (`None` when some Σ is singular or a number is
    /// not finite). The default sums [`Equations::whiten`]; a model with
    /// fixed-size per-speed work overrides it to allocate nothing.
    fn objective(&self, p: &[f64]) -> Option<f64> {
        self.whiten(p, None).map(|w| w.norm_squared())
    }
    /// The Gauss–Newton normal equations of the whitened residuals at `p`
    /// over the parameters `free` (model units, steps as in
    /// [`JacobianRequest`]): JᵀJ, Jᵀr and J = |r|². The default forms them
    /// from [`Equations::whiten`]; a model with analytic derivatives
    /// accumulates them speed by speed without the stacked Jacobian.
    fn normal_equations(&self, p: &[f64], free: &[usize], step: &[f64]) -> Option<Normal> {
        let mut jac = DMatrix::zeros(0, 0);
        let r = self.whiten(
            p,
            Some(JacobianRequest {
                free,
                step,
                out: &mut jac,
            }),
        )?;
        Some(Normal {
            hess: jac.tr_mul(&jac),
            grad: jac.tr_mul(&r),
            cost: r.norm_squared(),
        })
    }
    /// Fisher information Aᵀ Σ_s⁻¹ A of speed `s` at `p` (model units),
    /// A = ∂e_s/∂p; the default takes A by central differences with steps
    /// `scale`·1e-6.
    fn information(&self, s: usize, p: &[f64], scale: &[f64]) -> Option<DMatrix<f64>> {
        let n = p.len();
        let l = whitening(self, s, p)?;
        let e0 = self.error(s, p);
        let mut a = DMatrix::zeros(e0.len(), n);
        for k in 0..n {
            let h = 1e-6 * scale[k];
            let mut up = p.to_vec();
            up[k] += h;
            let mut dn = p.to_vec();
            dn[k] -= h;
            let d = (self.error(s, &up) - self.error(s, &dn)) / (2.0 * h);
            a.set_column(k, &d);
        }
        let w = l.solve_lower_triangular(&a)?;
        Some(w.transpose() * w)
    }
}

/// Where [`Equations::whiten`] writes the Jacobian of the whitened
/// residuals: one column per parameter index in `free`.
pub struct JacobianRequest<'a> {
    /// Indices into p of the parameters to differentiate by.
    pub free: &'a [usize],
    /// Central-difference step per entry of `free` [p units] (used only
    /// where the derivative is not analytic).
    pub step: &'a [f64],
    /// The Jacobian, resized to (residuals × `free.len()`).
    pub out: &'a mut DMatrix<f64>,
}

/// The Gauss–Newton normal equations of [`Equations::normal_equations`].
#[derive(Clone, Debug, PartialEq)]
pub struct Normal {
    /// JᵀJ over the free parameters (model units).
    pub hess: DMatrix<f64>,
    /// Jᵀr over the free parameters (model units).
    pub grad: DVector<f64>,
    /// J = |r|² [-].
    pub cost: f64,
}

/// Lower Cholesky factor of Σ_s(p) = B·D·Bᵀ, regularised by 1e-12 of its
/// mean diagonal when singular; `None` when Σ has no noise at all.
pub fn whitening<E: Equations + ?Sized>(eq: &E, s: usize, p: &[f64]) -> Option<DMatrix<f64>> {
    let (_, b) = eq.residual(s, p);
    let mut ws = Workspace::new();
    ws.factor(&b, eq.variance(s)).then(|| ws.lower())
}

/// Whitened residuals L_s⁻¹e_s stacked over speeds, with Σ at `p` or the
/// `frozen` factors; `None` when some Σ is singular or a number is not finite.
pub fn whitened<E: Equations + ?Sized>(
    eq: &E,
    p: &[f64],
    frozen: Option<&[DMatrix<f64>]>,
) -> Option<DVector<f64>> {
    match frozen {
        Some(_) => whitened_generic(eq, p, frozen, &mut Workspace::new()),
        None => eq.whiten(p, None),
    }
}

/// [`whitened`] from [`Equations::residual`] and [`Equations::variance`]
/// (e_s and B_s from one call of [`Equations::residual`] where Σ is not
/// frozen, each speed factored and whitened in the buffers of `ws`).
fn whitened_generic<E: Equations + ?Sized>(
    eq: &E,
    p: &[f64],
    frozen: Option<&[DMatrix<f64>]>,
    ws: &mut Workspace,
) -> Option<DVector<f64>> {
    let mut out = Vec::new();
    for s in 0..eq.speeds() {
        let mut e;
        let solved = match frozen {
            Some(f) => {
                e = eq.error(s, p);
                f[s].solve_lower_triangular_mut(&mut e)
            }
            None => {
                let b;
                (e, b) = eq.residual(s, p);
                if !ws.factor(&b, eq.variance(s)) {
                    return None;
                }
                ws.solve(&mut e)
            }
        };
        if !solved {
            return None;
        }
        out.extend(e.iter().copied());
    }
    out.iter()
        .all(|v| v.is_finite())
        .then(|| DVector::from_vec(out))
}

/// J(p) = Σ eᵀΣ⁻¹e [-] (`None` when it cannot be evaluated).
pub fn cost<E: Equations + ?Sized>(eq: &E, p: &[f64]) -> Option<f64> {
    eq.objective(p)
}

/// Fisher information Σ_s Aᵀ Σ_s⁻¹ A at `p` (model units), A = ∂e/∂p
/// ([`Equations::information`]: analytic where the model has it, else
/// central differences with steps `scale`·1e-6).
pub fn fisher<E: Equations + ?Sized>(eq: &E, p: &[f64], scale: &[f64]) -> Option<DMatrix<f64>> {
    let n = p.len();
    let mut f = DMatrix::zeros(n, n);
    for s in 0..eq.speeds() {
        f += eq.information(s, p, scale)?;
    }
    Some(f)
}

/// Inverse of a symmetric positive semi-definite matrix through its
/// unit-diagonal scaling; infinite diagonal where it is singular.
pub fn inverse_psd(f: &DMatrix<f64>) -> DMatrix<f64> {
    let p = f.nrows();
    let d: Vec<f64> = (0..p).map(|i| f[(i, i)].max(0.0).sqrt()).collect();
    let mut inf = DMatrix::zeros(p, p);
    for i in 0..p {
        inf[(i, i)] = f64::INFINITY;
    }
    if d.iter().any(|&x| !(x > 0.0 && x.is_finite())) {
        return inf;
    }
    let scaled = DMatrix::from_fn(p, p, |r, c| f[(r, c)] / (d[r] * d[c]));
    let eig = scaled.symmetric_eigen();
    let hi = eig.eigenvalues.iter().fold(0.0f64, |a, &v| a.max(v));
    let lo = eig.eigenvalues.iter().fold(f64::INFINITY, |a, &v| a.min(v));
    if lo.is_nan() || lo <= hi * 1e-14 {
        return inf;
    }
    let mut inv = eig.eigenvectors.clone();
    for (k, &v) in eig.eigenvalues.iter().enumerate() {
        inv.column_mut(k).scale_mut(1.0 / v);
    }
    let inv = inv * eig.eigenvectors.transpose();
    DMatrix::from_fn(p, p, |r, c| inv[(r, c)] / (d[r] * d[c]))
}

/// Square root of the condition number of the unit-diagonal scaling of a
/// Fisher information (the condition number of the whitened,
/// column-normalised regression) [-]; ∞ when singular.
pub fn condition_number(f: &DMatrix<f64>) -> f64 {
    let p = f.nrows();
    let d: Vec<f64> = (0..p).map(|i| f[(i, i)].max(0.0).sqrt()).collect();
    if p == 0 || d.iter().any(|&x| !(x > 0.0 && x.is_finite())) {
        return f64::INFINITY;
    }
    let scaled = DMatrix::from_fn(p, p, |r, c| f[(r, c)] / (d[r] * d[c]));
    let ev = scaled.symmetric_eigenvalues();
    let (lo, hi) = ev.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| {
        (lo.min(v), hi.max(v))
    });
    if lo > 0.0 {
        (hi / lo).sqrt()
    } else {
        f64::INFINITY
    }
}

/// Outcome of [`fit`].
#[derive(Clone, Debug)]
pub struct Minimum {
    /// Parameters at the minimum (model units).
    pub p: Vec<f64>,
    /// J at the minimum [-].
    pub cost: f64,
    /// Iterations taken.
    pub iterations: usize,
    /// True when the convergence test was met.
    pub converged: bool,
}

/// When [`minimise`] stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Most Levenberg–Marquardt iterations.
    pub max_iterations: usize,
    /// A step below this many standard errors in every parameter has converged [-].
    pub step_tol: f64,
    /// A relative decrease of J below this has converged [-].
    pub decrease_tol: f64,
}

impl Settings {
    /// The default tolerances with at most `max_iterations` iterations.
    pub fn iterations(max_iterations: usize) -> Self {
        Self {
            max_iterations,
            step_tol: 1e-6,
            decrease_tol: 1e-12,
        }
    }
}

/// Levenberg–Marquardt minimisation of J over the parameters with
/// `free[k]` true (the others stay at `start`), in units u = p/`scale`.
/// With `frozen` whitening factors Σ is held fixed. `None` when J cannot be
/// evaluated at the start.
pub fn fit<E: Equations + ?Sized>(
    eq: &E,
    start: &[f64],
    scale: &[f64],
    free: &[bool],
    frozen: Option<&[DMatrix<f64>]>,
    max_iterations: usize,
) -> Option<Minimum> {
    minimise(
        eq,
        start,
        scale,
        free,
        frozen,
        &Settings::iterations(max_iterations),
    )
}

/// [`fit`] with explicit [`Settings`]: the one Levenberg–Marquardt loop of
/// the estimation core (every ML fit, rigid ground or on a base, runs here).
pub fn minimise<E: Equations + ?Sized>(
    eq: &E,
    start: &[f64],
    scale: &[f64],
    free: &[bool],
    frozen: Option<&[DMatrix<f64>]>,
    settings: &Settings,
) -> Option<Minimum> {
    let idx: Vec<usize> = (0..start.len()).filter(|&k| free[k]).collect();
    let q = idx.len();
    let p_of = |u: &DVector<f64>| -> Vec<f64> {
        let mut p = start.to_vec();
        for (j, &k) in idx.iter().enumerate() {
            p[k] = u[j] * scale[k];
        }
        p
    };
    let mut u = DVector::from_fn(q, |j, _| start[idx[j]] / scale[idx[j]]);
    // With frozen weights the residuals themselves are kept (their forward
    // differences are the Jacobian); otherwise J and the normal equations
    // come from the model, speed by speed.
    let mut r = match frozen {
        Some(_) => whitened(eq, &p_of(&u), frozen)?,
        None => DVector::zeros(0),
    };
    let mut cost_now = match frozen {
        Some(_) => r.norm_squared(),
        None => eq.objective(&p_of(&u))?,
    };
    let mut lambda = 1e-3;
    let mut converged = false;
    let mut iterations = 0;
    while iterations < settings.max_iterations && q > 0 {
        iterations += 1;
        let normal = match frozen {
            // Forward differences with frozen weights (the residual is then
            // nearly linear in most parameters, and cheap).
            Some(_) => {
                let mut jac = DMatrix::zeros(r.len(), q);
                let ok = (0..q).all(|j| {
                    let h = 1e-6 * u[j].abs().max(1e-3);
                    let mut up = u.clone();
                    up[j] += h;
                    match whitened(eq, &p_of(&up), frozen) {
                        Some(a) => {
                            jac.set_column(j, &((a - &r) / h));
                            true
                        }
                        None => false,
                    }
                });
                ok.then(|| (jac.tr_mul(&r), jac.tr_mul(&jac)))
            }
            None => {
                let step: Vec<f64> = (0..q)
                    .map(|j| 1e-6 * u[j].abs().max(1e-3) * scale[idx[j]])
                    .collect();
                eq.normal_equations(&p_of(&u), &idx, &step).and_then(|n| {
                    // To the units u = p/scale.
                    let s = DVector::from_fn(q, |j, _| scale[idx[j]]);
                    let g = n.grad.component_mul(&s);
                    let hess = DMatrix::from_fn(q, q, |a, b| n.hess[(a, b)] * s[a] * s[b]);
                    (g.iter().chain(hess.iter()).all(|v| v.is_finite())).then_some((g, hess))
                })
            }
        };
        let Some((g, hess)) = normal else {
            return Some(Minimum {
                p: p_of(&u),
                cost: cost_now,
                iterations,
                converged: false,
            });
        };
        let mut evaluate = |u_new: &DVector<f64>| -> Option<(f64, DVector<f64>)> {
            match frozen {
                Some(_) => whitened(eq, &p_of(u_new), frozen).map(|r| (r.norm_squared(), r)),
                None => eq.objective(&p_of(u_new)).map(|c| (c, DVector::zeros(0))),
            }
        };
        match super::levenberg::step(
            &u,
            cost_now,
            &g,
            &hess,
            lambda,
            settings.step_tol,
            settings.decrease_tol,
            &mut evaluate,
        ) {
            Some(s) => {
                (u, r, cost_now, lambda) = (s.u, s.r, s.cost, s.lambda);
                converged = s.converged;
            }
            // No step lowers J: the start is already the minimum to
            // working precision.
            None => converged = true,
        }
        if converged {
            break;
        }
    }
    Some(Minimum {
        p: p_of(&u),
        cost: cost_now,
        iterations,
        converged: converged || q == 0,
    })
}
