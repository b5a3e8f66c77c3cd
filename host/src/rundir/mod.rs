//! Run directories (formats.md): `measurements.csv`, `bearings.csv`, `truth.json`.
//!
//! A run directory is the contract between the simulator, the field box, outside
//! data sets and the identification. Readers reject anything that breaks the
//! contract with an error naming the file, line and column.
//!
//! Modules: [`read`] (the readers, every fault located; one table at a
//! time in `table`), [`write`] (the
//! writers, digits reduced on writing), [`digits`] (significant-digit
//! reduction and the shortest round-trip number text), [`schedule`]
//! (bearing coefficients over speed). Everything is re-exported here.

pub mod bounds;
pub mod digits;
pub mod matches;
pub mod read;
pub mod resolution;
pub mod schedule;
mod table;
pub mod truth_keys;
pub mod write;

pub use digits::*;
pub use read::*;
pub use resolution::{RESOLUTION_COLUMNS, RESOLUTION_FILE};
pub use schedule::*;

use crate::estimate::Pedestal;
use plinth_shared::bearing::BearingCoefficients;
use plinth_shared::phasor::{Complex, Phasor2};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// One row of `measurements.csv`: the 1X phasors at one bearing and speed.
/// Two rows are equal when their data are (`written`, a record of how the
/// file spelt them, is not compared: a run read back equals the run written).
#[derive(Clone, Debug)]
pub struct Measurement {
    /// Rotor speed [Hz].
    pub speed_hz: f64,
    /// Bearing name (`left`, `right`, `B1`, ...).
    pub bearing: String,
    /// Rotor displacement relative to the pedestal, (y, z) [m].
    pub rel: Phasor2<f64>,
    /// Absolute pedestal displacement, (y, z) [m].
    pub ped: Phasor2<f64>,
    /// Noise of each phasor when the file carries formats.md's noise columns
    /// (`rel_y_sd, rel_z_sd, ped_y_sd, ped_z_sd`), else `None`.
    pub noise_sd: Option<NoiseSd>,
    /// The digits the eight phasor numbers were written with, counted from
    /// the text as it was read (`None`: made in memory; the noise model
    /// then counts them from the values).
    pub written: Option<WrittenDigits>,
}

impl PartialEq for Measurement {
    fn eq(&self, other: &Self) -> bool {
        self.speed_hz == other.speed_hz
            && self.bearing == other.bearing
            && self.rel == other.rel
            && self.ped == other.ped
            && self.noise_sd == other.noise_sd
    }
}

/// Standard deviations of the complex noise of one row's four phasors [m]:
/// sqrt(E|n|²), split equally between real and imaginary parts (formats.md,
/// "Noise columns"). Order: rel y, rel z, ped y, ped z.
pub type NoiseSd = [f64; 4];

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

/// The pedestal a simulated run was made with (`truth.json`: its keys
/// `k_y, k_z, m, c_y, c_z` next to `bearing`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PedestalTruth {
    /// Bearing name.
    pub bearing: String,
    /// The pedestal's parameters (k [N/m], m [kg], c [N·s/m]).
    #[serde(flatten)]
    pub pedestal: Pedestal,
}

/// An effect present in simulated data beyond the paper's model, with the
/// values it was made with (an extension of formats.md's `effects` list).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EffectTruth {
    /// Effect name (formats.md table), e.g. `pedestal_cross_coupling`.
    pub name: String,
    /// Bearing it acts on (for `foundation_coupling`, the first bearing on
    /// the base; the base itself is under [`Truth::bases`]).
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
    /// Bases the pedestals stood on (extension: absent = rigid ground).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bases: Vec<BaseTruth>,
}

