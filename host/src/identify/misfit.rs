//! How far a pedestal estimate is from its data, against the noise the data
//! carry: the noise floor of every phasor ([`noise_floor`], by the one noise
//! policy of [`crate::estimate::pedestal`]) and the misfit of eq. 3 ([`misfit`]): a χ² with the
//! noise of both readings propagated, and the residual relative to the
//! bearing forces. Used by [`super::convention`] to compare readings of a run.

use super::PedestalFit;
use crate::estimate::noise::{Quantisation, RunNoise};
use crate::estimate::pedestal::floor_sd;
use crate::estimate::{complex_stiffness, Observation};
use crate::rundir::{BearingSchedule, RunDir};
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
    let rows = run
        .measurements
        .iter()
        .zip(sigma)
        .filter(|(m, _)| m.bearing == fit.bearing)
        .filter_map(|(m, s)| {
            let bc = schedule.at(m.speed_hz).ok()?;
            let kstar = complex_stiffness(&bc, omega_from_hz(m.speed_hz));
            let o = Observation {
                speed_hz: m.speed_hz,
                rel: m.rel,
                ped: m.ped,
                kstar,
                var: [0.0; 8],
            };
            Some((o, s))
        });
    misfit_of(rows, fit)
}

/// Each fit's relative residual Σ|e|²/Σ|F|² [-] ([`Misfit::relative_residual`],
/// unweighted: the noise `noise` gives the χ² does not enter it) on its
/// bearing's data in `run`, by bearing name; bearings with no speed to
/// evaluate are left out. What the sign rule reads
/// ([`super::physical::recheck_run`]).
pub fn relative_residuals(
    run: &RunDir,
    noise: &RunNoise,
    fits: &[PedestalFit],
) -> BTreeMap<String, f64> {
    let schedules = run.bearing_schedules();
    let sigma = crate::estimate::pedestal::floor_sd(noise, run.measurements.len());
    fits.iter()
        .filter_map(|p| {
            misfit(run, &schedules, &sigma, p).map(|m| (p.bearing.clone(), m.relative_residual))
        })
        .collect()
}

/// The misfit of `fit` on its bearing's observations, each with the noise
/// sd of its four phasors ([`noise_floor`]'s row), in the order of the run's
/// rows; observations with a number that is not finite are left out.
/// `None` when no speed can be evaluated. [`misfit`] on data already paired
/// with their bearing's stiffness (the convention check's readings).
pub fn misfit_of<'a>(
    rows: impl IntoIterator<Item = (Observation, &'a [f64; 4])>,
    fit: &PedestalFit,
) -> Option<Misfit> {
    let th = fit.pedestal.theta();
    let mut total = 0.0;
    let mut residual = 0.0;
    let mut force = 0.0;
    let mut speeds = 0usize;
    for (o, s) in rows {
        if !finite(&o) {
            continue;
        }
        let w = omega_from_hz(o.speed_hz);
        let z = [
            C64::new(th[0] - w * w * th[2], w * th[3]),
            C64::new(th[1] - w * w * th[2], w * th[4]),
        ];
        let b = o.kstar;
        let e: [C64; 2] =
            std::array::from_fn(|d| z[d] * o.ped[d] - b[d][0] * o.rel[0] - b[d][1] * o.rel[1]);
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
            .map(|d| (b[d][0] * o.rel[0] + b[d][1] * o.rel[1]).norm_sqr())
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

/// Whether the speed and every phasor of `o` are finite numbers.
fn finite(o: &Observation) -> bool {
    o.speed_hz.is_finite()
        && o.rel
            .iter()
            .chain(&o.ped)
            .all(|z| z.re.is_finite() && z.im.is_finite())
}
