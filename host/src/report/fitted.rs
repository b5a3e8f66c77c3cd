//! Measured-versus-fitted figures of an identification: for each bearing
//! the measured dynamic stiffness F/X_ped against the fitted rigid pedestal
//! ([`crate::plots::stiffness`]). The only place that reads identify's
//! types for a figure; `identify --plots DIR` and `plinth report` call it.

use crate::identify::{pedestal_points, Identification, PedestalFit};
use crate::plots::stiffness::{
    RigidPedestal, StiffnessFigure, StiffnessInput, StiffnessModel, Uncertainty,
};
use crate::plots::Style;
use crate::rundir::{Measurement, RunDir};
use anyhow::{anyhow, Result};
use std::path::{Path, PathBuf};

/// The rigid pedestal of a fit: its parameters and their covariance (the
/// standard errors alone when the fit gives no covariance: the band says
/// so).
pub fn rigid_pedestal(fit: &PedestalFit) -> RigidPedestal {
    RigidPedestal {
        pedestal: fit.pedestal,
        uncertainty: match fit.covariance {
            Some(c) => Uncertainty::Covariance(c),
            None => Uncertainty::StdErrors(fit.std_err.theta()),
        },
    }
}

/// The figure input of every pedestal of `identification` fitted on rigid
/// ground, with the measured forces from `run`'s bearing coefficients, and
/// a line for each pedestal left out (on a base: its model relates the
/// pedestal's motion relative to the base, which F/X_ped does not show).
pub fn stiffness_inputs(
    run: &RunDir,
    identification: &Identification,
) -> Result<(Vec<StiffnessInput>, Vec<String>)> {
    let schedules = run.bearing_schedules();
    let mut inputs = Vec::new();
    let mut skipped = Vec::new();
    for fit in &identification.pedestals {
        if let Some(base) = &fit.base {
            skipped.push(format!(
                "pedestal `{}` stands on base `{base}`: its measured-vs-fitted figure is not drawn (the fit is relative to the base's motion)",
                fit.bearing
            ));
            continue;
        }
        let schedule = schedules
            .get(&fit.bearing)
            .ok_or_else(|| anyhow!("bearing `{}` has no coefficients", fit.bearing))?;
        let rows: Vec<&Measurement> = run
            .measurements
            .iter()
            .filter(|m| m.bearing == fit.bearing)
            .collect();
        let points = pedestal_points(rows, schedule)
            .map_err(|e| anyhow!("bearing `{}`: {e}", fit.bearing))?;
        let measured = [0, 1].map(|d| {
            points
                .iter()
                .map(|p| (p.speed_hz, p.force()[d], p.ped[d]))
                .collect()
        });
        inputs.push(StiffnessInput {
            bearing: fit.bearing.clone(),
            measured,
            model: StiffnessModel::Rigid(rigid_pedestal(fit)),
            model_label: "fit k − Ω²m + iΩc".into(),
            note: if fit.trusted {
                String::new()
            } else {
                "UNTRUSTED".into()
            },
        });
    }
    Ok((inputs, skipped))
}

/// The figure of one bearing's input.
pub fn figure(input: StiffnessInput, style: Style) -> StiffnessFigure {
    StiffnessFigure {
        title: format!(
            "Pedestal {}: measured dynamic stiffness F/X vs the fitted model",
            input.bearing
        ),
        bearings: vec![input],
        style,
    }
}

/// `identify --plots DIR`: writes `stiffness_<bearing>.png/.svg` for every
/// pedestal into `dir` (created if needed; Plinth's earlier figures there
/// are replaced, other files never) and returns the files written; notes on
/// pedestals left out go to stderr.
pub fn write_identify_plots(
    dir: &Path,
    run: &RunDir,
    identification: &Identification,
    style: Style,
) -> Result<Vec<PathBuf>> {
    let (inputs, skipped) = stiffness_inputs(run, identification)?;
    for s in &skipped {
        eprintln!("note: {s}");
    }
    let mut names = Vec::new();
    crate::output::write_dir_as("--plots", dir, true, |staging| {
        for input in inputs {
            let stem = crate::names::file_in(staging, &format!("stiffness_{}", input.bearing));
            for f in figure(input, style).write(&stem)? {
                names.extend(f.file_name().map(|n| dir.join(n)));
            }
        }
        Ok(())
    })?;
    Ok(names)
}
