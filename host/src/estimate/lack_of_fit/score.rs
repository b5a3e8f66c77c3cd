//! The efficient score of an extension of the one-mass fit, shared by the
//! score tests of [`super`] ([`super::support`], [`super::delay`]).
//!
//! At the fitted parameters θ the whitened residuals w = L⁻¹e and the
//! one-mass columns X = L⁻¹∂e/∂θ are formed per speed; an extension adds
//! columns X₂ (the derivative of the whitened residual in its extra
//! parameters at zero) and the half-gradient of the Gauss-Helmert
//! criterion in them. The score of the extension with the one-mass
//! parameters' part taken out (the efficient score, `b`), its information
//! G = X₂⊥ᵀX₂⊥ (X₂ less its projection on X's span) and the one-step
//! coefficient γ = G⁻¹b follow; under the null b/√G is standard normal per
//! direction of the extension (module docs of [`super::support`], "The
//! score").

use super::super::gauss_helmert::{self as gh, Equations};
use nalgebra::{DMatrix, DVector};

/// What an extension adds at one speed: its whitened columns (4 rows
/// each) and the half-gradient of the criterion in its parameters.
pub(super) struct Extension {
    /// L_s⁻¹·∂e_s/∂q per extra parameter q (4-vectors).
    pub columns: Vec<DVector<f64>>,
    /// ½∂|L_s⁻¹e_s|²/∂q per extra parameter q.
    pub half_gradient: Vec<f64>,
}

/// What one speed offers an extension: its index, whitening factor L_s,
/// residual e_s(θ), and per one-mass parameter k the whitened column
/// L_s⁻¹∂e_s/∂θ_k and the criterion's half-gradient in θ_k (weights
/// moving with θ).
pub(super) struct AtSpeed<'a> {
    /// The speed's index in the equations.
    pub s: usize,
    /// Lower Cholesky factor of the speed's Σ at θ.
    pub l: &'a DMatrix<f64>,
    /// e_s(θ).
    pub e0: &'a DVector<f64>,
    /// L_s⁻¹∂e_s/∂θ_k per one-mass parameter.
    pub columns: &'a [DVector<f64>],
    /// ½∂|L_s⁻¹e_s|²/∂θ_k per one-mass parameter (weights moving).
    pub half_gradient: &'a [f64],
}

/// The efficient score of an extension ([`efficient_score`]).
pub(super) struct Score {
    /// The efficient score, one entry per extra parameter.
    pub b: DVector<f64>,
    /// Its information G (the extension's columns outside the one-mass span).
    pub g: DMatrix<f64>,
    /// The one-step coefficient G⁻¹b (the residual's component the
    /// extension explains; the extension's parameter is −γ).
    pub gamma: DVector<f64>,
    /// The one-mass parameters' change β (model units) once the extension
    /// is taken out of w: the refit is θ − β.
    pub beta: Vec<f64>,
}

