//! CHANNELS.toml of `plinth extract` (formats.md "Recorded waveforms"):
//! which recording channel is which transducer, its sensitivity, and the
//! keyphasor channel.
//!
//! ```toml
//! full_scale_v = 10.0      # integer PCM: volts at full scale (float WAV, CSV: samples are volts)
//! revolutions = 4          # revolutions per phasor
//! # optional: speed_resolution_hz = 0.001 (consecutive phasors whose speeds
//! #   agree within it, a dwell, are averaged into one row at their mean speed),
//! # min_speed_hz = 1.0, max_acceleration_hz_per_s = 50.0, period_tolerance = 0.05,
//! # view = "driver", rotation = "ccw" (for `angle = "45L"`)
//!
//! [keyphasor]
//! channel = 8
//! threshold_v = -5.0
//! edge = "falling"         # "falling" (notch) | "rising" (projection)
//! # hysteresis_v = 0.5     # optional: the signal must come back this far past the threshold before the next edge
//!
//! [[channel]]
//! index = 0
//! bearing = "B1"
//! quantity = "rel"
//! angle_deg = 45.0         # or angle = "45L"
//! sensor = "proximity"     # "proximity" | "velocity" | "acceleration"
//! sensitivity = 7.87
//! sensitivity_unit = "V/mm"  # "V/mm", "mV/mil", "mV/(mm/s)", "mV/(in/s)", "mV/g", "V/(m/s2)"
//! ```

use crate::field::angle::{Rotation, View};
use crate::field::transducer::{angle_of, group_by_bearing, Placement, Quantity};
use crate::field::units::{INCH, MIL, STANDARD_GRAVITY};
use anyhow::{bail, Context, Result};
use plinth_shared::extractor::SensorKind;
use serde::Deserialize;
use std::path::Path;

/// Default hysteresis of the keyphasor detector [V].
pub const DEFAULT_HYSTERESIS_V: f64 = 0.5;
/// Default rounding of written speeds [Hz].
pub const DEFAULT_SPEED_RESOLUTION_HZ: f64 = 0.001;
/// The widest dwell `speed_resolution_hz` may give [Hz]: wider would merge
/// the speeds of a run-down.
pub const MAX_SPEED_RESOLUTION_HZ: f64 = 1.0;

/// Keyphasor edge direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Edge {
    /// The signal falls through the threshold (a notch under a proximity probe).
    Falling,
    /// The signal rises through it (a projection).
    Rising,
}

/// The keyphasor channel and its detector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeyphasorConfig {
    /// 0-based channel index.
    pub channel: usize,
    /// Threshold [V].
    pub threshold_v: f64,
    /// Edge direction.
    pub edge: Edge,
    /// Hysteresis [V] ≥ 0.
    pub hysteresis_v: f64,
}

/// One measuring channel.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelConfig {
    /// 0-based channel index in the recording.
    pub index: usize,
    /// Bearing, quantity, angle.
    pub placement: Placement,
    /// Transducer kind.
    pub kind: SensorKind,
    /// Sensitivity [V/m, V/(m/s) or V/(m/s²)].
    pub sensitivity_si: f64,
}

