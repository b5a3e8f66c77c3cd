//! The demo's figures: the 1X phasors the box extracted from the time
//! signals (markers) over the simulated truth (lines), as an engineer reads
//! them: peak-to-peak amplitude, phase lag, and the phase lag of each
//! pedestal's response behind the force its bearing transmits (0° below a
//! pedestal resonance, 180° above: Feng & Hahn's Figs. 5 and 9). PNG and SVG.

use crate::plots::{
    phase_lag_deg, Mark, PhaseStyle, PhasorFigure, PhasorPanel, PhasorSeries, PhasorView, Quantity,
    Rows, ScalarFigure, ScalarSeries,
};
use crate::rundir::{Measurement, RunDir};
use anyhow::{anyhow, Context, Result};
use num_complex::Complex;
use plinth_shared::phasor::omega_from_hz;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Most points drawn per truth line (the truth grid is 0.01 Hz).
pub const MAX_LINE_POINTS: usize = 2000;

/// Most markers drawn per measured series.
pub const MAX_MARKERS: usize = 150;

/// (rotor speed [Hz], phasor [m]) points of one channel.
type SpeedPhasors = Vec<(f64, Complex<f64>)>;

/// A channel: (bearing name, direction 0 = y / 1 = z).
type ChannelKey = (String, usize);

/// (rotor speed [Hz], phase difference [deg]) points of one channel.
type SpeedDegrees = Vec<(f64, f64)>;

/// Legend prefix of a bearing: `left` → `L`, `right` → `R`, else the name.
fn short(bearing: &str) -> String {
    match bearing {
        "left" => "L".into(),
        "right" => "R".into(),
        b => format!("{b} "),
    }
}

/// Legend key of (bearing, direction), e.g. `Ly`.
fn key(bearing: &str, d: usize) -> String {
    format!("{}{}", short(bearing), if d == 0 { "y" } else { "z" })
}

/// Every `len / n`-th element, at most about `n`.
fn thin<T: Clone>(v: &[T], n: usize) -> Vec<T> {
    let step = v.len().div_ceil(n.max(1)).max(1);
    v.iter().step_by(step).cloned().collect()
}

/// Phasors of rel (`ped = false`) or ped per (bearing, direction), in
/// bearing order of first appearance, sorted by speed.
fn channels(rows: &[Measurement], ped: bool) -> Vec<(ChannelKey, SpeedPhasors)> {
    let mut order: Vec<String> = Vec::new();
    let mut by: BTreeMap<(usize, usize), SpeedPhasors> = BTreeMap::new();
    for m in rows {
        if !order.contains(&m.bearing) {
            order.push(m.bearing.clone());
        }
        let bi = order.iter().position(|b| *b == m.bearing).unwrap_or(0);
        let v = if ped { m.ped } else { m.rel };
        for (d, x) in v.iter().enumerate() {
            by.entry((bi, d)).or_default().push((m.speed_hz, *x));
        }
    }
    by.into_iter()
        .map(|((bi, d), mut pts)| {
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            ((order[bi].clone(), d), pts)
        })
        .collect()
}

/// A panel of truth lines and measured markers for rel or ped.
fn panel(title: &str, measured: &RunDir, truth: &RunDir, ped: bool) -> PhasorPanel {
    let mut series = Vec::new();
    let truth_ch = channels(&truth.measurements, ped);
    let meas_ch = channels(&measured.measurements, ped);
    for ((b, d), pts) in &truth_ch {
        series.push(PhasorSeries {
            name: format!("{} truth", key(b, *d)),
            points: thin(pts, MAX_LINE_POINTS),
            mark: Mark::Line,
        });
        if let Some((_, m)) = meas_ch.iter().find(|(k, _)| k == &(b.clone(), *d)) {
            series.push(PhasorSeries {
                name: format!("{} box", key(b, *d)),
                points: thin(m, MAX_MARKERS),
                mark: Mark::Markers,
            });
        }
    }
    PhasorPanel {
        title: title.into(),
        series,
        quantity: None,
    }
}

