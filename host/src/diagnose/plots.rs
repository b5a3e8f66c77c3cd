//! Measured-versus-predicted figures of the diagnosis, drawn with the
//! project's figure code (`crate::plots`), PNG and SVG: at pedestal level
//! the dynamic stiffness F/X as `identify --plots` draws it
//! ([`crate::plots::stiffness`]), at machine level the 1X phasors in the
//! paper's conventions (peak-to-peak µm, phase lag in degrees).

use super::data::Prepared;
use super::gap::Prediction;
use super::machine::Readings;
use super::workflow::Outcome;
use crate::plots::stiffness::{StiffnessFigure, StiffnessInput, StiffnessModel};
use crate::plots::{
    PhaseStyle, PhasorFigure, PhasorPanel, PhasorSeries, PhasorView, Quantity, Rows, Style,
};
use anyhow::{Context, Result};
use num_complex::Complex;
use std::path::{Path, PathBuf};

const DIRS: [&str; 2] = ["y", "z"];

/// The stiffness figure's input of bearing `b`: measured (speed, F, X_ped)
/// with F = K*·rel, and the model's dynamic stiffness F/X_predicted at each
/// measured speed (the model with its effects maps the measured forces to
/// the predicted pedestal motion).
fn stiffness_input(prep: &Prepared, pred: &Prediction, b: usize, label: &str) -> StiffnessInput {
    let mut measured: [crate::plots::stiffness::MeasuredStiffness; 2] = [Vec::new(), Vec::new()];
    let mut model: [Vec<(f64, Complex<f64>)>; 2] = [Vec::new(), Vec::new()];
    for (j, p) in prep.points[b].iter().enumerate() {
        let Some(p) = p else { continue };
        let force = crate::estimate::mul(&p.kstar, &p.rel);
        for d in 0..2 {
            measured[d].push((p.speed_hz, force[d], p.ped[d]));
            if let Some(Some(x)) = pred.ped[b].get(j) {
                let dyn_stiffness = force[d] / x[d];
                if dyn_stiffness.re.is_finite() && dyn_stiffness.im.is_finite() {
                    model[d].push((p.speed_hz, dyn_stiffness));
                }
            }
        }
    }
    StiffnessInput {
        bearing: prep.bearings[b].clone(),
        measured,
        model: StiffnessModel::Points(model),
        model_label: label.to_string(),
        note: String::new(),
    }
}

/// The pedestal-level figures of a diagnosis, (stem, figure):
/// `pedestal_before` and `pedestal_after`, each bearing's measured dynamic
/// stiffness F/X_ped against the model's (F over the pedestal motion the
/// model predicts from the measured forces) and the residual, one column per
/// bearing, drawn as `identify --plots` draws it.
pub fn pedestal_figures(outcome: &Outcome) -> Vec<(&'static str, StiffnessFigure)> {
    let prep = &outcome.prep;
    let (Some(first), Some(last)) = (outcome.states.first(), outcome.states.last()) else {
        return Vec::new();
    };
    [
        ("pedestal_before", first, "base model"),
        ("pedestal_after", last, "with the effects"),
    ]
    .into_iter()
    .map(|(stem, state, label)| {
        let pred = Prediction::new(prep, &state.model, &state.params);
        let bearings = (0..prep.bearings.len())
            .map(|b| stiffness_input(prep, &pred, b, label))
            .collect();
        (
            stem,
            StiffnessFigure {
                title: format!("Pedestal dynamic stiffness F/X: measured vs the {label}"),
                bearings,
                style: Style::default(),
            },
        )
    })
    .collect()
}

/// Writes [`pedestal_figures`] into `dir`; returns the files written.
pub fn write_pedestal_figures(outcome: &Outcome, dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut files = Vec::new();
    for (stem, fig) in pedestal_figures(outcome) {
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
                quantity: None,
            });
        }
    }
    let fig = PhasorFigure {
        title: format!("Machine re-simulated with the identified pedestals ({label})"),
        quantity: Quantity::DisplacementMicrons,
        view: PhasorView::Engineer(PhaseStyle::Wrapped),
        rows: Rows::Both,
        panels,
        style: Default::default(),
    };
    Ok(fig.write(&dir.join(stem))?.to_vec())
}
