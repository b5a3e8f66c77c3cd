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
