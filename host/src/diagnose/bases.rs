//! The base candidates of a round: `foundation_coupling` and
//! `pedestal_sub_base` ([`super::foundation`]) fitted and tested on the data
//! the state's chosen corrections (runout, delays, table) correct.

use super::correct::corrected;
use super::data::Prepared;
use super::foundation::{self, FoundationFit};
use super::gap::Prediction;
use super::model::{Params, Term};
use super::state::{base_model, State};
use super::workflow::Options;
use anyhow::Result;

/// The base candidates of one round, fitted to the data the state corrects.
pub(super) struct BaseCandidates {
    /// The corrected data.
    pub(super) prep: Prepared,
    /// `foundation_coupling`, when it could be fitted.
    pub(super) shared: Option<FoundationFit>,
    /// `pedestal_sub_base`, when it could be fitted.
    pub(super) sub_base: Option<FoundationFit>,
}

/// Fits and tests both base models on the data `state` corrects, starting
/// from (and simulating the null from) the state's pedestals; on the base
/// model (`first`) from `plinth identify`'s fits, as before any effect.
pub(super) fn try_bases_on(
    prep: &Prepared,
    state: &State,
    opts: &Options,
    first: bool,
) -> Result<BaseCandidates> {
    let cprep = corrected(prep, state);
    let nb = prep.bearings.len();
    let start: Option<Vec<[f64; 5]>> = if first {
        None
    } else {
        let value = |t: Term| {
            state
                .model
                .terms
                .iter()
                .position(|u| *u == t)
                .map(|i| state.params.beta[i])
        };
        (0..nb)
            .map(|b| {
                Some([
                    value(Term::Stiffness { bearing: b, dir: 0 })?,
                    value(Term::Stiffness { bearing: b, dir: 1 })?,
                    value(Term::Mass {
                        bearing: b,
                        dir: None,
                    })?,
                    value(Term::Damping { bearing: b, dir: 0 })?,
                    value(Term::Damping { bearing: b, dir: 1 })?,
                ])
            })
            .collect()
    };
    if !first && start.is_none() {
        return Ok(BaseCandidates {
            prep: cprep,
            shared: None,
            sub_base: None,
        });
    }
    // The rigid model on the corrected data: the state less its corrections.
    let rigid = base_model(&opts.base, nb);
    let params = Params {
        beta: rigid
            .terms
            .iter()
            .map(|t| {
                state
                    .model
                    .terms
                    .iter()
                    .position(|u| u == t)
                    .map_or(0.0, |i| state.params.beta[i])
            })
            .collect(),
        nl: Vec::new(),
    };
    let pred = Prediction::new(&cprep, &rigid, &params);
    let gap = pred.gap(&cprep, None);
    // A base fit that cannot run is "not tried", not an error.
    let run = |kind| {
        foundation::evaluate(
            &cprep,
            &pred,
            gap,
            opts.alpha,
            opts.foundation_replicates,
            opts.foundation_seed,
            kind,
            start.clone(),
        )
        .ok()
        .flatten()
    };
    let shared = run(foundation::Kind::Shared);
    let sub_base = run(foundation::Kind::SubBase);
    Ok(BaseCandidates {
        prep: cprep,
        shared,
        sub_base,
    })
}
