//! The extractor's settings and the settings it refuses.

use super::Sensor;

/// Settings of a [`PhasorExtractor`](super::PhasorExtractor) with N channels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExtractorConfig<const N: usize> {
    /// Sampling rate of every channel [Hz] (51 200 on the field box).
    pub sample_rate_hz: f32,
    /// The transducer on each channel.
    pub sensors: [Sensor; N],
    /// Revolutions averaged into one output, R ≥ 1.
    pub revolutions_per_output: u16,
    /// Lowest speed tracked [Hz]: no edge within 1/`min_speed_hz` is a timeout.
    pub min_speed_hz: f32,
    /// Highest speed accepted [Hz]; at most `sample_rate_hz`/64.
    pub max_speed_hz: f32,
    /// Largest accepted relative deviation of a period from its prediction
    /// (dimensionless, in (0, 0.5)); beyond it the pulse counts as extra or
    /// missing.
    pub period_tolerance: f32,
    /// Largest plausible |d(speed)/dt| while acquiring [Hz/s].
    pub max_acceleration_hz_per_s: f32,
}

impl<const N: usize> ExtractorConfig<N> {
    /// Defaults for a run-down: one revolution per output, 1-400 Hz, 5 %
    /// period tolerance, speed changes up to 50 Hz/s.
    pub fn new(sample_rate_hz: f32, sensors: [Sensor; N]) -> Self {
        Self {
            sample_rate_hz,
            sensors,
            revolutions_per_output: 1,
            min_speed_hz: 1.0,
            max_speed_hz: 400.0,
            period_tolerance: 0.05,
            max_acceleration_hz_per_s: 50.0,
        }
    }
}

/// A setting of [`ExtractorConfig`] that cannot work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// `sample_rate_hz` is not finite and positive.
    SampleRate,
    /// The sensitivity of sensor `channel` is not finite and positive.
    Sensitivity {
        /// Channel index.
        channel: usize,
    },
    /// `revolutions_per_output` is 0.
    Revolutions,
    /// Not 0 < `min_speed_hz` < `max_speed_hz` ≤ `sample_rate_hz`/64, or a
    /// revolution at `min_speed_hz` would last 2²² samples or more.
    SpeedRange,
    /// `period_tolerance` is not in (0, 0.5).
    PeriodTolerance,
    /// `max_acceleration_hz_per_s` is not finite and positive.
    Acceleration,
}
