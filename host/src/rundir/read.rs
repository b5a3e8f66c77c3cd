//! Reading run directories: every fault named by file, line and column.

use super::table::{read_table, Table, TableRow};
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
                let truth =
                    serde_json::from_str::<Truth>(&text).map_err(|e| RunDirError::Truth {
                        file: t_path.clone(),
                        line: e.line(),
                        column: e.column(),
                        message: e.to_string(),
                    })?;
                Some((truth, text))
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(source) => {
                return Err(RunDirError::Io {
                    file: t_path,
                    source,
                })
            }
        };
        if let Some((t, text)) = &truth {
            for note in super::truth_keys::unread(text, t) {
                eprintln!("warning: {}:{note}", t_path.display());
            }
            if let Some(note) = check_truth_bearings(&run, t, &t_path)? {
                eprintln!("warning: {}: {note}", t_path.display());
            }
        }
        for note in super::schedule::unlisted_speeds_with(&run, &schedules) {
            eprintln!("warning: {}: {note}", b_path.display());
        }
        Ok(RunDir {
            truth: truth.map(|(t, _)| t),
            ..run
        })
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
    let mut seen = std::collections::HashSet::new();
    if let Some(twice) = truth
        .pedestals
        .iter()
        .find(|p| !seen.insert(p.bearing.as_str()))
    {
        let (line, column) =
            crate::input_file::json_value_place(path, "bearing", &twice.bearing, 2);
        return Err(RunDirError::Truth {
            file: path.to_path_buf(),
            line,
            column,
            message: format!(
                "pedestal `{}` is listed twice: one bearing has one pedestal (which of the two values is the truth?)",
                twice.bearing
            ),
        });
    }
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
    let (line, column) = crate::input_file::json_value_place(path, "bearing", &p.bearing, 1);
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
