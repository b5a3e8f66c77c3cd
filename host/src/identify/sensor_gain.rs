//! One channel's sensitivity off: what a bearing's one-mass fit sees of a
//! gain error on one of its four channels, and what it cannot see.
//!
//! A channel read with a relative sensitivity error ε (a probe calibrated
//! on another steel than the journal's reads 5-10 % off; a pick-up's
//! sensitivity moves a few % with temperature) scales that channel's
//! phasors by 1 + ε, its phase right. In eq. 3, Z(θ)·ped = K*·rel, per
//! speed and per direction:
//!
//! - a gain common to both `rel` probes of a bearing (or both `ped`
//!   pick-ups) scales the bearing force (or the motion) of both directions
//!   alike: θ/(1 + ε) (or θ·(1 + ε)) fits the data exactly as θ fits the
//!   machine. No run can see it (the "transducers' scale" condition of
//!   [`super::conditional`]);
//! - a gain **ratio** between y and z of the same kind is seen only
//!   through what ties the two directions together in the model: the one
//!   mass m of both directions, and the bearing table's cross terms
//!   (K*_yz·rel_z in the y force; a floating-ring table has k_yz = −k_zy
//!   ≈ 0.35 k_yy). Where the pedestal's resonance lies above the run m is
//!   weakly determined and the cross terms carry it alone.
//!
//! **The linearisation** ([`evidence`]): the fit's whitened equations at
//! the fitted θ (the one definition of them, [`crate::estimate::ml::Rigid`], under the fit's
//! noise level, `variance_scale`, and equation error) extended by one
//! column per channel: ∂e/∂ε of e = A(θ)·D_ped(ε)⁻¹·ped − K*·D_rel(ε)⁻¹·rel
//! at ε = 0, which is minus the equations' residual with only that
//! channel's phasor kept (`rel`: +K*·rel_c; `ped`: −Z(θ)·ped_c). The shift
//! of the fitted θ per unit ε of one channel alone is b = −X⁺t (X the θ
//! columns, t the channel's; [`GainEvidence::path`]): what the "Conditional
//! on" block states per channel and what `--sensor-uncertainty` carries
//! into the ± ([`super::conditional::sensor`]).
//!
//! **The test** ([`GainEvidence::statistic`]): the two ratios, rel_y against
//! rel_z and ped_y against ped_z (the y channel's column with θ free: its
//! common part with the z channel lies in θ's span), fitted in one
//! Gauss–Newton step from ε = 0; the statistic is ε̂ᵀC⁻¹ε̂, C their
//! covariance (the Schur complement of θ, times √(χ²/dof) squared where the
//! fit leaves more than its noise, and times the long-run factor of a
//! serial correlation the noise report found, as the delay's score test is
//! deflated). Under the null it is χ²₂. **Untrusted** where it passes the
//! run's Bonferroni point ([`significant`]: χ²₂ beyond −2·ln(1 % / bearings),
//! ≤ 1 % of clean runs across bearings); the message names the ratio that
//! shows, with its value and ±. **Widened** where the data favour a ratio
//! (beyond χ²₂'s 5 % point, [`FAVOURED`], as the delay's gate opens at
//! 2σ) but it is not significant, and the ratios the data allow (their 95 %
//! ellipse) move some value by more than its ± (not excluded): every ± is
//! multiplied by the delay's widening
//! ([`crate::estimate::lack_of_fit::delay_unknown::widening`]) with ρ =
//! σ(ratios free)/σ(ratios held) and the ratios' estimate projected on the
//! value's path, √(1 + (ρ² − 1)(1 + t²)), t² = (bᵀε̂)²/(bᵀCb): the
//! root-mean-square error of the held value when the ratios are as the data
//! give them.
//!
//! **A speed column off is not a gain** ([`speed`]): where the
//! speed-offset rule's gate is open, the ratios are tested on the
//! equations at the speed column less its offset, the offset's ± counted
//! in theirs; elsewhere at the speed column.

pub mod evidence;
pub mod speed;

pub use evidence::evidence;

use super::{Identification, PedestalFit, Warning, WarningKind};
use crate::estimate::lack_of_fit::delay_unknown::widening;
use crate::rundir::RunDir;
use plinth_shared::regression::{Parameter, PARAMETERS};
use serde::{Deserialize, Serialize};

/// The four channels of a bearing, in the order of [`GainEvidence::path`].
pub const CHANNELS: [&str; 4] = ["rel_y", "rel_z", "ped_y", "ped_z"];

/// The two gain ratios tested: (channel, the channel it is read against).
pub const RATIOS: [(usize, usize); 2] = [(0, 1), (2, 3)];

/// The level at which the data favour a gain ratio [-] (the gate of the
/// widening, as the delay's 2σ): χ²_k's upper 5 % point.
pub const FAVOURED_LEVEL: f64 = 0.05;