/// The efficient score (module docs) of the extension `extension` makes
/// per speed, for the equations `eq` at the fitted parameters `theta`
/// (model units), `extra` extra parameters; `None` when a weight or a
/// projection cannot be formed, the extension returns `None`, or no
/// residual degree of freedom is left beyond the extension.
pub(super) fn efficient_score<E, F>(
    eq: &E,
    theta: &[f64],
    extra: usize,
    mut extension: F,
) -> Option<Score>
where
    E: Equations + ?Sized,
    F: FnMut(&AtSpeed<'_>) -> Option<Extension>,
{
    let n = eq.speeds();
    let np = theta.len();
    if n * 4 <= np + extra + 1 || np == 0 || extra == 0 {
        return None;
    }
    let mut x = DMatrix::<f64>::zeros(4 * n, np);
    let mut x2 = DMatrix::<f64>::zeros(4 * n, extra);
    let mut w = DVector::<f64>::zeros(4 * n);
    // Half the gradient of the Gauss-Helmert criterion Σ_s |L_s⁻¹e_s|², its
    // weights L_s(θ) moving with θ: one-mass parameters (per unit of each)
    // and the extension.
    let mut grad = DVector::<f64>::zeros(np);
    let mut grad2 = DVector::<f64>::zeros(extra);
    let mut cols = Vec::with_capacity(np);
    let mut halves = Vec::with_capacity(np);
    for s in 0..n {
        let l = gh::whitening(eq, s, theta)?;
        let e0 = eq.error(s, theta);
        let ws = l.solve_lower_triangular(&e0)?;
        w.rows_mut(4 * s, 4).copy_from(&ws);
        cols.clear();
        halves.clear();
        for k in 0..np {
            let step = theta[k].abs().max(1e-30) * 1e-3;
            let mut p = theta.to_vec();
            p[k] += step;
            let a = (eq.error(s, &p) - &e0) / step;
            let col = l.solve_lower_triangular(&a)?;
            x.view_mut((4 * s, k), (4, 1)).copy_from(&col);
            cols.push(col);
            let half = criterion_slope(eq, s, theta, k, step)?;
            grad[k] += half;
            halves.push(half);
        }
        let ext = extension(&AtSpeed {
            s,
            l: &l,
            e0: &e0,
            columns: &cols,
            half_gradient: &halves,
        })?;
        if ext.columns.len() != extra || ext.half_gradient.len() != extra {
            return None;
        }
        for (j, (c, h)) in ext.columns.iter().zip(&ext.half_gradient).enumerate() {
            x2.view_mut((4 * s, j), (4, 1)).copy_from(c);
            grad2[j] += h;
        }
    }
    // The one-mass columns' span (orthonormal, columns scaled first: their
    // units differ by many orders), and what lies outside it.
    let norms: Vec<f64> = x.column_iter().map(|c| c.norm()).collect();
    for (mut c, &norm) in x.column_iter_mut().zip(&norms) {
        if norm > 0.0 {
            c /= norm;
        }
    }
    let svd = x.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let smax = svd.singular_values.max();
    let keep: Vec<usize> = (0..svd.singular_values.len())
        .filter(|&i| svd.singular_values[i] > 1e-10 * smax)
        .collect();
    let u = u.select_columns(&keep);
    let v_t = v_t.select_rows(&keep);
    let x2_out = &x2 - &u * (u.transpose() * &x2);
    let g = DMatrix::from_fn(extra, extra, |i, j| x2_out.column(i).dot(&x2_out.column(j)));
    // The extension's score with the one-mass parameters' taken out
    // (efficient score g_q − X₂ᵀU·S⁻¹Vᵀ·g_θ, g_θ per unit of the scaled
    // columns): the frozen-weight form X₂⊥ᵀw⊥ when the weights do not move.
    let mut g_scaled = v_t.clone()
        * grad.component_div(&DVector::from_iterator(
            np,
            norms.iter().map(|&n| if n > 0.0 { n } else { 1.0 }),
        ));
    for (i, c) in g_scaled.iter_mut().enumerate() {
        *c /= svd.singular_values[keep[i]];
    }
    let nuisance = x2.transpose() * (&u * g_scaled);
    let b = grad2 - nuisance;
    let gamma = g.clone().try_inverse()? * &b;
    // The refitted one-mass parameters θ − β: their change is the one-mass
    // columns' coefficient once the extension is taken out of w.
    let resid = &w - &x2 * &gamma;
    let mut coef = u.transpose() * resid;
    for (i, c) in coef.iter_mut().enumerate() {
        *c /= svd.singular_values[keep[i]];
    }
    let scaled = v_t.transpose() * coef;
    let beta = (0..np)
        .map(|k| {
            if norms[k] > 0.0 {
                scaled[k] / norms[k]
            } else {
                0.0
            }
        })
        .collect();
    Some(Score { b, g, gamma, beta })
}

/// ½∂/∂θ_k of speed `s`'s term |L_s⁻¹e_s|² of the Gauss-Helmert criterion
/// at `theta`, its weights L_s(θ) recomputed (central difference of step
/// `step` in θ_k's units) [criterion per unit of θ_k]; `None` when a
/// weight cannot be formed.
fn criterion_slope<E: Equations + ?Sized>(
    eq: &E,
    s: usize,
    theta: &[f64],
    k: usize,
    step: f64,
) -> Option<f64> {
    let term = |delta: f64| -> Option<f64> {
        let mut p = theta.to_vec();
        p[k] += delta;
        let l = gh::whitening(eq, s, &p)?;
        Some(l.solve_lower_triangular(&eq.error(s, &p))?.norm_squared())
    };
    Some(0.25 * (term(step)? - term(-step)?) / step)
}
