//! The streaming configuration file (`plinth stream --config CONFIG`): which
//! ADC channel carries which sensor at which bearing, how phasors are
//! averaged, how the box's recursive fit is tuned, and the known bearing
//! coefficients.
//!
//! A documented example (every key shown; defaults in comments):
//!
//! ```toml
//! # Known bearing coefficients: a bearings.csv (formats.md), relative to this file.
//! bearings = "bearings.csv"
//!
//! [averaging]
//! revolutions = 4          # keyphasor revolutions averaged into one phasor (default 4)
//!
//! [rls]
//! forgetting_factor = 1.0  # λ in (0, 1]; 1 = no forgetting (default 1.0)
//! k_scale = 1.0e7          # column scales [N/m], [kg], [N·s/m] (defaults 1e7, 1e2, 1e3)
//! m_scale = 1.0e2
//! c_scale = 1.0e3
//!
//! # One table per ADC channel: four per bearing (rel_y, rel_z, ped_y, ped_z).
//! [[channels]]
//! adc = 0                  # ADC channel index on the box (0..=15)
//! bearing = "left"         # bearing name, as in bearings.csv
//! quantity = "rel_y"       # rel_y | rel_z | ped_y | ped_z (formats.md)
//! sensor = "proximity"     # proximity | velocity | acceleration
//! sensitivity = 7870.0     # V/m (proximity), V/(m/s) (velocity), V/(m/s²) (acceleration)
//! ```
//!
//! `rel_*` channels must be proximity probes (only they see the rotor relative
//! to the pedestal); `ped_*` channels may be any of the three kinds (the box
//! integrates velocity and acceleration to displacement in the phasor domain).
//!
//! This module reads and validates the file; `bearing_tables` reads the
//! bearings.csv it names, and `device` turns both into the box's
//! configuration commands.

use anyhow::{bail, Context, Result};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

mod bearing_tables;
mod device;

pub use bearing_tables::{read_bearings_csv, BearingTables};

/// Highest ADC channel index the box has (16 channels).
pub const MAX_ADC_CHANNEL: u8 = 15;

/// What a channel measures at its bearing (formats.md `rel`/`ped`, y/z).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// Rotor relative to the pedestal, vertical.
    RelY,
    /// Rotor relative to the pedestal, horizontal.
    RelZ,
    /// Absolute pedestal motion, vertical.
    PedY,
    /// Absolute pedestal motion, horizontal.
    PedZ,
}

impl Quantity {
    /// All four, in the order of a `measurements.csv` row.
    pub const ALL: [Quantity; 4] = [
        Quantity::RelY,
        Quantity::RelZ,
        Quantity::PedY,
        Quantity::PedZ,
    ];

    /// The name used in the file.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::RelY => "rel_y",
            Quantity::RelZ => "rel_z",
            Quantity::PedY => "ped_y",
            Quantity::PedZ => "ped_z",
        }
    }

    /// Index in [`Quantity::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }
}

impl fmt::Display for Quantity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The kind of transducer on a channel, which fixes its sensitivity's unit
/// (`proximity` or `displacement`, `velocity`, `acceleration`): the one
/// definition shared with the extractor and the wire protocol.
pub use plinth_shared::extractor::SensorKind;

/// One ADC channel's assignment.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Channel {
    /// ADC channel index on the box (0..=15).
    pub adc: u8,
    /// Bearing name (as in bearings.csv).
    pub bearing: String,
    /// What the channel measures.
    pub quantity: Quantity,
    /// Transducer kind.
    pub sensor: SensorKind,
    /// Transducer sensitivity: V/m, V/(m/s) or V/(m/s²) by `sensor`.
    pub sensitivity: f64,
}

/// Phasor averaging on the box.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Averaging {
    /// Keyphasor revolutions averaged into one phasor (≥ 1).
    #[serde(default = "default_revolutions")]
    pub revolutions: u16,
}

impl Default for Averaging {
    fn default() -> Self {
        Self {
            revolutions: default_revolutions(),
        }
    }
}

fn default_revolutions() -> u16 {
    4
}

/// Tuning of the box's recursive least-squares fit per pedestal.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RlsSettings {
    /// Forgetting factor λ in (0, 1]; 1 keeps every equation forever.
    #[serde(default = "one")]
    pub forgetting_factor: f64,
    /// Stiffness column scale [N/m].
    #[serde(default = "k_scale")]
    pub k_scale: f64,
    /// Mass column scale [kg].
    #[serde(default = "m_scale")]
    pub m_scale: f64,
    /// Damping column scale [N·s/m].
    #[serde(default = "c_scale")]
    pub c_scale: f64,
}

impl Default for RlsSettings {
    fn default() -> Self {
        Self {
            forgetting_factor: one(),
            k_scale: k_scale(),
            m_scale: m_scale(),
            c_scale: c_scale(),
        }
    }
}

