//! The measurements of a run directory arranged for the discrepancy workflow:
//! one speed-sorted series of 1X phasors per bearing, with the complex bearing
//! stiffness K* = K_b + iΩ·C_b at each measured speed and the noise variance
//! of every real number (see [`super::noise`]): one [`Observation`] per
//! bearing and speed.

use super::noise::{BearingNoise, ColumnDigits, NoiseModel};
use crate::estimate::lack_of_fit::SupportMode;
use crate::estimate::noise::Quantisation;
use crate::estimate::pedestal::{data_alone_sd, unscale};
use crate::estimate::Observation;
use crate::identify::{estimator::fit_ml, observations, Options as IdentifyOptions, PedestalFit};
use crate::rundir::{Measurement, RunDir};
use anyhow::{anyhow, bail, Context, Result};

pub use crate::estimate::{mul, Complex2x2};

/// All bearings of a run, speed-aligned.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// Bearing names in order of first appearance in `measurements.csv`
    /// (neighbouring bearings are neighbours in this order).
    pub bearings: Vec<String>,
    /// Sorted distinct measured speeds [Hz].
    pub speeds_hz: Vec<f64>,
    /// `points[b][j]`: bearing `b` at `speeds_hz[j]`, when measured there.
    pub points: Vec<Vec<Option<Observation>>>,
    /// The measurement noise model the standard deviations come from.
    pub noise: NoiseModel,
    /// Per bearing, the maximum-likelihood fit of the paper's five-parameter
    /// model that decided the noise (`plinth identify`'s default fit).
    pub base_fits: Vec<PedestalFit>,
    /// Per bearing (aligned with `bearings`), the speeds [Hz] whose
    /// channels look negated, a keyphasor flip
    /// ([`crate::identify::flips::flipped_speeds`], the tests `plinth
    /// identify` runs), ascending: left out of `points`, the noise and
    /// everything fitted, and reported.
    pub flipped_speeds_hz: Vec<Vec<f64>>,
    /// Per bearing (aligned with `bearings`), the speeds [Hz] the robust
    /// fit of that bearing's base model down-weights as outliers (`plinth
    /// identify`'s `outlier_speeds_hz`, [`crate::estimate::robust`]),
    /// ascending: still in `points` (what is done with them is the
    /// workflow's, [`super::outliers`]).
    pub outlier_speeds_hz: Vec<Vec<f64>>,
    /// Per bearing (aligned with `bearings`), the support-mode test of its
    /// base model (`plinth identify`'s, [`crate::estimate::lack_of_fit::
    /// support_mode`]; `None` where identify does not make it), judged by
    /// [`super::trust::judge_support`].
    pub support_modes: Vec<Option<SupportMode>>,
    /// Per bearing (aligned with `bearings`), what `plinth identify`'s
    /// lack-of-fit rule finds in its base model's fit, level and structure
    /// ([`crate::identify::trust::lack_of_fit_findings`], the run's
    /// family-wise shares; empty where it finds nothing; the support-mode
    /// test is `support_modes`'), judged by [`super::trust::judge_support`].
    pub lack_of_fit: Vec<Vec<String>>,
}

impl Prepared {
    /// Number of real pedestal-level equations (four per bearing and speed
    /// measured: y and z, real and imaginary): the N of every BIC penalty.
    pub fn real_equations(&self) -> usize {
        (0..self.bearings.len())
            .map(|b| 4 * self.points[b].iter().flatten().count())
            .sum()
    }