/// A phase lag [deg] moved into [−90, 270), the range where the 0° → 180°
/// step of a pedestal resonance is continuous (a lag just over 180° would
/// otherwise wrap to −180°).
pub fn lag_for_plot(deg: f64) -> f64 {
    if deg < -90.0 {
        deg + 360.0
    } else {
        deg
    }
}

/// Phase lag of each pedestal's response behind the force transmitted to it
/// [deg] in [−90, 270) per (bearing, direction), forces from the run's
/// bearing table.
pub fn phase_differences(run: &RunDir) -> Result<Vec<(ChannelKey, SpeedDegrees)>> {
    let schedules = run.bearing_schedules();
    let mut by: BTreeMap<ChannelKey, SpeedDegrees> = BTreeMap::new();
    for m in &run.measurements {
        let s = schedules
            .get(&m.bearing)
            .ok_or_else(|| anyhow!("no bearing coefficients for bearing {:?}", m.bearing))?;
        let k = s
            .at(m.speed_hz)
            .map_err(|e| anyhow!("bearing {:?} at {} Hz: {e}", m.bearing, m.speed_hz))?;
        let f = k.force(omega_from_hz(m.speed_hz), &m.rel);
        for (d, (x, fd)) in m.ped.iter().zip(f).enumerate() {
            by.entry((m.bearing.clone(), d))
                .or_default()
                .push((m.speed_hz, lag_for_plot(phase_lag_deg(*x, fd))));
        }
    }
    Ok(by
        .into_iter()
        .map(|(k, mut v)| {
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
            (k, v)
        })
        .collect())
}

/// Writes `amplitudes`, `phases` and `phase_difference` (.png and .svg) into
/// `dir`: `measured` is the run directory derived from the box's frames,
/// `truth` the noise-free simulation over the run's speed range. Returns the
/// files written.
pub fn write_figures(measured: &RunDir, truth: &RunDir, dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create the figures directory {}", dir.display()))?;
    let mut files = Vec::new();
    let panels = vec![
        panel("Rotor relative to pedestal", measured, truth, false),
        panel("Pedestal (absolute)", measured, truth, true),
    ];
    let fig = PhasorFigure {
        title: "1X response amplitudes: box-extracted (markers) vs simulated truth (lines)".into(),
        quantity: Quantity::DisplacementMicrons,
        view: PhasorView::Engineer(PhaseStyle::Wrapped),
        rows: Rows::First,
        panels,
        style: Default::default(),
    };
    files.extend(fig.write(&dir.join("amplitudes"))?);
    let fig = PhasorFigure {
        title: "1X response phase lags: box-extracted (markers) vs simulated truth (lines)".into(),
        rows: Rows::Second,
        ..fig
    };
    files.extend(fig.write(&dir.join("phases"))?);

    let mut series = Vec::new();
    let meas = phase_differences(measured)?;
    for ((b, d), pts) in phase_differences(truth)? {
        series.push(ScalarSeries {
            name: format!("{} truth", key(&b, d)),
            points: thin(&pts, MAX_LINE_POINTS),
            mark: Mark::Line,
        });
        if let Some((_, m)) = meas.iter().find(|(k, _)| k == &(b.clone(), d)) {
            series.push(ScalarSeries {
                name: format!("{} box", key(&b, d)),
                points: thin(m, MAX_MARKERS),
                mark: Mark::Markers,
            });
        }
    }
    let fig = ScalarFigure {
        title: "Phase lag of pedestal response behind transmitted force".into(),
        y_label: "Phase difference [deg]".into(),
        y_range: Some((-30.0, 210.0)),
        y_tick_step: Some(30.0),
        series,
        style: Default::default(),
    };
    files.extend(fig.write(&dir.join("phase_difference"))?);
    Ok(files)
}
