//! One CSV table of a run directory (`measurements.csv` or `bearings.csv`)
//! read row by row: every number checked where it stands, duplicates named
//! with the line of their first appearance.

use super::digits::{read_counted, read_number};
use super::*;
use header::Columns;

mod header;

/// Fewest bytes of a data row in the reserve made for a table's rows: a
/// speed, a bearing name and eight numbers of about three characters.
const MIN_ROW_BYTES: u64 = 40;

/// Most rows reserved for at once (more grow the table as they come).
const MAX_ROOM: usize = 1 << 22;

/// One parsed data row of either CSV file: speed, bearing and the eight numbers
/// after them in the order of the expected columns.
pub(super) struct TableRow {
    /// Speed [Hz].
    pub(super) speed_hz: f64,
    /// Bearing name.
    pub(super) bearing: String,
    /// The eight numbers, in the order of the expected columns.
    pub(super) values: [f64; 8],
    /// The digits each of `values` was written with, when counted.
    pub(super) written: Option<super::WrittenDigits>,
    /// The optional noise columns, when the header has them.
    pub(super) noise_sd: Option<NoiseSd>,
}

/// A CSV table as read: its rows made into `T`, each row's line, and the
/// 1-based columns of the speed and the bearing name.
pub(super) struct Table<T> {
    /// The rows, in file order.
    pub(super) rows: Vec<T>,
    /// Each row's line (1-based).
    pub(super) lines: Vec<u64>,
    /// Column of the speed (1-based).
    pub(super) speed_column: usize,
    /// Column of the bearing name (1-based).
    pub(super) bearing_column: usize,
}

/// Hashes the duplicate check's keys (a speed's bits and a name's index):
/// one multiply-xorshift mix per word, no per-key allocation or SipHash
/// rounds.
#[derive(Default)]
struct KeyHasher(u64);

impl std::hash::Hasher for KeyHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u64(&mut self, word: u64) {
        let x = (self.0 ^ word).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        self.0 = x ^ (x >> 29);
    }

    fn write_usize(&mut self, word: usize) {
        self.write_u64(word as u64);
    }

    fn finish(&self) -> u64 {
        let x = self.0.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        x ^ (x >> 31)
    }
}

