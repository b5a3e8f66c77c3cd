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
//! found by the one Levenberg–Marquardt loop of [`super::gauss_helmert`]
//! on the whitened residuals w = L⁻¹e (Σ = L·Lᵀ), this model being its
//! [`Equations`](super::gauss_helmert::Equations) implementation [`Rigid`] with analytic derivatives: e is
//! linear in θ (∂e/∂θ = A, the paper's regression rows) and Σ quadratic in
//! it, so ∂w/∂θ_k = L⁻¹A_k − Φ(L⁻¹·∂Σ/∂θ_k·L⁻ᵀ)·w (Φ: the lower triangle
//! with half the diagonal, the derivative of the Cholesky factor). The
//! per-speed work that does not depend on θ (A, the right-hand side, the
//! covariance of the `rel` noise through K*) is done once, from a given
//! start (the OLS estimate). The Fisher
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

mod bound;
mod chi2;
mod eiv;
mod equation_error;
mod rigid;
#[cfg(test)]
mod tests;

pub use bound::{bound, fisher_information, ols_covariance, ols_covariance_with};
pub use chi2::{chi2_two_sided_p, cost, cost_over, cost_with};
pub use eiv::{eiv_covariance, EivCovariance, MIN_INFORMATION_SIGMAS};
pub use equation_error::{equation_var_for_chi2, fit_with_equation_error, log_det};
pub(crate) use rigid::rows;
pub use rigid::{equation_covariance, equation_residual, Rigid};

use super::gauss_helmert as gh;
use super::Observation;
use bound::{first_failure, fisher_of, spread};
use plinth_shared::regression::{Parameter, PARAMETERS};
use rigid::Speed;
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

/// What a fit assumes beyond the observations' own noise: the equation
/// error (module docs) and a factor on each observation's covariance (a
/// robust reweighting layered on top sets it to 1/weight).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Weighting<'a> {
    /// Variance τ² [N²] of an equation error on every real equation.
    pub equation_var: f64,
    /// Per observation (same order), the factor its covariance
    /// Σ_i(θ) + τ²·I is multiplied by [-]; `None`: 1 for all.
    pub cov_scale: Option<&'a [f64]>,
}

impl Weighting<'_> {
    /// Only an equation error of variance `equation_var` [N²].
    pub fn equation_error(equation_var: f64) -> Self {
        Self {
            equation_var,
            cov_scale: None,
        }
    }
}
/// When the ML iteration stops: at most 200 iterations, a step below 1e-7
/// standard errors or a relative decrease of J below 1e-13.
const SETTINGS: gh::Settings = gh::Settings {
    max_iterations: 200,
    step_tol: 1e-7,
    decrease_tol: 1e-13,
};

/// The ML estimate (module docs) of the parameters in `columns` from `start`
/// (the others held at their `start` values, normally 0).
pub fn fit(
    obs: &[Observation],
    columns: &[Parameter],
    start: &[f64; PARAMETERS],
) -> Result<MlFit, MlError> {
    fit_weighted(obs, columns, start, &Weighting::default())
}

/// [`fit`] with an equation error of variance `equation_var` [N²] on every
/// real equation ([`fit_with_equation_error`]).
pub fn fit_with(
    obs: &[Observation],
    columns: &[Parameter],
    start: &[f64; PARAMETERS],
    equation_var: f64,
) -> Result<MlFit, MlError> {
    fit_weighted(
        obs,
        columns,
        start,
        &Weighting::equation_error(equation_var),
    )
}

/// The ML fit of one pedestal on rigid ground from its observations (each
/// with the noise variance of every measured number) under `weighting`
/// (equation error, per-observation covariance factors): the estimation
/// core's entry point for one pedestal.
pub fn fit_weighted(
    obs: &[Observation],
    columns: &[Parameter],
    start: &[f64; PARAMETERS],
    weighting: &Weighting<'_>,
) -> Result<MlFit, MlError> {
    let eq = Rigid::new(obs, weighting);
    fit_system(&eq, obs.len(), columns, start)
}

pub(super) fn fit_system(
    eq: &Rigid,
    n_obs: usize,
    columns: &[Parameter],
    start: &[f64; PARAMETERS],
) -> Result<MlFit, MlError> {
    let p = columns.len();
    let n_eq = 4 * n_obs;
    if n_eq <= p {
        return Err(MlError::TooFewEquations {
            equations: n_eq,
            parameters: p,
        });
    }
    let finite = |sp: &Speed| {
        sp.a.iter()
            .chain(sp.b.iter())
            .chain(sp.sigma_rel.iter())
            .all(|v| v.is_finite())
            && sp.var_ped.iter().all(|v| v.is_finite() && *v >= 0.0)
            && sp.scale.is_finite()
            && sp.scale > 0.0
    };
    if !eq.speeds.iter().all(finite) || !start.iter().all(|v| v.is_finite()) {
        return Err(MlError::NonFinite);
    }
    // Unknowns in units where each explains the right-hand side: u_i = θ_i/s_i.
    let mut a_norm = [0.0f64; PARAMETERS];
    let mut b_norm = 0.0;
    for sp in &eq.speeds {
        for (c, v) in a_norm.iter_mut().enumerate() {
            *v += sp.a.column(c).norm_squared();
        }
        b_norm += sp.b.norm_squared();
    }
    let b_norm = b_norm.sqrt().max(f64::MIN_POSITIVE);
    let scale: [f64; PARAMETERS] = std::array::from_fn(|c| {
        let s = b_norm / a_norm[c].sqrt();
        if s.is_finite() && s > 0.0 {
            s
        } else {
            1.0
        }
    });
    let free: [bool; PARAMETERS] =
        std::array::from_fn(|k| columns.iter().any(|&c| c as usize == k));
    // J must be evaluable at the start: its failure names the speed.
    eq.cost(start)?;
    let m = gh::minimise(eq, start, &scale, &free, None, &SETTINGS)
        .ok_or_else(|| first_failure(eq, start))?;
    let theta: [f64; PARAMETERS] = std::array::from_fn(|i| m.p[i]);
    let (covariance, condition_number) = spread(&fisher_of(eq, columns, &theta)?, columns);
    Ok(MlFit {
        theta,
        covariance,
        equation_var: eq.equation_var,
        chi2: m.cost,
        dof: n_eq - p,
        iterations: m.iterations,
        converged: m.converged,
        condition_number,
        residual_rms: eq.residual_rms(&theta),
    })
}
