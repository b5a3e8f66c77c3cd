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
    if !file.exists() {
        return Ok(None);
    }
    let field = |line: u64, column: usize, message: String| BaseCsvError::Field {
        file: file.clone(),
        line,
        column,
        message,
    };
    let mut r = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .from_path(&file)
        .map_err(|e| BaseCsvError::Io {
            file: file.clone(),
            source: std::io::Error::other(e),
        })?;
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
    let mut rows = Vec::new();
    for rec in r.records() {
        let rec = rec.map_err(|e| {
            let line = e.position().map_or(0, |p| p.line());
            field(line, 1, e.to_string())
        })?;
        let line = rec.position().map_or(0, |p| p.line());
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
        if base.is_empty() {
            return Err(field(line, 2, "base: empty name".into()));
        }
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
        rows.push(BaseRow {
            speed_hz,
            base,
            bearings,
            motion: [
                Complex::new(num(3)?, num(4)?),
                Complex::new(num(5)?, num(6)?),
            ],
            noise_sd,
        });
    }
    Ok(Some(rows))
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
        }
    }

    #[test]
    fn noise_columns_round_trip_and_are_optional() {
        for sd in [None, Some([1.0e-8, 2.5e-8])] {
            let dir = tempfile::tempdir().unwrap();
            write(dir.path(), &[row(sd), row(sd)]).unwrap();
            let back = read(dir.path()).unwrap().unwrap();
            assert_eq!(back, vec![row(sd), row(sd)]);
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
}
