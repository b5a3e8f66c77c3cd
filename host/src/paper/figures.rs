//! The paper's figures (Figs. 3-9): response amplitudes and phases, the
//! pedestal's phase lag behind its force, and the re-prediction (Fig. 6),
//! PNG and SVG.

use super::*;
use crate::plots::{
    phase_lag_deg, Mark, PhaseStyle, PhasorFigure, PhasorPanel, PhasorSeries, PhasorView, Quantity,
    Rows, ScalarFigure, ScalarSeries,
};
use crate::rundir::{Measurement, RunDir};
use anyhow::{anyhow, Result};
use num_complex::Complex;
use plinth_shared::phasor::omega_from_hz;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Short label of a bearing for legends: `left` → `L`, `right` → `R`,
/// anything else as is.
pub(super) fn short(bearing: &str) -> String {
    match bearing {
        "left" => "L".into(),
        "right" => "R".into(),
        b => format!("{b} "),
    }
}

/// (speed [Hz], phasor [m]) points of one channel.
pub(super) type SpeedPhasors = Vec<(f64, Complex<f64>)>;

/// Series of one quantity per (bearing, direction): `Ly`, `Lz`, `Ry`, `Rz`,
/// each with its direction index (0 = y, 1 = z).
pub(super) fn channel_series(
    rows: &[Measurement],
    ped: bool,
    mark: Mark,
    suffix: &str,
) -> Vec<(usize, PhasorSeries)> {
    let mut by: BTreeMap<(usize, String, usize), SpeedPhasors> = BTreeMap::new();
    let mut order: Vec<String> = Vec::new();
    for m in rows {
        if !order.contains(&m.bearing) {
            order.push(m.bearing.clone());
        }
        let bi = order.iter().position(|b| *b == m.bearing).unwrap_or(0);
        let v = if ped { m.ped } else { m.rel };
        for (d, x) in v.iter().enumerate() {
            by.entry((bi, m.bearing.clone(), d))
                .or_default()
                .push((m.speed_hz, *x));
        }
    }
    by.into_iter()
        .map(|((_, b, d), points)| {
            (
                d,
                PhasorSeries {
                    name: format!("{}{}{suffix}", short(&b), if d == 0 { "y" } else { "z" }),
                    points,
                    mark,
                },
            )
        })
        .collect()
}

/// Phase lag of each pedestal's response behind the force transmitted to it
/// [deg] per (bearing, direction).
pub(super) fn phase_difference_series(run: &RunDir) -> Result<Vec<ScalarSeries>> {
    let schedules = run.bearing_schedules();
    let mut by: BTreeMap<(String, usize), Vec<(f64, f64)>> = BTreeMap::new();
    for m in &run.measurements {
        let s = schedules
            .get(&m.bearing)
            .ok_or_else(|| anyhow!("no bearing coefficients for {:?}", m.bearing))?;
        let k = s.at(m.speed_hz).map_err(|e| anyhow!("{e}"))?;
        let f = k.force(omega_from_hz(m.speed_hz), &m.rel);
        for (d, (x, fd)) in m.ped.iter().zip(f).enumerate() {
            by.entry((m.bearing.clone(), d))
                .or_default()
                .push((m.speed_hz, phase_lag_deg(*x, fd)));
        }
    }
    Ok(by
        .into_iter()
        .map(|((b, d), points)| ScalarSeries {
            name: format!("{}{}", short(&b), if d == 0 { "y" } else { "z" }),
            points,
            mark: Mark::Line,
        })
        .collect())
}

pub(super) fn response_panels(run: &RunDir) -> Vec<PhasorPanel> {
    vec![
        PhasorPanel {
            title: "Rotor relative to pedestal".into(),
            series: channel_series(&run.measurements, false, Mark::Line, "")
                .into_iter()
                .map(|(_, s)| s)
                .collect(),
            quantity: None,
        },
        PhasorPanel {
            title: "Pedestal (absolute)".into(),
            series: channel_series(&run.measurements, true, Mark::Line, "")
                .into_iter()
                .map(|(_, s)| s)
                .collect(),
            quantity: None,
        },
    ]
}

/// Keeps about `n` evenly spaced points of a series (markers stay legible).
pub(super) fn thin(points: Vec<(f64, Complex<f64>)>, n: usize) -> Vec<(f64, Complex<f64>)> {
    let step = points.len().div_ceil(n.max(1)).max(1);
    points.into_iter().step_by(step).collect()
}

