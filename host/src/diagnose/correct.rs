//! The measurements as a diagnosis state corrects them: probe runout removed
//! from `rel`, sensor delays undone, a bearing table's clearance correction
//! added to the bearing coefficients K*, pedestal cross-coupling taken off
//! the bearing force, so that a base can be fitted to data the chosen
//! corrections explain.

use super::data::Prepared;
use super::model::{Model, Nonlinear, Term};
use super::state::State;
use num_complex::Complex;

/// Whether every effect of `model` beyond the pedestal's own parameters is
/// a correction of the data (probe runout, sensor delay, a bearing table's
/// clearance): then a base can be fitted to the corrected data.
pub(super) fn corrections_only(model: &Model) -> bool {
    model.terms.iter().all(|t| {
        let split_mass = matches!(t, Term::Mass { dir: Some(_), .. });
        (t.is_pedestal() && !split_mass)
            || matches!(t, Term::Runout { .. } | Term::CrossStiffness { .. })
    }) && model
        .nonlinear
        .iter()
        .all(|p| !matches!(p, Nonlinear::LossFactor { .. }))
}

/// The measurements as `state` corrects them: runout removed from `rel`,
/// delays undone, a bearing table's clearance correction added to K*.
pub fn corrected(prep: &Prepared, state: &State) -> Prepared {
    let mut out = prep.clone();
    let value = |t: Term| {
        state
            .model
            .terms
            .iter()
            .position(|u| *u == t)
            .map_or(0.0, |i| state.params.beta[i])
    };
    for (b, row) in out.points.iter_mut().enumerate() {
        let runout: [Complex<f64>; 2] = std::array::from_fn(|dir| {
            Complex::new(
                value(Term::Runout {
                    bearing: b,
                    dir,
                    imag: false,
                }),
                value(Term::Runout {
                    bearing: b,
                    dir,
                    imag: true,
                }),
            )
        });
        for p in row.iter_mut().flatten() {
            for (k, nl) in state.model.nonlinear.iter().enumerate() {
                let v = state.params.nl[k];
                match *nl {
                    Nonlinear::Delay { bearing, channels } if bearing == b => {
                        let f = Complex::from_polar(1.0, p.omega() * v);
                        for d in 0..2 {
                            if channels.ped[d] {
                                p.ped[d] *= f;
                            }
                            if channels.rel[d] {
                                p.rel[d] *= f;
                            }
                        }
                    }
                    Nonlinear::Clearance { bearing } if bearing == b => {
                        let corr = state
                            .model
                            .tables
                            .get(b)
                            .copied()
                            .flatten()
                            .and_then(|t| t.correction(p.speed_hz, v));
                        if let Some(corr) = corr {
                            for (k_row, c_row) in p.kstar.iter_mut().zip(corr) {
                                for (k, c) in k_row.iter_mut().zip(c_row) {
                                    *k += c;
                                }
                            }
                        }
                    }
                    _ => {}
                }
            }
            for (rel, r) in p.rel.iter_mut().zip(runout) {
                *rel -= r;
            }
            // Pedestal cross-coupling k_yz as a force correction:
            // F' = F − k_yz·(X_z, X_y), carried into rel through K*⁻¹.
            let k_yz = value(Term::CrossStiffness { bearing: b });
            if k_yz != 0.0 {
                let k = p.kstar;
                let det = k[0][0] * k[1][1] - k[0][1] * k[1][0];
                if det.norm() > 0.0 {
                    let df = [p.ped[1] * k_yz, p.ped[0] * k_yz];
                    p.rel[0] -= (k[1][1] * df[0] - k[0][1] * df[1]) / det;
                    p.rel[1] -= (k[0][0] * df[1] - k[1][0] * df[0]) / det;
                }
            }
        }
    }
    out
}
