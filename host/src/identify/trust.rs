//! Run-level trust verdicts on identified pedestals: lack of fit
//! ([`crate::estimate::lack_of_fit`]) with a family-wise false-alarm rate
//! over the run's bearings, and the warnings that name bad speeds
//! ([`crate::estimate::robust`]).
//!
//! A bearing is judged when its fit could have absorbed model error as
//! noise: its noise level came from the scatter, or its χ² exceeded the
//! known level (digits, noise columns). It is not trusted when
//! - **level**: with noise columns, χ² is beyond them (upper tail below
//!   [`FAMILY_FALSE_ALARM`]/T, T the bearings judged: Bonferroni); with a
//!   scatter or digits level, χ²/dof exceeds [`SCATTER_LEVEL_TOLERANCE`]
//!   (the same factor beyond which the estimator models the excess as an
//!   equation error): measured on clean data 0.6-1.2;
//! - **structure**: the scan of its whitened residuals for a smooth curve
//!   in speed (over the whole run and over windows of it, against block
//!   shuffles) or their mean over the run (against blocks negated at
//!   random), Bonferroni over the two, is beyond its null at
//!   [`FAMILY_FALSE_ALARM`]/S, and the fit leaves more than
//!   [`STRUCTURE_LEVEL`] times its measured level (clean data: below 0.96
//!   with a scatter level, 1.28 with noise columns, over 3 600 runs; the
//!   block shuffle is only approximately the null of correlated residuals,
//!   so structure alone, inside the noise, is not taken for model error).
//!   S counts the bearings judged whose level exceeds [`STRUCTURE_LEVEL`]:
//!   only those can be flagged for structure, and the level ratio is
//!   independent of the structure p-value under the null (the p-value is a
//!   function of the residuals' direction w/|w| only: every figure of the
//!   test is unchanged when w is scaled, and for Gaussian noise |w| and
//!   w/|w| are independent), so a Bonferroni over the bearings that pass
//!   this filter keeps the family-wise rate (independent filtering:
//!   Bourgon, Gentleman & Huber 2010, *PNAS* 107). A bearing whose fit is
//!   inside its noise spends no share of the run's false-alarm rate.
//! - **support mode**: the one-sided score test of an Ω⁴ fall of each
//!   direction's stiffness ([`crate::estimate::lack_of_fit::
//!   support_mode`]: a support with a second mode above the speed range,
//!   whose χ² excess the level test cannot see; q ≥ 0, chi-bar-squared),
//!   against the noise columns (made only with them), p below
//!   [`SUPPORT_FALSE_ALARM`]/U, U the bearings tested (docs/trust-support-mode.md,
//!   sessions 29 and 35, for its measured rates).
//! - **sensor delay**: the two-sided score test of a delay τ on each
//!   bearing's `rel` probes ([`crate::estimate::lack_of_fit::sensor_delay`]:
//!   a phase error growing with speed, which the one-mass fit takes into its
//!   damping, c − τ(k − Ω²m)), against the noise columns (made only with
//!   them), χ²(1), p below [`DELAY_FALSE_ALARM`]/D, D the bearings tested
//!   (docs/trust.md, Session 45 (idelay17) for its measured rates).
//!
//! The rates are measured by `scripts/bench-trust.sh` (false alarms on clean
//! machines, detections on a pedestal with its own sub-base): docs/trust.md.

use super::estimator::SCATTER_LEVEL_TOLERANCE;
use super::{Identification, Warning, WarningKind};
use crate::estimate::noise::NoiseSource;
use crate::estimate::pedestal::CHI2_P_THRESHOLD;
use crate::estimate::robust;
use crate::estimate::Observation;

/// Family-wise false-alarm rate of the lack-of-fit rule per run [-].
pub const FAMILY_FALSE_ALARM: f64 = 0.01;

/// χ²/dof against the measured level above which structure in the
/// residuals is taken for model error [-].
pub const STRUCTURE_LEVEL: f64 = crate::estimate::lack_of_fit::EXCESS_LEVEL;

/// False-alarm rate per run of the support-mode test
/// ([`crate::estimate::lack_of_fit::support_mode`]), Bonferroni over the
/// bearings tested [-]. A Neyman-Pearson choice (session 36,
/// docs/trust-support-mode.md): half the clean budget of 1 % per
/// run, its clean rate measured within it on every machine
/// (`scripts/bench_support_rate.py`, which checks the claim); 0.001 before
/// printed a pedestal on a sub-base `ok` 40 % off on 17/96 seeds of the
/// third unseen machine (5/96 at this rate).
pub const SUPPORT_FALSE_ALARM: f64 = 0.005;