/// Writes every figure into `dir`; returns the files written.
pub fn write_figures(paper: &Paper, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let case_label = |case: DampingCase| {
        paper
            .tables
            .table2_cases
            .iter()
            .find(|c| c.case == case)
            .map(|c| {
                format!(
                    "c ≠ 0: scan's c ×{}, ζ ≈ {:.2} %",
                    c.damping_scale,
                    100.0 * c.mean_damping_ratio()
                )
            })
            .unwrap_or_else(|| "c ≠ 0".into())
    };
    let (scan_label, heavy_label) = (
        case_label(DampingCase::ScanDamping),
        case_label(DampingCase::HeavyDamping),
    );
    let cases = [
        (&paper.undamped, "c = 0", ["fig3", "fig4", "fig5"], ""),
        (
            &paper.damped,
            scan_label.as_str(),
            ["fig7", "fig8", "fig9"],
            "",
        ),
        (
            &paper.heavily_damped,
            heavy_label.as_str(),
            ["fig7", "fig8", "fig9"],
            "_heavy_damping",
        ),
    ];
    for (run, case, [amp, phase, diff], suffix) in cases {
        let fig = PhasorFigure {
            title: format!("Response amplitudes at the measurement points ({case})"),
            quantity: Quantity::DisplacementMicrons,
            view: PhasorView::Engineer(PhaseStyle::Wrapped),
            rows: Rows::First,
            panels: response_panels(run),
            style: Default::default(),
        };
        files.extend(fig.write(&dir.join(format!("{amp}_amplitudes{suffix}")))?);
        let fig = PhasorFigure {
            title: format!("Response phase lags at the measurement points ({case})"),
            rows: Rows::Second,
            ..fig
        };
        files.extend(fig.write(&dir.join(format!("{phase}_phases{suffix}")))?);
        let fig = ScalarFigure {
            title: format!("Phase lag of pedestal response behind transmitted force ({case})"),
            y_label: "Phase difference [deg]".into(),
            y_range: Some((-30.0, 210.0)),
            y_tick_step: Some(30.0),
            series: phase_difference_series(run)?,
            style: Default::default(),
        };
        files.extend(fig.write(&dir.join(format!("{diff}_phase_difference{suffix}")))?);
    }

    let mut series = Vec::new();
    let measured = channel_series(
        &paper.undamped_truncated.measurements,
        false,
        Mark::Markers,
        " measured",
    );
    let predicted = channel_series(&paper.repredicted, false, Mark::Line, " predicted");
    for ((d, m), (_, p)) in measured.into_iter().zip(predicted) {
        if d == 0 {
            series.push(PhasorSeries {
                points: thin(m.points, 40),
                ..m
            });
            series.push(p);
        }
    }
    let fig = PhasorFigure {
        title: format!(
            "Rotor response, y: measured ({} digits) vs re-predicted; {}",
            paper.fig6_digits,
            gap_caption(paper)
        ),
        quantity: Quantity::DisplacementMicrons,
        view: PhasorView::Engineer(PhaseStyle::Wrapped),
        rows: Rows::Both,
        panels: vec![PhasorPanel {
            title: "Rotor relative to pedestal, y".into(),
            series,
            quantity: None,
        }],
        style: Default::default(),
    };
    files.extend(fig.write(&dir.join("fig6_measured_vs_predicted"))?);
    Ok(files)
}

/// Short text of the Fig. 6 gap: "gap RMS 44 %, max 65 %, mostly at 27, 45 Hz".
pub(super) fn gap_caption(paper: &Paper) -> String {
    let o = &paper.reprediction.overall;
    let mut s = format!(
        "gap RMS {:.0} %, max {:.0} %",
        o.rms_rel * 100.0,
        o.max_rel * 100.0
    );
    let bands = &paper.reprediction_gap.bands;
    if !bands.is_empty() {
        let share: f64 = bands.iter().map(|b| b.share).sum();
        let mut at: Vec<f64> = bands.iter().map(|b| b.speed_hz).collect();
        at.sort_by(f64::total_cmp);
        let at: Vec<String> = at.iter().map(|f| f.to_string()).collect();
        // Floor: never print 100 % for 99.9 %.
        s += &format!(
            ", {:.0} % of it within {GAP_HALF_WIDTH_HZ} Hz of {} Hz",
            (share * 100.0).floor(),
            at.join(", ")
        );
    }
    s
}
