//! Writing run directories: numbers in full round-trip precision or reduced
//! to significant digits.

use super::*;

impl RunDir {
    /// Writes the run directory (creating it if needed) with every number in
    /// full round-trip precision; `truth.json` only when `truth` is set,
    /// `resolution.csv` only when a row carries a rounding floor
    /// ([`Measurement::resolution_sd`]).
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
        // The rounding the rows carry from a table they were converted from.
        super::resolution::write(dir, &self.measurements)?;

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
        if let Err(reason) = crate::names::check("bearing", bearing) {
            return Err(RunDirError::BadBearingName {
                reason,
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
