//! Run directories (formats.md): `measurements.csv`, `bearings.csv`, `truth.json`.
//!
//! A run directory is the contract between the simulator, the field box, outside
//! data sets and the identification. Readers reject anything that breaks the
//! contract with an error naming the file, line and column.

use plinth_shared::bearing::BearingCoefficients;
use plinth_shared::phasor::Phasor2;
use serde::{Deserialize, Serialize};

/// One row of `measurements.csv`: the 1X phasors at one bearing and speed.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// Rotor speed [Hz].
    pub speed_hz: f64,
    /// Bearing name (`left`, `right`, `B1`, ...).
    pub bearing: String,
    /// Rotor displacement relative to the pedestal, (y, z) [m].
    pub rel: Phasor2<f64>,
    /// Absolute pedestal displacement, (y, z) [m].
    pub ped: Phasor2<f64>,
}

/// One row of `bearings.csv`: the known bearing coefficients at one speed.
#[derive(Clone, Debug, PartialEq)]
pub struct BearingRow {
    /// Rotor speed [Hz].
    pub speed_hz: f64,
    /// Bearing name.
    pub bearing: String,
    /// Stiffness [N/m] and damping [N·s/m] coefficients.
    pub coefficients: BearingCoefficients<f64>,
}

/// The pedestal a simulated run was made with (`truth.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PedestalTruth {
    /// Bearing name.
    pub bearing: String,
    /// Vertical stiffness [N/m].
    pub k_y: f64,
    /// Horizontal stiffness [N/m].
    pub k_z: f64,
    /// Mass [kg].
    pub m: f64,
    /// Vertical viscous damping [N·s/m].
    pub c_y: f64,
    /// Horizontal viscous damping [N·s/m].
    pub c_z: f64,
}

/// An effect present in simulated data beyond the paper's model, with the
/// values it was made with (an extension of formats.md's `effects` list).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EffectTruth {
    /// Effect name (formats.md table), e.g. `pedestal_cross_coupling`.
    pub name: String,
    /// Bearing it acts on (for `foundation_coupling`, one of the coupled pair).
    pub bearing: String,
    /// The effect's own parameters by name, SI units (see `crate::effects`).
    pub parameters: std::collections::BTreeMap<String, f64>,
}

/// Contents of `truth.json` (simulated data only).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// The pedestals the data were made with.
    pub pedestals: Vec<PedestalTruth>,
    /// Names of effects present beyond the base model (formats.md).
    #[serde(default)]
    pub effects: Vec<String>,
    /// The same effects with their bearing and parameters.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub effect_details: Vec<EffectTruth>,
}

/// A whole run directory in memory.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunDir {
    /// Rows of `measurements.csv`, in file order.
    pub measurements: Vec<Measurement>,
    /// Rows of `bearings.csv`, in file order.
    pub bearings: Vec<BearingRow>,
    /// `truth.json`, when present.
    pub truth: Option<Truth>,
}
