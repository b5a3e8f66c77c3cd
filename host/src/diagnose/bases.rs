//! The base candidates of a round: `foundation_coupling` and
//! `pedestal_sub_base` ([`super::foundation`]) fitted and tested on the data
//! the state's chosen corrections (runout, delays, table) correct, and
//! the corrections tested on top of a chosen base ([`corrections`]), each
//! re-estimated with the base held ([`held`]).

use super::correct::{carrying_noise, corrected, corrected_on, mixes_channels, residual_noise};
use super::data::Prepared;
use super::foundation::{self, FoundationFit};
use super::gap::Prediction;
use super::model::{Model, Params, Term};
use super::state::{base_model, State};
use super::workflow::Options;
use anyhow::Result;
use plinth_shared::regression::Parameter;

pub(super) use corrections::{correction_on_base, lr_test, weakest_on_base};
pub(super) use joint::{
    joint_on_base, scale_to_misfit, widen_by_corrections, CarriedVariance, JointCorrections,
};

mod corrections;
mod held;
mod joint;

/// The base candidates of one round, fitted to the data the state corrects.
pub(super) struct BaseCandidates {
    /// The corrected data.
    pub(super) prep: Prepared,
    /// `foundation_coupling`, when it could be fitted (not yet tested).
    pub(super) shared: Option<foundation::Fitted>,
    /// `pedestal_sub_base`, when it could be fitted (not yet tested).
    pub(super) sub_base: Option<foundation::Fitted>,
}

/// Fits both base models on the data `state` corrects, starting
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
    let mut pred = rigid_prediction(&cprep, state, &opts.base);
    // A cross-coupling chosen on rigid ground mixes the channels: the base
    // fits and their test weight each residual by the noise the correction
    // carries into it (`carrying_noise`), the rigid model's gap is judged
    // with it.
    let cprep = if mixes_channels(state) {
        let rigid = |c: &Prepared| Some(rigid_prediction(c, state, &opts.base));
        match residual_noise(prep, state, None, &rigid) {
            Some(carried) => {
                let weighted = carrying_noise(&cprep, &pred, &carried);
                pred.noise_var = carried;
                weighted
            }
            None => cprep,
        }
    } else {
        cprep
    };
    let gap = pred.gap(&cprep, None);
    // A base fit that cannot run is "not tried", not an error.
    let run = |kind| {
        foundation::fit(&cprep, &pred, gap, kind, start.clone())
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

/// The rigid pedestal model's prediction on the corrected data `cprep`:
/// the state's pedestal values less its corrections.
pub(super) fn rigid_prediction(cprep: &Prepared, state: &State, base: &[Parameter]) -> Prediction {
    let rigid = base_model(base, cprep.bearings.len());
    let params = Params {
        beta: carried_linear(&rigid, state),
        nl: Vec::new(),
    };
    Prediction::new(cprep, &rigid, &params)
}

/// A chosen base refitted on the data a state corrects.
#[derive(Clone, Debug)]
pub(super) struct BaseOn {
    /// The corrected data.
    pub(super) prep: Prepared,
    /// The base refitted to them.
    pub(super) fit: FoundationFit,
    /// Its pedestal-level χ² and real equations ([`Prediction::chi2`]).
    pub(super) chi2: f64,
}

impl BaseOn {
    /// `base` refitted on the data `state` corrects; `None` when the fit
    /// fails or ends non-physical.
    pub(super) fn refit(
        prep: &Prepared,
        state: &State,
        base: &FoundationFit,
        opts: &Options,
    ) -> Option<Self> {
        let cprep = corrected_on(prep, state, Some(base));
        let rigid = rigid_prediction(&cprep, state, &opts.base);
        let rigid_of = |c: &Prepared| rigid_prediction(c, state, &opts.base);
        let mixing = mixes_channels(state);
        // The refit weights each residual by the noise the correction
        // carries into it (at the base held), not by the corrected numbers'
        // as if measured.
        let weighted = if mixing {
            let own = base.predict_on(&cprep, &rigid)?;
            let held = |c: &Prepared| base.motion_on(c, &rigid_of);
            let carried = residual_noise(prep, state, Some(base), &held)?;
            carrying_noise(&cprep, &own, &carried)
        } else {
            cprep.clone()
        };
        let mut fit = base.refit(&weighted, &rigid)?;
        if mixing {
            let predict = |c: &Prepared| fit.motion_on(c, &rigid_of);
            let noise = residual_noise(prep, state, Some(base), &predict)?;
            fit.prediction.noise_var = noise;
            fit.gap = fit.prediction.gap(&cprep, None);
        }
        let (chi2, _) = fit.prediction.chi2(&cprep);
        Some(Self {
            prep: cprep,
            fit,
            chi2,
        })
    }

    /// This base as fitted (its data and χ²).
    pub(super) fn of(prep: Prepared, fit: FoundationFit) -> Self {
        let (chi2, _) = fit.prediction.chi2(&prep);
        Self { prep, fit, chi2 }
    }
}

/// The linear values of `state` carried over to `model`'s terms (0 for new
/// ones).
pub(super) fn carried_linear(model: &Model, state: &State) -> Vec<f64> {
    model
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
        .collect()
}

/// The nonlinear values of `state` carried over to `model` (0 for new ones).
pub(super) fn carried_nonlinear(model: &Model, state: &State) -> Vec<f64> {
    model
        .nonlinear
        .iter()
        .map(|p| {
            state
                .model
                .nonlinear
                .iter()
                .position(|q| q == p)
                .map_or(0.0, |k| state.params.nl[k])
        })
        .collect()
}
