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

/// Folds a standard uncertainty `sd` [Hz] of the speed column (one offset
/// Δ for the run, mean 0) into the ± and covariance of every pedestal
/// `identification.speed_lag` has a shift b for: Σ' = Σ + sd²·b·bᵀ (the
/// fitted values move by b·Δ to first order); the ± of a parameter the
/// model fixes stay 0.
pub fn widen(identification: &mut Identification, sd: f64) {
    let Some(lag) = identification.speed_lag.clone() else {
        return;
    };
    for b in &lag.bearings {
        let Some(p) = identification
            .pedestals
            .iter_mut()
            .find(|p| p.bearing == b.bearing)
        else {
            continue;
        };
        let path = &b.path_per_hz;
        p.add_covariance(&std::array::from_fn(|i| {
            std::array::from_fn(|j| sd * sd * path[i] * path[j])
        }));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::speed_lag::BearingLag;

    fn lag(tolerance: f64) -> SpeedLag {
        SpeedLag {
            offset: None,
            top_speed_hz: 250.0,
            bearings: vec![BearingLag {
                bearing: "B1".into(),
                path_per_hz: [4.0e6, 1.0e6, 0.1, 0.0, 0.0],
                held_std_err: [1.0e6, 1.0e6, 1.0, 1.0, 1.0],
                ratio: [1.0; 5],
                tolerance_hz: tolerance,
                tolerance_of: "k_y".into(),
                widened: false,
            }],
        }
    }

    /// Said below 1 % of the top speed (2.5 Hz here), kept in the JSON
    /// above it; the sentence names the figure and the parameter.
    #[test]
    fn the_tolerance_is_said_where_it_is_small() {
        let b = bounds(Some(&lag(0.25)));
        assert!(b[0].said);
        let m = b[0].message();
        assert!(
            m.contains("better than about 0.250 Hz (0.10 % of the top speed 250.0 Hz)"),
            "{m}"
        );
        assert!(m.contains("moves k_y by its ±"), "{m}");
        assert!(!bounds(Some(&lag(3.0)))[0].said);
        assert!(bounds(Some(&lag(f64::INFINITY))).is_empty());
        assert!(bounds(None).is_empty());
    }
}
