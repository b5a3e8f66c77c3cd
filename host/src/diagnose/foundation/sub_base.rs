//! A pedestal on its own sub-base fitted from a physical start: the
//! two-degree-of-freedom chain read off the measured pedestal receptance,
//! then the likelihood of `crate::estimate::base` (its cost
//! [`chi2`], called, never copied) minimised over the logarithms of every
//! stiffness, damping and mass, so that the fit cannot leave the physical
//! region.
//!
//! **Why.** `estimate::base`'s fit starts every base mode of its profile
//! from the rigid-ground fit of the pedestal, and a pedestal on a sub-base
//! seen from rigid ground is the two springs in series: on the skid
//! machine's right pedestal the rigid fit has k_y 2.5 MN/m for a pedestal
//! of 6.0 MN/m on a sub-base of 8.0 MN/m. In some noise draws (bench seeds
//! 24001 and 24008) every start then ends in a non-physical optimum (a
//! negative or quasi-static sub-base, a pedestal k_y of 0.03-1 MN/m,
//! χ² 7e4-4e5) beside the physical one (χ² ≈ 200 for 232 real equations);
//! the θ start the diagnosis passes is replaced by that rigid fit, so no
//! choice of it reaches the physical optimum reliably.
//!
//! **The start.** Per direction the pedestal (mass m, spring d = k + iΩc)
//! on its sub-base (S = K_S + iΩC_S − Ω²M_S) has the driving-point
//! dynamic stiffness F/X = m·s² + d·S/(d + S), s = iΩ: a ratio
//! Q(s)/P(s) of a quartic and a quadratic,
//!
//! ```text
//! P = (d + S)/λ = 1 + a₁s + a₂s²,            λ = k + K_S
//! Q = (m·s²·(d + S) + d·S)/λ = b₀ + b₁s + … + b₄s⁴,
//! ```
//!
//! fitted to the measured X and F = K*·rel by linear least squares
//! (F·P − X·Q = 0, Sanathanan–Koerner reweighting by the equation's noise
//! |P|²·var F + |Q|²·var X). The chain follows in closed form: m = b₄/a₂,
//! c = (b₃ − m·a₁)/a₂, then k and 1/λ from b₂ = m + c·a₁ − c²/λ + k·a₂ and
//! b₀ = k − k²/λ (a fixed point; c²/λ is small), K_S = λ − k,
//! M_S = a₂·λ, C_S = a₁·λ − c. A direction whose chain is not physical
//! starts on a stiff sub-base (100× the pedestal) and is held rigid if the
//! data do not detect it.
//!
//! **The fit.** Levenberg–Marquardt (`estimate::levenberg::step`, the one
//! loop) on J = [`chi2`] with a finite-difference gradient and Hessian in
//! the logarithms (the Hessian's eigenvalues taken positive). Its
//! covariance is 2·H⁻¹ in the logarithms (relative standard errors).
//! What the data determine per direction is decided as in
//! `estimate::base`: the base is detected when holding that direction
//! rigid (refitted) raises J by at least [`DETECTION_THRESHOLD`], and it is
//! fully identified when its mode lies inside the speed range; a direction
//! whose mode lies outside is not offered here (the parent's
//! [`super::physical`] would reject such a sub-base anyway).

use crate::estimate::base::{chi2, BaseFitResult, BaseGroup, BaseIdentifiability, BaseParams};
use crate::estimate::base::{spring, DETECTION_THRESHOLD};
use crate::estimate::gauss_helmert::{condition_number, inverse_psd};
use crate::estimate::levenberg;
use crate::estimate::Observation;
use nalgebra::{DMatrix, DVector};
use num_complex::Complex;
use std::f64::consts::TAU;

pub mod above_range;

type C = Complex<f64>;

/// Parameters of the fit, in this order: the pedestal θ (k_y, k_z, m, c_y,
/// c_z), then (K_S, C_S, M_S) of y, then of z; all positive, fitted as
/// logarithms.
const N_PAR: usize = 11;

/// Offset of direction `d`'s sub-base (K_S, C_S, M_S) in the parameters.
fn base_at(d: usize) -> usize {
    5 + 3 * d
}

