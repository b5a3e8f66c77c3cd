//! The box's configuration for a demo: `stream.toml` with the signal set's
//! channels, and a bearing table that fits the box's capacity, chosen so
//! that linear interpolation stays closest to the exact coefficients.

use crate::rundir::{BearingRow, RunDir};
use crate::sim::signals::{SensorKind, SignalSet};
use crate::stream::config::StreamConfig;
use anyhow::{bail, Context, Result};
use std::path::Path;

/// Writes the box's configuration into `dir` (`stream.toml` with the signal
/// set's channels on ADC channels 0.., `bearings.csv` with `table`) and
/// loads it back as `plinth stream` would.
pub fn write_box_config(
    dir: &Path,
    set: &SignalSet,
    table: &[BearingRow],
    averaging: u32,
) -> Result<StreamConfig> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    RunDir {
        measurements: Vec::new(),
        bearings: table.to_vec(),
        truth: None,
    }
    .write(dir)
    .with_context(|| format!("writing the box's bearing table into {}", dir.display()))?;
    // RunDir::write also wrote an empty measurements.csv: not part of a configuration.
    let _ = std::fs::remove_file(dir.join(crate::rundir::MEASUREMENTS_FILE));
    let path = dir.join("stream.toml");
    std::fs::write(&path, config_text(set, "bearings.csv", averaging))
        .with_context(|| format!("cannot write {}", path.display()))?;
    StreamConfig::load(&path)
}

/// A stream configuration for a signal set's channels (ADC channel = the
/// set's column, so the replay needs no reordering).
pub fn config_text(set: &SignalSet, bearings_csv: &str, averaging: u32) -> String {
    let mut s = format!(
        "# Field box configuration written by `plinth demo` for {}.\n\
         # Known bearing coefficients (docs/formats.md), relative to this file.\n\
         bearings = \"{bearings_csv}\"\n\n[averaging]\nrevolutions = {averaging}\n\n[rls]\nforgetting_factor = 1.0\n",
        set.header.machine
    );
    for (adc, ch) in set.header.channels.iter().enumerate() {
        let sensor = match ch.kind {
            SensorKind::Displacement => "proximity",
            SensorKind::Velocity => "velocity",
            SensorKind::Acceleration => "acceleration",
        };
        s.push_str(&format!(
            "\n[[channels]]\nadc = {adc}\nbearing = \"{}\"\nquantity = \"{}\"\nsensor = \"{sensor}\"\nsensitivity = {:e}\n",
            ch.bearing,
            ch.quantity.name(),
            ch.sensitivity
        ));
    }
    s
}

/// Relative difference of two bearing coefficient sets: the largest
/// stiffness difference over the largest stiffness magnitude, or the same
/// for damping, whichever is larger.
pub(super) fn coefficient_error(
    a: &plinth_shared::bearing::BearingCoefficients<f64>,
    b: &plinth_shared::bearing::BearingCoefficients<f64>,
) -> f64 {
    let rel = |x: &[[f64; 2]; 2], y: &[[f64; 2]; 2]| {
        let mut d: f64 = 0.0;
        let mut n: f64 = 0.0;
        for i in 0..2 {
            for j in 0..2 {
                d = d.max((x[i][j] - y[i][j]).abs());
                n = n.max(y[i][j].abs());
            }
        }
        if n > 0.0 {
            d / n
        } else {
            d
        }
    };
    rel(&a.k, &b.k).max(rel(&a.c, &b.c))
}

/// The bearing table the box holds (at most `max_rows` rows per bearing,
/// the firmware's capacity), chosen from the exact coefficients `exact` on a
/// fine speed grid so that linear interpolation between the chosen rows is
/// as close to them as the row budget allows over [`lo_hz`, `hi_hz`]: the
/// rows bracketing the run first, then repeatedly the grid row where the
/// interpolated table is worst. Returns the rows and the largest relative
/// error left (see `coefficient_error`).
pub fn box_bearing_table(
    exact: &[BearingRow],
    lo_hz: f64,
    hi_hz: f64,
    max_rows: usize,
) -> Result<(Vec<BearingRow>, f64)> {
    if max_rows < 2 {
        bail!("a bearing table needs at least 2 rows");
    }
    let mut names: Vec<&str> = Vec::new();
    for r in exact {
        if !names.contains(&r.bearing.as_str()) {
            names.push(&r.bearing);
        }
    }
    let mut out = Vec::new();
    let mut worst_all: f64 = 0.0;
    for name in names {
        let mut grid: Vec<&BearingRow> = exact.iter().filter(|r| r.bearing == name).collect();
        grid.sort_by(|a, b| a.speed_hz.total_cmp(&b.speed_hz));
        let first = grid.iter().rposition(|r| r.speed_hz <= lo_hz);
        let last = grid.iter().position(|r| r.speed_hz >= hi_hz);
        let (Some(first), Some(last)) = (first, last) else {
            bail!("bearing {name:?}: the exact coefficients do not cover {lo_hz}-{hi_hz} Hz");
        };
        let span = &grid[first..=last];
        let mut chosen: Vec<usize> = vec![0, span.len() - 1];
        chosen.dedup();
        let worst = loop {
            // Interpolation error at every grid row between chosen rows.
            let mut max = (0.0, None);
            for w in chosen.windows(2) {
                let (a, b) = (span[w[0]], span[w[1]]);
                for (i, r) in span.iter().enumerate().take(w[1]).skip(w[0] + 1) {
                    let t = (r.speed_hz - a.speed_hz) / (b.speed_hz - a.speed_hz);
                    let interp = a.coefficients.lerp(&b.coefficients, t);
                    let e = coefficient_error(&interp, &r.coefficients);
                    if e > max.0 {
                        max = (e, Some(i));
                    }
                }
            }
            match max.1 {
                Some(i) if chosen.len() < max_rows => {
                    let at = chosen.partition_point(|&c| c < i);
                    chosen.insert(at, i);
                }
                _ => break max.0,
            }
        };
        worst_all = worst_all.max(worst);
        out.extend(chosen.iter().map(|&i| span[i].clone()));
    }
    Ok((out, worst_all))
}