/// The family-wise false-alarm rate per run of the untrusting rule [-].
pub const RUN_LEVEL: f64 = 0.01;

/// Largest ± of a direction of the two ratios that is tested [-]: beyond
/// it the data do not estimate it (the linearisation 1/(1 + ε) ≈ 1 − ε is
/// off by a tenth of ε at ε = 10 %, within 2σ of a ± of 5 %).
pub const MAX_RATIO_STD_ERR: f64 = 0.05;

/// χ²_`dof`'s upper `level` point [-].
pub(crate) fn chi2_upper(level: f64, dof: usize) -> f64 {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    ChiSquared::new(dof.max(1) as f64).map_or(f64::INFINITY, |d| d.inverse_cdf(1.0 - level))
}

/// The statistic beyond which the ratios are significant in a run of
/// `bearings` bearings tested, on `dof` estimable directions [-]:
/// χ²_dof's upper RUN_LEVEL/bearings point (Bonferroni; 10.6 for two
/// bearings and two directions).
pub fn significant(bearings: usize, dof: usize) -> f64 {
    chi2_upper(RUN_LEVEL / bearings.max(1) as f64, dof)
}

/// What the data say of one bearing's channel gains (module docs;
/// `sensor_gain` in `plinth identify --json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GainEvidence {
    /// Bearing name.
    pub bearing: String,
    /// Per channel ([`CHANNELS`]), per θ = (k_y, k_z, m, c_y, c_z): the
    /// shift of the fitted value per unit relative sensitivity error of
    /// that channel alone, b = −X⁺t [SI per unit ε] (0 for a fixed value).
    pub path: [[f64; PARAMETERS]; 4],
    /// ε̂ of rel_y read against rel_z and of ped_y against ped_z: the
    /// relative sensitivity of the y channel over the z one, minus 1 [-].
    pub ratio: [f64; 2],
    /// Their ± [-].
    pub ratio_std_err: [f64; 2],
    /// Their correlation [-].
    pub ratio_correlation: f64,
    /// ε̂ᵀC⁻¹ε̂, χ²₂ under the null [-].
    pub statistic: f64,
    /// The estimable directions of the two ratios tested (0-2) [-].
    pub dof: usize,
    /// The run's significance point [`significant`] [-].
    pub threshold: f64,
    /// The point beyond which the data favour a ratio, χ²_dof at 5 % [-].
    pub favoured: f64,
    /// ρ = σ(ratios free)/σ(ratios held) per θ [-] (1 for a fixed value).
    pub rho: [f64; PARAMETERS],
    /// t² = (bᵀε̂)²/(bᵀCb) per θ, the ratios' estimate along the value's
    /// path in units of its spread [-].
    pub t_squared: [f64; PARAMETERS],
    /// `untrusted` (significant), `widened` (favoured, not excluded),
    /// `none`, or `not_judged` (the noise not measured: no noise columns).
    pub verdict: std::borrow::Cow<'static, str>,
    /// Where the speed-offset rule's gate is open, the offset Δ̂ of the
    /// speed column the ratios were tested at [Hz] (the equations at the
    /// vectors' speed f − Δ̂, Δ̂'s ± counted in the ratios' ±,
    /// [`speed`]); `null` where they were tested at the speed column.
    #[serde(default)]
    pub speed_offset_hz: Option<f64>,
}

impl GainEvidence {
    /// The widening factor of each ± where counted ([`widening`]) [-].
    pub fn widening(&self) -> [f64; PARAMETERS] {
        std::array::from_fn(|i| widening(self.rho[i], self.t_squared[i].sqrt(), 1.0))
    }

    /// Whether the ratios the data allow (their 95 % ellipse) move some
    /// value by more than its held ±: |bᵀε̂| + √q·√(bᵀCb) > σ_held, with
    /// bᵀCb = σ_held²(ρ² − 1) (module docs).
    pub fn excluded(&self) -> bool {
        (0..PARAMETERS).all(|i| {
            let spread = (self.rho[i] * self.rho[i] - 1.0).max(0.0).sqrt();
            spread * (self.t_squared[i].sqrt() + self.favoured.sqrt()) <= 1.0
        })
    }

    /// The ratio that shows most, in words: "rel_y reads about −5.0 ± 0.4 %
    /// relative to rel_z".
    pub fn strongest(&self) -> String {
        let z = |j: usize| {
            let v = (self.ratio[j] / self.ratio_std_err[j]).abs();
            if v.is_finite() {
                v
            } else {
                0.0
            }
        };
        let j = if z(0) >= z(1) { 0 } else { 1 };
        let (a, b) = RATIOS[j];
        format!(
            "{} reads about {:+.1} ± {:.1} % relative to {}",
            CHANNELS[a],
            100.0 * self.ratio[j],
            100.0 * self.ratio_std_err[j],
            CHANNELS[b]
        )
    }
}