/// Most Levenberg–Marquardt iterations.
const MAX_ITERATIONS: usize = 200;

/// Sanathanan–Koerner reweightings of the rational fit.
const SK_ITERATIONS: usize = 12;

/// Logarithmic step of the finite differences [-].
const LOG_STEP: f64 = 1e-4;

/// One direction's two-degree-of-freedom chain: pedestal (k [N/m],
/// c [N·s/m], m [kg]) on a sub-base (K_S, C_S, M_S, same units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chain {
    /// Pedestal stiffness, damping, mass.
    pub k: f64,
    /// Pedestal damping [N·s/m].
    pub c: f64,
    /// Pedestal mass [kg].
    pub m: f64,
    /// Sub-base stiffness to ground [N/m].
    pub k_s: f64,
    /// Sub-base damping [N·s/m].
    pub c_s: f64,
    /// Sub-base mass [kg].
    pub m_s: f64,
}

impl Chain {
    fn positive(&self) -> bool {
        [self.k, self.c, self.m, self.k_s, self.c_s, self.m_s]
            .iter()
            .all(|v| v.is_finite() && *v > 0.0)
    }
}

/// The chain of direction `d` read off the measured receptance of `obs`
/// (module docs); `None` when the rational fit fails or its chain is not
/// physical.
pub fn chain_from_receptance(obs: &[Observation], d: usize) -> Option<Chain> {
    let rows: Vec<(f64, C, C, f64, f64)> = obs
        .iter()
        .filter(|o| o.is_finite())
        .map(|o| {
            let f = o.force()[d];
            let var_x = o.var[4 + 2 * d] + o.var[5 + 2 * d];
            let var_f: f64 = (0..2)
                .map(|c| o.kstar[d][c].norm_sqr() * (o.var[2 * c] + o.var[2 * c + 1]))
                .sum();
            (o.omega(), o.ped[d], f, var_x, var_f)
        })
        .filter(|r| r.1.norm() > 0.0)
        .collect();
    if rows.len() < 8 {
        return None;
    }
    let w_ref = rows.iter().map(|r| r.0).fold(0.0, f64::max);
    if w_ref <= 0.0 || !w_ref.is_finite() {
        return None;
    }
    // Unknowns (scaled s' = s/w_ref): a₁', a₂', b₀', …, b₄'.
    let mut coef = [0.0; 7];
    let eval = |coef: &[f64; 7], s: C| -> (C, C) {
        let p = C::new(1.0, 0.0) + s * coef[0] + s * s * coef[1];
        let q = (0..5)
            .rev()
            .fold(C::new(0.0, 0.0), |acc, k| acc * s + coef[2 + k]);
        (p, q)
    };
    for it in 0..SK_ITERATIONS {
        let mut a = DMatrix::zeros(2 * rows.len(), 7);
        let mut rhs = DVector::zeros(2 * rows.len());
        for (j, &(w, x, f, var_x, var_f)) in rows.iter().enumerate() {
            let s = C::new(0.0, w / w_ref);
            let var = if it == 0 {
                var_f + (f / x).norm_sqr() * var_x
            } else {
                let (p, q) = eval(&coef, s);
                p.norm_sqr() * var_f + q.norm_sqr() * var_x
            };
            if !(var > 0.0 && var.is_finite()) {
                return None;
            }
            let wt = 1.0 / var.sqrt();
            // X·Q − F·(a₁'s' + a₂'s'²) = F.
            let mut cols = [C::new(0.0, 0.0); 7];
            cols[0] = -f * s;
            cols[1] = -f * s * s;
            let mut sk = C::new(1.0, 0.0);
            for col in cols.iter_mut().skip(2) {
                *col = x * sk;
                sk *= s;
            }
            for (k, col) in cols.iter().enumerate() {
                a[(2 * j, k)] = wt * col.re;
                a[(2 * j + 1, k)] = wt * col.im;
            }
            rhs[2 * j] = wt * f.re;
            rhs[2 * j + 1] = wt * f.im;
        }
        // Columns normalised: X and F differ by many orders of magnitude.
        let norms: Vec<f64> = (0..7).map(|k| a.column(k).norm()).collect();
        if norms.iter().any(|n| !(*n > 0.0 && n.is_finite())) {
            return None;
        }
        for (k, n) in norms.iter().enumerate() {
            a.column_mut(k).scale_mut(1.0 / n);
        }
        let sol = a.svd(true, true).solve(&rhs, 1e-14).ok()?;
        for (k, n) in norms.iter().enumerate() {
            coef[k] = sol[k] / n;
        }
    }
    // Unscaled coefficients.
    let (a1, a2) = (coef[0] / w_ref, coef[1] / (w_ref * w_ref));
    let b: [f64; 5] = std::array::from_fn(|k| coef[2 + k] / w_ref.powi(k as i32));
    let m = b[4] / a2;
    let c = (b[3] - m * a1) / a2;
    let (mut k, mut v) = ((b[2] - m - c * a1) / a2, 0.0);
    for _ in 0..20 {
        v = (k - b[0]) / (k * k);
        k = (b[2] - m - c * a1 + c * c * v) / a2;
    }
    let lambda = 1.0 / v;
    let chain = Chain {
        k,
        c,
        m,
        k_s: lambda - k,
        c_s: a1 * lambda - c,
        m_s: a2 * lambda,
    };
    chain.positive().then_some(chain)
}

