//! Maximum-likelihood errors-in-variables fit of the pedestal model.
//!
//! Per speed the pedestal equation residual (Feng & Hahn eq. 3 with eq. 2)
//!
//! ```text
//! e = H(θ)·X_ped − K*·rel,   H = diag(k_y − Ω²m + iΩc_y, k_z − Ω²m + iΩc_z),
//! K* = K_b + iΩ·C_b
//! ```
//!
//! is zero for the true phasors. The measured phasors carry noise in *both*
//! `ped` and `rel` (variances per real number from [`super::noise`]), so the
//! real 4-vector e = (Re e_y, Im e_y, Re e_z, Im e_z) at the true θ is
//! zero-mean with covariance
//!
//! ```text
//! Σ(θ) = B_ped(θ)·D_ped·B_pedᵀ + B_rel·D_rel·B_relᵀ
//! ```
//!
//! where B are the real 4×4 forms of ∂e/∂ped = H(θ) and ∂e/∂rel = −K*
//! (a complex factor a acts on (re, im) as [[Re a, −Im a], [Im a, Re a]]).
//! Σ depends on θ, correlates y and z through K*'s cross terms, and real and
//! imaginary parts when the noise of the real and imaginary parts differ.
//!
//! With Gaussian noise, eliminating the unknown true phasors from the
//! likelihood (the Gauss–Helmert model; e is linear in the measured numbers)
//! leaves the ML estimate as the minimiser of
//!
//! ```text
//! J(θ) = Σ_speeds eᵀ Σ(θ)⁻¹ e
//! ```
//!
//! found here by Levenberg–Marquardt on the whitened residuals L⁻¹e
//! (Σ = L·Lᵀ), with the Jacobian by central differences (it includes the
//! dependence of Σ on θ), from a given start (the OLS estimate). The Fisher
//! information of θ in this model is F = Σ Aᵀ Σ(θ)⁻¹ A with A = ∂e/∂θ (the
//! paper's regression rows); F⁻¹ is the Cramér–Rao bound, at the estimate the
//! covariance reported, at the truth the bound `plinth accuracy` compares with.
//! At the minimum J is χ² with 4n − p degrees of freedom when the noise model
//! is right: the check of its absolute scale.
//!
//! **Equation error.** When J is far above its degrees of freedom with a
//! noise level that was measured (noise columns, digits), the residuals hold
//! something the noise does not: a model error (bearing coefficients a little
//! off, a constant vector left on `rel`, unsteady phasors through a fast
//! resonance). Σ(θ) then says nothing about it, and the fit, free to trade
//! residual against Σ(θ), goes where the model error is small relative to
//! the *noise* (near the pedestal resonance, where H(θ)·ped is small) rather
//! than where the data are right: on field-like data it can end further from
//! the truth than OLS. [`fit_with_equation_error`] adds the paper's own error
//! model to the noise: an independent error of the same variance τ² [N²] on
//! every real equation (what OLS assumes), Σ_τ(θ) = Σ(θ) + τ²·I, with τ² set
//! so that J = 4n − p (the method of moments, iterated with θ). τ = 0 when
//! the noise explains the residuals (the ML fit unchanged); when the model
//! error dominates the fit tends to OLS, and its Fisher information, the
//! covariance of the combined model, grows accordingly.

use super::Observation;
use nalgebra::{DMatrix, DVector, Matrix4, SMatrix, Vector4};
use num_complex::Complex;
use plinth_shared::regression::{equations, Parameter, PARAMETERS};

/// Why an ML fit could not run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MlError {
    /// No more equations than parameters.
    #[error("{equations} equations for {parameters} parameters: nothing to fit")]
    TooFewEquations {
        /// Real equations available.
        equations: usize,
        /// Parameters estimated.
        parameters: usize,
    },
    /// The noise model gives no noise at all at some speed.
    #[error("the noise model gives zero noise at {speed_hz} Hz: the equation cannot be weighted")]
    NoNoise {
        /// The speed [Hz].
        speed_hz: f64,
    },
    /// A non-finite number in the data or the start.
    #[error("non-finite number in the data or the starting estimate")]
    NonFinite,
}

