//! `plinth import TABLE.csv --layout LAYOUT.toml --bearings BEARINGS.csv
//! --out DIR`: a 1X vector table (one row per speed, as field instruments
//! export it) to a run directory (formats.md "A 1X vector table").
//!
//! Each transducer's amplitude (its unit: pp/0-pk/rms, displacement,
//! velocity or acceleration, [`super::units`]) and phase (lag or lead) become
//! a 1X phasor of what it measures, then a displacement phasor at the row's
//! speed (D = V/(iΩ), D = −A/Ω²); each bearing's `rel` and `ped`
//! transducers, at any distinct angles, are resolved into y and z
//! ([`super::angle::resolve`]). Errors name TABLE.csv's line and column, or
//! LAYOUT.toml's key.

use super::angle::{resolve, Rotation, View};
use super::resolution::ReadingSteps;
use super::slow_roll::{subtract_slow_roll, SlowRollBand};
use super::transducer::{angle_of, group_by_bearing, Placement, Quantity};
use super::units::{reading_phasor, to_displacement, AmplitudeUnit, PhaseConvention, UNIT_HELP};
use crate::rundir::{read_bearings, round_to_digits, BearingRow, DigitsMode, Measurement, RunDir};
use anyhow::{bail, Context, Result};
use num_complex::Complex;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Command-line arguments of `plinth import`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The 1X vector table (CSV: a header row, one row per speed).
    pub table: PathBuf,
    /// Which columns are which transducer, units and phase convention (TOML,
    /// docs/formats.md "A 1X vector table").
    #[arg(long)]
    pub layout: PathBuf,
    /// Bearing coefficients (`bearings.csv` layout).
    #[arg(long)]
    pub bearings: PathBuf,
    /// Run directory to write (refused if it exists and is not empty, unless --force).
    #[arg(long)]
    pub out: PathBuf,
    /// Subtract each bearing's mean `rel` vector between LO and HI Hz (slow roll).
    #[arg(long, value_name = "LO:HI")]
    pub slow_roll: Option<SlowRollBand>,
    /// Also draw Bode and polar plots into DIR/figures.
    #[arg(long)]
    pub plots: bool,
    /// Replace the files this command writes in an existing --out.
    #[arg(long)]
    pub force: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLayout {
    phase: PhaseConvention,
    speed: RawSpeed,
    view: Option<View>,
    rotation: Option<Rotation>,
    #[serde(rename = "transducer", default)]
    transducers: Vec<RawTransducer>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSpeed {
    column: String,
    unit: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTransducer {
    bearing: String,
    quantity: Quantity,
    angle_deg: Option<f64>,
    angle: Option<String>,
    amplitude: RawAmplitude,
    phase: RawColumn,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAmplitude {
    column: String,
    unit: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawColumn {
    column: String,
}

/// Significant digits [-] of a speed converted to Hz (rpm / 60): far more
/// than any tachometer gives, few enough to drop the conversion's binary
/// residue.
pub const SPEED_DIGITS: u32 = 12;

/// A checked layout.
#[derive(Clone, Debug)]
pub struct Layout {
    /// Lag or lead.
    pub phase: PhaseConvention,
    /// Speed column name.
    pub speed_column: String,
    /// Factor from the speed column to Hz (1 for Hz, 1/60 for rpm).
    pub speed_to_hz: f64,
    /// Transducers in layout order.
    pub transducers: Vec<Transducer>,
    /// Direction of rotation seen from the layout's `view` (figures).
    pub rotation: Option<Rotation>,
}

/// One transducer's columns and placement.
#[derive(Clone, Debug)]
pub struct Transducer {
    /// Bearing, quantity, angle.
    pub placement: Placement,
    /// Amplitude column name.
    pub amplitude_column: String,
    /// Its unit.
    pub unit: AmplitudeUnit,
    /// Phase column name.
    pub phase_column: String,
}

impl Layout {
    /// Reads and checks LAYOUT.toml.
    pub fn read(path: &Path) -> Result<Layout> {
        let text = crate::input_file::read_to_string(path)
            .with_context(|| format!("{}", path.display()))?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Parses layout text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Layout> {
        let raw: RawLayout = toml::from_str(text)
            .map_err(|e| anyhow::anyhow!("{file}: {}", crate::input_file::toml_error(text, &e)))?;
        let speed_to_hz = match raw.speed.unit.trim().to_ascii_lowercase().as_str() {
            "rpm" => 1.0 / 60.0,
            "hz" => 1.0,
            u => bail!("{file}: speed.unit: unknown unit `{u}` (expected \"rpm\" or \"Hz\")"),
        };
        if raw.transducers.is_empty() {
            bail!("{file}: no [[transducer]] tables: each bearing needs two `rel` and two `ped` transducers");
        }
        let rotation = raw.rotation;
        if raw.view.is_some() != raw.rotation.is_some() {
            bail!("{file}: `view` and `rotation` come together (the rotation is as seen from the view), e.g. view = \"driver\", rotation = \"ccw\"");
        }
        let mut transducers = Vec::new();
        for (i, t) in raw.transducers.iter().enumerate() {
            let key = format!("transducer[{i}]");
            let unit = AmplitudeUnit::parse(&t.amplitude.unit).ok_or_else(|| {
                anyhow::anyhow!(
                    "{file}: {key}.amplitude.unit: unknown unit `{}`; expected {UNIT_HELP}",
                    t.amplitude.unit
                )
            })?;
            if t.quantity == Quantity::Rel
                && unit.kind != plinth_shared::extractor::SensorKind::Displacement
            {
                bail!(
                    "{file}: {key}.amplitude.unit: `{}` is not a displacement, but a `rel` transducer is a proximity probe",
                    t.amplitude.unit
                );
            }
            let angle_deg = angle_of(file, &key, t.angle_deg, t.angle.as_deref(), rotation)?;
            transducers.push(Transducer {
                placement: Placement {
                    bearing: t.bearing.clone(),
                    quantity: t.quantity,
                    angle_deg,
                    key,
                },
                amplitude_column: t.amplitude.column.clone(),
                unit,
                phase_column: t.phase.column.clone(),
            });
        }
        let placements: Vec<Placement> = transducers.iter().map(|t| t.placement.clone()).collect();
        group_by_bearing(file, &placements)?;
        Ok(Layout {
            phase: raw.phase,
            speed_column: raw.speed.column,
            speed_to_hz,
            transducers,
            rotation,
        })
    }
}

/// One bearing's measurement from a table row, with where the row is.
#[derive(Clone, Debug)]
pub struct ImportedRow {
    /// Line in TABLE.csv [1-based].
    pub line: u64,
    /// Column of the speed [1-based].
    pub speed_column: usize,
    /// The phasors [m] at the row's speed [Hz].
    pub measurement: Measurement,
    /// sd [m] of the rounding the table leaves on each phasor (rel y, rel
    /// z, ped y, ped z; sqrt(E|n|²), [`super::resolution`]).
    pub resolution: crate::rundir::NoiseSd,
}

/// Reads TABLE.csv through `layout`: one row per table row and bearing,
/// displacement phasors [m], y and z resolved.
pub fn read_table(path: &Path, layout: &Layout, layout_file: &str) -> Result<Vec<ImportedRow>> {
    let file = path.display().to_string();
    let handle = crate::csv_layout::open(path, &layout.speed_column).map_err(|e| match e {
        crate::csv_layout::LayoutError::NotAFile(m) => anyhow::anyhow!("{file}: {m}"),
        crate::csv_layout::LayoutError::At(line, m) => anyhow::anyhow!("{file}:{line}: {m}"),
    })?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(handle);
    let mut records = reader.records();
    let header = match records.next() {
        Some(r) => r.with_context(|| format!("{file}:1"))?,
        None => bail!("{file}:1: empty file: expected a header row naming the columns"),
    };
    let names: Vec<String> = header
        .iter()
        .map(|s| s.trim_start_matches('\u{feff}').to_string())
        .collect();
    let find =
        |key: &str, name: &str| -> Result<usize> {
            names.iter().position(|n| n == name).ok_or_else(|| {
                anyhow::anyhow!(
                "{layout_file}: {key}: {file}:1: the header has no column `{name}` (it has: {})",
                names.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
            )
            })
        };
    let speed_col = find("speed.column", &layout.speed_column)?;
    let cols: Vec<(usize, usize)> = layout
        .transducers
        .iter()
        .map(|t| {
            Ok((
                find(
                    &format!("{}.amplitude.column", t.placement.key),
                    &t.amplitude_column,
                )?,
                find(
                    &format!("{}.phase.column", t.placement.key),
                    &t.phase_column,
                )?,
            ))
        })
        .collect::<Result<_>>()?;
    let placements: Vec<Placement> = layout
        .transducers
        .iter()
        .map(|t| t.placement.clone())
        .collect();
    let groups = group_by_bearing(layout_file, &placements)?;

    let mut rows = Vec::new();
    // Each table row's readings (amplitude, phase) per transducer and its
    // Ω [rad/s], for the rounding floor once every column's steps are known.
    let mut readings: Vec<(Vec<(f64, f64)>, f64)> = Vec::new();
    let mut seen: BTreeMap<u64, u64> = BTreeMap::new();
    let mut watches = vec![super::plausible::ReadingsWatch::default(); layout.transducers.len()];
    // The table's speeds and the run's rows (one per speed and bearing),
    // counted as the table is read: a table past either budget is refused
    // at its first row past it, before the rest is read or anything written.
    let mut speeds_read = crate::sim::budget::SPEEDS
        .reading()
        .map_err(|m| anyhow::anyhow!("{file}: {m}"))?;
    let mut rows_read = crate::sim::budget::ROWS
        .reading()
        .map_err(|m| anyhow::anyhow!("{file}: {m}"))?;
    for record in records {
        let record = record.with_context(|| file.to_string())?;
        let line = record.position().map_or(0, |p| p.line());
        if record.iter().all(|f| f.is_empty()) {
            continue;
        }
        // A row wider than the header with something in its extra fields:
        // an unquoted `,` inside a number (`1,234`, a decimal comma) shifted
        // every later column. Empty extra fields (a spreadsheet's trailing
        // empty columns) are harmless.
        if let Some(extra) = record.iter().skip(names.len()).position(|f| !f.is_empty()) {
            bail!(
                "{file}:{line}:{}: the row has {} fields but the header {}: an unquoted `,` inside a number (a thousands separator such as `1,234`, or a decimal comma) shifts every later column; write numbers without separators, with `.` as the decimal point",
                names.len() + extra + 1,
                record.len(),
                names.len()
            );
        }
        let cell = |col: usize, what: &str| -> Result<f64> {
            let text = record.get(col).ok_or_else(|| {
                anyhow::anyhow!(
                    "{file}:{line}:{}: missing column `{}` (the row has {} fields)",
                    col + 1,
                    names[col],
                    record.len()
                )
            })?;
            let v: f64 = text.parse().map_err(|_| {
                anyhow::anyhow!(
                    "{file}:{line}:{}: column `{}` ({what}): `{text}` is not a number",
                    col + 1,
                    names[col]
                )
            })?;
            if !v.is_finite() {
                bail!(
                    "{file}:{line}:{}: column `{}`: `{text}` is not finite",
                    col + 1,
                    names[col]
                );
            }
            Ok(v)
        };
        // Snapped to SPEED_DIGITS significant digits: an rpm column's
        // 794.70/60 is 13.245000000000001 in binary, which matched no row of
        // a bearing table written in Hz (13.245) and had every such speed
        // interpolated with a warning listing 28 of 102 speeds.
        let speed_hz = round_to_digits(
            cell(speed_col, "speed")? * layout.speed_to_hz,
            SPEED_DIGITS,
            DigitsMode::Round,
        );
        if speed_hz <= 0.0 {
            bail!(
                "{file}:{line}:{}: column `{}`: the speed must be > 0 (a 1X phasor needs rotation)",
                speed_col + 1,
                names[speed_col]
            );
        }
        if let Some(first) = seen.insert(speed_hz.to_bits(), line) {
            bail!(
                "{file}:{line}:{}: speed {} Hz twice (first at line {first})",
                speed_col + 1,
                crate::rundir::digits::format_number(speed_hz)
            );
        }
        speeds_read
            .count(path, 1)
            .map_err(|m| anyhow::anyhow!("{file}:{line}: {m}"))?;
        rows_read
            .count(path, groups.len() as u64)
            .map_err(|m| anyhow::anyhow!("{file}:{line}: the run made from it would hold {m}"))?;
        let omega = std::f64::consts::TAU * speed_hz;
        let mut disp = Vec::with_capacity(cols.len());
        let mut read = Vec::with_capacity(cols.len());
        for ((t, &(ac, pc)), watch) in layout.transducers.iter().zip(&cols).zip(&mut watches) {
            let amplitude = cell(ac, "amplitude")?;
            if amplitude < 0.0 {
                bail!(
                    "{file}:{line}:{}: column `{}`: amplitude {amplitude} is negative",
                    ac + 1,
                    names[ac]
                );
            }
            let phase = cell(pc, "phase [deg]")?;
            let si = amplitude * t.unit.to_si_zero_peak;
            let most = super::plausible::max_amplitude_si(t.unit.kind);
            if si > most {
                bail!(
                    "{file}:{line}:{}: column `{}`: amplitude {amplitude:e} ({si:.3e} {} 0-pk) is beyond any machine's vibration (at most {most:e} {}): a typo, or the wrong unit in the layout?",
                    ac + 1,
                    names[ac],
                    super::plausible::si_unit(t.unit.kind),
                    super::plausible::si_unit(t.unit.kind)
                );
            }
            watch.push(amplitude, phase);
            read.push((amplitude, phase));
            let q = reading_phasor(si, phase, layout.phase);
            disp.push(to_displacement(t.unit.kind, q, omega));
        }
        for (bearing, [rel, ped]) in &groups {
            let pick = |set: &[usize]| -> [Complex<f64>; 2] {
                let angles: Vec<f64> = set.iter().map(|&i| placements[i].angle_deg).collect();
                let q: Vec<Complex<f64>> = set.iter().map(|&i| disp[i]).collect();
                resolve(&angles, &q, None).0
            };
            let (rel, ped) = (pick(rel), pick(ped));
            rows.push(ImportedRow {
                line,
                speed_column: speed_col + 1,
                measurement: Measurement {
                    speed_hz,
                    bearing: bearing.clone(),
                    rel,
                    ped,
                    // No noise columns: the table's rounding is only a floor under
                    // the sensors' own noise, which a vector table does not carry
                    // (columns are taken as the whole noise); identify estimates it.
                    noise_sd: None,
                    written: None,
                },
                resolution: [0.0; 4],
            });
        }
        readings.push((read, omega));
    }
    if rows.is_empty() {
        bail!("{file}: no data rows after the header");
    }
    // The table's rounding, propagated to each phasor (super::resolution).
    let steps: Vec<ReadingSteps> = (0..cols.len())
        .map(|t| {
            let (a, p): (Vec<f64>, Vec<f64>) = readings.iter().map(|(r, _)| r[t]).unzip();
            ReadingSteps::of(&a, &p)
        })
        .collect();
    for (row, (read, omega)) in rows.chunks_mut(groups.len().max(1)).zip(&readings) {
        let sd: Vec<f64> = layout
            .transducers
            .iter()
            .zip(&steps)
            .zip(read)
            .map(|((t, s), &(a, p))| s.displacement_sd(&t.unit, a, p, *omega))
            .collect();
        for (r, (_, [rel, ped])) in row.iter_mut().zip(&groups) {
            let pick = |set: &[usize]| -> [f64; 2] {
                let angles: Vec<f64> = set.iter().map(|&i| placements[i].angle_deg).collect();
                let sd: Vec<f64> = set.iter().map(|&i| sd[i]).collect();
                let zero = vec![Complex::new(0.0, 0.0); set.len()];
                resolve(&angles, &zero, Some(&sd)).1.unwrap_or([0.0; 2])
            };
            let ([ry, rz], [py, pz]) = (pick(rel), pick(ped));
            r.resolution = [ry, rz, py, pz];
        }
    }
    for ((t, &(ac, _)), watch) in layout.transducers.iter().zip(&cols).zip(&watches) {
        let what = format!(
            "{file}: column {} `{}` ({layout_file}: {}, bearing `{}`)",
            ac + 1,
            names[ac],
            t.placement.key,
            t.placement.bearing
        );
        watch.check(&what).map_err(anyhow::Error::msg)?;
    }
    if super::plausible::radians_suspected(&watches) {
        eprintln!(
            "warning: {file}: every phase of every transducer, over {} rows, lies within ±2π (6.28), e.g. column `{}`: are the phases in radians? {layout_file} and docs/formats.md read degrees; if so convert them (× 180/π)",
            rows.len() / groups.len().max(1),
            names[cols[0].1]
        );
    }
    Ok(rows)
}

/// Checks that every measurement's bearing is in `bearings` and its speed in
/// the listed range (no extrapolation).
pub fn check_against_bearings(
    rows: &[ImportedRow],
    bearings: &[BearingRow],
    table: &str,
    bearings_file: &str,
) -> Result<()> {
    let run = RunDir {
        measurements: Vec::new(),
        bearings: bearings.to_vec(),
        truth: None,
    };
    let schedules = run.bearing_schedules();
    for r in rows {
        let m = &r.measurement;
        let Some(s) = schedules.get(&m.bearing) else {
            bail!(
                "{table}:{}: bearing `{}` has no rows in {bearings_file} (it lists: {})",
                r.line,
                m.bearing,
                schedules.keys().cloned().collect::<Vec<_>>().join(", ")
            );
        };
        if let Err(e) = s.at(m.speed_hz) {
            bail!(
                "{table}:{}:{}: speed {} Hz is outside the range {}..={} Hz that {bearings_file} lists for bearing `{}` (coefficients are not extrapolated)",
                r.line,
                r.speed_column,
                crate::rundir::digits::format_number(m.speed_hz),
                crate::rundir::digits::format_number(e.min_hz),
                crate::rundir::digits::format_number(e.max_hz),
                m.bearing
            );
        }
    }
    Ok(())
}

/// Writes the run directory of imported or extracted `rows` (with the
/// known `bearings`): first subtracts the slow-roll vector of `slow_roll`
/// when given (warnings on stderr, the vectors in `slow_roll.csv`), then
/// writes measurements and bearings, and the transducers' placement
/// (`transducers.csv`, for `plinth plot`); with `plots`, Bode and polar figures in
/// `figures/` for the resolved y/z phasors and every transducer in
/// `transducers` (bearing, quantity, angle [deg]). Returns the run written.
pub fn write_run(
    out: &Path,
    force: bool,
    mut rows: Vec<Measurement>,
    bearings: Vec<BearingRow>,
    slow_roll: Option<SlowRollBand>,
    plots: Option<super::plot::FieldFigures>,
    transducers: &[Placement],
) -> Result<RunDir> {
    let slow_roll = match slow_roll {
        Some(band) => {
            let s = subtract_slow_roll(&mut rows, band)?;
            for w in &s.warnings {
                eprintln!("warning: {w}");
            }
            Some(s)
        }
        None => None,
    };
    let run = RunDir {
        measurements: rows,
        bearings,
        truth: None,
    };
    let slow_roll = slow_roll.as_ref();
    let run_ref = &run;
    crate::output::write_dir(out, force, |dir| {
        run_ref.write(dir)?;
        super::transducers_csv::write(dir, transducers)?;
        if let Some(s) = slow_roll {
            s.write(dir)?;
        }
        if let Some(f) = &plots {
            super::plot::plot_run_with(run_ref, &dir.join("figures"), &f.transducers, &f.options)?;
        }
        Ok(())
    })?;
    Ok(run)
}

/// Runs `plinth import`.
pub fn run(args: &Args) -> Result<()> {
    let layout_file = args.layout.display().to_string();
    let layout = Layout::read(&args.layout)?;
    let mut ticker = crate::progress::Ticker::new("import: read, check, write", 3, true);
    let imported = read_table(&args.table, &layout, &layout_file)?;
    ticker.tick(1);
    let bearings = read_bearings(&args.bearings)?;
    check_against_bearings(
        &imported,
        &bearings,
        &args.table.display().to_string(),
        &args.bearings.display().to_string(),
    )?;
    ticker.tick(2);
    let rows: Vec<Measurement> = imported
        .into_iter()
        .map(|r| {
            let mut m = r.measurement;
            m.set_resolution(r.resolution);
            m
        })
        .collect();
    let n = rows.len();
    let placements: Vec<Placement> = layout
        .transducers
        .iter()
        .map(|t| t.placement.clone())
        .collect();
    let run = write_run(
        &args.out,
        args.force,
        rows,
        bearings,
        args.slow_roll,
        args.plots
            .then(|| super::plot::FieldFigures::from_layout(&layout)),
        &placements,
    )?;
    ticker.finish();
    println!(
        "{}: {} rows ({} bearings) -> {}",
        args.table.display(),
        n,
        run.measured_bearings().len(),
        args.out.display()
    );
    Ok(())
}