/// The pedestal θ and the sub-base of parameters `p`; directions not in
/// `moving` stand on rigid ground.
fn unpack(p: &[f64; N_PAR], moving: [bool; 2]) -> ([f64; 5], BaseParams) {
    let theta = std::array::from_fn(|k| p[k]);
    let mut base = BaseParams::RIGID;
    for d in (0..2).filter(|&d| moving[d]) {
        let o = base_at(d);
        base.k[d] = p[o];
        base.c[d] = p[o + 1];
        base.m[d] = p[o + 2];
    }
    (theta, base)
}

/// The likelihood of one pedestal `b` on its sub-base, over the
/// logarithms of the free parameters.
struct Problem<'a> {
    obs: &'a [Vec<Observation>],
    group: BaseGroup,
    /// Every parameter (module order), positive.
    p: [f64; N_PAR],
    /// Directions whose sub-base moves.
    moving: [bool; 2],
}

impl Problem<'_> {
    /// Indices of the free parameters.
    fn free(&self) -> Vec<usize> {
        (0..N_PAR)
            .filter(|&k| k < 5 || self.moving[(k - 5) / 3])
            .collect()
    }

    /// J at the parameters with the free ones at exp(`u`).
    fn cost(&self, free: &[usize], u: &DVector<f64>) -> Option<f64> {
        let mut p = self.p;
        for (i, &k) in free.iter().enumerate() {
            p[k] = u[i].exp();
        }
        let (theta, base) = unpack(&p, self.moving);
        chi2(self.obs, &self.group, &[theta], &base)
            .ok()
            .filter(|v| v.is_finite())
    }

    /// Half the gradient and half the Hessian of J in the logarithms
    /// (finite differences; the Hessian's eigenvalues taken positive, so
    /// that every damped step is a descent direction).
    fn derivatives(
        &self,
        free: &[usize],
        u: &DVector<f64>,
        f0: f64,
    ) -> Option<(DVector<f64>, DMatrix<f64>)> {
        let n = free.len();
        let h = LOG_STEP;
        let at = |moves: &[(usize, f64)]| {
            let mut v = u.clone();
            for &(i, d) in moves {
                v[i] += d;
            }
            self.cost(free, &v)
        };
        let plus: Vec<f64> = (0..n).map(|i| at(&[(i, h)])).collect::<Option<_>>()?;
        let minus: Vec<f64> = (0..n).map(|i| at(&[(i, -h)])).collect::<Option<_>>()?;
        let mut g = DVector::zeros(n);
        let mut hess = DMatrix::zeros(n, n);
        for i in 0..n {
            g[i] = 0.25 * (plus[i] - minus[i]) / h;
            hess[(i, i)] = 0.5 * (plus[i] - 2.0 * f0 + minus[i]) / (h * h);
            for j in 0..i {
                let both = at(&[(i, h), (j, h)])?;
                let v = 0.5 * (both - plus[i] - plus[j] + f0) / (h * h);
                hess[(i, j)] = v;
                hess[(j, i)] = v;
            }
        }
        let eig = hess.symmetric_eigen();
        let top = eig.eigenvalues.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut vecs = eig.eigenvectors.clone();
        for (k, &v) in eig.eigenvalues.iter().enumerate() {
            vecs.column_mut(k).scale_mut(v.abs().max(1e-12 * top));
        }
        let hess = vecs * eig.eigenvectors.transpose();
        Some((g, hess))
    }

    /// Minimises J over the free parameters from the current ones; returns
    /// J, half the Hessian at the end (the Fisher information in the
    /// logarithms), whether it converged and the iterations.
    fn minimise(&mut self) -> Option<(f64, DMatrix<f64>, bool, usize)> {
        let free = self.free();
        let mut u = DVector::from_iterator(free.len(), free.iter().map(|&k| self.p[k].ln()));
        let mut cost = self.cost(&free, &u)?;
        let mut lambda = 1e-3;
        let mut converged = false;
        let mut iterations = 0;
        for it in 0..MAX_ITERATIONS {
            iterations = it + 1;
            let (g, hess) = self.derivatives(&free, &u, cost)?;
            let mut eval = |v: &DVector<f64>| self.cost(&free, v).map(|c| (c, DVector::zeros(0)));
            let Some(step) = levenberg::step(&u, cost, &g, &hess, lambda, 1e-4, 1e-12, &mut eval)
            else {
                converged = true;
                break;
            };
            u = step.u;
            cost = step.cost;
            lambda = step.lambda;
            if step.converged {
                converged = true;
                break;
            }
        }
        for (i, &k) in free.iter().enumerate() {
            self.p[k] = u[i].exp();
        }
        let (_, hess) = self.derivatives(&free, &u, cost)?;
        Some((cost, hess, converged, iterations))
    }
}