    /// Arranges a run directory ([`Self::arrange`]) without the readings
    /// of the keyphasor flips `plinth identify` finds in it
    /// ([`crate::identify::flips::flipped_speeds`] of every bearing's
    /// series): a flipped (rel, ped) pair fits the pedestal equation as
    /// well as the pair negated back, but it poisons the noise estimated
    /// from the scatter between neighbouring speeds and every gap and fit
    /// of an effect that is not homogeneous in (rel, ped) (a runout, a
    /// base). Those readings are left out of everything and listed in
    /// `flipped_speeds_hz`. Fails as [`Self::arrange`] does.
    pub fn from_run(run: &RunDir) -> Result<Self> {
        let all = Self::arrange(run)?;
        let series: Vec<Vec<Observation>> = all
            .points
            .iter()
            .map(|row| row.iter().flatten().cloned().collect())
            .collect();
        let refs: Vec<&[Observation]> = series.iter().map(Vec::as_slice).collect();
        let flipped = crate::identify::flips::flipped_speeds(&refs);
        if flipped.iter().all(Vec::is_empty) {
            return Ok(all);
        }
        let all = Self {
            flipped_speeds_hz: flipped,
            ..all
        };
        all.leaving_out(run, &[]).context(
            "the run without the speeds whose phasors look flipped by 180° (keyphasor flips)",
        )
    }

    /// `run` arranged again ([`Self::arrange`]: the noise and the base fits
    /// estimated afresh) without the readings of these data's keyphasor
    /// flips and, per bearing of these data, of the speeds `speeds` [Hz].
    /// The flips stay listed in `flipped_speeds_hz`; `outlier_speeds_hz`
    /// is that of the data arranged again. Fails as [`Self::arrange`] does.
    pub fn leaving_out(&self, run: &RunDir, speeds: &[Vec<f64>]) -> Result<Self> {
        let out = |b: usize| {
            self.flipped_speeds_hz
                .get(b)
                .into_iter()
                .chain(speeds.get(b))
                .flatten()
        };
        let mut kept = run.clone();
        kept.measurements.retain(|m| {
            self.bearing_index(&m.bearing)
                .is_none_or(|b| !out(b).any(|s| *s == m.speed_hz))
        });
        let mut prep = Self::arrange(&kept)?;
        // `arrange` orders the bearings by first appearance: align the
        // list with its order (a bearing whose first rows were left out
        // may move).
        prep.flipped_speeds_hz = prep
            .bearings
            .iter()
            .map(|name| {
                self.bearing_index(name)
                    .and_then(|b| self.flipped_speeds_hz.get(b).cloned())
                    .unwrap_or_default()
            })
            .collect();
        Ok(prep)
    }

