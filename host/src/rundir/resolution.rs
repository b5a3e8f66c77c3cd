//! `resolution.csv` (optional, docs/formats.md "Extensions of the run
//! directory"): the rounding each measured phasor carries from the table it
//! was converted from, as a standard deviation [m] per complex channel.
//!
//! A vector table prints each reading's amplitude with a few digits and its
//! phase in whole degrees (or tenths); `plinth import` knows those steps, the
//! unit conversion and the angle transform to y and z, and propagates the
//! rounding through them (`crate::field::import`). Once converted to metres
//! and written in full precision, the numbers of `measurements.csv` no
//! longer show it in their digits. It is a floor under the noise, not the
//! noise (the sensors' own noise comes on top), so it is kept apart from
//! the noise columns, which are taken as the whole noise: the noise model
//! ([`crate::estimate::noise`]) takes it as each number's rounding, next to
//! its digits ([`super::WrittenDigits::with_resolution`]).

use super::{Measurement, NoiseSd, RunDirError};
use std::collections::HashMap;
use std::path::Path;

/// File name of the rounding floor in a run directory.
pub const RESOLUTION_FILE: &str = "resolution.csv";

/// Columns of [`RESOLUTION_FILE`], in the order Plinth writes them: the row
/// of `measurements.csv` (speed [Hz], bearing) and the sd [m] of the complex
/// rounding error, sqrt(E|n|²), of each of its four phasors.
pub const RESOLUTION_COLUMNS: [&str; 6] = [
    "speed_hz", "bearing", "rel_y_sd", "rel_z_sd", "ped_y_sd", "ped_z_sd",
];

/// Writes [`RESOLUTION_FILE`] into `dir` from the rows of `measurements`
/// that carry a rounding floor ([`Measurement::resolution_sd`]); when none
/// does, none (an earlier one in `dir` is removed). Returns whether it was
/// written.
pub fn write(dir: &Path, measurements: &[Measurement]) -> Result<bool, RunDirError> {
    let rows: Vec<(&Measurement, NoiseSd)> = measurements
        .iter()
        .filter_map(|m| m.resolution_sd().map(|sd| (m, sd)))
        .collect();
    let path = dir.join(RESOLUTION_FILE);
    if rows.is_empty() {
        // A file of an earlier run written here would describe other rows.
        return match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(RunDirError::Io {
                file: path,
                source: e,
            }),
            _ => Ok(false),
        };
    }
    let mut text = RESOLUTION_COLUMNS.join(",");
    text.push('\n');
    for (m, sd) in rows {
        let mut fields = vec![super::format_number(m.speed_hz), m.bearing.clone()];
        fields.extend(sd.iter().map(|&s| super::format_number(s)));
        text.push_str(&fields.join(","));
        text.push('\n');
    }
    std::fs::write(&path, text).map_err(|source| RunDirError::Io { file: path, source })?;
    Ok(true)
}

