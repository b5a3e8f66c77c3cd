//! A table's header: its columns found by name, a number or an empty,
//! doubled or missing name named where it stands.

use super::super::*;
use super::csv_error;

/// The columns of a table as its header names them.
pub(super) struct Columns {
    /// The header's names, trimmed.
    pub(super) header: csv::StringRecord,
    /// The 0-based column of each expected name, in the expected order.
    pub(super) index: [usize; 10],
    /// The 0-based columns of the four optional noise names, when the
    /// header has all four.
    pub(super) noise: Option<[usize; 4]>,
    /// The number of columns of the header (every row must have as many).
    pub(super) width: usize,
}

impl Columns {
    /// Reads the header of `reader` (the table at `path`) and finds
    /// `columns` in it, and `optional` (all four or none) when given;
    /// `expected` is the layout named in errors.
    pub(super) fn read<R: std::io::Read>(
        reader: &mut csv::Reader<R>,
        path: &Path,
        columns: &[&'static str; 10],
        optional: Option<&[&'static str; 4]>,
        expected: String,
    ) -> Result<Self, RunDirError> {
        let file = || path.to_path_buf();
        let mut header = csv::StringRecord::new();
        if !reader
            .read_record(&mut header)
            .map_err(|e| csv_error(path, e))?
        {
            return Err(RunDirError::MissingHeader {
                file: file(),
                expected,
            });
        }
        // Fields are trimmed (Unicode whitespace, as `csv::Trim::All` would):
        // the header once here, each data field as it is used, so that no
        // record is rebuilt per line.
        header.trim();
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
        // A set, not a scan of the columns before: a header of 500 000
        // columns (a 1 MiB line) took hours by the scan.
        let mut seen = std::collections::HashSet::with_capacity(header.len());
        for (i, name) in header.iter().enumerate() {
            let reason = if name.is_empty() {
                Some("empty column name")
            } else if !seen.insert(name) {
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
        let mut noise: Option<[usize; 4]> = None;
        if let Some(names) = optional {
            let found = names.map(|n| header.iter().position(|h| h == n));
            let present: Vec<&str> = names
                .iter()
                .zip(&found)
                .filter_map(|(n, f)| f.map(|_| *n))
                .collect();
            if present.len() == 4 {
                noise = Some(found.map(|f| f.unwrap_or_default()));
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
        Ok(Self {
            header,
            index,
            noise,
            width,
        })
    }
}