/// The result of [`fit`].
#[derive(Clone, Debug, PartialEq)]
pub struct MlFit {
    /// θ = (k_y [N/m], k_z [N/m], m [kg], c_y [N·s/m], c_z [N·s/m]); fixed
    /// parameters stay at their start value.
    pub theta: [f64; PARAMETERS],
    /// F⁻¹ at the estimate in θ units, over all five parameters (zero rows
    /// and columns for fixed ones, infinite diagonal when not estimable):
    /// the covariance if the noise model's absolute scale is right.
    pub covariance: [[f64; PARAMETERS]; PARAMETERS],
    /// The equation error's variance the fit assumed [N²] per real equation
    /// (0 unless [`fit_with_equation_error`]; see [`fit_with_equation_error`]).
    pub equation_var: f64,
    /// J(θ̂) = Σ eᵀΣ⁻¹e at the estimate [-].
    pub chi2: f64,
    /// Degrees of freedom 4n − p.
    pub dof: usize,
    /// Levenberg–Marquardt iterations taken.
    pub iterations: usize,
    /// True when the iteration met its convergence test.
    pub converged: bool,
    /// Condition number of the whitened, column-normalised regression [-].
    pub condition_number: f64,
    /// RMS of the unweighted equation residuals e [N].
    pub residual_rms: f64,
}

impl MlFit {
    /// Standard errors sqrt(variance_scale·diag(F⁻¹)) in θ units.
    pub fn std_err(&self, variance_scale: f64) -> [f64; PARAMETERS] {
        std::array::from_fn(|i| (variance_scale * self.covariance[i][i]).sqrt())
    }

    /// χ²/dof: 1 when the noise model's absolute scale is right.
    pub fn chi2_per_dof(&self) -> f64 {
        self.chi2 / self.dof.max(1) as f64
    }
}

/// Real 2×2 block of a complex factor `a` acting on (re, im).
fn put(j: &mut SMatrix<f64, 4, 8>, row: usize, col: usize, a: Complex<f64>) {
    j[(row, col)] = a.re;
    j[(row, col + 1)] = -a.im;
    j[(row + 1, col)] = a.im;
    j[(row + 1, col + 1)] = a.re;
}

/// The pedestal's dynamic stiffness (y, z) k − Ω²m + iΩc [N/m] at Ω [rad/s].
fn dynamic_stiffness(theta: &[f64; PARAMETERS], omega: f64) -> [Complex<f64>; 2] {
    let w2 = omega * omega;
    [
        Complex::new(theta[0] - w2 * theta[2], omega * theta[3]),
        Complex::new(theta[1] - w2 * theta[2], omega * theta[4]),
    ]
}

/// Σ(θ) of one speed (module docs) [N²].
pub fn equation_covariance(o: &Observation, theta: &[f64; PARAMETERS]) -> Matrix4<f64> {
    let h = dynamic_stiffness(theta, o.omega());
    let mut b = SMatrix::<f64, 4, 8>::zeros();
    for (d, &hd) in h.iter().enumerate() {
        put(&mut b, 2 * d, 4 + 2 * d, hd);
        for c in 0..2 {
            put(&mut b, 2 * d, 2 * c, -o.kstar[d][c]);
        }
    }
    let mut bd = b;
    for (c, v) in o.var.iter().enumerate() {
        bd.column_mut(c).scale_mut(*v);
    }
    bd * b.transpose()
}

/// The regression rows A (4×5, eq. 4 in (y re, y im, z re, z im) order) and
/// right-hand side of one speed, from the shared definition.
fn rows(o: &Observation) -> (SMatrix<f64, 4, PARAMETERS>, Vector4<f64>) {
    let eqs = equations(o.omega(), &o.ped, &o.force());
    let a = SMatrix::<f64, 4, PARAMETERS>::from_fn(|r, c| eqs[r].row[c]);
    let rhs = Vector4::from_fn(|r, _| eqs[r].rhs);
    (a, rhs)
}

