//! The speed accuracy each pedestal's values need, said with them
//! (`conditional_on.speed_column`): the values are fitted at the speeds
//! the speed column gives, and a column off by δf [Hz] moves each value
//! by b·δf (b its shift per Hz, [`crate::identify::speed_lag`]: through
//! the bearing table read at the wrong speed and the pedestal's Ω²m,
//! iΩc). The values hold within their ± only if the column is right to
//! better than min σ/|b| (for k: f·σ_k/(k·s), s = (dk/k)/(df/f) the
//! value's relative sensitivity). Said where that is below
//! [`TOLERANCE_SAID`] of the run's top speed (a speed error a real speed
//! channel can make); kept in the JSON for every bearing.

use crate::identify::speed_lag::{SpeedLag, TOLERANCE_SAID};
use crate::identify::Identification;
use serde::Serialize;

/// How right one bearing's speed column must be for its values to hold.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpeedBound {
    /// Bearing name.
    pub bearing: String,
    /// The speed error that moves some value by its (noise) ± [Hz]
    /// (`null` where a speed error moves nothing).
    pub tolerance_hz: f64,
    /// The value it moves first (`k_y`, `k_z`, `m`, `c_y` or `c_z`).
    pub parameter: String,
    /// The run's top speed [Hz].
    pub top_speed_hz: f64,
    /// True where the text report says it (below [`TOLERANCE_SAID`] of
    /// the top speed).
    pub said: bool,
}

impl SpeedBound {
    /// One line for people.
    pub fn message(&self) -> String {
        format!(
            "{}: its values hold only if the speed column is the speed of the revolutions each vector is made of to better than about {:.3} Hz ({:.2} % of the top speed {:.1} Hz): a speed error that large moves {} by its ± (through the bearing table read at the wrong speed and Ω²m, iΩc); a speed channel filtered or sampled apart from the vectors on a fast run-down can be off by that",
            self.bearing,
            self.tolerance_hz,
            100.0 * self.tolerance_hz / self.top_speed_hz,
            self.top_speed_hz,
            self.parameter
        )
    }
}

/// Every bearing's [`SpeedBound`] from `lag` (none without it).
pub fn bounds(lag: Option<&SpeedLag>) -> Vec<SpeedBound> {
    let Some(lag) = lag else {
        return Vec::new();
    };
    lag.bearings
        .iter()
        .filter(|b| b.tolerance_hz.is_finite())
        .map(|b| SpeedBound {
            bearing: b.bearing.clone(),
            tolerance_hz: b.tolerance_hz,
            parameter: b.tolerance_of.clone(),
            top_speed_hz: lag.top_speed_hz,
            said: b.tolerance_hz < TOLERANCE_SAID * lag.top_speed_hz,
        })
        .collect()
}

/// [`bounds`] of `identification`.
pub fn of(identification: &Identification) -> Vec<SpeedBound> {
    bounds(identification.speed_lag.as_ref())
}