/// False-alarm rate per run of the sensor-delay test
/// ([`crate::estimate::lack_of_fit::sensor_delay`]), Bonferroni over the
/// bearings tested [-]: a fifth of the clean budget of 1 % per run
/// (session 45, docs/trust.md, Session 45 (idelay17) for its measured rates).
pub const DELAY_FALSE_ALARM: f64 = 0.002;

/// The support-mode test's limit on one bearing's p-value when it was made
/// at `tested` bearings of the run: [`SUPPORT_FALSE_ALARM`] shared among
/// them (Bonferroni) [-]. One rule for identify and diagnose.
pub fn support_limit(tested: usize) -> f64 {
    SUPPORT_FALSE_ALARM / tested.max(1) as f64
}

/// One bearing's lack-of-fit findings (module docs), each a sentence: what
/// the rule saw and its limit.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Findings {
    /// Level and structure: the fit leaves model error as noise would not.
    pub model_error: Vec<String>,
    /// The support-mode test: an Ω⁴ fall of the stiffness.
    pub support_mode: Option<String>,
    /// The sensor-delay test: a phase error growing with speed.
    pub sensor_delay: Option<String>,
}

impl Findings {
    /// Whether any rule flagged the bearing.
    pub fn any(&self) -> bool {
        !self.model_error.is_empty() || self.support_mode.is_some() || self.sensor_delay.is_some()
    }
}

/// The lack-of-fit rule (module docs) over a run's bearings, each bearing's
/// noise report `noise` as its base fit gave it (`plinth identify`'s
/// `noise`): the findings of every bearing flagged, with the family-wise
/// shares of the run. One rule for identify ([`mark_lack_of_fit`]) and
/// diagnose (`diagnose::trust::lack_of_fit_reasons`).
pub fn lack_of_fit_findings(
    noise: &std::collections::BTreeMap<String, super::NoiseReport>,
) -> std::collections::BTreeMap<String, Findings> {
    let judged = noise.values().filter(|n| n.lack_of_fit.is_some()).count();
    let alpha = FAMILY_FALSE_ALARM / judged.max(1) as f64;
    // Noise columns' level test: at most the χ² limit beyond which the fit
    // was judged before the support-mode test made every fit with columns
    // judged (`lack_of_fit::assess`): the level rule is unchanged by it.
    let level_alpha = alpha.min(CHI2_P_THRESHOLD);
    // The structure rule's share: over the bearings it can flag (module docs).
    let can_flag = noise
        .values()
        .filter_map(|n| n.lack_of_fit)
        .filter(|l| l.structure.is_some() && l.level_ratio > STRUCTURE_LEVEL)
        .count();
    let alpha_structure = FAMILY_FALSE_ALARM / can_flag.max(1) as f64;
    // The support-mode test's share: over the bearings it was made at.
    let support_tested = noise
        .values()
        .filter_map(|n| n.lack_of_fit)
        .filter(|l| l.support_mode.is_some())
        .count();
    let alpha_support = support_limit(support_tested);
    // The sensor-delay test's share: over the bearings it was made at.
    let delay_tested = noise
        .values()
        .filter_map(|n| n.lack_of_fit)
        .filter(|l| l.sensor_delay.is_some())
        .count();
    let alpha_delay = DELAY_FALSE_ALARM / delay_tested.max(1) as f64;
    let mut flagged = std::collections::BTreeMap::new();
    for (bearing, n) in noise {
        let Some(l) = n.lack_of_fit else {
            continue;
        };
        let mut found = Findings::default();
        match l.level_from {
            NoiseSource::Columns if l.level_p < level_alpha => found.model_error.push(format!(
                "χ²/dof = {:.3} against its noise columns (p = {:.1e}, limit {level_alpha:.1e})",
                l.level_ratio, l.level_p
            )),
            NoiseSource::Scatter | NoiseSource::Digits
                if l.level_ratio > SCATTER_LEVEL_TOLERANCE =>
            {
                found.model_error.push(format!(
                    "its fit leaves {:.3} times the variance its {} allow (the scatter between neighbouring speeds, floored by the digits, measured without the model; at most {SCATTER_LEVEL_TOLERANCE} for noise)",
                    l.level_ratio,
                    l.level_from.name()
                ))
            }
            _ => {}
        }
        if let Some(s) = l.structure {
            if s.p_value < alpha_structure && l.level_ratio > STRUCTURE_LEVEL {
                let evidence = if s.mean_p_value < s.shape_p_value {
                    format!(
                        "their mean over {:.1}-{:.1} Hz is one-signed, as a broad model error makes it and noise symmetric about zero does not (it explains {:.1} % of them; score {:.1} against {:.1} with blocks of speeds negated at random",
                        s.window_hz[0],
                        s.window_hz[1],
                        100.0 * s.explained,
                        s.statistic,
                        s.statistic_null_median,
                    )
                } else {
                    format!(
                        "over {:.1}-{:.1} Hz a degree-{} polynomial explains {:.1} % of them; scan score {:.1} against {:.1} with blocks of speeds shuffled",
                        s.window_hz[0],
                        s.window_hz[1],
                        s.degree,
                        100.0 * s.explained,
                        s.statistic,
                        s.statistic_null_median,
                    )
                };
                found.model_error.push(format!(
                    "its residuals ({:.3} times its measured level) follow a smooth curve in speed as model error does and noise does not ({evidence}; p = {:.1e}, twice the smaller of the scan score's {:.1e} and the mean's {:.1e} (Bonferroni); limit {alpha_structure:.1e}: {FAMILY_FALSE_ALARM} over the {can_flag} bearing(s) whose fit leaves more than their level)",
                    l.level_ratio,
                    s.p_value,
                    s.shape_p_value,
                    s.mean_p_value
                ));
            }
        }
        if let Some(t) = l.support_mode {
            if t.p_value < alpha_support {
                found.support_mode = Some(format!(
                    "its dynamic stiffness does not follow one mass on one spring over speed: an Ω⁴ term, what a support with a second mode above the speed range adds (a sub-base, a frame: per direction K − Ω²M − Ω⁴Q below that mode, Q > 0), explains {:.1} of its whitened residuals' sum of squares beyond the one-mass model (in units of its noise columns; one-sided, Ω⁴Q ≥ 0: p = {:.1e}, limit {alpha_support:.1e}: {SUPPORT_FALSE_ALARM} over the {support_tested} bearing(s) tested); Ω⁴Q at the top speed is {:+.1} % (y) and {:+.1} % (z) of the stiffness (positive: it falls faster than one mass allows); the k and m printed are then the support's apparent values, not the pedestal's",
                    t.statistic,
                    t.p_value,
                    100.0 * t.drop_at_top[0],
                    100.0 * t.drop_at_top[1]
                ));
            }
        }
        if let Some(t) = l.sensor_delay {
            if t.p_value < alpha_delay {
                found.sensor_delay = Some(format!(
                    "a phase error growing with speed: a sensor delay of about {:.0} ± {:.0} µs on its rel probes (negative: on its ped pick-ups) explains {:.1} of its whitened residuals' sum of squares beyond the one-mass model (in units of its noise columns; p = {:.1e}, limit {alpha_delay:.1e}: {DELAY_FALSE_ALARM} over the {delay_tested} bearing(s) tested); the one-mass fit takes a delay into its damping (c − τ(k − Ω²m)), and other model error (a sub-base, a frame) can show as one too; run plinth diagnose",
                    t.delay_us, t.delay_std_us, t.statistic, t.p_value
                ));
            }
        }
        if found.any() {
            flagged.insert(bearing.clone(), found);
        }
    }
    flagged
}

