//! χ² of a pedestal estimate under the noise model: J(θ) = Σ eᵀΣ(θ)⁻¹e
//! over the speeds and where it falls in its χ² distribution.

use super::MlError;
use crate::estimate::Observation;
use plinth_shared::regression::PARAMETERS;

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
    cost_over(obs, theta, equation_var)
}

/// [`cost_with`] over the observations `obs` as they come, one speed at a
/// time (the same arithmetic as `Rigid::cost` under
/// `Weighting::equation_error`, without holding every speed's data) [-].
pub fn cost_over<'a>(
    obs: impl IntoIterator<Item = &'a Observation>,
    theta: &[f64; PARAMETERS],
    equation_var: f64,
) -> Result<f64, MlError> {
    super::rigid::cost_of(
        obs.into_iter().map(|o| super::rigid::Speed::new(o, 1.0)),
        theta,
        equation_var,
    )
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