/// Judges the channel gains of every ML pedestal of `identification` on
/// rigid ground from its observations in `prepared` (module docs): the
/// evidence into `identification.sensor_gain`, a significant ratio
/// untrusts the bearing ([`WarningKind::SensorGain`]), a favoured one not
/// excluded widens its ± ([`WarningKind::SensorGainNotExcluded`]).
pub fn mark(run: &RunDir, prepared: &super::data::Prepared, identification: &mut Identification) {
    if identification.estimator != "ml" {
        return;
    }
    let schedules = run.bearing_schedules();
    let tested: Vec<usize> = identification
        .pedestals
        .iter()
        .enumerate()
        .filter(|(_, p)| p.base.is_none())
        .map(|(i, _)| i)
        .collect();
    let bearings = tested.len();
    let mut found = Vec::new();
    for i in tested {
        let p = &identification.pedestals[i];
        let Some(obs) = prepared
            .bearings
            .iter()
            .find(|b| b.bearing == p.bearing)
            .and_then(|b| b.observations.as_ref().ok())
        else {
            continue;
        };
        let Some(report) = identification.noise.get(&p.bearing) else {
            continue;
        };
        let inflation = report
            .serial_correlation
            .as_ref()
            .map_or(1.0, |s| crate::estimate::serial::long_run_factor(s.lag_one));
        // Where the speed-offset rule's gate is open, at the offset with
        // its ± counted ([`speed`]); at the speed column otherwise.
        let conditioned = identification
            .speed_lag
            .as_ref()
            .zip(schedules.get(&p.bearing))
            .and_then(|(lag, schedule)| {
                speed::evidence(
                    p,
                    obs,
                    &report.outlier_speeds_hz,
                    report.variance_scale,
                    report.equation_error_sd,
                    inflation,
                    bearings,
                    schedule,
                    lag,
                )
            });
        let Some(e) = conditioned.or_else(|| {
            evidence(
                p,
                obs,
                &report.outlier_speeds_hz,
                report.variance_scale,
                report.equation_error_sd,
                inflation,
                bearings,
            )
        }) else {
            continue;
        };
        // Acted on only where the noise was measured (noise columns): with
        // the level from digits or from the scatter the statistic is not
        // calibrated (docs/trust.md, Session 49 (gain17): the 12-digit
        // runs' simulator spline, unseen-eight's scatter-level runs).
        let mut e = e;
        if report.source != crate::estimate::noise::NoiseSource::Columns {
            e.verdict = "not_judged".into();
        }
        let p = &mut identification.pedestals[i];
        match e.verdict.as_ref() {
            "untrusted" => {
                p.warnings.push(Warning {
                    kind: WarningKind::SensorGain,
                    message: format!(
                        "{} {} (the y/z sensitivity ratios' statistic {:.1} > {:.1}, χ² on {} at 1 % per run across the bearings{}): check the probe's calibration (a probe calibrated on another steel than the journal's reads 5-10 % off; a pick-up's sensitivity moves a few % with temperature); a channel's sensitivity error goes into that direction's k and c",
                        p.bearing,
                        e.strongest(),
                        e.statistic,
                        e.threshold,
                        e.dof,
                        e.speed_offset_hz.map_or(String::new(), |d| format!(
                            "; tested at the vectors' speed, the speed column less its offset {d:+.3} Hz, the offset's ± counted"
                        ))
                    ),
                });
                p.trusted = false;
            }
            "widened" => widen(p, &e),
            _ => {}
        }
        found.push(e);
    }
    identification.sensor_gain = found;
}

/// Multiplies `p`'s ± and covariance by `e`'s widening and says so.
fn widen(p: &mut PedestalFit, e: &GainEvidence) {
    let w = e.widening();
    p.widen_by(w);
    let widened: Vec<String> = Parameter::ALL
        .iter()
        .filter(|&&c| w[c as usize] >= 1.05)
        .map(|&c| format!("{} ±×{:.2}", c.name(), w[c as usize]))
        .collect();
    p.warnings.push(Warning {
        kind: WarningKind::SensorGainNotExcluded,
        message: format!(
            "the data do not exclude a sensitivity error between its y and z channels ({}; statistic {:.1} > {:.1}, below the {:.1} that untrusts): its ± count the ratios as unknown, multiplied by √(1 + (ρ² − 1)·(1 + t²)) ({}); the values are the fit's",
            e.strongest(),
            e.statistic,
            e.favoured,
            e.threshold,
            if widened.is_empty() {
                "every factor below 1.05".to_string()
            } else {
                widened.join(", ")
            }
        ),
    });
}

/// Under the table: one line per pedestal whose ± count a sensitivity
/// ratio as unknown; empty when none.
pub fn describe(identification: &Identification) -> String {
    identification
        .warnings_of(WarningKind::SensorGainNotExcluded)
        .map(|(bearing, w)| format!("\n{bearing}: {}\n", w.message))
        .collect()
}