/// A checked CHANNELS.toml.
#[derive(Clone, Debug, PartialEq)]
pub struct Channels {
    /// Direction of rotation seen from the file's `view` (figures).
    pub rotation: Option<Rotation>,
    /// Volts at integer full scale, when given.
    pub full_scale_v: Option<f64>,
    /// Revolutions per phasor, ≥ 1.
    pub revolutions: u16,
    /// Consecutive phasors within this of the first [Hz] are one dwell, averaged.
    pub speed_resolution_hz: f64,
    /// Lowest speed tracked [Hz].
    pub min_speed_hz: f64,
    /// Largest plausible |d speed/dt| [Hz/s].
    pub max_acceleration_hz_per_s: f64,
    /// Period tolerance of the pulse checks [-].
    pub period_tolerance: f64,
    /// The keyphasor.
    pub keyphasor: KeyphasorConfig,
    /// The measuring channels, in file order.
    pub channels: Vec<ChannelConfig>,
    /// Bearings in first-seen order with the indices (into `channels`) of
    /// their `rel` and `ped` channels.
    pub bearings: Vec<(String, [Vec<usize>; 2])>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Raw {
    full_scale_v: Option<f64>,
    revolutions: Option<i64>,
    speed_resolution_hz: Option<f64>,
    min_speed_hz: Option<f64>,
    max_acceleration_hz_per_s: Option<f64>,
    period_tolerance: Option<f64>,
    view: Option<View>,
    rotation: Option<Rotation>,
    keyphasor: RawKeyphasor,
    #[serde(rename = "channel", default)]
    channels: Vec<RawChannel>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawKeyphasor {
    channel: i64,
    threshold_v: f64,
    edge: Edge,
    hysteresis_v: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawChannel {
    index: i64,
    bearing: String,
    quantity: Quantity,
    angle_deg: Option<f64>,
    angle: Option<String>,
    sensor: String,
    sensitivity: f64,
    sensitivity_unit: String,
}

/// A sensitivity unit: the sensor kind it belongs to and the factor to SI
/// (V/m, V/(m/s), V/(m/s²)).
pub fn sensitivity_unit(unit: &str) -> Option<(SensorKind, f64)> {
    let u: String = unit.chars().filter(|c| !c.is_whitespace()).collect();
    Some(match u.as_str() {
        "V/mm" => (SensorKind::Displacement, 1e3),
        "mV/um" | "mV/µm" => (SensorKind::Displacement, 1e3),
        "mV/mil" => (SensorKind::Displacement, 1e-3 / MIL),
        "V/m" => (SensorKind::Displacement, 1.0),
        "mV/(mm/s)" => (SensorKind::Velocity, 1.0),
        "mV/(in/s)" => (SensorKind::Velocity, 1e-3 / INCH),
        "V/(m/s)" => (SensorKind::Velocity, 1.0),
        "mV/g" => (SensorKind::Acceleration, 1e-3 / STANDARD_GRAVITY),
        "V/g" => (SensorKind::Acceleration, 1.0 / STANDARD_GRAVITY),
        "V/(m/s2)" | "V/(m/s^2)" | "V/(m/s²)" => (SensorKind::Acceleration, 1.0),
        _ => return None,
    })
}

fn kind_name(k: SensorKind) -> &'static str {
    match k {
        SensorKind::Displacement => "proximity",
        SensorKind::Velocity => "velocity",
        SensorKind::Acceleration => "acceleration",
    }
}

impl Channels {
    /// Reads and checks CHANNELS.toml.
    pub fn read(path: &Path) -> Result<Channels> {
        let text = crate::input_file::read_to_string(path)
            .with_context(|| format!("{}", path.display()))?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Parses CHANNELS.toml text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Channels> {
        let raw: Raw = toml::from_str(text)
            .map_err(|e| anyhow::anyhow!("{file}: {}", crate::input_file::toml_error(text, &e)))?;
        let positive = |key: &str, v: f64| -> Result<f64> {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                bail!("{file}: {key}: {v} must be finite and > 0")
            }
        };
        let full_scale_v = raw
            .full_scale_v
            .map(|v| positive("full_scale_v", v))
            .transpose()?;
        let revolutions = match raw.revolutions.unwrap_or(1) {
            r @ 1..=1000 => r as u16,
            r => bail!("{file}: revolutions: {r} must be 1..=1000"),
        };
        let speed_resolution_hz = positive(
            "speed_resolution_hz",
            raw.speed_resolution_hz
                .unwrap_or(DEFAULT_SPEED_RESOLUTION_HZ),
        )?;
        let min_speed_hz = positive("min_speed_hz", raw.min_speed_hz.unwrap_or(1.0))?;
        if speed_resolution_hz > MAX_SPEED_RESOLUTION_HZ {
            bail!(
                "{file}: speed_resolution_hz: {speed_resolution_hz} Hz would average phasors {speed_resolution_hz} Hz apart (a whole run-down) into one row; it is the width of a dwell: at most {MAX_SPEED_RESOLUTION_HZ} Hz (default {DEFAULT_SPEED_RESOLUTION_HZ})"
            );
        }
        let max_acceleration_hz_per_s = positive(
            "max_acceleration_hz_per_s",
            raw.max_acceleration_hz_per_s.unwrap_or(50.0),
        )?;
        let period_tolerance = raw.period_tolerance.unwrap_or(0.05);
        if !(period_tolerance > 0.0 && period_tolerance < 0.5) {
            bail!("{file}: period_tolerance: {period_tolerance} must be in (0, 0.5)");
        }
        if raw.view.is_some() != raw.rotation.is_some() {
            bail!("{file}: `view` and `rotation` come together (the rotation is as seen from the view)");
        }
        let k = &raw.keyphasor;
        let kp_channel = usize::try_from(k.channel).map_err(|_| {
            anyhow::anyhow!(
                "{file}: keyphasor.channel: {} is not a 0-based channel index",
                k.channel
            )
        })?;
        if !k.threshold_v.is_finite() {
            bail!("{file}: keyphasor.threshold_v: not finite");
        }
        let hysteresis_v = k.hysteresis_v.unwrap_or(DEFAULT_HYSTERESIS_V);
        if !(hysteresis_v.is_finite() && hysteresis_v >= 0.0) {
            bail!("{file}: keyphasor.hysteresis_v: {hysteresis_v} must be finite and >= 0");
        }
        if raw.channels.is_empty() {
            bail!("{file}: no [[channel]] tables: each bearing needs two `rel` and two `ped` channels");
        }
        let mut channels: Vec<ChannelConfig> = Vec::new();
        for (i, c) in raw.channels.iter().enumerate() {
            let key = format!("channel[{i}]");
            let index = usize::try_from(c.index).map_err(|_| {
                anyhow::anyhow!(
                    "{file}: {key}.index: {} is not a 0-based channel index",
                    c.index
                )
            })?;
            if index == kp_channel {
                bail!("{file}: {key}.index: channel {index} is the keyphasor channel");
            }
            if let Some(j) = channels.iter().position(|o| o.index == index) {
                bail!("{file}: {key}.index: channel {index} is already channel[{j}]");
            }
            let kind = SensorKind::parse(&c.sensor).ok_or_else(|| {
                anyhow::anyhow!(
                    "{file}: {key}.sensor: unknown sensor `{}` (expected \"proximity\", \"velocity\" or \"acceleration\")",
                    c.sensor
                )
            })?;
            let (unit_kind, factor) = sensitivity_unit(&c.sensitivity_unit).ok_or_else(|| {
                anyhow::anyhow!(
                    "{file}: {key}.sensitivity_unit: unknown unit `{}` (expected \"V/mm\", \"mV/mil\", \"mV/(mm/s)\", \"mV/(in/s)\", \"mV/g\" or \"V/(m/s2)\")",
                    c.sensitivity_unit
                )
            })?;
            if unit_kind != kind {
                bail!(
                    "{file}: {key}.sensitivity_unit: `{}` is for a {} sensor, but sensor = \"{}\"",
                    c.sensitivity_unit,
                    kind_name(unit_kind),
                    c.sensor
                );
            }
            if c.quantity == Quantity::Rel && kind != SensorKind::Displacement {
                bail!("{file}: {key}.sensor: a `rel` channel is a proximity probe (relative displacement), not `{}`", c.sensor);
            }
            let sensitivity_si = positive(&format!("{key}.sensitivity"), c.sensitivity)? * factor;
            let angle_deg = angle_of(file, &key, c.angle_deg, c.angle.as_deref(), raw.rotation)?;
            channels.push(ChannelConfig {
                index,
                placement: Placement {
                    bearing: c.bearing.clone(),
                    quantity: c.quantity,
                    angle_deg,
                    key,
                },
                kind,
                sensitivity_si,
            });
        }
        let placements: Vec<Placement> = channels.iter().map(|c| c.placement.clone()).collect();
        let bearings = group_by_bearing(file, &placements)?;
        Ok(Channels {
            rotation: raw.rotation,
            full_scale_v,
            revolutions,
            speed_resolution_hz,
            min_speed_hz,
            max_acceleration_hz_per_s,
            period_tolerance,
            keyphasor: KeyphasorConfig {
                channel: kp_channel,
                threshold_v: k.threshold_v,
                edge: k.edge,
                hysteresis_v,
            },
            channels,
            bearings,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CHANNELS: &str = r#"
full_scale_v = 10.0
[keyphasor]
channel = 4
threshold_v = -5.0
edge = "falling"
[[channel]]
index = 0
bearing = "B1"
quantity = "rel"
angle_deg = 45.0
sensor = "proximity"
sensitivity = 7.87
sensitivity_unit = "V/mm"
[[channel]]
index = 1
bearing = "B1"
quantity = "rel"
angle_deg = 135.0
sensor = "proximity"
sensitivity = 7.87
sensitivity_unit = "V/mm"
[[channel]]
index = 2
bearing = "B1"
quantity = "ped"
angle_deg = 0.0
sensor = "velocity"
sensitivity = 100
sensitivity_unit = "mV/(mm/s)"
[[channel]]
index = 3
bearing = "B1"
quantity = "ped"
angle_deg = 90.0
sensor = "velocity"
sensitivity = 100
sensitivity_unit = "mV/(mm/s)"
"#;

    #[test]
    fn a_dwell_wider_than_a_hertz_and_hostile_names_are_refused() {
        assert!(Channels::parse(CHANNELS, "c.toml").is_ok());
        let wide = format!("speed_resolution_hz = 1000.0\n{CHANNELS}");
        let e = Channels::parse(&wide, "c.toml").unwrap_err().to_string();
        assert!(
            e.contains("speed_resolution_hz") && e.contains("whole run-down"),
            "{e}"
        );
        let hostile = CHANNELS.replacen("bearing = \"B1\"", "bearing = \"../B1\"", 1);
        let e = Channels::parse(&hostile, "c.toml").unwrap_err().to_string();
        assert!(
            e.contains("channel[0].bearing") && e.contains("path separator"),
            "{e}"
        );
    }
}
