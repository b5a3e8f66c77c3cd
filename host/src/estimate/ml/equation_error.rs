//! The equation error (module docs of [`super`], "Equation error"): the
//! variance τ² that brings χ² to its degrees of freedom, the fit of the
//! combined model iterated with it, and the log-determinant term that
//! compares it with a rescaled noise.

use super::rigid::{theta_vector, Rigid};
use super::{fit_system, MlError, MlFit, Weighting};
use crate::estimate::Observation;
use plinth_shared::regression::{Parameter, PARAMETERS};

/// The equation error's variance τ² [N²] (module docs) under which
/// J(θ) = `dof` at `theta`: 0 when J(θ) ≤ `dof` with the noise alone.
/// J falls monotonically with τ², and with τ² = Σ|e|²/dof alone it is at
/// most `dof`, so bisection between the two finds it.
pub fn equation_var_for_chi2(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    dof: usize,
) -> Result<f64, MlError> {
    let mut eq = Rigid::new(obs, &Weighting::default());
    var_for_chi2(&mut eq, theta, dof)
}

/// τ² with J(θ; τ²) = `dof` (see [`equation_var_for_chi2`]) by safeguarded
/// Newton steps on 1/J, nearly linear in τ² (exactly so when the equation
/// error dominates), inside a bracket that bisects when a step leaves it.
fn var_for_chi2(eq: &mut Rigid, theta: &[f64; PARAMETERS], dof: usize) -> Result<f64, MlError> {
    let target = dof.max(1) as f64;
    eq.set_equation_var(0.0);
    let (mut cost, mut slope) = eq.cost_and_slope(theta)?;
    if cost <= target {
        return Ok(0.0);
    }
    let sum_sq: f64 = eq
        .speeds
        .iter()
        .map(|sp| (sp.a * theta_vector(theta) - sp.b).norm_squared())
        .sum();
    let (mut lo, mut hi) = (0.0, sum_sq / target);
    if !(hi.is_finite() && hi > 0.0) {
        return Err(MlError::NonFinite);
    }
    let mut x = 0.0;
    for _ in 0..200 {
        if cost > target {
            lo = x;
        } else {
            hi = x;
        }
        // Newton on 1/J − 1/target: x + (J/J')·(1 − J/target).
        let newton = x + (cost / slope) * (1.0 - cost / target);
        let next = if newton.is_finite() && newton > lo && newton < hi {
            newton
        } else if lo > 0.0 {
            (lo * hi).sqrt()
        } else {
            0.5 * hi
        };
        if (next - x).abs() <= 1e-9 * next || hi - lo <= 1e-6 * hi {
            return Ok(next);
        }
        x = next;
        eq.set_equation_var(x);
        (cost, slope) = eq.cost_and_slope(theta)?;
    }
    Ok(x)
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
    let eq = Rigid::new(obs, &Weighting::equation_error(equation_var));
    let mut sum = 0.0;
    for s in 0..eq.speeds.len() {
        let l = eq.factor(s, theta)?;
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
    let mut eq = Rigid::new(obs, &Weighting::default());
    let mut fit = fit_system(&eq, obs.len(), columns, start)?;
    let dof = fit.dof;
    for _ in 0..MAX_EQUATION_ERROR_ITERATIONS {
        let var = var_for_chi2(&mut eq, &fit.theta, dof)?;
        let settled =
            (var - fit.equation_var).abs() <= EQUATION_ERROR_TOLERANCE * var.max(fit.equation_var);
        eq.set_equation_var(var);
        fit = fit_system(&eq, obs.len(), columns, &fit.theta)?;
        if settled {
            return Ok((fit, true));
        }
    }
    Ok((fit, false))
}