/// Reads a CSV table whose columns are `speed_hz`, `bearing` and eight numbers,
/// plus, when `optional` is given and the header names them, four
/// non-negative numbers (all four or none); with `count_digits` the digits
/// each of the eight numbers was written with (the measurements' noise
/// model needs them, the bearing table does not). Each row is made into a
/// `T` by `make` as it is read.
pub(super) fn read_table<T>(
    path: &Path,
    columns: &[&'static str; 10],
    optional: Option<&[&'static str; 4]>,
    positive_speed: bool,
    count_digits: bool,
    mut make: impl FnMut(TableRow) -> T,
) -> Result<Table<T>, RunDirError> {
    let file = || path.to_path_buf();
    let expected = columns.join(",");
    // Spreadsheet exports and non-files are named before the CSV reader runs.
    let handle = crate::csv_layout::open(path, &expected).map_err(|e| match e {
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
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .quoting(false)
        .from_reader(handle);
    let Columns {
        header,
        index,
        noise: noise_index,
        width,
    } = Columns::read(&mut reader, path, columns, optional, expected)?;

    // Room for every row at once (a row is at least `MIN_ROW_BYTES`
    // long): no growth by copying; what is not used is given back below.
    let room = std::fs::metadata(path).map_or(0, |m| {
        usize::try_from(m.len() / MIN_ROW_BYTES).map_or(MAX_ROOM, |n| n.min(MAX_ROOM))
    });
    let mut rows = Vec::with_capacity(room);
    let mut lines = Vec::with_capacity(room);
    // (speed bits, bearing index in `names`) → first line: one allocation
    // per bearing name, not per row.
    let mut names: HashMap<String, usize> = HashMap::new();
    let mut seen: HashMap<(u64, usize), u64, std::hash::BuildHasherDefault<KeyHasher>> =
        HashMap::with_capacity_and_hasher(room, Default::default());
    // The table's distinct speeds (their bits).
    let mut speeds: std::collections::HashSet<u64, std::hash::BuildHasherDefault<KeyHasher>> =
        Default::default();
    // The rows and speeds budgets, counted as the file is read: a table far
    // past them is refused at its first row past the limit.
    let budget = |limit: &crate::sim::budget::Limit| {
        limit.reading().map_err(|m| RunDirError::Io {
            file: file(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidInput, m),
        })
    };
    let mut rows_read = budget(&crate::sim::budget::ROWS)?;
    let mut speeds_read = budget(&crate::sim::budget::SPEEDS)?;
    // One record, reused for every line.
    let mut record = csv::StringRecord::new();
    while reader
        .read_record(&mut record)
        .map_err(|e| csv_error(path, e))?
    {
        let line = record.position().map_or(0, csv::Position::line);
        let over = |message: String| RunDirError::Csv {
            file: file(),
            line,
            message,
        };
        rows_read.count(path, 1).map_err(over)?;
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
        let field = |col: usize| super::digits::trimmed(record.get(col).unwrap_or_default());
        // A number as read (`None`: not a number) checked at its column.
        let located = |col: usize, name: &'static str, value: Option<f64>| {
            let text = field(col);
            let value = value.ok_or_else(|| RunDirError::BadNumber {
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
        let number_at = |col: usize, name| located(col, name, read_number(field(col)));
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
        let bearing = field(index[1]);
        if bearing.is_empty() {
            return Err(RunDirError::EmptyBearing {
                file: file(),
                line,
                column: index[1] + 1,
            });
        }
        let known = names.contains_key(bearing);
        if let Err(reason) = if known {
            Ok(())
        } else {
            crate::names::check("bearing", bearing)
        } {
            return Err(RunDirError::BadBearingName {
                reason,
                file: file(),
                line,
                column: index[1] + 1,
                name: bearing.to_string(),
            });
        }
        // The eight numbers, with the digits of each counted in the same
        // scan when they are wanted.
        let mut values = [0.0; 8];
        let mut counted = [None; 8];
        for k in 0..8 {
            values[k] = if count_digits {
                let (col, read) = (index[k + 2], read_counted(field(index[k + 2])));
                counted[k] = read.and_then(|(_, d)| d);
                located(col, columns[k + 2], read.map(|(v, _)| v))?
            } else {
                number(k + 2)?
            };
        }
        super::bounds::check(path, line, columns, &index, &values)?;
        let written = count_digits.then(|| super::WrittenDigits::from_counted(values, counted));
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
        let name = match names.get(bearing) {
            Some(&i) => i,
            None => {
                let i = names.len();
                names.insert(bearing.to_string(), i);
                i
            }
        };
        let speed = (speed_hz + 0.0).to_bits();
        if speeds.insert(speed) {
            speeds_read.count(path, 1).map_err(|m| RunDirError::Csv {
                file: file(),
                line,
                message: format!("speed {speed_hz} Hz: {m}"),
            })?;
        }
        let key = (speed, name);
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
        lines.push(line);
        rows.push(make(TableRow {
            speed_hz,
            bearing: bearing.to_string(),
            values,
            written,
            noise_sd,
        }));
    }
    rows.shrink_to_fit();
    lines.shrink_to_fit();
    Ok(Table {
        rows,
        lines,
        speed_column: index[0] + 1,
        bearing_column: index[1] + 1,
    })
}

/// The error of the CSV reader on `path`: its I/O error as such, any other
/// at the line it names.
fn csv_error(path: &Path, e: csv::Error) -> RunDirError {
    match e.kind() {
        csv::ErrorKind::Io(_) => match e.into_kind() {
            csv::ErrorKind::Io(source) => RunDirError::Io {
                file: path.to_path_buf(),
                source,
            },
            _ => unreachable_csv(path.to_path_buf()),
        },
        _ => RunDirError::Csv {
            file: path.to_path_buf(),
            line: e.position().map_or(0, csv::Position::line),
            message: e.to_string(),
        },
    }
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