/// RMS [N] of the unweighted equation residual of pedestal θ on `base`
/// (`estimate::base`'s equation for a group of one: e = (d − Ω²m)·X − F −
/// d·G·(F + Ω²m·X), d = k + iΩc, G the base's receptance) over the finite
/// observations `obs` and both directions.
fn residual_rms(obs: &[Observation], theta: &[f64; 5], base: &BaseParams) -> f64 {
    let (mut ss, mut n) = (0.0, 0usize);
    for o in obs.iter().filter(|o| o.is_finite()) {
        let w = o.omega();
        let f = o.force();
        for (d, (f, x)) in f.iter().zip(o.ped).enumerate() {
            let spring = spring(theta, d, w);
            let g = base.receptance(d, w);
            let inertia = w * w * theta[2];
            let e = (spring - inertia) * x - f - spring * g * (f + inertia * x);
            ss += e.norm_sqr();
            n += 2;
        }
    }
    (ss / n.max(1) as f64).sqrt()
}

/// Bearing `b` (index into `obs`) on its own sub-base, fitted from the
/// chain its receptance shows (module docs). `rigid` is
/// `estimate::base`'s fit of the same group on the same data: its
/// rigid-ground χ² (the likelihood ratio's reference) and speeds are kept.
/// `None` when no direction's chain is physical, the fit fails, or a
/// detected sub-base's mode lies outside the speed range.
pub fn fit_from_receptance(
    obs: &[Vec<Observation>],
    b: usize,
    rigid: &BaseFitResult,
) -> Option<BaseFitResult> {
    let row = obs.get(b)?;
    let chains = [chain_from_receptance(row, 0), chain_from_receptance(row, 1)];
    let pedestal = rigid.pedestals.first()?;
    let masses: Vec<f64> = chains.iter().flatten().map(|c| c.m).collect();
    if masses.is_empty() {
        return None;
    }
    let m = masses.iter().sum::<f64>() / masses.len() as f64;
    let mut p = [0.0; N_PAR];
    p[2] = m;
    for d in 0..2 {
        let o = base_at(d);
        let chain = chains[d].unwrap_or(Chain {
            k: pedestal[d].abs().max(1.0),
            c: pedestal[3 + d].abs().max(1e-6),
            m,
            k_s: 100.0 * pedestal[d].abs().max(1.0),
            c_s: 100.0 * pedestal[3 + d].abs().max(1e-6),
            m_s: m,
        });
        p[d] = chain.k;
        p[3 + d] = chain.c;
        p[o] = chain.k_s;
        p[o + 1] = chain.c_s;
        p[o + 2] = chain.m_s;
    }
    let mut problem = Problem {
        obs,
        group: BaseGroup { bearings: vec![b] },
        p,
        moving: [true; 2],
    };
    let (mut cost, mut hess, mut converged, mut iterations) = problem.minimise()?;
    // Detection per direction: the same fit with that direction held
    // rigid; a direction not detected stays rigid.
    for d in 0..2 {
        if !problem.moving[d] {
            continue;
        }
        let mut null = Problem {
            obs,
            group: problem.group.clone(),
            p: problem.p,
            moving: problem.moving,
        };
        null.moving[d] = false;
        let Some(fit) = null.minimise() else { continue };
        if fit.0 - cost < DETECTION_THRESHOLD {
            problem = null;
            (cost, hess, converged, iterations) = fit;
        }
    }
    if !problem.moving.iter().any(|&m| m) {
        return None;
    }
    let speeds = &rigid.speeds_hz;
    let (f_lo, f_hi) = (
        speeds.iter().copied().fold(f64::INFINITY, f64::min),
        speeds.iter().copied().fold(0.0, f64::max),
    );
    let free = problem.free();
    let cov_log = inverse_psd(&hess);
    let se_of = |k: usize| -> f64 {
        free.iter()
            .position(|&x| x == k)
            .map_or(0.0, |i| problem.p[k] * cov_log[(i, i)].max(0.0).sqrt())
    };
    let (theta, base) = unpack(&problem.p, problem.moving);
    let mut base_se = BaseParams {
        k: [f64::INFINITY; 2],
        c: [f64::INFINITY; 2],
        m: [f64::INFINITY; 2],
    };
    let mut base_frequency_hz = [f64::NAN; 2];
    let mut identifiability = [BaseIdentifiability::NotDetected; 2];
    for d in (0..2).filter(|&d| problem.moving[d]) {
        let o = base_at(d);
        base_se.k[d] = se_of(o);
        base_se.c[d] = se_of(o + 1);
        base_se.m[d] = se_of(o + 2);
        let f = (base.k[d] / base.m[d]).sqrt() / TAU;
        base_frequency_hz[d] = f;
        if !(f >= f_lo && f <= f_hi) {
            return None;
        }
        identifiability[d] = BaseIdentifiability::Full;
    }
    // The pedestal's covariance in θ's units.
    let mut pedestal_covariance = [[0.0; 5]; 5];
    for (a, row) in pedestal_covariance.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            if let (Some(i), Some(j)) = (
                free.iter().position(|&x| x == a),
                free.iter().position(|&x| x == c),
            ) {
                *v = problem.p[a] * problem.p[c] * cov_log[(i, j)];
            }
        }
    }
    Some(BaseFitResult {
        pedestals: vec![theta],
        pedestal_std_err: vec![std::array::from_fn(se_of)],
        split_unresolved: vec![[false; 3]],
        base_unresolved: [[false; 3]; 2],
        pedestal_covariance: vec![pedestal_covariance],
        base,
        base_std_err: base_se,
        base_frequency_hz,
        identifiability,
        chi2: cost,
        dof: (4 * speeds.len()).saturating_sub(free.len()),
        chi2_rigid: rigid.chi2_rigid,
        pedestal_residual_rms: vec![residual_rms(&obs[b], &theta, &base)],
        condition_number: condition_number(&hess),
        converged,
        iterations,
        speeds_hz: speeds.clone(),
    })
}