    /// Arranges a run directory as it is; fails on a bearing without
    /// coefficients at a measured speed, non-finite numbers or too few
    /// speeds to identify.
    pub fn arrange(run: &RunDir) -> Result<Self> {
        if run.measurements.is_empty() {
            bail!("measurements.csv holds no rows");
        }
        let mut bearings: Vec<String> = Vec::new();
        for m in &run.measurements {
            if !bearings.contains(&m.bearing) {
                bearings.push(m.bearing.clone());
            }
        }
        let mut speeds_hz: Vec<f64> = run.measurements.iter().map(|m| m.speed_hz).collect();
        speeds_hz.sort_by(f64::total_cmp);
        speeds_hz.dedup();
        let schedules = run.bearing_schedules();
        let mut points: Vec<Vec<Option<Observation>>> =
            vec![vec![None; speeds_hz.len()]; bearings.len()];
        for (row, m) in run.measurements.iter().enumerate() {
            let finite = m.speed_hz.is_finite()
                && m.speed_hz > 0.0
                && m.rel
                    .iter()
                    .chain(&m.ped)
                    .all(|z| z.re.is_finite() && z.im.is_finite());
            if !finite {
                bail!(
                    "measurements.csv row {} (bearing {}, {} Hz): speed must be positive and every phasor finite",
                    row + 1,
                    m.bearing,
                    m.speed_hz
                );
            }
            let b = bearings.iter().position(|n| *n == m.bearing).unwrap_or(0);
            let j = speeds_hz.partition_point(|&s| s < m.speed_hz);
            let coefficients = schedules
                .get(&m.bearing)
                .ok_or_else(|| {
                    anyhow!("bearings.csv has no coefficients for bearing {}", m.bearing)
                })?
                .at(m.speed_hz)
                .with_context(|| format!("bearings.csv, bearing {}", m.bearing))?;
            points[b][j] = Some(Observation::without_noise(
                m.speed_hz,
                m.rel,
                m.ped,
                &coefficients,
            ));
        }
        let mut columns = Vec::with_capacity(bearings.len());
        let mut noises = Vec::with_capacity(bearings.len());
        let mut base_fits = Vec::with_capacity(bearings.len());
        let mut outliers = Vec::with_capacity(bearings.len());
        let mut support_modes = Vec::with_capacity(bearings.len());
        let mut reports = std::collections::BTreeMap::new();
        let mut written_reports = std::collections::BTreeMap::new();
        let mut centred_reports = std::collections::BTreeMap::new();
        for (b, name) in bearings.iter().enumerate() {
            let mut rows: Vec<&Measurement> = run
                .measurements
                .iter()
                .filter(|m| &m.bearing == name)
                .collect();
            rows.sort_by(|x, y| x.speed_hz.total_cmp(&y.speed_hz));
            columns.push(ColumnDigits::of_rows(&rows));
            // The written digits cannot tell rounding from truncation: the
            // significance tests take truncation's mean square (ulp²/3), which
            // bounds both, so that a truncation bias is not named an effect.
            let mut noise = BearingNoise::estimate(&rows, &columns[b], Quantisation::Truncation);
            let schedule = schedules
                .get(name)
                .ok_or_else(|| anyhow!("bearings.csv has no coefficients for bearing {name}"))?;
            let obs = observations(&rows, schedule, &noise)
                .with_context(|| format!("bearings.csv, bearing {name}"))?;
            let options = IdentifyOptions {
                quantisation: Quantisation::Truncation,
                ..IdentifyOptions::default()
            };
            let (fit, report) = fit_ml(name, &obs, &mut noise, &options)
                .with_context(|| format!("fitting the base model of bearing {name}"))?;
            let (written, centred) = rounded_reports(name, &rows, &columns[b], schedule)?;
            written_reports.insert(name.clone(), written);
            centred_reports.insert(name.clone(), centred);
            outliers.push(report.outlier_speeds_hz.clone());
            support_modes.push(report.lack_of_fit.and_then(|l| l.support_mode));
            reports.insert(name.clone(), report);
            // The noise from the data alone (module docs of `noise`).
            unscale(&mut noise);
            for (m, var) in rows.iter().zip(&noise.var) {
                let j = speeds_hz.partition_point(|&s| s < m.speed_hz);
                if let Some(p) = points[b].get_mut(j).and_then(Option::as_mut) {
                    let magnitude: [f64; 8] = std::array::from_fn(|c| p.magnitude(c));
                    let sd = data_alone_sd(var, &magnitude);
                    p.var = sd.map(|s| s * s);
                }
            }
            noises.push(noise);
            base_fits.push(fit);
        }
        let noise = NoiseModel {
            columns,
            bearings: noises,
        };
        for (b, name) in bearings.iter().enumerate() {
            let n = points[b].iter().flatten().count();
            if n < 3 {
                bail!(
                    "bearing {name}: only {n} speeds measured; the pedestal model needs at least 3"
                );
            }
        }
        let findings = crate::identify::trust::lack_of_fit_findings(&reports);
        let written = crate::identify::trust::lack_of_fit_findings(&written_reports);
        let centred = crate::identify::trust::lack_of_fit_findings(&centred_reports);
        let lack_of_fit = bearings
            .iter()
            .map(|name| lack_of_fit_either_way(name, &findings, &written, &centred))
            .collect();
        let flipped_speeds_hz = vec![Vec::new(); bearings.len()];
        Ok(Self {
            bearings,
            speeds_hz,
            points,
            noise,
            base_fits,
            flipped_speeds_hz,
            outlier_speeds_hz: outliers,
            support_modes,
            lack_of_fit,
        })
    }