/// A base body a simulated run was made with (`truth.json`, `bases`): its
/// pedestals' springs and dampers act between pedestal and base.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BaseTruth {
    /// Base name.
    pub name: String,
    /// Bearings whose pedestals stand on it.
    pub bearings: Vec<String>,
    /// Vertical mass [kg].
    pub m_y: f64,
    /// Horizontal mass [kg].
    pub m_z: f64,
    /// Vertical stiffness to ground [N/m].
    pub k_y: f64,
    /// Horizontal stiffness to ground [N/m].
    pub k_z: f64,
    /// Vertical viscous damping to ground [N·s/m].
    pub c_y: f64,
    /// Horizontal viscous damping to ground [N·s/m].
    pub c_z: f64,
    /// Hysteretic loss factor of the springs to ground [-].
    pub eta: f64,
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

// ---------------------------------------------------------------------------
// Reading and writing
// ---------------------------------------------------------------------------

/// File name of the measured phasors in a run directory.
pub const MEASUREMENTS_FILE: &str = "measurements.csv";
/// File name of the known bearing coefficients in a run directory.
pub const BEARINGS_FILE: &str = "bearings.csv";
/// File name of the simulation truth in a run directory.
pub const TRUTH_FILE: &str = "truth.json";

/// Columns of `measurements.csv`, in the order Plinth writes them.
pub const MEASUREMENT_COLUMNS: [&str; 10] = [
    "speed_hz", "bearing", "rel_y_re", "rel_y_im", "rel_z_re", "rel_z_im", "ped_y_re", "ped_y_im",
    "ped_z_re", "ped_z_im",
];
/// formats.md's optional noise columns of `measurements.csv` (all four or
/// none), in the order of [`NoiseSd`].
pub const NOISE_COLUMNS: [&str; 4] = ["rel_y_sd", "rel_z_sd", "ped_y_sd", "ped_z_sd"];
/// Columns of `bearings.csv`, in the order Plinth writes them.
pub const BEARING_COLUMNS: [&str; 10] = [
    "speed_hz", "bearing", "kyy", "kyz", "kzy", "kzz", "cyy", "cyz", "czy", "czz",
];

