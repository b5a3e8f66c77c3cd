//! One Levenberg–Marquardt step, shared by the pedestal ML fit
//! ([`super::ml`]) and the general errors-in-variables fit
//! ([`super::gauss_helmert`]): raise the damping λ until a step lowers the
//! whitened cost J = |r|², then say whether the fit has converged.

use nalgebra::{DMatrix, DVector};

/// J and the whitened residuals (or J alone with an empty vector) at a
/// trial point, `None` where they cannot be evaluated.
pub type Evaluate<'a> = dyn FnMut(&DVector<f64>) -> Option<(f64, DVector<f64>)> + 'a;

/// The outcome of [`step`].
pub struct Step {
    /// New (scaled) parameters, whitened residuals and cost J.
    pub u: DVector<f64>,
    /// Whitened residuals at `u` (what `residual` returned with J; empty
    /// when the caller keeps only J).
    pub r: DVector<f64>,
    /// J = |r|² at `u`.
    pub cost: f64,
    /// Damping to start the next step with.
    pub lambda: f64,
    /// The step was negligible (relative decrease of J below `decrease_tol`,
    /// or every parameter moved less than `step_tol` of its standard error),
    /// or no step lowers J: the start is already the minimum.
    pub converged: bool,
}

/// From `u` with cost `cost_now`, gradient `g` = Jᵀr and Gauss–Newton
/// Hessian `hess` = JᵀJ, tries damped steps (λ raised ×4 on failure, eased
/// ÷3 on success) until `residual(u_new)` (J and the whitened residuals,
/// or J alone with an empty vector) exists and does not raise J.
#[allow(clippy::too_many_arguments)]
pub fn step(
    u: &DVector<f64>,
    cost_now: f64,
    g: &DVector<f64>,
    hess: &DMatrix<f64>,
    mut lambda: f64,
    step_tol: f64,
    decrease_tol: f64,
    residual: &mut Evaluate<'_>,
) -> Option<Step> {
    let q = u.len();
    while lambda < 1e12 {
        let mut damped = hess.clone();
        for j in 0..q {
            damped[(j, j)] += lambda * hess[(j, j)].max(1e-300);
        }
        let Some(delta) = damped.cholesky().map(|c| c.solve(&(-g))) else {
            lambda *= 4.0;
            continue;
        };
        let u_new = u + &delta;
        let Some((cost_new, r_new)) = residual(&u_new) else {
            lambda *= 4.0;
            continue;
        };
        if cost_new <= cost_now {
            let decrease = cost_now - cost_new;
            // The step measured in its own standard errors (Hessian⁻¹).
            let small = hess
                .clone()
                .cholesky()
                .map(|c| {
                    let inv = c.inverse();
                    (0..q).all(|j| delta[j].abs() <= step_tol * inv[(j, j)].sqrt())
                })
                .unwrap_or(false);
            return Some(Step {
                u: u_new,
                r: r_new,
                cost: cost_new,
                lambda: (lambda / 3.0).max(1e-12),
                converged: decrease <= decrease_tol * cost_new.max(f64::MIN_POSITIVE) || small,
            });
        }
        lambda *= 4.0;
    }
    None
}