/// Adds a [`WarningKind::LackOfFit`] warning to every pedestal whose fit
/// shows model error ([`lack_of_fit_findings`]), and updates `trusted`.
pub fn mark_lack_of_fit(identification: &mut Identification) {
    let flagged = lack_of_fit_findings(&identification.noise);
    let levels: Vec<(String, f64)> = identification
        .noise
        .iter()
        .filter(|(_, n)| n.dof > 0)
        .map(|(b, n)| (b.clone(), n.chi2 / n.dof as f64))
        .collect();
    for p in &mut identification.pedestals {
        let Some(found) = flagged.get(&p.bearing) else {
            continue;
        };
        let reasons: Vec<&str> = found
            .model_error
            .iter()
            .chain(&found.support_mode)
            .chain(&found.sensor_delay)
            .map(String::as_str)
            .collect();
        let others: Vec<String> = levels
            .iter()
            .filter(|(b, _)| *b != p.bearing)
            .map(|(b, r)| format!("{b} {r:.3}"))
            .collect();
        let context = if others.is_empty() {
            String::new()
        } else {
            format!(
                "; χ²/dof of the other bearings against their own noise: {}",
                others.join(", ")
            )
        };
        p.warnings.push(Warning {
            kind: WarningKind::LackOfFit,
            message: format!(
                "lack of fit: {}{context}. The one-mass pedestal model does not describe this bearing's data; its ± count noise only and exclude this model error: try `plinth diagnose`",
                reasons.join("; ")
            ),
        });
        p.trusted = false;
    }
}

