//! Measured-versus-predicted figures of the diagnosis, in the conventions of
//! the paper's figures (peak-to-peak µm, phase lag in degrees, speed in Hz),
//! drawn with the project's figure code (`crate::plots`), PNG and SVG.

use super::data::Prepared;
use super::gap::Prediction;
use super::machine::Readings;
use super::workflow::Outcome;
use crate::plots::{
    PhaseStyle, PhasorFigure, PhasorPanel, PhasorSeries, PhasorView, Quantity, Rows,
};
use anyhow::{Context, Result};
use num_complex::Complex;
use std::path::{Path, PathBuf};

const DIRS: [&str; 2] = ["y", "z"];

fn measured_ped(prep: &Prepared, b: usize, d: usize) -> Vec<(f64, Complex<f64>)> {
    prep.points[b]
        .iter()
        .flatten()
        .map(|p| (p.speed_hz, p.ped[d]))
        .collect()
}

fn predicted_ped(
    prep: &Prepared,
    pred: &Prediction,
    b: usize,
    d: usize,
) -> Vec<(f64, Complex<f64>)> {
    pred.ped[b]
        .iter()
        .enumerate()
        .filter_map(|(j, x)| x.map(|x| (prep.speeds_hz[j], x[d])))
        .collect()
}

/// Writes `pedestal_before` and `pedestal_after` (pedestal level: measured
/// pedestal response against the response predicted from the measured
/// forces, one column per bearing) into `dir`; returns the files written.
pub fn write_pedestal_figures(outcome: &Outcome, dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let prep = &outcome.prep;
    let mut files = Vec::new();
    let (Some(first), Some(last)) = (outcome.states.first(), outcome.states.last()) else {
        return Ok(files);
    };
    for (stem, state, label) in [
        ("pedestal_before", first, "base model"),
        ("pedestal_after", last, "with the effects added"),
    ] {
        let pred = Prediction::new(prep, &state.model, &state.params);
        let panels = prep
            .bearings
            .iter()
            .enumerate()
            .map(|(b, name)| {
                let mut series = Vec::new();
                for (d, dir) in DIRS.iter().enumerate() {
                    series.push(PhasorSeries::markers(
                        format!("{name} {dir} measured"),
                        measured_ped(prep, b, d),
                    ));
                    series.push(PhasorSeries::line(
                        format!("{name} {dir} predicted"),
                        predicted_ped(prep, &pred, b, d),
                    ));
                }
                PhasorPanel {
                    title: format!("Pedestal {name}"),
                    series,
                }
            })
            .collect();
        let fig = PhasorFigure {
            title: format!(
                "Pedestal response: measured vs predicted from the measured forces ({label})"
            ),
            quantity: Quantity::DisplacementMicrons,
            view: PhasorView::Engineer(PhaseStyle::Wrapped),
            rows: Rows::Both,
            panels,
        };
        files.extend(fig.write(&dir.join(stem))?);
    }
    Ok(files)
}

/// Writes a machine-level figure `stem` (measured rel and ped channels
/// against the re-simulated machine) into `dir`.
pub fn write_machine_figure(
    prep: &Prepared,
    readings: &Readings,
    dir: &Path,
    stem: &str,
    label: &str,
) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut panels = Vec::new();
    for (b, name) in prep.bearings.iter().enumerate() {
        for (kind, pick) in [("rotor (relative)", 0usize), ("pedestal", 1usize)] {
            let mut series = Vec::new();
            for d in 0..2 {
                let meas: Vec<_> = prep.points[b]
                    .iter()
                    .flatten()
                    .map(|p| (p.speed_hz, if pick == 0 { p.rel[d] } else { p.ped[d] }))
                    .collect();
                let sim: Vec<_> = readings[b]
                    .iter()
                    .enumerate()
                    .filter_map(|(j, r)| {
                        r.map(|(rel, ped)| {
                            (prep.speeds_hz[j], if pick == 0 { rel[d] } else { ped[d] })
                        })
                    })
                    .collect();
                series.push(PhasorSeries::markers(
                    format!("{name} {} measured", DIRS[d]),
                    meas,
                ));
                series.push(PhasorSeries::line(
                    format!("{name} {} simulated", DIRS[d]),
                    sim,
                ));
            }
            panels.push(PhasorPanel {
                title: format!("{name}: {kind}"),
                series,
            });
        }
    }
    let fig = PhasorFigure {
        title: format!("Machine re-simulated with the identified pedestals ({label})"),
        quantity: Quantity::DisplacementMicrons,
        view: PhasorView::Engineer(PhaseStyle::Wrapped),
        rows: Rows::Both,
        panels,
    };
    Ok(fig.write(&dir.join(stem))?.to_vec())
}
