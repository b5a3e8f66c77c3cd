//! Chosen and tried effects as report entries: the library test's name,
//! a candidate's summary and an effect's estimates as reported.

use super::candidates::Candidate;
use super::data::Prepared;
use super::forward::Evaluated;
use super::model::Model;
use super::report::{CandidateSummary, Estimate};
use super::state::State;
use crate::effects::EffectKind;
use anyhow::Result;

/// The name of the library's test, with the Bonferroni count.
pub(super) fn wald_test(tried: usize) -> String {
    format!("Wald, χ² with Bonferroni over {tried} candidates")
}

/// The candidate as a report entry (`tried`: candidates of its step).
pub(super) fn summary(prep: &Prepared, e: &Evaluated, tried: usize) -> CandidateSummary {
    CandidateSummary {
        effect: e.candidate.effect.name().to_string(),
        bearing: prep.bearings[e.candidate.bearing].clone(),
        channels: e.candidate.variant.clone(),
        test: wald_test(tried),
        evidence: e.evidence,
        parameters: as_reported(
            &e.candidate.model,
            e.candidate.bearing,
            e.candidate.effect,
            e.effect_parameters()
                .into_iter()
                .map(|(name, value, std_err)| Estimate {
                    name,
                    value,
                    std_err,
                })
                .collect(),
        ),
    }
}

/// An effect's estimates as reported: the clearance scalar δ of
/// `bearing_coefficients` as `clearance_ratio` = 1 + δ, with the written
/// and the true clearance [m]; its stiffness-ratio scalar δ as `k_scale` =
/// 1 + δ (the table's stiffness relative to its damping, `c_scale` held at
/// 1: `super::bearing_table`).
pub(super) fn as_reported(
    model: &Model,
    bearing: usize,
    effect: EffectKind,
    raw: Vec<Estimate>,
) -> Vec<Estimate> {
    if effect.name() != super::candidates::BEARING_COEFFICIENTS {
        return raw;
    }
    let table = model.tables.get(bearing).copied().flatten();
    let mut out = Vec::new();
    for e in raw {
        if e.name == "k_scale" {
            out.push(Estimate {
                name: e.name,
                value: 1.0 + e.value,
                std_err: e.std_err,
            });
        } else if let (Some(table), "clearance_ratio") = (table, e.name.as_str()) {
            let c_w = table.film.clearance;
            out.push(Estimate {
                name: e.name,
                value: 1.0 + e.value,
                std_err: e.std_err,
            });
            out.push(Estimate {
                name: "clearance_true".into(),
                value: c_w * (1.0 + e.value),
                std_err: c_w * e.std_err,
            });
            out.push(Estimate {
                name: "clearance_written".into(),
                value: c_w,
                std_err: 0.0,
            });
        } else {
            out.push(e);
        }
    }
    out
}

/// The effect's own parameters in a refitted state.
pub(super) fn effect_estimates(
    prep: &Prepared,
    state: &State,
    cand: &Candidate,
) -> Result<Vec<Estimate>> {
    let infs = state.inference(prep)?;
    let mut out = Vec::new();
    for (name, r) in &cand.parameters {
        for (_, inf, refs) in &infs {
            if let Some(i) = refs.iter().position(|x| x == r) {
                out.push(Estimate {
                    name: name.clone(),
                    value: inf.estimate[i],
                    std_err: inf.std_err(i),
                });
            }
        }
    }
    Ok(as_reported(&state.model, cand.bearing, cand.effect, out))
}