/// The warnings naming one bearing's bad speeds: the outlier speeds
/// `outliers` [Hz] left out of its fit ([`robust::outlier_refit`]) and the
/// speeds at which every channel of its `observations` looks flipped by
/// 180° ([`robust::keyphasor_flips`]), which are added to `outliers`
/// (ascending, no repeats); with the test in speed's findings
/// ([`robust::flip_search`], for the test across bearings:
/// [`super::flips::mark_cross_bearing_flips`]).
pub fn bad_speeds(
    observations: &[Observation],
    outliers: &mut Vec<f64>,
) -> (Vec<Warning>, robust::FlipSearch) {
    let mut warnings = Vec::new();
    if !outliers.is_empty() {
        warnings.push(Warning {
            kind: WarningKind::OutlierSpeeds,
            message: format!(
                "the residuals at {} Hz are beyond what the noise allows (χ²(4) limit at {:.2} % per fit, Bonferroni over the speeds), also against the fit without them: those speeds are left out of the fit",
                hz_list(outliers),
                100.0 * robust::OUTLIER_FAMILY_RATE
            ),
        });
    }
    let grid: Vec<f64> = observations.iter().map(|o| o.speed_hz).collect();
    if let Some(run) = adjacent_run(&grid, outliers) {
        warnings.push(Warning {
            kind: WarningKind::LackOfFit,
            message: format!(
                "lack of fit: {} adjacent speeds ({} Hz) were left out as outliers; bad readings (a glitch, a mis-trigger) strike speeds one by one, a run of {ADJACENT_OUTLIERS} or more neighbours is a change in speed the model lacks (a narrow resonance of a sub-base or a bracket, or a burst of bad data), which leaving them out hides. Its ± count noise only and exclude this: try `plinth diagnose`",
                run.len(),
                hz_list(&run)
            ),
        });
    }
    let search = robust::flip_search(observations);
    let flips = search.flipped_hz.clone();
    if !flips.is_empty() {
        warnings.push(Warning {
            kind: WarningKind::KeyphasorFlip,
            message: format!(
                "every channel (rel and ped, y and z) is flipped by 180° against its neighbouring speeds at {} Hz: a likely keyphasor fault (the once-per-revolution mark triggered half a revolution off); the pedestal equation is blind to it (rel and ped flip together), but check those speeds",
                hz_list(&flips)
            ),
        });
        outliers.extend(flips);
        outliers.sort_by(f64::total_cmp);
        outliers.dedup();
    }
    (warnings, search)
}

/// Fewest neighbouring speeds of the run's grid left out as outliers that
/// make a lack of fit, not outliers: a speed's bad reading may spill into
/// the next speed's averaging, not into a third (docs/trust-lack-of-fit.md, session
/// 31: ROSS machine-d's sub-base resonance, 3-4 speeds, was listed as
/// outliers and its bearing printed `ok`).
pub const ADJACENT_OUTLIERS: usize = 3;

/// The longest run of neighbouring speeds of the grid `speeds_hz` [Hz]
/// among `outliers` [Hz], when it is [`ADJACENT_OUTLIERS`] long or longer.
fn adjacent_run(speeds_hz: &[f64], outliers: &[f64]) -> Option<Vec<f64>> {
    let mut grid = speeds_hz.to_vec();
    grid.sort_by(f64::total_cmp);
    grid.dedup();
    let mut best: Vec<f64> = Vec::new();
    let mut run: Vec<f64> = Vec::new();
    for f in grid {
        if outliers.contains(&f) {
            run.push(f);
            if run.len() > best.len() {
                best.clone_from(&run);
            }
        } else {
            run.clear();
        }
    }
    (best.len() >= ADJACENT_OUTLIERS).then_some(best)
}

/// Speeds [Hz] as a comma-separated list (the one wording of identify's
/// and diagnose's speed lists).
pub(crate) fn hz_list(speeds_hz: &[f64]) -> String {
    speeds_hz
        .iter()
        .map(|s| format!("{s}"))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_of_neighbouring_outlier_speeds_is_found_and_scattered_ones_are_not() {
        // A 2.5 Hz grid from 5 to 52.5 Hz, descending (a run directory may
        // hold a run-down in time order).
        let grid: Vec<f64> = (0..20).rev().map(|i| 5.0 + 2.5 * i as f64).collect();
        // Scattered outliers, and two neighbours: outliers.
        assert_eq!(adjacent_run(&grid, &[5.0, 12.5, 50.0]), None);
        assert_eq!(adjacent_run(&grid, &[20.0, 22.5, 30.0]), None);
        // Three neighbours given in any order; the longest run.
        assert_eq!(
            adjacent_run(&grid, &[22.5, 20.0, 25.0, 10.0, 12.5]),
            Some(vec![20.0, 22.5, 25.0])
        );
        assert_eq!(
            adjacent_run(&grid, &[5.0, 7.5, 10.0, 30.0, 32.5, 35.0, 37.5]),
            Some(vec![30.0, 32.5, 35.0, 37.5])
        );
        // A speed not on the grid makes no run.
        assert_eq!(adjacent_run(&grid, &[21.0, 22.0, 23.0]), None);
        assert_eq!(adjacent_run(&[], &[1.0, 2.0, 3.0]), None);
    }
}