    /// Index of a bearing by name.
    pub fn bearing_index(&self, name: &str) -> Option<usize> {
        self.bearings.iter().position(|b| b == name)
    }
}

/// `plinth identify`'s lack-of-fit findings per bearing name.
type FindingsByBearing = std::collections::BTreeMap<String, crate::identify::trust::Findings>;

/// What `plinth identify`'s lack-of-fit rule finds at bearing `name`
/// (its model-error findings; empty: nothing). The written digits cannot
/// tell rounding from truncation, so a model error is one that stands
/// however they were made: found with the digits taken as truncated
/// (`truncated`, mean square ulp²/3, which bounds both), or found both in
/// the data as written taken as rounded (`written`: identify's default
/// reading) and in the data moved half an ulp away from zero (`centred`:
/// truncated data so moved are rounded ones, [`rounded_reports`]). The
/// truncated reading alone misses a model error identify sees: its level
/// is 4 times rounding's in variance (unseen-four `sub-base-d3` seed 1201:
/// B3 1.55 times identify's level, smooth in speed, p 1.0e-3, untrusted
/// by identify; not flagged at truncation's level, and diagnose printed
/// it trusted with B3 23.8 % off at z 25).
fn lack_of_fit_either_way(
    name: &str,
    truncated: &FindingsByBearing,
    written: &FindingsByBearing,
    centred: &FindingsByBearing,
) -> Vec<String> {
    let found = |m: &FindingsByBearing| {
        m.get(name)
            .map(|f| f.model_error.clone())
            .unwrap_or_default()
    };
    let own = found(truncated);
    if !own.is_empty() {
        return own;
    }
    let (w, c) = (found(written), found(centred));
    if w.is_empty() || c.is_empty() {
        return Vec::new();
    }
    w.into_iter()
        .map(|f| format!("{f} (digits read as rounded, as `plinth identify` reads them; and the same with every number moved half a last digit away from zero, as truncated digits would be rounded)"))
        .collect()
}

/// The noise reports (lack-of-fit tests) of bearing `name`'s base model
/// fitted with its digits taken as rounded (`plinth identify`'s default),
/// on `rows` as written and on `rows` with every number moved half its
/// last digit (`column`'s ulp) away from zero: what truncated digits
/// would read if they had been rounded. Fails as the base fit does.
fn rounded_reports(
    name: &str,
    rows: &[&Measurement],
    column: &[ColumnDigits; 8],
    schedule: &crate::rundir::BearingSchedule,
) -> Result<(crate::identify::NoiseReport, crate::identify::NoiseReport)> {
    let centred: Vec<Measurement> = rows
        .iter()
        .map(|m| {
            let mut m = (*m).clone();
            let half: [f64; 8] = std::array::from_fn(|c| 0.5 * column[c].ulp_of(&m, c));
            let away = |v: f64, h: f64| if v == 0.0 { v } else { v + h.copysign(v) };
            for ch in 0..2 {
                m.rel[ch].re = away(m.rel[ch].re, half[2 * ch]);
                m.rel[ch].im = away(m.rel[ch].im, half[2 * ch + 1]);
                m.ped[ch].re = away(m.ped[ch].re, half[4 + 2 * ch]);
                m.ped[ch].im = away(m.ped[ch].im, half[4 + 2 * ch + 1]);
            }
            m
        })
        .collect();
    let centred_refs: Vec<&Measurement> = centred.iter().collect();
    let options = IdentifyOptions::default();
    let report = |rows: &[&Measurement]| -> Result<crate::identify::NoiseReport> {
        let mut noise = BearingNoise::estimate(rows, column, Quantisation::Rounding);
        let obs = observations(rows, schedule, &noise)
            .with_context(|| format!("bearings.csv, bearing {name}"))?;
        let (_, report) = fit_ml(name, &obs, &mut noise, &options)
            .with_context(|| format!("fitting the base model of bearing {name}"))?;
        Ok(report)
    };
    Ok((report(rows)?, report(&centred_refs)?))
}
