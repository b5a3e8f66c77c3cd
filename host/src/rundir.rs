//! Run directories (formats.md): `measurements.csv`, `bearings.csv`, `truth.json`.
//!
//! A run directory is the contract between the simulator, the field box, outside
//! data sets and the identification. Readers reject anything that breaks the
//! contract with an error naming the file, line and column.

use plinth_shared::bearing::BearingCoefficients;
use plinth_shared::phasor::{Complex, Phasor2};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

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
    /// Noise of each phasor when the file carries formats.md's noise columns
    /// (`rel_y_sd, rel_z_sd, ped_y_sd, ped_z_sd`), else `None`.
    pub noise_sd: Option<NoiseSd>,
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
    /// The bearing name contains a quote, comma or line break (formats.md forbids them).
    #[error("{}:{line}:{column}: bearing name `{name}` contains a quote, comma or line break", file.display())]
    BadBearingName {
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
    #[error("{}:{line}:{column}: speed {speed_hz} Hz is outside the range {min_hz}..={max_hz} Hz that {} lists for bearing `{bearing}` (coefficients are not extrapolated)", file.display(), bearings_file.display())]
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

/// How numbers are reduced to a number of significant digits on writing,
/// imitating instrument accuracy (the paper truncated its data).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DigitsMode {
    /// Round half away from zero.
    Round,
    /// Drop the digits beyond the last kept one (towards zero), as the paper did.
    Truncate,
}

/// Options for [`RunDir::write_with`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WriteOptions {
    /// Significant digits of the measured phasors (`rel_*`, `ped_*`); `None`
    /// writes every value with full round-trip precision. Speeds, bearing
    /// coefficients and the truth are always written in full.
    pub digits: Option<u32>,
    /// How the digits are reduced.
    pub digits_mode: DigitsMode,
}

impl Default for WriteOptions {
    fn default() -> Self {
        Self {
            digits: None,
            digits_mode: DigitsMode::Round,
        }
    }
}

