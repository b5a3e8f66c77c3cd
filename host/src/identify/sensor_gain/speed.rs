//! The sensitivity ratios conditional on the speed column's offset.
//!
//! A speed column Δ off (the speed-offset rule, [`crate::identify::speed_lag`])
//! puts every vector at the wrong speed: the bearing table is read at f
//! instead of f − Δ and the pedestal's Ω²m and iΩc carry 2Δ/f and Δ/f
//! too much. θ takes most of that misfit, and what θ cannot take is not
//! the same in y and z (a tilting-pad table's k_yy and k_zz rise with the
//! speed at different rates; the pedestal's k_y and k_z differ): the y/z
//! sensitivity-ratio test ([`super::evidence`]) reads part of it as a
//! ratio. On a 6 Hz lag of unseen-eight it untrusted B1 for a "1.6 % y/z
//! ratio" whose cause is the speed column (docs/trust-speed.md, Session 50
//! (speed50)).
//!
//! **Where the speed-offset rule's gate is open** (Δ̂ significant and
//! spread over the run as an offset's pull is, [`crate::identify::speed_lag::Offset::favoured`])
//! the ratios are tested on the equations at the vectors' speed f − Δ̂
//! (each observation moved through the bearing's table and Ω, the one
//! definition of that move, [`crate::identify::speed_lag::linearise::moved`]),
//! linearised at θ̂ + b·Δ̂ (b the bearing's shift per Hz of Δ, the Newton
//! step of the test takes θ the rest of the way), and Δ̂'s own ± is
//! counted: the ratios' estimate at Δ̂ ± σ_Δ gives its change per σ_Δ,
//! d, and C + d·dᵀ is the ratios' covariance (the delta method: ε̂(Δ) ≈
//! ε̂(Δ̂) + (Δ − Δ̂)·∂ε̂/∂Δ with Δ − Δ̂ of variance σ_Δ²). Where the
//! gate is shut the ratios are tested at the speed column, as before: an
//! offset the data do not show is not conditioned on, and a real gain
//! is read at the speed column as it was.

use super::evidence::{as_fitted, evidence_at};
use super::GainEvidence;
use crate::estimate::Observation;
use crate::identify::speed_lag::{linearise::moved, SpeedLag};
use crate::identify::PedestalFit;
use crate::rundir::BearingSchedule;
use nalgebra::DMatrix;
use plinth_shared::regression::PARAMETERS;

/// The evidence of [`super::evidence`] (same arguments) at the speed
/// column's offset of `lag` with its ± counted (module docs), `schedule`
/// the bearing's table; `None` where the gate of `lag` is shut, the
/// bearing has no share in it, or a figure cannot be formed.
#[allow(clippy::too_many_arguments)]
pub fn evidence(
    fit: &PedestalFit,
    obs: &[Observation],
    outliers: &[f64],
    variance_scale: f64,
    equation_error_sd: f64,
    inflation: f64,
    bearings: usize,
    schedule: &BearingSchedule,
    lag: &SpeedLag,
) -> Option<GainEvidence> {
    let offset = lag.offset.as_ref().filter(|o| o.favoured())?;
    let share = lag.bearings.iter().find(|b| b.bearing == fit.bearing)?;
    let fitted = as_fitted(obs, outliers, variance_scale);
    let (delta, sigma) = (offset.offset_hz, offset.offset_std_hz);
    if !(delta.is_finite() && sigma.is_finite() && sigma > 0.0) {
        return None;
    }
    // The vectors belong to f − Δ; the same speeds at every Δ tried (a
    // speed moved off the table at one of them is left out at all three).
    let tried = [delta - sigma, delta, delta + sigma];
    let moves: Vec<Vec<Option<Observation>>> =
        tried.iter().map(|d| moved(&fitted, schedule, -d)).collect();
    let kept: Vec<usize> = (0..fitted.len())
        .filter(|&i| moves.iter().all(|m| m[i].is_some()))
        .collect();
    let at = |k: usize, extra: Option<&DMatrix<f64>>| {
        let obs: Vec<Observation> = kept.iter().filter_map(|&i| moves[k][i]).collect();
        let mut theta = fit.pedestal.theta();
        for (i, t) in theta.iter_mut().enumerate().take(PARAMETERS) {
            *t += share.path_per_hz[i] * tried[k];
        }
        evidence_at(
            fit,
            &theta,
            &obs,
            equation_error_sd,
            inflation,
            bearings,
            extra,
        )
    };
    let (minus, plus) = (at(0, None)?, at(2, None)?);
    // d: the ratios' change per σ_Δ of Δ (central difference over ±σ_Δ).
    let d = [
        0.5 * (plus.ratio[0] - minus.ratio[0]),
        0.5 * (plus.ratio[1] - minus.ratio[1]),
    ];
    let extra = DMatrix::from_fn(2, 2, |i, j| d[i] * d[j]);
    let mut e = at(1, Some(&extra))?;
    e.speed_offset_hz = Some(delta);
    Some(e)
}
