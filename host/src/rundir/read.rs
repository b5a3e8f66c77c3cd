//! Reading run directories: every fault named by file, line and column.

use super::*;

/// Reads and checks a `bearings.csv` on its own (formats.md layout), e.g. the
/// bearing table given to `plinth import` or `plinth extract`.
pub fn read_bearings(path: impl AsRef<Path>) -> Result<Vec<BearingRow>, RunDirError> {
    Ok(read_table(
        path.as_ref(),
        &BEARING_COLUMNS,
        None,
        false,
        false,
        bearing_row,
    )?
    .rows)
}

/// A row of `bearings.csv` as read.
fn bearing_row(r: TableRow) -> BearingRow {
    let v = &r.values;
    BearingRow {
        speed_hz: r.speed_hz,
        bearing: r.bearing,
        coefficients: BearingCoefficients {
            k: [[v[0], v[1]], [v[2], v[3]]],
            c: [[v[4], v[5]], [v[6], v[7]]],
        },
    }
}

/// A row of `measurements.csv` as read.
fn measurement(r: TableRow) -> Measurement {
    let v = &r.values;
    Measurement {
        speed_hz: r.speed_hz,
        bearing: r.bearing,
        rel: [Complex::new(v[0], v[1]), Complex::new(v[2], v[3])],
        ped: [Complex::new(v[4], v[5]), Complex::new(v[6], v[7])],
        noise_sd: r.noise_sd,
        written: r.written,
    }
}