/// The shortest decimal text that reads back as exactly `x` (finite `x`),
/// in plain notation for moderate magnitudes and exponent notation otherwise.
pub fn format_number(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || (1e-4..1e9).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// `x` reduced to `digits` significant decimal digits (at least one), working
/// on the shortest decimal text of `x` so that e.g. 0.29 truncates to 0.29,
/// not 0.28. Non-finite values are returned unchanged.
pub fn round_to_digits(x: f64, digits: u32, mode: DigitsMode) -> f64 {
    if !x.is_finite() || x == 0.0 {
        return x;
    }
    let digits = digits.max(1) as usize;
    // `{:e}` is the shortest round-trip text: "-1.2345e-7".
    let text = format!("{:e}", x.abs());
    let (mantissa, exponent) = text.split_once('e').unwrap_or((text.as_str(), "0"));
    let exponent: i32 = exponent.parse().unwrap_or(0);
    let mut ds: Vec<u8> = mantissa
        .bytes()
        .filter(u8::is_ascii_digit)
        .map(|b| b - b'0')
        .collect();
    if ds.len() <= digits {
        return x;
    }
    let round_up = mode == DigitsMode::Round && ds[digits] >= 5;
    ds.truncate(digits);
    let mut exponent = exponent;
    if round_up {
        let mut i = digits;
        loop {
            if i == 0 {
                // 9.99 → 10.0: a carry out of the leading digit.
                ds.insert(0, 1);
                ds.truncate(digits);
                exponent += 1;
                break;
            }
            i -= 1;
            if ds[i] == 9 {
                ds[i] = 0;
            } else {
                ds[i] += 1;
                break;
            }
        }
    }
    let mut s = String::with_capacity(digits + 8);
    if x < 0.0 {
        s.push('-');
    }
    for (i, d) in ds.iter().enumerate() {
        if i == 1 {
            s.push('.');
        }
        s.push(char::from(b'0' + d));
    }
    s.push('e');
    s.push_str(&exponent.to_string());
    s.parse().unwrap_or(x)
}

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

/// Reads and checks a `bearings.csv` on its own (formats.md layout), e.g. the
/// bearing table given to `plinth import` or `plinth extract`.
pub fn read_bearings(path: impl AsRef<Path>) -> Result<Vec<BearingRow>, RunDirError> {
    let rows = read_table(path.as_ref(), &BEARING_COLUMNS, None, false)?;
    Ok(rows
        .iter()
        .map(|r| BearingRow {
            speed_hz: r.speed_hz,
            bearing: r.bearing.clone(),
            coefficients: BearingCoefficients {
                k: [[r.values[0], r.values[1]], [r.values[2], r.values[3]]],
                c: [[r.values[4], r.values[5]], [r.values[6], r.values[7]]],
            },
        })
        .collect())
}

impl RunDir {
    /// Reads and checks a run directory: `measurements.csv` and
    /// `bearings.csv` are required, `truth.json` is optional. Every
    /// measurement's bearing must have rows in `bearings.csv` that cover its
    /// speed. Columns are found by header name; header columns Plinth does
    /// not know are ignored (formats.md allows new optional columns).
    pub fn read(dir: impl AsRef<Path>) -> Result<RunDir, RunDirError> {
        let dir = dir.as_ref();
        let m_path = dir.join(MEASUREMENTS_FILE);
        let b_path = dir.join(BEARINGS_FILE);
        let t_path = dir.join(TRUTH_FILE);

        let m_rows = read_table(&m_path, &MEASUREMENT_COLUMNS, Some(&NOISE_COLUMNS), true)?;
        let b_rows = read_table(&b_path, &BEARING_COLUMNS, None, false)?;

        let bearings: Vec<BearingRow> = b_rows
            .iter()
            .map(|r| BearingRow {
                speed_hz: r.speed_hz,
                bearing: r.bearing.clone(),
                coefficients: BearingCoefficients {
                    k: [[r.values[0], r.values[1]], [r.values[2], r.values[3]]],
                    c: [[r.values[4], r.values[5]], [r.values[6], r.values[7]]],
                },
            })
            .collect();
        let run = RunDir {
            measurements: m_rows
                .iter()
                .map(|r| {
                    let v = &r.values;
                    Measurement {
                        speed_hz: r.speed_hz,
                        bearing: r.bearing.clone(),
                        rel: [Complex::new(v[0], v[1]), Complex::new(v[2], v[3])],
                        ped: [Complex::new(v[4], v[5]), Complex::new(v[6], v[7])],
                        noise_sd: r.noise_sd,
                    }
                })
                .collect(),
            bearings,
            truth: None,
        };

        // Every measurement must be covered by its bearing's table.
        let schedules = run.bearing_schedules();
        for r in &m_rows {
            let Some(schedule) = schedules.get(&r.bearing) else {
                let first = m_rows
                    .iter()
                    .find(|x| x.bearing == r.bearing)
                    .map_or(r.line, |x| x.line);
                return Err(RunDirError::UnknownBearing {
                    file: m_path,
                    line: first,
                    column: r.bearing_column,
                    bearing: r.bearing.clone(),
                    bearings_file: b_path,
                });
            };
            if let Err(e) = schedule.at(r.speed_hz) {
                return Err(RunDirError::SpeedOutOfRange {
                    file: m_path,
                    line: r.line,
                    column: r.speed_column,
                    speed_hz: r.speed_hz,
                    bearing: r.bearing.clone(),
                    min_hz: e.min_hz,
                    max_hz: e.max_hz,
                    bearings_file: b_path,
                });
            }
        }

        let truth = match crate::input_file::read_to_string(&t_path) {
            Ok(text) => {
                Some(
                    serde_json::from_str::<Truth>(&text).map_err(|e| RunDirError::Truth {
                        file: t_path.clone(),
                        line: e.line(),
                        column: e.column(),
                        message: e.to_string(),
                    })?,
                )
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(source) => {
                return Err(RunDirError::Io {
                    file: t_path,
                    source,
                })
            }
        };
        Ok(RunDir { truth, ..run })
    }

    /// Writes the run directory (creating it if needed) with every number in
    /// full round-trip precision; `truth.json` only when `truth` is set.
    pub fn write(&self, dir: impl AsRef<Path>) -> Result<(), RunDirError> {
        self.write_with(dir, &WriteOptions::default())
    }

    /// Writes the run directory with the given options (e.g. the measured
    /// phasors reduced to 2 significant digits, as in the paper).
    pub fn write_with(
        &self,
        dir: impl AsRef<Path>,
        options: &WriteOptions,
    ) -> Result<(), RunDirError> {
        let dir = dir.as_ref();
        std::fs::create_dir_all(dir).map_err(|source| RunDirError::Io {
            file: dir.to_path_buf(),
            source,
        })?;
        let reduce = |x: f64| match options.digits {
            Some(d) => round_to_digits(x, d, options.digits_mode),
            None => x,
        };

        let m_path = dir.join(MEASUREMENTS_FILE);
        // The noise columns are written when every row has them.
        let with_noise =
            !self.measurements.is_empty() && self.measurements.iter().all(|m| m.noise_sd.is_some());
        let rows = self.measurements.iter().map(|m| {
            let [ry, rz] = m.rel;
            let [py, pz] = m.ped;
            let values = [ry.re, ry.im, rz.re, rz.im, py.re, py.im, pz.re, pz.im].map(reduce);
            let noise = if with_noise { m.noise_sd } else { None };
            (m.speed_hz, m.bearing.as_str(), values, noise)
        });
        let extra: &[&'static str] = if with_noise { &NOISE_COLUMNS } else { &[] };
        write_table(&m_path, &MEASUREMENT_COLUMNS, extra, rows)?;

        let b_path = dir.join(BEARINGS_FILE);
        let rows = self.bearings.iter().map(|b| {
            let (k, c) = (b.coefficients.k, b.coefficients.c);
            let values = [
                k[0][0], k[0][1], k[1][0], k[1][1], c[0][0], c[0][1], c[1][0], c[1][1],
            ];
            (b.speed_hz, b.bearing.as_str(), values, None)
        });
        write_table(&b_path, &BEARING_COLUMNS, &[], rows)?;

        let t_path = dir.join(TRUTH_FILE);
        if let Some(truth) = &self.truth {
            let text = serde_json::to_string_pretty(truth).map_err(|e| RunDirError::Io {
                file: t_path.clone(),
                source: e.into(),
            })?;
            std::fs::write(&t_path, text + "\n").map_err(|source| RunDirError::Io {
                file: t_path,
                source,
            })?;
        }
        Ok(())
    }

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
        let mut rows: BTreeMap<String, Vec<(f64, BearingCoefficients<f64>)>> = BTreeMap::new();
        for b in &self.bearings {
            rows.entry(b.bearing.clone())
                .or_default()
                .push((b.speed_hz, b.coefficients));
        }
        rows.into_iter()
            .map(|(name, r)| (name, BearingSchedule::new(r)))
            .collect()
    }
}

/// One parsed data row of either CSV file: speed, bearing and the eight numbers
/// after them in the order of the expected columns.
struct TableRow {
    line: u64,
    speed_hz: f64,
    speed_column: usize,
    bearing: String,
    bearing_column: usize,
    values: [f64; 8],
    /// The optional noise columns, when the header has them.
    noise_sd: Option<NoiseSd>,
}

/// Reads a CSV table whose columns are `speed_hz`, `bearing` and eight numbers,
/// plus, when `optional` is given and the header names them, four
/// non-negative numbers (all four or none).
fn read_table(
    path: &Path,
    columns: &[&'static str; 10],
    optional: Option<&[&'static str; 4]>,
    positive_speed: bool,
) -> Result<Vec<TableRow>, RunDirError> {
    let file = || path.to_path_buf();
    let expected = columns.join(",");
    // Spreadsheet exports and non-files are named before the CSV reader runs.
    let layout = crate::csv_layout::check(path, &expected).map_err(|e| match e {
        crate::csv_layout::LayoutError::NotAFile(m) => RunDirError::Io {
            file: file(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidInput, m),
        },
        crate::csv_layout::LayoutError::At(line, message) => RunDirError::Csv {
            file: file(),
            line,
            message,
        },
    })?;
    let mut handle = std::fs::File::open(path).map_err(|source| RunDirError::Io {
        file: file(),
        source,
    })?;
    std::io::Seek::seek(&mut handle, std::io::SeekFrom::Start(layout.skip)).map_err(|source| {
        RunDirError::Io {
            file: file(),
            source,
        }
    })?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .quoting(false)
        .trim(csv::Trim::All)
        .from_reader(std::io::BufReader::new(handle));
    let csv_error = |e: csv::Error| match e.kind() {
        csv::ErrorKind::Io(_) => match e.into_kind() {
            csv::ErrorKind::Io(source) => RunDirError::Io {
                file: file(),
                source,
            },
            _ => unreachable_csv(file()),
        },
        _ => RunDirError::Csv {
            file: file(),
            line: e.position().map_or(0, csv::Position::line),
            message: e.to_string(),
        },
    };
    let mut records = reader.records();

    // Header.
    let header = match records.next() {
        None => {
            return Err(RunDirError::MissingHeader {
                file: file(),
                expected,
            })
        }
        Some(r) => r.map_err(csv_error)?,
    };
    let header_line = header.position().map_or(1, csv::Position::line);
    if header
        .iter()
        .next()
        .is_some_and(|f| f.parse::<f64>().is_ok())
    {
        return Err(RunDirError::MissingHeader {
            file: file(),
            expected,
        });
    }
    for (i, name) in header.iter().enumerate() {
        let reason = if name.is_empty() {
            Some("empty column name")
        } else if header.iter().take(i).any(|n| n == name) {
            Some("appears twice")
        } else {
            None
        };
        if let Some(reason) = reason {
            return Err(RunDirError::BadHeaderColumn {
                file: file(),
                line: header_line,
                column: i + 1,
                name: name.to_string(),
                reason,
            });
        }
    }
    let mut index = [0usize; 10];
    for (slot, name) in index.iter_mut().zip(columns) {
        *slot = header.iter().position(|h| h == *name).ok_or_else(|| {
            RunDirError::MissingHeaderColumn {
                file: file(),
                line: header_line,
                name: name.to_string(),
                expected: expected.clone(),
            }
        })?;
    }
    let mut noise_index: Option<[usize; 4]> = None;
    if let Some(names) = optional {
        let found = names.map(|n| header.iter().position(|h| h == n));
        let present: Vec<&str> = names
            .iter()
            .zip(&found)
            .filter_map(|(n, f)| f.map(|_| *n))
            .collect();
        if present.len() == 4 {
            noise_index = Some(found.map(|f| f.unwrap_or_default()));
        } else if !present.is_empty() {
            let missing: Vec<&str> = names
                .iter()
                .zip(&found)
                .filter_map(|(n, f)| f.is_none().then_some(*n))
                .collect();
            return Err(RunDirError::PartialNoiseColumns {
                file: file(),
                line: header_line,
                present: present.join(","),
                missing: missing.join(","),
            });
        }
    }
    let width = header.len();

    let mut rows = Vec::new();
    let mut seen: HashMap<(u64, String), u64> = HashMap::new();
    for record in records {
        let record = record.map_err(csv_error)?;
        let line = record.position().map_or(0, csv::Position::line);
        if record.len() < width {
            let column = record.len() + 1;
            return Err(RunDirError::MissingColumn {
                file: file(),
                line,
                column,
                name: header.get(record.len()).unwrap_or_default().to_string(),
                found: record.len(),
                expected: width,
            });
        }
        if record.len() > width {
            return Err(RunDirError::ExtraColumn {
                file: file(),
                line,
                column: width + 1,
                found: record.len(),
                expected: width,
            });
        }
        let number_at = |col: usize, name: &'static str| -> Result<f64, RunDirError> {
            let text = record.get(col).unwrap_or_default();
            let value: f64 = text.parse().map_err(|_| RunDirError::BadNumber {
                file: file(),
                line,
                column: col + 1,
                name,
                text: text.to_string(),
            })?;
            if !value.is_finite() {
                return Err(RunDirError::NonFinite {
                    file: file(),
                    line,
                    column: col + 1,
                    name,
                    text: text.to_string(),
                });
            }
            Ok(value)
        };
        let number = |k: usize| number_at(index[k], columns[k]);
        let speed_hz = number(0)?;
        let speed_ok = if positive_speed {
            speed_hz > 0.0
        } else {
            speed_hz >= 0.0
        };
        if !speed_ok {
            return Err(RunDirError::BadSpeed {
                file: file(),
                line,
                column: index[0] + 1,
                speed_hz,
                requirement: if positive_speed {
                    "positive"
                } else {
                    "zero or positive"
                },
            });
        }
        let bearing = record.get(index[1]).unwrap_or_default();
        if bearing.is_empty() {
            return Err(RunDirError::EmptyBearing {
                file: file(),
                line,
                column: index[1] + 1,
            });
        }
        if !bearing_name_ok(bearing) {
            return Err(RunDirError::BadBearingName {
                file: file(),
                line,
                column: index[1] + 1,
                name: bearing.to_string(),
            });
        }
        let mut values = [0.0; 8];
        for (k, v) in values.iter_mut().enumerate() {
            *v = number(k + 2)?;
        }
        let noise_sd = match (noise_index, optional) {
            (Some(cols), Some(names)) => {
                let mut sd = [0.0; 4];
                for ((v, &col), &name) in sd.iter_mut().zip(&cols).zip(names) {
                    *v = number_at(col, name)?;
                    if *v < 0.0 {
                        return Err(RunDirError::NegativeNoise {
                            file: file(),
                            line,
                            column: col + 1,
                            name,
                            value: *v,
                        });
                    }
                }
                Some(sd)
            }
            _ => None,
        };
        // -0.0 and 0.0 are the same speed.
        let key = ((speed_hz + 0.0).to_bits(), bearing.to_string());
        if let Some(&first_line) = seen.get(&key) {
            return Err(RunDirError::Duplicate {
                file: file(),
                line,
                first_line,
                speed_hz,
                bearing: bearing.to_string(),
            });
        }
        seen.insert(key, line);
        rows.push(TableRow {
            line,
            speed_hz,
            speed_column: index[0] + 1,
            bearing: bearing.to_string(),
            bearing_column: index[1] + 1,
            values,
            noise_sd,
        });
    }
    Ok(rows)
}

/// The csv crate only hands out an I/O kind for I/O errors; this keeps the
/// match total without a panic.
fn unreachable_csv(file: PathBuf) -> RunDirError {
    RunDirError::Csv {
        file,
        line: 0,
        message: "unexpected CSV error".to_string(),
    }
}

/// A bearing name formats.md allows: no quotes, commas or line breaks.
fn bearing_name_ok(name: &str) -> bool {
    !name.is_empty() && !name.contains(['"', '\'', ',', '\n', '\r']) && name.trim() == name
}

/// One row to write: speed [Hz], bearing, the eight numbers and, when the table
/// has the `extra` columns, their four values.
type WriteRow<'a> = (f64, &'a str, [f64; 8], Option<[f64; 4]>);

/// Writes a CSV table of `speed_hz`, `bearing`, eight numbers and the `extra`
/// columns (empty, or four filled from every row's fourth element).
fn write_table<'a>(
    path: &Path,
    columns: &[&'static str; 10],
    extra: &[&'static str],
    rows: impl Iterator<Item = WriteRow<'a>>,
) -> Result<(), RunDirError> {
    let io = |source: std::io::Error| RunDirError::Io {
        file: path.to_path_buf(),
        source,
    };
    let csv_err = |e: csv::Error| match e.into_kind() {
        csv::ErrorKind::Io(source) => io(source),
        other => io(std::io::Error::other(format!("{other:?}"))),
    };
    let mut writer = csv::WriterBuilder::new()
        .quote_style(csv::QuoteStyle::Never)
        .from_path(path)
        .map_err(csv_err)?;
    writer
        .write_record(columns.iter().chain(extra))
        .map_err(csv_err)?;
    for (i, (speed_hz, bearing, values, noise)) in rows.enumerate() {
        if !bearing_name_ok(bearing) {
            return Err(RunDirError::BadBearingName {
                file: path.to_path_buf(),
                line: 0,
                column: 2,
                name: bearing.to_string(),
            });
        }
        let mut record: Vec<String> = Vec::with_capacity(10 + extra.len());
        let noise = if extra.is_empty() { None } else { noise };
        for (k, v) in std::iter::once(speed_hz)
            .chain(values)
            .chain(noise.into_iter().flatten())
            .enumerate()
        {
            if !v.is_finite() {
                let name = match k {
                    0 => columns[0],
                    1..=8 => columns[k + 1],
                    _ => extra[k - 9],
                };
                return Err(RunDirError::NotWritable {
                    file: path.to_path_buf(),
                    what: format!("row {} (bearing `{bearing}`), column `{name}`", i + 1),
                    value: v,
                });
            }
            record.push(format_number(v));
            if k == 0 {
                record.push(bearing.to_string());
            }
        }
        writer.write_record(&record).map_err(csv_err)?;
    }
    writer.flush().map_err(io)
}