/// Reads [`RESOLUTION_FILE`] of `dir`, when there is one, onto the rows of
/// `measurements` (read from `measurements_file`) it names: every row of it
/// must name one row of `measurements.csv` by its speed (as written there)
/// and bearing, once; rows it does not name carry no floor. Each sd must be
/// a finite number ≥ 0. Errors name the file, line and column.
pub fn read_into(
    dir: &Path,
    measurements: &mut [Measurement],
    measurements_file: &Path,
) -> Result<(), RunDirError> {
    let path = dir.join(RESOLUTION_FILE);
    match path.symlink_metadata() {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        _ => {}
    }
    let at = |line: usize, message: String| RunDirError::Csv {
        file: path.clone(),
        line: line as u64,
        message,
    };
    // Read a line at a time (a table as long as measurements.csv is tens of
    // megabytes: not a whole-file text), through the table readers' checks
    // (a regular file, UTF-8 or UTF-16 named, lines and NUL bytes bounded).
    let expected = RESOLUTION_COLUMNS.join(",");
    let mut reader = crate::csv_layout::open(&path, &expected).map_err(|e| match e {
        crate::csv_layout::LayoutError::NotAFile(m) => RunDirError::Io {
            file: path.clone(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidInput, m),
        },
        crate::csv_layout::LayoutError::At(line, message) => RunDirError::Csv {
            file: path.clone(),
            line,
            message,
        },
    })?;
    let mut bytes = Vec::new();
    let mut next_line = |line: usize| -> Result<Option<String>, RunDirError> {
        bytes.clear();
        let n = std::io::BufRead::read_until(&mut reader, b'\n', &mut bytes).map_err(|source| {
            RunDirError::Io {
                file: path.clone(),
                source,
            }
        })?;
        if n == 0 {
            return Ok(None);
        }
        while bytes.last().is_some_and(|&b| b == b'\n' || b == b'\r') {
            bytes.pop();
        }
        // The one line through the whole-file readers' check: its place
        // within the line ("line 1, column C: byte 0xE9 ...") is placed at
        // this line.
        crate::input_file::utf8_text(std::mem::take(&mut bytes))
            .map(Some)
            .map_err(|e| {
                let message = e.to_string();
                let within = message.strip_prefix("line 1, ").unwrap_or(&message);
                at(line, within.to_string())
            })
    };
    let Some(header) = next_line(1)? else {
        return Err(at(
            1,
            format!(
                "empty file: expected the header `{}`",
                RESOLUTION_COLUMNS.join(",")
            ),
        ));
    };
    let names: Vec<&str> = header
        .split(',')
        .map(|n| n.trim().trim_start_matches('\u{feff}'))
        .collect();
    let mut index = [0usize; 6];
    for (slot, want) in index.iter_mut().zip(RESOLUTION_COLUMNS) {
        let found: Vec<usize> = (0..names.len()).filter(|&i| names[i] == want).collect();
        match found.as_slice() {
            [i] => *slot = *i,
            [] => {
                return Err(at(
                    1,
                    format!(
                        "header has no column `{want}` (expected `{}`)",
                        RESOLUTION_COLUMNS.join(",")
                    ),
                ))
            }
            _ => {
                return Err(at(
                    1,
                    format!("column `{want}` appears twice in the header"),
                ))
            }
        }
    }
    let mut rows: HashMap<(u64, &str), usize> = HashMap::with_capacity(measurements.len());
    for (i, m) in measurements.iter().enumerate() {
        rows.insert((m.speed_hz.to_bits(), m.bearing.as_str()), i);
    }
    let mut found: Vec<(usize, NoiseSd)> = Vec::new();
    let mut seen: HashMap<usize, usize> = HashMap::new();
    let mut rows_read = crate::sim::budget::ROWS.reading().map_err(|m| at(1, m))?;
    let mut line = 1;
    while let Some(record) = next_line(line + 1)? {
        line += 1;
        if record.trim().is_empty() {
            continue;
        }
        rows_read.count(&path, 1).map_err(|m| at(line, m))?;
        let fields: Vec<&str> = record.split(',').map(str::trim).collect();
        if fields.len() != names.len() {
            return Err(at(
                line,
                format!(
                    "the row has {} fields, the header {}",
                    fields.len(),
                    names.len()
                ),
            ));
        }
        let number = |k: usize| -> Result<f64, RunDirError> {
            let (column, text) = (index[k] + 1, fields[index[k]]);
            let name = RESOLUTION_COLUMNS[k];
            let v: f64 = text.parse().map_err(|_| {
                at(
                    line,
                    format!("column {column} `{name}`: `{text}` is not a number"),
                )
            })?;
            if !v.is_finite() || v < 0.0 {
                return Err(at(
                    line,
                    format!("column {column} `{name}`: `{text}` must be a finite number ≥ 0 (a standard deviation)"),
                ));
            }
            Ok(v)
        };
        let speed_hz = number(0)?;
        let bearing = fields[index[1]];
        let Some(&row) = rows.get(&(speed_hz.to_bits(), bearing)) else {
            return Err(at(
                line,
                format!(
                    "no row of {} has speed {} Hz and bearing `{bearing}`: each row here gives the rounding of one row there",
                    measurements_file.display(),
                    fields[index[0]]
                ),
            ));
        };
        if let Some(first) = seen.insert(row, line) {
            return Err(at(
                line,
                format!(
                    "speed {} Hz, bearing `{bearing}` twice (first at line {first})",
                    fields[index[0]]
                ),
            ));
        }
        let sd: NoiseSd = [number(2)?, number(3)?, number(4)?, number(5)?];
        found.push((row, sd));
    }
    for (row, sd) in found {
        measurements[row].set_resolution(sd);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_complex::Complex;

    fn row(speed_hz: f64, bearing: &str) -> Measurement {
        Measurement {
            speed_hz,
            bearing: bearing.into(),
            rel: [Complex::new(1e-6, -2e-6), Complex::new(3e-6, 0.5e-6)],
            ped: [Complex::new(-4e-7, 1e-7), Complex::new(2e-7, 2e-7)],
            noise_sd: None,
            written: None,
        }
    }

    #[test]
    fn round_trips_and_names_every_fault() {
        let dir = tempfile::tempdir().unwrap();
        let m_file = dir.path().join("measurements.csv");
        let mut rows = vec![row(10.0, "left"), row(12.5, "left"), row(10.0, "right")];
        // Nothing known: nothing written.
        assert!(!write(dir.path(), &rows).unwrap());
        let sd = [1e-9, 2e-9, 3e-10, 4e-10];
        rows[1].set_resolution(sd);
        assert!(write(dir.path(), &rows).unwrap());
        let mut back = vec![row(10.0, "left"), row(12.5, "left"), row(10.0, "right")];
        read_into(dir.path(), &mut back, &m_file).unwrap();
        assert_eq!(back[0].resolution_sd(), None);
        let got = back[1].resolution_sd().unwrap();
        for (g, s) in got.iter().zip(sd) {
            assert!((g - s).abs() < 1e-12 * s, "{got:?}");
        }
        // A value changed since (a slow-roll subtraction) carries no floor.
        back[1].rel[0] += Complex::new(1e-9, 1e-9);
        assert_eq!(back[1].resolution_sd().unwrap()[0], 0.0);
        assert!((back[1].resolution_sd().unwrap()[1] - 2e-9).abs() < 1e-21);

        let fault = |text: &str| {
            std::fs::write(dir.path().join(RESOLUTION_FILE), text).unwrap();
            let mut rows = vec![row(10.0, "left"), row(12.5, "left")];
            read_into(dir.path(), &mut rows, &m_file)
                .unwrap_err()
                .to_string()
        };
        let h = "speed_hz,bearing,rel_y_sd,rel_z_sd,ped_y_sd,ped_z_sd\n";
        assert!(fault("speed_hz,bearing,rel_y_sd\n")
            .contains("resolution.csv:1: header has no column `rel_z_sd`"));
        let e = fault(&format!("{h}10,left,1e-9,1e-9,x,1e-9\n"));
        assert!(
            e.contains(":2: column 5 `ped_y_sd`: `x` is not a number"),
            "{e}"
        );
        let e = fault(&format!("{h}10,left,1e-9,-1e-9,1e-9,1e-9\n"));
        assert!(
            e.contains(":2: column 4 `rel_z_sd`") && e.contains("≥ 0"),
            "{e}"
        );
        let e = fault(&format!("{h}11,left,1e-9,1e-9,1e-9,1e-9\n"));
        assert!(
            e.contains(":2: no row of") && e.contains("speed 11 Hz and bearing `left`"),
            "{e}"
        );
        let e = fault(&format!(
            "{h}10,left,1,1,1,1\n12.5,left,1,1,1,1\n10,left,1,1,1,1\n"
        ));
        assert!(
            e.contains(":4: speed 10 Hz, bearing `left` twice (first at line 2)"),
            "{e}"
        );
        let e = fault(&format!("{h}10,left,1,1,1\n"));
        assert!(e.contains(":2: the row has 5 fields, the header 6"), "{e}");
        // Extra columns are ignored (formats.md allows new optional columns).
        std::fs::write(
            dir.path().join(RESOLUTION_FILE),
            "note,speed_hz,bearing,rel_y_sd,rel_z_sd,ped_y_sd,ped_z_sd\nx,10,left,1,2,3,4\n",
        )
        .unwrap();
        let mut rows = vec![row(10.0, "left")];
        read_into(dir.path(), &mut rows, &m_file).unwrap();
        assert!((rows[0].resolution_sd().unwrap()[3] - 4.0).abs() < 1e-12);
        // Read a line at a time: a Latin-1 byte is still placed at its line
        // and column; CRLF line ends read as LF.
        let h = "speed_hz,bearing,rel_y_sd,rel_z_sd,ped_y_sd,ped_z_sd\n";
        std::fs::write(
            dir.path().join(RESOLUTION_FILE),
            [h.as_bytes(), b"10,l\xe9ft,1,1,1,1\n"].concat(),
        )
        .unwrap();
        let e = read_into(dir.path(), &mut rows, &m_file)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("resolution.csv:2: column 5: byte 0xE9 is not UTF-8"),
            "{e}"
        );
        std::fs::write(
            dir.path().join(RESOLUTION_FILE),
            format!("{h}10,left,1,2,3,4\n").replace('\n', "\r\n"),
        )
        .unwrap();
        let mut rows = vec![row(10.0, "left")];
        read_into(dir.path(), &mut rows, &m_file).unwrap();
        assert!((rows[0].resolution_sd().unwrap()[3] - 4.0).abs() < 1e-12);
    }
}
