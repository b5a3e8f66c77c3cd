//! The support-mode test of [`super`]: does the pedestal's dynamic stiffness
//! fall faster with speed than one mass on one spring allows?
//!
//! A pedestal on something softer (its own sub-base, a frame) whose second
//! mode lies above the speed range moves there, per direction, with the
//! dynamic stiffness of a two-mass chain,
//!
//! D(Ω) = z₁ − Ω²m₁ − z₁²/(z₁ + z₂ − Ω²m₂),  zᵢ = kᵢ + iΩcᵢ,
//!
//! whose expansion in x = Ω²m₂/(k₁ + k₂) < 1 is
//! K_s − Ω²M_e − Ω⁴Q − … with K_s the series stiffness, M_e = m₁ + m₂r²
//! (r = k₁/(k₁ + k₂)) and Q = m₂²r²/(k₁ + k₂) > 0. The one-mass model
//! k − Ω²m + iΩc follows the first two terms only; the Ω⁴ term is what it
//! cannot follow, and it is not small near the top speed when the second
//! mode is just above it (the fourth unseen machine's stiff block on its
//! sub-base: x = 0.08/0.12 at 110 Hz, Ω⁴Q 5 % of K_s). A fit leaves it in
//! its residuals as a smooth curve rising to the top speed, which the
//! scan of [`super::structure`] spreads over its windows.
//!
//! This test asks the data for that term directly: the fitted model is
//! extended by −Ω⁴q_y, −Ω⁴q_z on the stiffness of each direction and the
//! whitened residuals w are projected on it with the weights of the fit
//! frozen (a score test, the two extra columns L⁻¹∂e/∂q = −Ω⁴L⁻¹∂e/∂k;
//! the equation is linear in the parameters, so its columns are exact):
//! T = |P_full w|² − |P_θ w|², the share of w only the extension explains.
//! With the noise known (noise columns) T is χ²(2) under the one-mass
//! model; nothing in it is tuned to a machine.

use super::super::gauss_helmert::{self as gh, Equations};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Degrees of freedom of the extension (one Ω⁴ term per direction) [-].
pub const EXTRA: usize = 2;

/// The support-mode test's figures ([`support_mode`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SupportMode {
    /// T: the whitened sum of squares the Ω⁴ terms explain beyond the
    /// one-mass model, in units of the noise level [-].
    pub statistic: f64,
    /// Upper-tail p-value of T under χ²([`EXTRA`]) [-].
    pub p_value: f64,
    /// The Ω⁴ coefficient fitted with the frozen weights, y and z, as a
    /// fraction of the fitted stiffness at the top speed: Ω_max⁴q/k [-]
    /// (positive: the stiffness falls faster than one mass allows).
    pub drop_at_top: [f64; 2],
}

/// The test on the equations `eq` at the fitted parameters `theta` (model
/// units, the stiffnesses k_y, k_z at indices 0 and 1), speeds `speeds_hz`
/// [Hz] (one per block of `eq`); `None` when a weight or a projection
/// cannot be formed.
pub fn support_mode<E: Equations + ?Sized>(
    eq: &E,
    theta: &[f64],
    speeds_hz: &[f64],
) -> Option<SupportMode> {
    let n = eq.speeds();
    let np = theta.len();
    if n != speeds_hz.len() || n * 4 <= np + EXTRA || np < 2 {
        return None;
    }
    let top = speeds_hz.iter().copied().fold(0.0_f64, f64::max);
    if top.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let mut x = DMatrix::<f64>::zeros(4 * n, np + EXTRA);
    let mut w = DVector::<f64>::zeros(4 * n);
    for (s, &speed) in speeds_hz.iter().enumerate() {
        let l = gh::whitening(eq, s, theta)?;
        let e0 = eq.error(s, theta);
        let ws = l.solve_lower_triangular(&e0)?;
        w.rows_mut(4 * s, 4).copy_from(&ws);
        // (Ω/Ω_max)⁴: the extension's column, scaled to order one.
        let r4 = (speed / top).powi(4);
        for k in 0..np {
            let step = theta[k].abs().max(1e-30) * 1e-3;
            let mut p = theta.to_vec();
            p[k] += step;
            let a = (eq.error(s, &p) - &e0) / step;
            let col = l.solve_lower_triangular(&a)?;
            x.view_mut((4 * s, k), (4, 1)).copy_from(&col);
            if k < EXTRA {
                x.view_mut((4 * s, np + k), (4, 1))
                    .copy_from(&(col * (-r4)));
            }
        }
    }
    let explained = |cols: usize| -> Option<(f64, DVector<f64>)> {
        let xs = x.columns(0, cols).into_owned();
        let svd = xs.clone().svd(true, true);
        let beta = svd.solve(&w, 1e-12).ok()?;
        let fit = &xs * &beta;
        Some((fit.norm_squared(), beta))
    };
    let (null, _) = explained(np)?;
    let (full, beta) = explained(np + EXTRA)?;
    let statistic = (full - null).max(0.0);
    let p_value = ChiSquared::new(EXTRA as f64)
        .map(|d| 1.0 - d.cdf(statistic))
        .unwrap_or(f64::NAN);
    // w ≈ Xβ is the residual the parameters' change −β removes (a
    // Gauss-Newton step): the extension's coefficient is −β, Ω_max⁴q in the
    // stiffness's units, relative to the refitted stiffness θ − β.
    let drop_at_top = std::array::from_fn(|k| {
        let kk = theta[k] - beta[k];
        if kk != 0.0 {
            -beta[np + k] / kk
        } else {
            f64::NAN
        }
    });
    (statistic.is_finite() && p_value.is_finite()).then_some(SupportMode {
        statistic,
        p_value,
        drop_at_top,
    })
}
