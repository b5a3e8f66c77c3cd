//! How far a pedestal estimate is from its data, against the noise the data
//! carry: the noise floor of every phasor ([`noise_floor`], by the one noise
//! policy of [`crate::estimate::pedestal`]) and the misfit of eq. 3 ([`misfit`]): a χ² with the
//! noise of both readings propagated, and the residual relative to the
//! bearing forces. Used by [`super::convention`] to compare readings of a run.

use super::PedestalFit;
use crate::estimate::noise::{Quantisation, RunNoise};
use crate::estimate::pedestal::floor_sd;
use crate::rundir::{BearingSchedule, Measurement, RunDir};
use plinth_shared::phasor::{omega_from_hz, Complex};
use std::collections::BTreeMap;

type C64 = Complex<f64>;

/// The noise standard deviation per real component [m] of the four phasors
/// (rel y, rel z, ped y, ped z) of every measurement of a run, in the order of
/// `run.measurements`, from the one noise model ([`crate::estimate::noise`])
/// by the one noise policy ([`crate::estimate::pedestal::floor_sd`]): the measurement's noise
/// columns (formats.md: sqrt(E|n|²), split equally between real and imaginary
/// parts) when present, else the larger of the digits each number carries and
/// the scatter between neighbouring speeds (local smooth fits, so that a
/// resonance's curvature is not taken for noise). `None` when a bearing has
/// no rows.
pub fn noise_floor(run: &RunDir) -> Option<Vec<[f64; 4]>> {
    Some(floor_sd(
        &RunNoise::estimate(run, Quantisation::Rounding),
        run.measurements.len(),
    ))
}

/// How far one pedestal estimate is from its data.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Misfit {
    /// Noise-whitened residual sum of squares χ² [-].
    pub chi2: f64,
    /// Degrees of freedom ν = 4·speeds − parameters.
    pub dof: usize,
    /// Σ|e|² / Σ|F|² [-]: the residual of eq. 3 relative to the bearing
    /// forces, unweighted (what least squares minimises, free of the scale
    /// of the data).
    pub relative_residual: f64,
}

/// The misfit of `fit` on the measurements of its bearing in `run` (whose
/// [`RunDir::bearing_schedules`] are `schedules`), with the per-measurement
/// noise `sigma` ([`noise_floor`]). `None` when no speed can
/// be evaluated.
pub fn misfit(
    run: &RunDir,
    schedules: &BTreeMap<String, BearingSchedule>,
    sigma: &[[f64; 4]],
    fit: &PedestalFit,
) -> Option<Misfit> {
    let schedule = schedules.get(&fit.bearing)?;
    let th = fit.pedestal.theta();
    let mut total = 0.0;
    let mut residual = 0.0;
    let mut force = 0.0;
    let mut speeds = 0usize;
    for (m, s) in run.measurements.iter().zip(sigma) {
        if m.bearing != fit.bearing || !finite(m) {
            continue;
        }
        let Ok(bc) = schedule.at(m.speed_hz) else {
            continue;
        };
        let w = omega_from_hz(m.speed_hz);
        let z = [
            C64::new(th[0] - w * w * th[2], w * th[3]),
            C64::new(th[1] - w * w * th[2], w * th[4]),
        ];
        let b = [
            [
                C64::new(bc.k[0][0], w * bc.c[0][0]),
                C64::new(bc.k[0][1], w * bc.c[0][1]),
            ],
            [
                C64::new(bc.k[1][0], w * bc.c[1][0]),
                C64::new(bc.k[1][1], w * bc.c[1][1]),
            ],
        ];
        let e: [C64; 2] =
            std::array::from_fn(|d| z[d] * m.ped[d] - b[d][0] * m.rel[0] - b[d][1] * m.rel[1]);
        // S = Z Σ_ped Z^H + B Σ_rel B^H (Hermitian 2×2).
        let var_rel = [s[0] * s[0], s[1] * s[1]];
        let mut cov = [[C64::new(0.0, 0.0); 2]; 2];
        for (i, row) in cov.iter_mut().enumerate() {
            for (j, cij) in row.iter_mut().enumerate() {
                *cij = (0..2).map(|k| b[i][k] * b[j][k].conj() * var_rel[k]).sum();
            }
            row[i] += z[i].norm_sqr() * s[2 + i] * s[2 + i];
        }
        let (a, d, c) = (cov[0][0].re, cov[1][1].re, cov[0][1]);
        let det = a * d - c.norm_sqr();
        if !(det > 0.0 && det.is_finite()) {
            continue;
        }
        // e^H S⁻¹ e with S⁻¹ = [[d, −c], [−c̄, a]] / det.
        let q =
            (d * e[0].norm_sqr() + a * e[1].norm_sqr() - 2.0 * (e[0].conj() * c * e[1]).re) / det;
        total += q;
        residual += e[0].norm_sqr() + e[1].norm_sqr();
        force += (0..2)
            .map(|d| (b[d][0] * m.rel[0] + b[d][1] * m.rel[1]).norm_sqr())
            .sum::<f64>();
        speeds += 1;
    }
    let params = super::PARAMETERS - fit.fixed.len();
    (speeds > 0 && force > 0.0).then(|| Misfit {
        chi2: total,
        dof: (4 * speeds).saturating_sub(params),
        relative_residual: residual / force,
    })
}

fn finite(m: &Measurement) -> bool {
    m.speed_hz.is_finite()
        && m.rel
            .iter()
            .chain(&m.ped)
            .all(|z| z.re.is_finite() && z.im.is_finite())
}
