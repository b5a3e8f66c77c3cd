//! A bearing's coefficients over speed, as `bearings.csv` lists them.

use super::*;

/// A bearing's coefficients over speed in f64, from `bearings.csv`: linear
/// interpolation between the two nearest listed speeds and no extrapolation,
/// as [`plinth_shared::bearing::BearingTable`] does on the box (which has a
/// fixed capacity; this one grows).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BearingSchedule {
    speeds_hz: Vec<f64>,
    coefficients: Vec<BearingCoefficients<f64>>,
}

/// A speed [Hz] outside a [`BearingSchedule`]'s listed range.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("speed {speed_hz} Hz is outside the listed range {min_hz}..={max_hz} Hz (coefficients are not extrapolated)")]
pub struct OutOfRange {
    /// The requested speed [Hz].
    pub speed_hz: f64,
    /// Lowest listed speed [Hz] (NaN for an empty schedule).
    pub min_hz: f64,
    /// Highest listed speed [Hz] (NaN for an empty schedule).
    pub max_hz: f64,
}

impl BearingSchedule {
    /// A schedule from (speed [Hz], coefficients) pairs in any order; the
    /// speeds must be finite and distinct (the reader guarantees it).
    pub fn new(mut rows: Vec<(f64, BearingCoefficients<f64>)>) -> Self {
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (speeds_hz, coefficients) = rows.into_iter().unzip();
        Self {
            speeds_hz,
            coefficients,
        }
    }

    /// The listed speeds [Hz], increasing.
    pub fn speeds_hz(&self) -> &[f64] {
        &self.speeds_hz
    }

    /// The listed coefficients, in the order of [`Self::speeds_hz`].
    pub fn coefficients(&self) -> &[BearingCoefficients<f64>] {
        &self.coefficients
    }

    /// Lowest and highest listed speed [Hz], or `None` when empty.
    pub fn range_hz(&self) -> Option<(f64, f64)> {
        Some((*self.speeds_hz.first()?, *self.speeds_hz.last()?))
    }

    /// The same schedule with `f` applied to every listed coefficient set
    /// (the listed speeds unchanged): what a bearing table with `f` applied
    /// to each row gives, as the order by speed does not change.
    pub fn map_coefficients(&self, f: impl Fn(&mut BearingCoefficients<f64>)) -> Self {
        let mut out = self.clone();
        out.coefficients.iter_mut().for_each(f);
        out
    }

    /// Coefficients at `speed_hz` [Hz], interpolated linearly in speed.
    pub fn at(&self, speed_hz: f64) -> Result<BearingCoefficients<f64>, OutOfRange> {
        let (min_hz, max_hz) = self.range_hz().unwrap_or((f64::NAN, f64::NAN));
        let out = OutOfRange {
            speed_hz,
            min_hz,
            max_hz,
        };
        plinth_shared::bearing::interpolate(&self.speeds_hz, &self.coefficients, speed_hz)
            .ok_or(out)
    }
}

/// One bearing's measurement speeds that its `bearings.csv` rows do not
/// list although they list most of its speeds (a table on the measurement
/// grid with rows missing, e.g. a line deleted): formats.md interpolates
/// their coefficients linearly between the neighbouring listed speeds, which
/// a lost row would otherwise make silently.
#[derive(Clone, Debug, PartialEq)]
pub struct UnlistedSpeeds {
    /// The bearing.
    pub bearing: String,
    /// Its measurement speeds without a `bearings.csv` row [Hz], increasing.
    pub speeds_hz: Vec<f64>,
    /// Its distinct measurement speeds.
    pub measured: usize,
}

impl std::fmt::Display for UnlistedSpeeds {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        const SHOWN: usize = 6;
        let mut list: Vec<String> = self
            .speeds_hz
            .iter()
            .take(SHOWN)
            .map(|s| s.to_string())
            .collect();
        if self.speeds_hz.len() > SHOWN {
            list.push(format!("… {} more", self.speeds_hz.len() - SHOWN));
        }
        write!(
            f,
            "bearing `{}`: no row at {} of its {} measurement speeds ({} Hz) although the others have one: their coefficients are interpolated linearly between the neighbouring listed speeds (formats.md); restore the rows if they were lost",
            self.bearing,
            self.speeds_hz.len(),
            self.measured,
            list.join(", ")
        )
    }
}

/// The [`UnlistedSpeeds`] of every bearing of `run` whose `bearings.csv`
/// rows list at least half of its distinct measurement speeds but not all
/// (a coarser table, listing fewer, is interpolation by design).
pub fn unlisted_speeds(run: &RunDir) -> Vec<UnlistedSpeeds> {
    unlisted_speeds_with(run, &run.bearing_schedules())
}

/// [`unlisted_speeds`] of `run`, whose bearing schedules are `schedules`.
pub fn unlisted_speeds_with(
    run: &RunDir,
    schedules: &BTreeMap<String, BearingSchedule>,
) -> Vec<UnlistedSpeeds> {
    let mut speeds: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
    for m in &run.measurements {
        speeds
            .entry(m.bearing.as_str())
            .or_default()
            .push(m.speed_hz);
    }
    let mut out = Vec::new();
    for (bearing, mut measured) in speeds {
        let Some(schedule) = schedules.get(bearing) else {
            continue;
        };
        measured.sort_by(f64::total_cmp);
        measured.dedup();
        let listed = schedule.speeds_hz();
        let unlisted: Vec<f64> = measured
            .iter()
            .copied()
            .filter(|s| listed.binary_search_by(|l| l.total_cmp(s)).is_err())
            .collect();
        if !unlisted.is_empty() && 2 * (measured.len() - unlisted.len()) >= measured.len() {
            out.push(UnlistedSpeeds {
                bearing: bearing.to_string(),
                speeds_hz: unlisted,
                measured: measured.len(),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(measured: &[f64], listed: &[f64]) -> RunDir {
        let zero = Complex::new(0.0, 0.0);
        RunDir {
            measurements: measured
                .iter()
                .map(|&speed_hz| Measurement {
                    speed_hz,
                    bearing: "left".into(),
                    rel: [zero; 2],
                    ped: [zero; 2],
                    noise_sd: None,
                    written: None,
                })
                .collect(),
            bearings: listed
                .iter()
                .map(|&speed_hz| BearingRow {
                    speed_hz,
                    bearing: "left".into(),
                    coefficients: BearingCoefficients::isotropic(1e8, 1e4),
                })
                .collect(),
            truth: None,
        }
    }

    #[test]
    fn a_row_missing_from_a_table_on_the_measurement_grid_is_named() {
        let speeds: Vec<f64> = (1..=12).map(|k| 5.0 * f64::from(k)).collect();
        let mut listed = speeds.clone();
        listed.remove(4); // 25 Hz
        let found = unlisted_speeds(&run(&speeds, &listed));
        assert_eq!(found.len(), 1);
        assert_eq!(found[0].speeds_hz, vec![25.0]);
        let text = found[0].to_string();
        assert!(
            text.contains("bearing `left`") && text.contains("(25 Hz)"),
            "{text}"
        );
        // Every speed listed, or a coarse table (interpolation by design):
        // nothing to say.
        assert!(unlisted_speeds(&run(&speeds, &speeds)).is_empty());
        assert!(unlisted_speeds(&run(&speeds, &[5.0, 30.0, 60.0])).is_empty());
    }
}