/// Why a run directory could not be read or written. Every variant names the
/// file and, where there is one, the 1-based line and column (CSV field).
#[derive(Debug, thiserror::Error)]
pub enum RunDirError {
    /// The file could not be opened, read or written.
    #[error("{}: {source}", file.display())]
    Io {
        /// The file.
        file: PathBuf,
        /// The operating-system error.
        #[source]
        source: std::io::Error,
    },
    /// The CSV layer rejected the file (e.g. invalid UTF-8).
    #[error("{}:{line}: {message}", file.display())]
    Csv {
        /// The file.
        file: PathBuf,
        /// Line of the offending record.
        line: u64,
        /// What the CSV reader said.
        message: String,
    },
    /// The file is empty or its first line is data, not the header.
    #[error("{}:1: missing header: the first line must name the columns `{expected}`", file.display())]
    MissingHeader {
        /// The file.
        file: PathBuf,
        /// The header Plinth expects.
        expected: String,
    },
    /// A required column is not in the header.
    #[error("{}:{line}: header has no column `{name}` (expected `{expected}`)", file.display())]
    MissingHeaderColumn {
        /// The file.
        file: PathBuf,
        /// Line of the header.
        line: u64,
        /// The missing column.
        name: String,
        /// The header Plinth expects.
        expected: String,
    },
    /// A column name appears twice in the header, or is empty.
    #[error("{}:{line}:{column}: bad header column `{name}`: {reason}", file.display())]
    BadHeaderColumn {
        /// The file.
        file: PathBuf,
        /// Line of the header.
        line: u64,
        /// 1-based column.
        column: usize,
        /// The column name as written.
        name: String,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A data row has fewer fields than the header.
    #[error("{}:{line}:{column}: missing column `{name}` (the row has {found} fields, the header {expected})", file.display())]
    MissingColumn {
        /// The file.
        file: PathBuf,
        /// Line of the row.
        line: u64,
        /// 1-based column of the first missing field.
        column: usize,
        /// Header name of that column.
        name: String,
        /// Fields in the row.
        found: usize,
        /// Fields in the header.
        expected: usize,
    },
    /// A data row has more fields than the header.
    #[error("{}:{line}:{column}: extra column (the row has {found} fields, the header {expected})", file.display())]
    ExtraColumn {
        /// The file.
        file: PathBuf,
        /// Line of the row.
        line: u64,
        /// 1-based column of the first extra field.
        column: usize,
        /// Fields in the row.
        found: usize,
        /// Fields in the header.
        expected: usize,
    },
    /// A field that must be a number is not one.
    #[error("{}:{line}:{column}: column `{name}`: `{text}` is not a number", file.display())]
    BadNumber {
        /// The file.
        file: PathBuf,
        /// Line of the row.
        line: u64,
        /// 1-based column.
        column: usize,
        /// Header name of the column.
        name: &'static str,
        /// The field as written.
        text: String,
    },
    /// A number is infinite or NaN.
    #[error("{}:{line}:{column}: column `{name}`: `{text}` is not finite", file.display())]
    NonFinite {
        /// The file.
        file: PathBuf,
        /// Line of the row.
        line: u64,
        /// 1-based column.
        column: usize,
        /// Header name of the column.
        name: &'static str,
        /// The field as written.
        text: String,
    },
    /// A speed is negative (or zero in `measurements.csv`, where Ω = 0 has no 1X phasor).
    #[error("{}:{line}:{column}: column `speed_hz`: {speed_hz} Hz must be {requirement}", file.display())]
    BadSpeed {
        /// The file.
        file: PathBuf,
        /// Line of the row.
        line: u64,
        /// 1-based column.
        column: usize,
        /// The speed [Hz].
        speed_hz: f64,
        /// What it must be.
        requirement: &'static str,
    },
    /// The bearing name is empty.
    #[error("{}:{line}:{column}: empty bearing name", file.display())]
    EmptyBearing {
        /// The file.
        file: PathBuf,
        /// Line of the row.
        line: u64,
        /// 1-based column.
        column: usize,
    },
    /// The bearing name is not a name (crate::names: no separators, quotes, commas, control characters).
    #[error("{}:{line}:{column}: {reason}", file.display())]
    BadBearingName {
        /// What is wrong with the name and what a name may hold.
        reason: String,
        /// The file.
        file: PathBuf,
        /// Line of the row (0 when writing from memory).
        line: u64,
        /// 1-based column.
        column: usize,
        /// The name.
        name: String,
    },
    /// The same (speed, bearing) appears twice.
    #[error("{}:{line}: duplicate row for speed {speed_hz} Hz, bearing `{bearing}` (first at line {first_line})", file.display())]
    Duplicate {
        /// The file.
        file: PathBuf,
        /// Line of the second occurrence.
        line: u64,
        /// Line of the first occurrence.
        first_line: u64,
        /// The speed [Hz].
        speed_hz: f64,
        /// The bearing.
        bearing: String,
    },
    /// A measured bearing has no rows in `bearings.csv`.
    #[error("{}:{line}:{column}: bearing `{bearing}` has no rows in {}", file.display(), bearings_file.display())]
    UnknownBearing {
        /// `measurements.csv`.
        file: PathBuf,
        /// Line of the first measurement of that bearing.
        line: u64,
        /// 1-based column of the bearing name.
        column: usize,
        /// The bearing.
        bearing: String,
        /// `bearings.csv`.
        bearings_file: PathBuf,
    },
    /// A measurement speed lies outside the speeds `bearings.csv` lists for its bearing.
    #[error("{}:{line}:{column}: speed {} Hz is outside the range {}..={} Hz that {} lists for bearing `{bearing}` (coefficients are not extrapolated)", file.display(), digits::format_number(*speed_hz), digits::format_number(*min_hz), digits::format_number(*max_hz), bearings_file.display())]
    SpeedOutOfRange {
        /// `measurements.csv`.
        file: PathBuf,
        /// Line of the measurement.
        line: u64,
        /// 1-based column of the speed.
        column: usize,
        /// The measurement speed [Hz].
        speed_hz: f64,
        /// The bearing.
        bearing: String,
        /// Lowest listed speed [Hz].
        min_hz: f64,
        /// Highest listed speed [Hz].
        max_hz: f64,
        /// `bearings.csv`.
        bearings_file: PathBuf,
    },
    /// `truth.json` is not valid JSON or does not have the formats.md layout.
    #[error("{}:{line}:{column}: {message}", file.display())]
    Truth {
        /// The file.
        file: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What serde_json said.
        message: String,
    },
    /// Some but not all of the optional noise columns are in the header.
    #[error("{}:{line}: the noise columns come all four or none: header has `{present}` but not `{missing}`", file.display())]
    PartialNoiseColumns {
        /// The file.
        file: PathBuf,
        /// Line of the header.
        line: u64,
        /// The noise columns found.
        present: String,
        /// The noise columns missing.
        missing: String,
    },
    /// A noise standard deviation is negative.
    #[error("{}:{line}:{column}: column `{name}`: {value} m is negative (a standard deviation is zero or positive)", file.display())]
    NegativeNoise {
        /// The file.
        file: PathBuf,
        /// Line of the row.
        line: u64,
        /// 1-based column.
        column: usize,
        /// Header name of the column.
        name: &'static str,
        /// The value [m].
        value: f64,
    },
    /// A value in memory cannot be written (non-finite number).
    #[error("{}: cannot write {what}: {value} is not finite", file.display())]
    NotWritable {
        /// The file being written.
        file: PathBuf,
        /// Which record and field.
        what: String,
        /// The value.
        value: f64,
    },
}

impl RunDir {
    /// Bearing names in the order they first appear in `measurements`.
    pub fn measured_bearings(&self) -> Vec<&str> {
        let mut names: Vec<&str> = Vec::new();
        for m in &self.measurements {
            if !names.contains(&m.bearing.as_str()) {
                names.push(&m.bearing);
            }
        }
        names
    }

