//! `base.csv`: the measured (or simulated) 1X motion of the bases pedestals
//! stand on, an extension of the run directory (README, "Bases").
//!
//! One row per speed and base:
//! `speed_hz,base,bearings,y_re,y_im,z_re,z_im` — speed [Hz], base name, the
//! bearings whose pedestals stand on it separated by `;`, and the base's
//! absolute displacement phasors [m] (q(t) = Re{Q e^{iΩt}}, y vertical,
//! z horizontal, as in `measurements.csv`). Optional noise columns after
//! them, `y_sd,z_sd`: the complex noise sd sqrt(E|n|²) [m] of each phasor, as
//! formats.md's `*_sd` columns of `measurements.csv`.

use crate::sim::Response;
use num_complex::Complex;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// File name of the base motion in a run directory.
pub const BASE_FILE: &str = "base.csv";

/// Header of `base.csv`.
pub const BASE_COLUMNS: [&str; 7] = [
    "speed_hz", "base", "bearings", "y_re", "y_im", "z_re", "z_im",
];

/// The optional noise columns of `base.csv`.
pub const BASE_NOISE_COLUMNS: [&str; 2] = ["y_sd", "z_sd"];

/// One row of `base.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct BaseRow {
    /// Speed [Hz].
    pub speed_hz: f64,
    /// Base name.
    pub base: String,
    /// Bearings whose pedestals stand on the base.
    pub bearings: Vec<String>,
    /// Base displacement phasors (y, z) [m].
    pub motion: [Complex<f64>; 2],
    /// Noise sd sqrt(E|n|²) of the y and z phasors [m] (`y_sd,z_sd`), when given.
    pub noise_sd: Option<[f64; 2]>,
    /// The line of `base.csv` the row was read from (1-based, the header is
    /// line 1), so a later check can say where; 0 for a row not read from a file.
    pub line: u64,
}

