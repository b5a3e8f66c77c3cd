//! The base candidates of a round: `foundation_coupling` and
//! `pedestal_sub_base` ([`super::foundation`]) fitted and tested on the data
//! the state's chosen corrections (runout, delays, table) correct.

use super::backward::Chosen;
use super::correct::{corrected, corrections_only};
use super::criterion::{chi2_sf, Evidence};
use super::data::Prepared;
use super::forward::StepOutcome;
use super::foundation::{self, FoundationFit};
use super::gap::Prediction;
use super::model::{Model, Params, Term};
use super::state::{base_model, State};
use super::workflow::Options;
use anyhow::Result;
use plinth_shared::regression::Parameter;

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
    let pred = rigid_prediction(&cprep, state, &opts.base);
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

/// The rigid pedestal model's prediction on the corrected data `cprep`:
/// the state's pedestal values less its corrections.
fn rigid_prediction(cprep: &Prepared, state: &State, base: &[Parameter]) -> Prediction {
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
        let cprep = corrected(prep, state);
        let rigid = rigid_prediction(&cprep, state, &opts.base);
        let fit = base.refit(&cprep, &rigid)?;
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

/// Evidence of a correction from the drop of the base's pedestal-level χ²
/// (a likelihood ratio, `lr`) with `q` parameters: χ²(q), Bonferroni over
/// `tried`, Schwarz penalty q·ln N with `n` real equations.
fn lr_evidence(lr: f64, q: usize, tried: usize, n: usize) -> Evidence {
    let p_value = chi2_sf(lr, q);
    Evidence {
        wald_floor: lr,
        wald_robust: lr,
        wald: lr,
        extra_parameters: q,
        delta_bic: lr - q as f64 * (n.max(2) as f64).ln(),
        p_value,
        p_adjusted: (p_value * tried.max(1) as f64).min(1.0),
    }
}

/// The name of the test of a correction on top of a base.
pub(super) fn lr_test(tried: usize) -> String {
    format!("likelihood ratio with the base refitted, χ² with Bonferroni over {tried} candidates")
}

/// The best correction on top of a chosen base: every library candidate of
/// `outcome` that corrects the data (probe runout, sensor delay, a table's
/// clearance, pedestal cross-coupling: [`corrections_only`]) applied with
/// its values from the rigid-model fit, the base refitted to the corrected
/// data, and tested by the drop of the base's χ². Rigid-model values are
/// not the joint maximum-likelihood ones, so the drop is at most the
/// likelihood ratio: the test is conservative. Returns the candidate's
/// index in `outcome.ranked`, its state, the refitted base and the
/// evidence; `None` when no candidate is significant.
pub(super) fn correction_on_base(
    prep: &Prepared,
    state: &State,
    base: &BaseOn,
    outcome: &StepOutcome,
    opts: &Options,
) -> (usize, Option<(usize, State, BaseOn, Evidence)>) {
    let n = base.fit.prediction.chi2(&base.prep).1;
    let tried: Vec<usize> = (0..outcome.ranked.len())
        .filter(|&i| corrections_only(&outcome.ranked[i].candidate.model))
        .collect();
    let mut best: Option<(usize, State, BaseOn, Evidence)> = None;
    for &i in &tried {
        let e = &outcome.ranked[i];
        let cstate = State {
            model: e.candidate.model.clone(),
            params: e.params.clone(),
            weights: state.weights.clone(),
        };
        let Some(on) = BaseOn::refit(prep, &cstate, &base.fit, opts) else {
            continue;
        };
        let ev = lr_evidence(base.chi2 - on.chi2, e.candidate.null.len(), tried.len(), n);
        if ev.delta_bic > 0.0
            && ev.p_adjusted < opts.alpha
            && best.as_ref().is_none_or(|b| ev.delta_bic > b.3.delta_bic)
        {
            best = Some((i, cstate, on, ev));
        }
    }
    (tried.len(), best)
}

/// The backward check on top of a base: each chosen correction removed in
/// turn (the rest refitted, the base refitted) must still lower the base's
/// χ² significantly (Bonferroni over the corrections checked). Returns the
/// weakest that no longer does, with its evidence.
pub(super) fn weakest_on_base(
    prep: &Prepared,
    state: &State,
    base: &BaseOn,
    chosen: &[Chosen],
    opts: &Options,
) -> Option<(usize, Evidence, State, BaseOn)> {
    let n = base.fit.prediction.chi2(&base.prep).1;
    let mut weakest: Option<(usize, Evidence, State, BaseOn)> = None;
    for (i, c) in chosen.iter().enumerate() {
        let model = c.removed_from(&state.model);
        let nl = carried_nonlinear(&model, state);
        let Ok(without) = State::fit(prep, model, nl) else {
            continue;
        };
        let Some(on) = BaseOn::refit(prep, &without, &base.fit, opts) else {
            continue;
        };
        let ev = lr_evidence(on.chi2 - base.chi2, c.null_len(), chosen.len(), n);
        let still = ev.delta_bic > 0.0 && ev.p_adjusted < opts.alpha;
        if !still
            && weakest
                .as_ref()
                .is_none_or(|(_, w, _, _)| ev.p_value > w.p_value)
        {
            weakest = Some((i, ev, without, on));
        }
    }
    weakest
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