    /// The coefficient schedule of every bearing listed in `bearings`.
    pub fn bearing_schedules(&self) -> BTreeMap<String, BearingSchedule> {
        self.bearing_schedules_with(|f| f)
    }

    /// [`RunDir::bearing_schedules`] of this run with every speed `f` [Hz]
    /// of `bearings` read as `speed(f)` (a table whose speeds were written
    /// in another unit), made exactly as that run's would be.
    pub fn bearing_schedules_with(
        &self,
        speed: impl Fn(f64) -> f64,
    ) -> BTreeMap<String, BearingSchedule> {
        // Each row's bearing (an index into `names`, in order of first
        // appearance; a row usually has the previous row's bearing, tried
        // first), then each bearing's rows in the table's order, with room
        // for all of them at once.
        let mut names: Vec<&str> = Vec::new();
        let mut counts: Vec<usize> = Vec::new();
        let mut of_row: Vec<usize> = Vec::with_capacity(self.bearings.len());
        let mut last = 0;
        for b in &self.bearings {
            if names.get(last) != Some(&b.bearing.as_str()) {
                last = match names.iter().position(|n| *n == b.bearing) {
                    Some(k) => k,
                    None => {
                        names.push(&b.bearing);
                        counts.push(0);
                        names.len() - 1
                    }
                };
            }
            counts[last] += 1;
            of_row.push(last);
        }
        let mut rows: Vec<Vec<(f64, BearingCoefficients<f64>)>> =
            counts.into_iter().map(Vec::with_capacity).collect();
        for (b, &k) in self.bearings.iter().zip(&of_row) {
            rows[k].push((speed(b.speed_hz), b.coefficients));
        }
        names
            .into_iter()
            .zip(rows)
            .map(|(name, r)| (name.to_string(), BearingSchedule::new(r)))
            .collect()
    }
}