impl RunDir {
    /// Reads and checks a run directory: `measurements.csv` and
    /// `bearings.csv` are required, `truth.json` and `resolution.csv`
    /// ([`super::resolution`]) are optional. Every
    /// measurement's bearing must have rows in `bearings.csv` that cover its
    /// speed. Columns are found by header name; header columns Plinth does
    /// not know are ignored (formats.md allows new optional columns).
    pub fn read(dir: impl AsRef<Path>) -> Result<RunDir, RunDirError> {
        let dir = dir.as_ref();
        let m_path = dir.join(MEASUREMENTS_FILE);
        let b_path = dir.join(BEARINGS_FILE);
        let t_path = dir.join(TRUTH_FILE);

        let m_table = read_table(
            &m_path,
            &MEASUREMENT_COLUMNS,
            Some(&NOISE_COLUMNS),
            true,
            true,
            measurement,
        )?;
        let bearings = read_table(&b_path, &BEARING_COLUMNS, None, false, false, bearing_row)?.rows;
        check_noise_not_all_zero(&m_table, &m_path)?;
        let Table {
            rows: mut measurements,
            lines,
            speed_column,
            bearing_column,
        } = m_table;
        super::resolution::read_into(dir, &mut measurements, &m_path)?;
        let run = RunDir {
            measurements,
            bearings,
            truth: None,
        };

        // Every measurement must be covered by its bearing's table.
        let schedules = run.bearing_schedules();
        for (r, &line) in run.measurements.iter().zip(&lines) {
            let Some(schedule) = schedules.get(&r.bearing) else {
                let first = run
                    .measurements
                    .iter()
                    .zip(&lines)
                    .find(|(x, _)| x.bearing == r.bearing)
                    .map_or(line, |(_, &l)| l);
                return Err(RunDirError::UnknownBearing {
                    file: m_path,
                    line: first,
                    column: bearing_column,
                    bearing: r.bearing.clone(),
                    bearings_file: b_path,
                });
            };
            if let Err(e) = schedule.at(r.speed_hz) {
                return Err(RunDirError::SpeedOutOfRange {
                    file: m_path,
                    line,
                    column: speed_column,
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
        if let Some(t) = &truth {
            if let Some(note) = check_truth_bearings(&run, t, &t_path)? {
                eprintln!("warning: {}: {note}", t_path.display());
            }
        }
        for note in super::schedule::unlisted_speeds_with(&run, &schedules) {
            eprintln!("warning: {}: {note}", b_path.display());
        }
        Ok(RunDir { truth, ..run })
    }
}

/// A noise column that is 0 on every row says the phasors are exact: an
/// instrument that wrote 0 for "not measured". Weighting by it would make
/// every misfit infinitely significant, so it is refused (single zeros are
/// allowed: a channel may be noise-free at one speed).
fn check_noise_not_all_zero(table: &Table<Measurement>, path: &Path) -> Result<(), RunDirError> {
    let (Some(_), Some(&line)) = (table.rows.first(), table.lines.first()) else {
        return Ok(());
    };
    for (c, name) in NOISE_COLUMNS.iter().enumerate() {
        let all_zero = table
            .rows
            .iter()
            .all(|r| r.noise_sd.is_some_and(|sd| sd[c] == 0.0));
        if all_zero {
            return Err(RunDirError::Csv {
                file: path.to_path_buf(),
                line,
                message: format!(
                    "column `{name}` is 0 on every row: a standard deviation of 0 says the phasors are exact (\"not measured\" written as 0?); write the measured scatter, or leave out the four `*_sd` columns and Plinth estimates the noise"
                ),
            });
        }
    }
    Ok(())
}

/// The measured bearings of `run` that `truth` has no pedestal for, in
/// order of first appearance: identified, but compared with nothing.
pub fn bearings_without_truth<'a>(run: &'a RunDir, truth: &Truth) -> Vec<&'a str> {
    run.measured_bearings()
        .into_iter()
        .filter(|b| !truth.pedestals.iter().any(|p| p.bearing == *b))
        .collect()
}

/// `truth.json` describes the run's own pedestals: a pedestal whose bearing
/// has no rows in `measurements.csv` (another run's truth, a renamed
/// bearing, a different case) is an error at the line that names it.
/// A truth over some of the measured bearings is legitimate (the simulator
/// writes none for a bearing without a pedestal; a field run may have a
/// shaker-tested value for one pedestal only): the bearings it lacks
/// ([`bearings_without_truth`]) are returned as a note to print, and the
/// identification table shows "none" as their truth.
fn check_truth_bearings(
    run: &RunDir,
    truth: &Truth,
    path: &Path,
) -> Result<Option<String>, RunDirError> {
    let measured = run.measured_bearings();
    let Some(p) = truth
        .pedestals
        .iter()
        .find(|p| !measured.contains(&p.bearing.as_str()))
    else {
        let missing = bearings_without_truth(run, truth);
        return Ok((!missing.is_empty()).then(|| {
            format!(
                "no pedestal for measured bearing{} {}: {} identified but compared with no truth",
                if missing.len() == 1 { "" } else { "s" },
                missing
                    .iter()
                    .map(|b| format!("`{b}`"))
                    .collect::<Vec<_>>()
                    .join(", "),
                if missing.len() == 1 {
                    "it is"
                } else {
                    "they are"
                }
            )
        }));
    };
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let needle = format!("\"{}\"", p.bearing);
    let (line, column) = text
        .lines()
        .enumerate()
        .find_map(|(i, l)| l.find(&needle).map(|c| (i + 1, c + 1)))
        .unwrap_or((1, 1));
    Err(RunDirError::Truth {
        file: path.to_path_buf(),
        line,
        column,
        message: format!(
            "pedestal `{}` is not a bearing of measurements.csv (it has {}): the truth of another run?",
            p.bearing,
            measured
                .iter()
                .map(|b| format!("`{b}`"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    })
}

/// Fewest bytes of a data row in the reserve made for a table's rows: a
/// speed, a bearing name and eight numbers of about three characters.
const MIN_ROW_BYTES: u64 = 40;

/// Most rows reserved for at once (more grow the table as they come).
const MAX_ROOM: usize = 1 << 22;

/// One parsed data row of either CSV file: speed, bearing and the eight numbers
/// after them in the order of the expected columns.
struct TableRow {
    speed_hz: f64,
    bearing: String,
    values: [f64; 8],
    /// The digits each of `values` was written with, when counted.
    written: Option<super::WrittenDigits>,
    /// The optional noise columns, when the header has them.
    noise_sd: Option<NoiseSd>,
}

/// A CSV table as read: its rows made into `T`, each row's line, and the
/// 1-based columns of the speed and the bearing name.
struct Table<T> {
    rows: Vec<T>,
    lines: Vec<u64>,
    speed_column: usize,
    bearing_column: usize,
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
fn read_table<T>(
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
    // Header.
    let mut header = csv::StringRecord::new();
    if !reader.read_record(&mut header).map_err(csv_error)? {
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

    // Room for every row at once (a row is at least `MIN_ROW_BYTES`
    // long): no growth by copying; what is not used is given back below.
    let room = std::fs::metadata(path).map_or(0, |m| {
        usize::try_from(m.len() / MIN_ROW_BYTES).map_or(MAX_ROOM, |n| n.min(MAX_ROOM))
    });
    let mut rows = Vec::with_capacity(room);
    let mut lines = Vec::with_capacity(room);
    // (speed bits, bearing index in `names`) → first line: one allocation
    // per bearing name, not per row.
    let mut names: Vec<String> = Vec::new();
    let mut seen: HashMap<(u64, usize), u64, std::hash::BuildHasherDefault<KeyHasher>> =
        HashMap::with_capacity_and_hasher(room, Default::default());
    // One record, reused for every line.
    let mut record = csv::StringRecord::new();
    while reader.read_record(&mut record).map_err(csv_error)? {
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
        let field = |col: usize| super::digits::trimmed(record.get(col).unwrap_or_default());
        let number_at = |col: usize, name: &'static str| -> Result<f64, RunDirError> {
            let text = field(col);
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
        let bearing = field(index[1]);
        if bearing.is_empty() {
            return Err(RunDirError::EmptyBearing {
                file: file(),
                line,
                column: index[1] + 1,
            });
        }
        let known = names.iter().any(|n| n == bearing);
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
        let mut values = [0.0; 8];
        for (k, v) in values.iter_mut().enumerate() {
            *v = number(k + 2)?;
        }
        super::bounds::check(path, line, columns, &index, &values)?;
        let written = count_digits.then(|| {
            super::WrittenDigits::from_text(std::array::from_fn(|k| field(index[k + 2])), values)
        });
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
        let name = match names.iter().position(|n| n == bearing) {
            Some(i) => i,
            None => {
                names.push(bearing.to_string());
                names.len() - 1
            }
        };
        let key = ((speed_hz + 0.0).to_bits(), name);
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

/// The csv crate only hands out an I/O kind for I/O errors; this keeps the
/// match total without a panic.
fn unreachable_csv(file: PathBuf) -> RunDirError {
    RunDirError::Csv {
        file,
        line: 0,
        message: "unexpected CSV error".to_string(),
    }
}