/// A problem reading `base.csv`, with file, line and column.
#[derive(Debug, thiserror::Error)]
pub enum BaseCsvError {
    /// The file could not be read or written.
    #[error("{file}: {source}")]
    Io {
        /// File.
        file: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// A malformed header or field.
    #[error("{file}:{line}:{column}: {message}")]
    Field {
        /// File.
        file: PathBuf,
        /// Line (1-based, the header is line 1).
        line: u64,
        /// Column (1-based field number).
        column: usize,
        /// What is wrong.
        message: String,
    },
}

/// The base rows of a simulated response (empty when the machine has no
/// base); `bases[j]` names base j and the bearings on it.
pub fn rows_of(response: &Response, bases: &[(String, Vec<String>)]) -> Vec<BaseRow> {
    let mut rows = Vec::new();
    for (s, motion) in response.bases.iter().enumerate() {
        for ((name, bearings), m) in bases.iter().zip(motion) {
            rows.push(BaseRow {
                speed_hz: response.speeds_hz[s],
                base: name.clone(),
                bearings: bearings.clone(),
                motion: *m,
                noise_sd: None,
                line: 0,
            });
        }
    }
    rows
}

/// Writes `rows` as `dir/base.csv` (full round-trip precision).
pub fn write(dir: &Path, rows: &[BaseRow]) -> Result<(), BaseCsvError> {
    let file = dir.join(BASE_FILE);
    let io = |e: csv::Error| BaseCsvError::Io {
        file: file.clone(),
        source: std::io::Error::other(e),
    };
    let mut w = csv::Writer::from_path(&file).map_err(io)?;
    let with_noise = !rows.is_empty() && rows.iter().all(|r| r.noise_sd.is_some());
    let mut header: Vec<&str> = BASE_COLUMNS.to_vec();
    if with_noise {
        header.extend(BASE_NOISE_COLUMNS);
    }
    w.write_record(&header).map_err(io)?;
    for r in rows {
        let [y, z] = r.motion;
        let mut record = vec![
            r.speed_hz.to_string(),
            r.base.clone(),
            r.bearings.join(";"),
            y.re.to_string(),
            y.im.to_string(),
            z.re.to_string(),
            z.im.to_string(),
        ];
        if let (true, Some(sd)) = (with_noise, r.noise_sd) {
            record.extend(sd.map(|v| v.to_string()));
        }
        w.write_record(&record).map_err(io)?;
    }
    w.flush().map_err(|source| BaseCsvError::Io {
        file: file.clone(),
        source,
    })
}

/// Reads `dir/base.csv`; `Ok(None)` when the run has no base channel.
pub fn read(dir: &Path) -> Result<Option<Vec<BaseRow>>, BaseCsvError> {
    let file = dir.join(BASE_FILE);
    if file.symlink_metadata().is_err() {
        return Ok(None);
    }
    let field = |line: u64, column: usize, message: String| BaseCsvError::Field {
        file: file.clone(),
        line,
        column,
        message,
    };
    // Not a regular file (a FIFO would block), a spreadsheet's separator or
    // encoding: named before the CSV reader runs.
    let handle = crate::csv_layout::open(&file, &BASE_COLUMNS.join(",")).map_err(|e| match e {
        crate::csv_layout::LayoutError::NotAFile(m) => BaseCsvError::Io {
            file: file.clone(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidInput, m),
        },
        crate::csv_layout::LayoutError::At(line, m) => field(line, 1, m),
    })?;
    let mut r = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .quoting(false)
        .trim(csv::Trim::All)
        .from_reader(handle);
    let header = r.headers().map_err(|e| field(1, 1, e.to_string()))?.clone();
    for (i, want) in BASE_COLUMNS.iter().enumerate() {
        if header.get(i) != Some(want) {
            return Err(field(
                1,
                i + 1,
                format!(
                    "expected column {want:?} (header must be {})",
                    BASE_COLUMNS.join(",")
                ),
            ));
        }
    }
    let with_noise = match header.len() {
        7 => false,
        9 if header.get(7) == Some("y_sd") && header.get(8) == Some("z_sd") => true,
        n => {
            return Err(field(
                1,
                n.min(8),
                format!(
                    "expected {} or {},{} (optional noise columns), got {n} columns",
                    BASE_COLUMNS.join(","),
                    BASE_COLUMNS.join(","),
                    BASE_NOISE_COLUMNS.join(",")
                ),
            ))
        }
    };
    let mut rows: Vec<BaseRow> = Vec::new();
    // Each base's first row [index into `rows`], each bearing's base, and
    // each (base, speed bits)'s line: the checks below look up, never scan
    // the rows read so far (a scan made a long base.csv quadratic).
    let mut first_of: HashMap<String, usize> = HashMap::new();
    let mut base_of: HashMap<String, String> = HashMap::new();
    let mut line_of: HashMap<(String, u64), u64> = HashMap::new();
    let mut rows_read = crate::sim::budget::ROWS
        .reading()
        .map_err(|m| field(1, 1, m))?;
    for rec in r.records() {
        let rec = rec.map_err(|e| {
            let line = e.position().map_or(0, |p| p.line());
            field(line, 1, e.to_string())
        })?;
        let line = rec.position().map_or(0, |p| p.line());
        rows_read.count(&file, 1).map_err(|m| field(line, 1, m))?;
        if rec.len() != header.len() {
            return Err(field(
                line,
                rec.len().min(header.len()) + 1,
                format!(
                    "the row has {} fields, the header {}: separate the bearings of a base with `;` (left;right), and write numbers without thousands separators",
                    rec.len(),
                    header.len()
                ),
            ));
        }
        let num = |c: usize| -> Result<f64, BaseCsvError> {
            let text = rec.get(c).unwrap_or("");
            text.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    field(
                        line,
                        c + 1,
                        format!("{}: {text:?} is not a finite number", BASE_COLUMNS[c]),
                    )
                })
        };
        let speed_hz = num(0)?;
        let base = rec.get(1).unwrap_or("").to_string();
        crate::names::check("base", &base).map_err(|m| field(line, 2, m))?;
        let bearings: Vec<String> = rec
            .get(2)
            .unwrap_or("")
            .split(';')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(String::from)
            .collect();
        if bearings.is_empty() {
            return Err(field(line, 3, "bearings: no bearing named".into()));
        }
        for b in &bearings {
            crate::names::check("bearing", b).map_err(|m| field(line, 3, m))?;
        }
        if let Some(first) = first_of.get(&base).and_then(|&i| rows.get(i)) {
            if first.bearings != bearings {
                return Err(field(
                    line,
                    3,
                    format!(
                        "base `{base}` lists the bearings {} here but {} on an earlier row: every row of a base lists the same bearings",
                        bearings.join(";"),
                        first.bearings.join(";")
                    ),
                ));
            }
        }
        if let Some(other) = bearings
            .iter()
            .filter_map(|b| base_of.get(b))
            .find(|other| **other != base)
        {
            return Err(field(
                line,
                3,
                format!(
                    "a bearing of base `{base}` is also on base `{other}`: a pedestal stands on one base"
                ),
            ));
        }
        let noise_sd = if with_noise {
            let sd = |c: usize| -> Result<f64, BaseCsvError> {
                let text = rec.get(c).unwrap_or("");
                text.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite() && *v >= 0.0)
                    .ok_or_else(|| {
                        field(
                            line,
                            c + 1,
                            format!(
                                "{}: {text:?} is not a finite noise sd >= 0 [m]",
                                BASE_NOISE_COLUMNS[c - 7]
                            ),
                        )
                    })
            };
            Some([sd(7)?, sd(8)?])
        } else {
            None
        };
        if let Some(first) = line_of.get(&(base.clone(), (speed_hz + 0.0).to_bits())) {
            return Err(field(
                line,
                1,
                format!(
                    "a second row for base `{base}` at {speed_hz} Hz (the first is line {first})"
                ),
            ));
        }
        line_of.insert((base.clone(), (speed_hz + 0.0).to_bits()), line);
        first_of.entry(base.clone()).or_insert(rows.len());
        for b in &bearings {
            base_of.entry(b.clone()).or_insert_with(|| base.clone());
        }
        rows.push(BaseRow {
            speed_hz,
            base,
            bearings,
            motion: [
                Complex::new(num(3)?, num(4)?),
                Complex::new(num(5)?, num(6)?),
            ],
            noise_sd,
            line,
        });
    }
    if rows.is_empty() {
        return Err(field(
            2,
            1,
            "no data rows after the header: give the base motion (one row per speed and base) or remove base.csv".into(),
        ));
    }
    Ok(Some(rows))
}