/// The residual e = A·θ − b of one speed [N].
pub fn equation_residual(o: &Observation, theta: &[f64; PARAMETERS]) -> Vector4<f64> {
    let (a, rhs) = rows(o);
    a * nalgebra::SVector::<f64, PARAMETERS>::from_column_slice(theta) - rhs
}

/// Lower Cholesky factor of Σ, regularised by 1e-12 of its mean diagonal
/// when it is singular (a channel without noise).
fn cholesky(s: Matrix4<f64>, speed_hz: f64) -> Result<Matrix4<f64>, MlError> {
    let trace = s.trace();
    if !(trace > 0.0 && trace.is_finite()) {
        return Err(MlError::NoNoise { speed_hz });
    }
    if let Some(c) = s.cholesky() {
        return Ok(c.l());
    }
    let jitter = Matrix4::identity() * (1e-12 * trace / 4.0);
    (s + jitter)
        .cholesky()
        .map(|c| c.l())
        .ok_or(MlError::NoNoise { speed_hz })
}

/// Σ(θ) of one speed plus an equation error of variance `equation_var`
/// [N²] on each of its four real equations ([`fit_with_equation_error`]).
fn covariance_with(o: &Observation, theta: &[f64; PARAMETERS], equation_var: f64) -> Matrix4<f64> {
    equation_covariance(o, theta) + Matrix4::identity() * equation_var
}

/// Whitened residuals L⁻¹e of every speed, stacked [-].
fn whitened(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    equation_var: f64,
) -> Result<DVector<f64>, MlError> {
    let mut out = DVector::zeros(4 * obs.len());
    for (j, o) in obs.iter().enumerate() {
        let l = cholesky(covariance_with(o, theta, equation_var), o.speed_hz)?;
        let e = equation_residual(o, theta);
        let w = l.solve_lower_triangular(&e).ok_or(MlError::NoNoise {
            speed_hz: o.speed_hz,
        })?;
        out.fixed_rows_mut::<4>(4 * j).copy_from(&w);
    }
    Ok(out)
}

/// J(θ) = Σ eᵀΣ(θ)⁻¹e over the speeds [-].
pub fn cost(obs: &[Observation], theta: &[f64; PARAMETERS]) -> Result<f64, MlError> {
    cost_with(obs, theta, 0.0)
}

/// J(θ) with an equation error of variance `equation_var` [N²] per real
/// equation ([`fit_with_equation_error`]) [-].
pub fn cost_with(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    equation_var: f64,
) -> Result<f64, MlError> {
    Ok(whitened(obs, theta, equation_var)?.norm_squared())
}

/// Fisher information Σ Aᵀ Σ(θ)⁻¹ A over `columns` (θ units) at `theta`:
/// its inverse is the Cramér–Rao bound when the observations hold the true
/// phasors and the true noise.
pub fn fisher_information(
    obs: &[Observation],
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
) -> Result<DMatrix<f64>, MlError> {
    fisher_with(obs, columns, theta, 0.0)
}

fn fisher_with(
    obs: &[Observation],
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
    equation_var: f64,
) -> Result<DMatrix<f64>, MlError> {
    let p = columns.len();
    let mut f = DMatrix::zeros(p, p);
    for o in obs {
        let (a, _) = rows(o);
        let l = cholesky(covariance_with(o, theta, equation_var), o.speed_hz)?;
        let sel = DMatrix::from_fn(4, p, |r, c| a[(r, columns[c] as usize)]);
        let l_dyn = DMatrix::from_fn(4, 4, |r, c| l[(r, c)]);
        let w = l_dyn.solve_lower_triangular(&sel).ok_or(MlError::NoNoise {
            speed_hz: o.speed_hz,
        })?;
        f += w.transpose() * w;
    }
    Ok(f)
}