fn one() -> f64 {
    1.0
}
fn k_scale() -> f64 {
    1.0e7
}
fn m_scale() -> f64 {
    1.0e2
}
fn c_scale() -> f64 {
    1.0e3
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConfig {
    bearings: PathBuf,
    #[serde(default)]
    averaging: Averaging,
    #[serde(default)]
    rls: RlsSettings,
    channels: Vec<Channel>,
}

/// A validated streaming configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct StreamConfig {
    /// The bearings.csv with the known bearing coefficients (resolved path).
    pub bearings_csv: PathBuf,
    /// Phasor averaging.
    pub averaging: Averaging,
    /// Recursive fit tuning.
    pub rls: RlsSettings,
    /// Channel assignments, sorted by ADC index.
    pub channels: Vec<Channel>,
    /// Bearing names in the order the box numbers them (first appearance in
    /// the file).
    pub bearings: Vec<String>,
}

impl StreamConfig {
    /// Reads and validates a configuration file; relative paths in it are
    /// relative to the file's directory.
    pub fn load(path: &Path) -> Result<Self> {
        let text = crate::input_file::read_to_string(path)
            .with_context(|| format!("cannot read the stream configuration {}", path.display()))?;
        let base = path.parent().unwrap_or(Path::new("."));
        Self::parse(&text, base)
            .with_context(|| format!("in the stream configuration {}", path.display()))
    }

    /// Parses and validates configuration text; `base` resolves relative paths.
    pub fn parse(text: &str, base: &Path) -> Result<Self> {
        let raw: RawConfig = toml::from_str(text)
            .map_err(|e| anyhow::anyhow!("{}", crate::input_file::toml_error(text, &e)))?;
        let bearings_csv = if raw.bearings.is_absolute() {
            raw.bearings.clone()
        } else {
            base.join(&raw.bearings)
        };
        if raw.averaging.revolutions == 0 {
            bail!("averaging.revolutions must be at least 1");
        }
        let lambda = raw.rls.forgetting_factor;
        if !(lambda > 0.0 && lambda <= 1.0) {
            bail!("rls.forgetting_factor must lie in (0, 1], got {lambda}");
        }
        for (name, v) in [
            ("rls.k_scale", raw.rls.k_scale),
            ("rls.m_scale", raw.rls.m_scale),
            ("rls.c_scale", raw.rls.c_scale),
        ] {
            if !(v.is_finite() && v > 0.0) {
                bail!("{name} must be a positive number, got {v}");
            }
        }
        if raw.channels.is_empty() {
            bail!("no [[channels]]: at least one bearing needs rel_y, rel_z, ped_y and ped_z");
        }
        let mut bearings: Vec<String> = Vec::new();
        let mut seen_adc: BTreeMap<u8, usize> = BTreeMap::new();
        let mut seen_quantity: BTreeMap<(String, Quantity), usize> = BTreeMap::new();
        for (i, ch) in raw.channels.iter().enumerate() {
            let here = format!("channels[{i}] (adc {})", ch.adc);
            if ch.adc > MAX_ADC_CHANNEL {
                bail!("{here}: the box has ADC channels 0..={MAX_ADC_CHANNEL}");
            }
            if let Some(j) = seen_adc.insert(ch.adc, i) {
                bail!(
                    "{here}: ADC channel {} is already assigned by channels[{j}]",
                    ch.adc
                );
            }
            if let Err(m) = crate::names::check("bearing", &ch.bearing) {
                bail!("{here}: {m}");
            }
            if !(ch.sensitivity.is_finite() && ch.sensitivity != 0.0) {
                bail!(
                    "{here}: sensitivity must be a non-zero number in {}, got {}",
                    ch.sensor.sensitivity_unit(),
                    ch.sensitivity
                );
            }
            if matches!(ch.quantity, Quantity::RelY | Quantity::RelZ)
                && ch.sensor != SensorKind::Displacement
            {
                bail!(
                    "{here}: {} is rotor motion relative to the pedestal and needs a proximity probe, not a {:?} sensor",
                    ch.quantity,
                    ch.sensor
                );
            }
            if let Some(j) = seen_quantity.insert((ch.bearing.clone(), ch.quantity), i) {
                bail!(
                    "{here}: {} of bearing {:?} is already measured by channels[{j}]",
                    ch.quantity,
                    ch.bearing
                );
            }
            if !bearings.contains(&ch.bearing) {
                bearings.push(ch.bearing.clone());
            }
        }
        for b in &bearings {
            let missing: Vec<&str> = Quantity::ALL
                .iter()
                .filter(|q| !seen_quantity.contains_key(&(b.clone(), **q)))
                .map(|q| q.name())
                .collect();
            if !missing.is_empty() {
                bail!(
                    "bearing {b:?} has no channel for {} (each bearing needs rel_y, rel_z, ped_y and ped_z)",
                    missing.join(", ")
                );
            }
        }
        let mut channels = raw.channels;
        channels.sort_by_key(|c| c.adc);
        Ok(Self {
            bearings_csv,
            averaging: raw.averaging,
            rls: raw.rls,
            channels,
            bearings,
        })
    }