/// Checks that every bearing `rows` names is a measured bearing of the run
/// (`measured`): a base on bearings the run does not have would be ignored.
pub fn check_bearings(dir: &Path, rows: &[BaseRow], measured: &[&str]) -> Result<(), BaseCsvError> {
    for r in rows {
        if let Some(b) = r.bearings.iter().find(|b| !measured.contains(&b.as_str())) {
            return Err(BaseCsvError::Field {
                file: dir.join(BASE_FILE),
                line: r.line,
                column: 3,
                message: format!(
                    "base `{}`: bearing `{b}` is not in measurements.csv (it has: {})",
                    r.base,
                    measured.join(", ")
                ),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(noise_sd: Option<[f64; 2]>) -> BaseRow {
        BaseRow {
            speed_hz: 12.5,
            base: "skid".into(),
            bearings: vec!["left".into(), "right".into()],
            motion: [
                Complex::new(1.5e-6, -2.0e-7),
                Complex::new(-3.0e-7, 4.25e-6),
            ],
            noise_sd,
            line: 2,
        }
    }

    #[test]
    fn noise_columns_round_trip_and_are_optional() {
        for sd in [None, Some([1.0e-8, 2.5e-8])] {
            let dir = tempfile::tempdir().unwrap();
            let second = BaseRow {
                speed_hz: 13.0,
                line: 3,
                ..row(sd)
            };
            write(dir.path(), &[row(sd), second.clone()]).unwrap();
            let back = read(dir.path()).unwrap().unwrap();
            assert_eq!(back, vec![row(sd), second]);
        }
    }

    #[test]
    fn bad_noise_columns_are_named_with_line_and_column() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join(BASE_FILE);
        std::fs::write(
            &file,
            "speed_hz,base,bearings,y_re,y_im,z_re,z_im,y_sd,z_sd\n10,skid,left;right,1e-6,0,0,1e-6,1e-8,-1\n",
        )
        .unwrap();
        let e = read(dir.path()).unwrap_err().to_string();
        assert!(e.contains(":2:9:") && e.contains("z_sd"), "{e}");
        std::fs::write(
            &file,
            "speed_hz,base,bearings,y_re,y_im,z_re,z_im,y_sd\n10,skid,left,1e-6,0,0,1e-6,1e-8\n",
        )
        .unwrap();
        let e = read(dir.path()).unwrap_err().to_string();
        assert!(e.contains(":1:") && e.contains("y_sd,z_sd"), "{e}");
    }

    #[test]
    fn base_csv_that_would_be_ignored_is_refused_with_line_and_column() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join(BASE_FILE);
        let head = "speed_hz,base,bearings,y_re,y_im,z_re,z_im\n";
        let cases = [
            ("".to_string(), ":2:1:", "no data rows"),
            (
                "10,skid,left,right,1e-6,0,0,1e-6\n".into(),
                ":2:",
                "separate the bearings",
            ),
            (
                "10,skid,../x,1e-6,0,0,1e-6\n".into(),
                ":2:3:",
                "path separator",
            ),
            (
                "10,skid,left;right,1e-6,0,0,1e-6\n10,skid,left;right,2e-6,0,0,1e-6\n".into(),
                ":3:1:",
                "first is line 2",
            ),
            (
                "10,skid,left,1e-6,0,0,1e-6\n20,skid,left;right,1e-6,0,0,1e-6\n".into(),
                ":3:3:",
                "same bearings",
            ),
            (
                "10,a,left,1e-6,0,0,1e-6\n10,b,left,1e-6,0,0,1e-6\n".into(),
                ":3:3:",
                "one base",
            ),
        ];
        for (rows, at, what) in cases {
            std::fs::write(&file, format!("{head}{rows}")).unwrap();
            let e = read(dir.path()).unwrap_err().to_string();
            assert!(e.contains(at) && e.contains(what), "{rows}: {e}");
        }
        std::fs::write(
            &file,
            "speed_hz;base;bearings;y_re;y_im;z_re;z_im\n10;skid;left;1,5e-6;0;0;1e-6\n",
        )
        .unwrap();
        let e = read(dir.path()).unwrap_err().to_string();
        assert!(e.contains("`;`") && e.contains("decimal commas"), "{e}");
        std::fs::write(
            &file,
            format!("{head}10,skid,left,1e-6,0,0,1e-6\n11,skid,left,1e-6,0,0,1e-6\n12,pad,NDE,1e-6,0,0,1e-6\n"),
        )
        .unwrap();
        let rows = read(dir.path()).unwrap().unwrap();
        let e = check_bearings(dir.path(), &rows, &["DE", "NDE"])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`left` is not in measurements.csv") && e.contains("DE, NDE"),
            "{e}"
        );
        // The first row naming it, at its line and the bearings' column
        // (it was placed at line 0 before session 37).
        assert!(e.contains("base.csv:2:3:"), "{e}");
        let e = check_bearings(dir.path(), &rows, &["left"])
            .unwrap_err()
            .to_string();
        assert!(e.contains("base.csv:4:3:") && e.contains("`NDE`"), "{e}");
        assert!(check_bearings(dir.path(), &rows, &["left", "NDE"]).is_ok());
    }
}