/// Inverse of a symmetric positive semi-definite matrix through its unit-
/// diagonal scaling, with the condition number of the scaled matrix; the
/// diagonal is infinite where the matrix is singular.
fn inverse_psd(f: &DMatrix<f64>) -> (DMatrix<f64>, f64) {
    let p = f.nrows();
    let d: Vec<f64> = (0..p).map(|i| f[(i, i)].max(0.0).sqrt()).collect();
    if d.iter().any(|&x| !(x > 0.0 && x.is_finite())) {
        let mut inf = DMatrix::zeros(p, p);
        for i in 0..p {
            inf[(i, i)] = f64::INFINITY;
        }
        return (inf, f64::INFINITY);
    }
    let scaled = DMatrix::from_fn(p, p, |r, c| f[(r, c)] / (d[r] * d[c]));
    let eig = scaled.clone().symmetric_eigen();
    let (lo, hi) = eig
        .eigenvalues
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let condition = if lo > 0.0 {
        (hi / lo).sqrt()
    } else {
        f64::INFINITY
    };
    if lo.is_nan() || lo <= hi * 1e-14 {
        let mut inf = DMatrix::zeros(p, p);
        for i in 0..p {
            inf[(i, i)] = f64::INFINITY;
        }
        return (inf, condition);
    }
    let mut inv = eig.eigenvectors.clone();
    for (k, &v) in eig.eigenvalues.iter().enumerate() {
        inv.column_mut(k).scale_mut(1.0 / v);
    }
    let inv = inv * eig.eigenvectors.transpose();
    (
        DMatrix::from_fn(p, p, |r, c| inv[(r, c)] / (d[r] * d[c])),
        condition,
    )
}

/// The covariance F⁻¹ (θ units) over all five parameters at `theta`, and the
/// condition number of the whitened column-normalised regression.
pub fn bound(
    obs: &[Observation],
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
) -> Result<([[f64; PARAMETERS]; PARAMETERS], f64), MlError> {
    bound_with(obs, columns, theta, 0.0)
}

fn bound_with(
    obs: &[Observation],
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
    equation_var: f64,
) -> Result<([[f64; PARAMETERS]; PARAMETERS], f64), MlError> {
    let f = fisher_with(obs, columns, theta, equation_var)?;
    let (inv, condition) = inverse_psd(&f);
    let mut cov = [[0.0; PARAMETERS]; PARAMETERS];
    for (r, &pr) in columns.iter().enumerate() {
        for (c, &pc) in columns.iter().enumerate() {
            cov[pr as usize][pc as usize] = inv[(r, c)];
        }
    }
    Ok((cov, condition))
}

/// The true covariance of the paper's OLS estimate under the noise model
/// (θ units, all five parameters), the sandwich
/// (AᵀA)⁻¹·(Σ Aᵀ Σ(θ) A)·(AᵀA)⁻¹ with Σ at `theta`: what OLS's scatter
/// really is, to compare with [`bound`].
pub fn ols_covariance(
    obs: &[Observation],
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
) -> [[f64; PARAMETERS]; PARAMETERS] {
    ols_covariance_with(obs, columns, theta, 0.0)
}

/// [`ols_covariance`] with an equation error of variance `equation_var`
/// [N²] per real equation ([`fit_with_equation_error`]).
pub fn ols_covariance_with(
    obs: &[Observation],
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
    equation_var: f64,
) -> [[f64; PARAMETERS]; PARAMETERS] {
    let p = columns.len();
    let mut ata = DMatrix::zeros(p, p);
    let mut meat = DMatrix::zeros(p, p);
    for o in obs {
        let (a, _) = rows(o);
        let sel = DMatrix::from_fn(4, p, |r, c| a[(r, columns[c] as usize)]);
        let s = covariance_with(o, theta, equation_var);
        let s_dyn = DMatrix::from_fn(4, 4, |r, c| s[(r, c)]);
        ata += sel.transpose() * &sel;
        meat += sel.transpose() * s_dyn * &sel;
    }
    let (inv, _) = inverse_psd(&ata);
    let cov = &inv * meat * &inv;
    let mut out = [[0.0; PARAMETERS]; PARAMETERS];
    for (r, &pr) in columns.iter().enumerate() {
        for (c, &pc) in columns.iter().enumerate() {
            out[pr as usize][pc as usize] = if inv[(r, r)].is_finite() {
                cov[(r, c)]
            } else {
                f64::INFINITY
            };
        }
    }
    out
}