    /// Index of a bearing as the box numbers it.
    pub fn bearing_index(&self, name: &str) -> Option<usize> {
        self.bearings.iter().position(|b| b == name)
    }

    /// The channel measuring `quantity` at bearing `bearing` (an index into
    /// [`StreamConfig::bearings`]).
    pub fn channel_for(&self, bearing: usize, quantity: Quantity) -> Option<&Channel> {
        let name = self.bearings.get(bearing)?;
        self.channels
            .iter()
            .find(|c| &c.bearing == name && c.quantity == quantity)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn four(bearing: &str, first_adc: u8) -> String {
        let mut s = String::new();
        for (i, q) in ["rel_y", "rel_z", "ped_y", "ped_z"].iter().enumerate() {
            let sensor = if q.starts_with("rel") {
                "proximity"
            } else {
                "velocity"
            };
            s.push_str(&format!(
                "[[channels]]\nadc = {}\nbearing = \"{bearing}\"\nquantity = \"{q}\"\nsensor = \"{sensor}\"\nsensitivity = 7870.0\n",
                first_adc + i as u8
            ));
        }
        s
    }

    #[test]
    fn a_two_bearing_configuration_parses_with_defaults() {
        let text = format!(
            "bearings = \"b.csv\"\n{}{}",
            four("left", 4),
            four("right", 0)
        );
        let c = StreamConfig::parse(&text, Path::new("/runs")).unwrap();
        assert_eq!(c.bearings_csv, PathBuf::from("/runs/b.csv"));
        assert_eq!(c.bearings, vec!["left", "right"]);
        assert_eq!(c.averaging.revolutions, 4);
        assert_eq!(c.rls.forgetting_factor, 1.0);
        assert_eq!(c.channels[0].adc, 0);
        assert_eq!(c.channel_for(0, Quantity::PedZ).unwrap().adc, 7);
        assert_eq!(c.bearing_index("right"), Some(1));
    }

    #[test]
    fn bad_configurations_are_named() {
        let cases = [
            (
                format!("bearings = \"b.csv\"\n{}", four("left", 14)),
                "0..=15",
            ),
            (
                format!(
                    "bearings = \"b.csv\"\n{}{}",
                    four("left", 0),
                    four("right", 3)
                ),
                "already assigned",
            ),
            (
                format!(
                    "bearings = \"b.csv\"\n{}",
                    four("left", 0).replace("\"ped_z\"", "\"ped_y\"")
                ),
                "already measured",
            ),
            (
                format!(
                    "bearings = \"b.csv\"\n{}",
                    four("left", 0).replacen("\"proximity\"", "\"acceleration\"", 1)
                ),
                "needs a proximity probe",
            ),
            (
                format!(
                    "bearings = \"b.csv\"\n[rls]\nforgetting_factor = 1.5\n{}",
                    four("l", 0)
                ),
                "forgetting_factor",
            ),
            (
                format!(
                    "bearings = \"b.csv\"\n{}",
                    four("l", 0).replacen("7870.0", "0.0", 1)
                ),
                "sensitivity must be",
            ),
            (
                format!(
                    "bearings = \"b.csv\"\n{}",
                    four("l", 0).replace("sensor", "sensr")
                ),
                "sensr",
            ),
            (
                "bearings = \"b.csv\"\nchannels = []\n".to_string(),
                "no [[channels]]",
            ),
            (
                format!("bearings = \"b.csv\"\n{}", four("../DE", 0)),
                "bearing `../DE`: the character '/' is not allowed",
            ),
        ];
        for (text, needle) in cases {
            let err = format!(
                "{:#}",
                StreamConfig::parse(&text, Path::new(".")).unwrap_err()
            );
            assert!(err.contains(needle), "{needle:?} not in {err:?}");
        }
        let text = "bearings = \"b.csv\"\n[[channels]]\nadc = 0\nbearing = \"l\"\nquantity = \"rel_y\"\nsensor = \"proximity\"\nsensitivity = 1.0\n";
        let err = format!(
            "{:#}",
            StreamConfig::parse(text, Path::new(".")).unwrap_err()
        );
        assert!(err.contains("rel_z, ped_y, ped_z"), "{err}");
    }

    #[test]
    fn toml_syntax_errors_give_line_and_column() {
        let err = format!(
            "{:#}",
            StreamConfig::parse("bearings = \"b.csv\"\n[averaging\n", Path::new(".")).unwrap_err()
        );
        assert!(err.contains("line 2"), "{err}");
    }
}