/// Most Levenberg–Marquardt iterations.
const MAX_ITERATIONS: usize = 200;

/// The ML estimate (module docs) of the parameters in `columns` from `start`
/// (the others held at their `start` values, normally 0).
pub fn fit(
    obs: &[Observation],
    columns: &[Parameter],
    start: &[f64; PARAMETERS],
) -> Result<MlFit, MlError> {
    fit_with(obs, columns, start, 0.0)
}

/// [`fit`] with an equation error of variance `equation_var` [N²] on every
/// real equation ([`fit_with_equation_error`]).
pub fn fit_with(
    obs: &[Observation],
    columns: &[Parameter],
    start: &[f64; PARAMETERS],
    equation_var: f64,
) -> Result<MlFit, MlError> {
    let p = columns.len();
    let n_eq = 4 * obs.len();
    if n_eq <= p {
        return Err(MlError::TooFewEquations {
            equations: n_eq,
            parameters: p,
        });
    }
    if !obs.iter().all(Observation::is_finite) || !start.iter().all(|v| v.is_finite()) {
        return Err(MlError::NonFinite);
    }
    // Unknowns in units where each explains the right-hand side: u_i = θ_i/s_i.
    let mut a_norm = [0.0f64; PARAMETERS];
    let mut b_norm = 0.0;
    for o in obs {
        let (a, rhs) = rows(o);
        for (c, v) in a_norm.iter_mut().enumerate() {
            *v += a.column(c).norm_squared();
        }
        b_norm += rhs.norm_squared();
    }
    let b_norm = b_norm.sqrt().max(f64::MIN_POSITIVE);
    let scale: Vec<f64> = columns
        .iter()
        .map(|&c| {
            let s = b_norm / a_norm[c as usize].sqrt();
            if s.is_finite() && s > 0.0 {
                s
            } else {
                1.0
            }
        })
        .collect();
    let theta_of = |u: &DVector<f64>| -> [f64; PARAMETERS] {
        let mut t = *start;
        for (k, &c) in columns.iter().enumerate() {
            t[c as usize] = u[k] * scale[k];
        }
        t
    };
    let mut u = DVector::from_fn(p, |k, _| start[columns[k] as usize] / scale[k]);
    let mut r = whitened(obs, &theta_of(&u), equation_var)?;
    let mut cost_now = r.norm_squared();
    let mut lambda = 1e-3;
    let mut converged = false;
    let mut iterations = 0;
    const STEP: f64 = 1e-6;
    while iterations < MAX_ITERATIONS {
        iterations += 1;
        let mut jac = DMatrix::zeros(n_eq, p);
        for k in 0..p {
            let h = STEP * u[k].abs().max(1e-3);
            let mut up = u.clone();
            up[k] += h;
            let mut dn = u.clone();
            dn[k] -= h;
            let d = (whitened(obs, &theta_of(&up), equation_var)?
                - whitened(obs, &theta_of(&dn), equation_var)?)
                / (2.0 * h);
            jac.set_column(k, &d);
        }
        let g = jac.transpose() * &r;
        let hess = jac.transpose() * &jac;
        let mut residual =
            |u_new: &DVector<f64>| match whitened(obs, &theta_of(u_new), equation_var) {
                Ok(r) if r.iter().all(|v| v.is_finite()) => Some(r),
                _ => None,
            };
        match super::levenberg::step(&u, cost_now, &g, &hess, lambda, 1e-7, 1e-13, &mut residual) {
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
    let theta = theta_of(&u);
    let (covariance, condition_number) = bound_with(obs, columns, &theta, equation_var)?;
    let residual_rms = (obs
        .iter()
        .map(|o| equation_residual(o, &theta).norm_squared())
        .sum::<f64>()
        / n_eq as f64)
        .sqrt();
    Ok(MlFit {
        theta,
        covariance,
        equation_var,
        chi2: cost_now,
        dof: n_eq - p,
        iterations,
        converged,
        condition_number,
        residual_rms,
    })
}

/// The equation error's variance τ² [N²] (module docs) under which
/// J(θ) = `dof` at `theta`: 0 when J(θ) ≤ `dof` with the noise alone.
/// J falls monotonically with τ², and with τ² = Σ|e|²/dof alone it is at
/// most `dof`, so bisection between the two finds it.
pub fn equation_var_for_chi2(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    dof: usize,
) -> Result<f64, MlError> {
    let target = dof.max(1) as f64;
    if cost_with(obs, theta, 0.0)? <= target {
        return Ok(0.0);
    }
    let sum_sq: f64 = obs
        .iter()
        .map(|o| equation_residual(o, theta).norm_squared())
        .sum();
    let (mut lo, mut hi) = (0.0, sum_sq / target);
    if !(hi.is_finite() && hi > 0.0) {
        return Err(MlError::NonFinite);
    }
    for _ in 0..200 {
        let mid = if lo > 0.0 { (lo * hi).sqrt() } else { 0.5 * hi };
        if cost_with(obs, theta, mid)? > target {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-6 * hi {
            break;
        }
    }
    Ok(hi)
}

/// Most outer iterations of [`fit_with_equation_error`] (θ, then τ²).
const MAX_EQUATION_ERROR_ITERATIONS: usize = 10;

/// Relative change of τ² at which [`fit_with_equation_error`] stops.
const EQUATION_ERROR_TOLERANCE: f64 = 1e-2;

/// Σ ln det Σ_i over the speeds, Σ_i the covariance of speed i's four
/// equations with an equation error of variance `equation_var` [N²]:
/// with J, the Gaussian log-likelihood of the residuals is
/// −½(J + Σ ln det Σ_i) + const, which compares two noise hypotheses with
/// the same number of free parameters (e.g. a rescaled noise against an
/// added equation error).
pub fn log_det(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    equation_var: f64,
) -> Result<f64, MlError> {
    let mut sum = 0.0;
    for o in obs {
        let l = cholesky(covariance_with(o, theta, equation_var), o.speed_hz)?;
        sum += 2.0 * (0..4).map(|k| l[(k, k)].ln()).sum::<f64>();
    }
    Ok(sum)
}

/// The ML fit of the combined model (module docs, "Equation error"): noise
/// in the variables plus an equation error of variance τ² set by χ² = 4n − p,
/// iterated with θ from `start` until τ² changes by less than 1 %.
/// Returns the fit (its `equation_var` is τ²) and whether the iteration
/// settled.
pub fn fit_with_equation_error(
    obs: &[Observation],
    columns: &[Parameter],
    start: &[f64; PARAMETERS],
) -> Result<(MlFit, bool), MlError> {
    let mut fit = fit_with(obs, columns, start, 0.0)?;
    let dof = fit.dof;
    for _ in 0..MAX_EQUATION_ERROR_ITERATIONS {
        let var = equation_var_for_chi2(obs, &fit.theta, dof)?;
        let settled =
            (var - fit.equation_var).abs() <= EQUATION_ERROR_TOLERANCE * var.max(fit.equation_var);
        fit = fit_with(obs, columns, &fit.theta, var)?;
        if settled {
            return Ok((fit, true));
        }
    }
    Ok((fit, false))
}

/// Where χ² = `chi2` falls in the χ²(`dof`) distribution: the probability of
/// a value at least this far into the upper or lower tail (two-sided p).
pub fn chi2_two_sided_p(chi2: f64, dof: usize) -> f64 {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    match ChiSquared::new(dof.max(1) as f64) {
        Ok(d) => {
            let lower = d.cdf(chi2);
            (2.0 * lower.min(1.0 - lower)).clamp(0.0, 1.0)
        }
        Err(_) => f64::NAN,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::mul;
    use rand::{Rng, SeedableRng};

    /// A pedestal on an isotropic, cross-coupled bearing driven through its
    /// resonances: true phasors from eq. 3 solved for the pedestal, then
    /// Gaussian noise on rel and ped.
    fn synthetic(noise: f64, seed: u64) -> (Vec<Observation>, Vec<Observation>, [f64; 5]) {
        let theta = [1.0e7, 8.0e6, 150.0, 900.0, 700.0];
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let mut clean = Vec::new();
        let mut noisy = Vec::new();
        for i in 0..120 {
            let f = 10.0 + i as f64;
            let omega = 2.0 * std::f64::consts::PI * f;
            let kstar = [
                [
                    Complex::new(3e7, omega * 2e3),
                    Complex::new(1e7, omega * 3e2),
                ],
                [
                    Complex::new(-8e6, -omega * 3e2),
                    Complex::new(2.5e7, omega * 1.8e3),
                ],
            ];
            let rel = [
                Complex::from_polar(2e-5, 0.01 * f),
                Complex::from_polar(1.5e-5, 1.0 - 0.02 * f),
            ];
            let force = mul(&kstar, &rel);
            let h = dynamic_stiffness(&theta, omega);
            let ped = [force[0] / h[0], force[1] / h[1]];
            let sd = [2e-5 * noise, 1.5e-5 * noise, 1e-6 * noise, 1e-6 * noise];
            let var = std::array::from_fn(|c| 0.5 * sd[c / 2] * sd[c / 2]);
            let o = Observation {
                speed_hz: f,
                rel,
                ped,
                kstar,
                var,
            };
            clean.push(o);
            let mut n = o;
            for (c, v) in n.rel.iter_mut().chain(n.ped.iter_mut()).enumerate() {
                let s = (0.5f64).sqrt() * sd[c];
                *v += Complex::new(
                    s * rng.sample::<f64, _>(rand_distr::StandardNormal),
                    s * rng.sample::<f64, _>(rand_distr::StandardNormal),
                );
            }
            noisy.push(n);
        }
        (clean, noisy, theta)
    }

    #[test]
    fn exact_data_give_the_truth_and_zero_cost() {
        let (clean, _, theta) = synthetic(0.01, 1);
        let start = [0.9e7, 0.9e7, 140.0, 0.0, 0.0];
        let fit = fit(&clean, &Parameter::ALL, &start).unwrap();
        for (a, b) in fit.theta.iter().zip(&theta) {
            assert!((a - b).abs() <= 1e-6 * b.abs(), "{a} vs {b}");
        }
        assert!(fit.chi2 < 1e-6, "{}", fit.chi2);
    }

    #[test]
    fn noisy_fits_scatter_as_the_bound_says() {
        let (clean, _, theta) = synthetic(0.01, 1);
        let (crb, _) = bound(&clean, &Parameter::ALL, &theta).unwrap();
        let draws = 60;
        let mut sq = [0.0; 5];
        let mut chi2 = 0.0;
        for s in 0..draws {
            let (_, noisy, _) = synthetic(0.01, 100 + s);
            let f = fit(&noisy, &Parameter::ALL, &theta).unwrap();
            assert!(f.converged);
            chi2 += f.chi2_per_dof() / draws as f64;
            for i in 0..5 {
                sq[i] += (f.theta[i] - theta[i]).powi(2) / draws as f64;
            }
        }
        for i in 0..5 {
            let ratio = sq[i].sqrt() / crb[i][i].sqrt();
            assert!(
                (0.75..1.3).contains(&ratio),
                "parameter {i}: rms/crb {ratio}"
            );
        }
        assert!((chi2 - 1.0).abs() < 0.05, "χ²/dof {chi2}");
    }

    /// A model error the noise does not explain (a constant vector left on
    /// every `rel` reading, as after an imperfect slow-roll subtraction,
    /// far above the stated noise): the combined model's fit stays within
    /// 1.5 × OLS's error, its τ² brings χ²/dof to 1, and on data the noise
    /// explains it adds nothing.
    #[test]
    fn equation_error_absorbs_a_model_error() {
        let (clean, noisy, theta) = synthetic(0.001, 7);
        let offset = [
            Complex::from_polar(4e-7, 0.3),
            Complex::from_polar(3e-7, -1.2),
        ];
        let spoiled: Vec<Observation> = noisy
            .iter()
            .map(|o| {
                let mut o = *o;
                o.rel[0] += offset[0];
                o.rel[1] += offset[1];
                o
            })
            .collect();
        let worst = |t: &[f64; 5]| -> f64 {
            (0..3)
                .map(|i| ((t[i] - theta[i]) / theta[i]).abs())
                .fold(0.0, f64::max)
        };
        // OLS on the regression rows (the same rows, equal weights).
        let ols = {
            let mut ata = DMatrix::<f64>::zeros(5, 5);
            let mut atb = DVector::<f64>::zeros(5);
            for o in &spoiled {
                let (a, b) = rows(o);
                let a = DMatrix::from_fn(4, 5, |r, c| a[(r, c)]);
                let b = DVector::from_fn(4, |r, _| b[r]);
                ata += a.transpose() * &a;
                atb += a.transpose() * b;
            }
            let d: Vec<f64> = (0..5).map(|i| ata[(i, i)].sqrt()).collect();
            let scaled = DMatrix::from_fn(5, 5, |r, c| ata[(r, c)] / (d[r] * d[c]));
            let x = scaled
                .lu()
                .solve(&DVector::from_fn(5, |r, _| atb[r] / d[r]))
                .unwrap();
            let t: [f64; 5] = std::array::from_fn(|i| x[i] / d[i]);
            t
        };
        let plain = fit(&spoiled, &Parameter::ALL, &ols).unwrap();
        assert!(plain.chi2_per_dof() > 100.0, "{}", plain.chi2_per_dof());
        let (combined, settled) = fit_with_equation_error(&spoiled, &Parameter::ALL, &ols).unwrap();
        assert!(settled);
        assert!(combined.equation_var > 0.0);
        assert!(
            (combined.chi2_per_dof() - 1.0).abs() < 0.01,
            "{}",
            combined.chi2_per_dof()
        );
        let (e_ols, e_plain, e_comb) = (worst(&ols), worst(&plain.theta), worst(&combined.theta));
        assert!(
            e_comb <= 1.5 * e_ols,
            "OLS {e_ols}, ML {e_plain}, ML with equation error {e_comb}"
        );
        // Noise alone: τ² = 0 and the plain ML fit.
        let (_, noisy, _) = synthetic(0.01, 8);
        let start = theta;
        let (f, _) = fit_with_equation_error(&noisy, &Parameter::ALL, &start).unwrap();
        let g = fit(&noisy, &Parameter::ALL, &start).unwrap();
        if g.chi2 <= g.dof as f64 {
            assert_eq!(f.equation_var, 0.0);
            assert_eq!(f.theta, g.theta);
        }
        let _ = clean;
    }

    #[test]
    fn chi2_p_values() {
        assert!(chi2_two_sided_p(100.0, 100) > 0.9);
        assert!(chi2_two_sided_p(200.0, 100) < 1e-6);
        assert!(chi2_two_sided_p(40.0, 100) < 1e-6);
    }
}
