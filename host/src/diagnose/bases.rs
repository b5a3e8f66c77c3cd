//! The base candidates of a round: `foundation_coupling` and
//! `pedestal_sub_base` ([`super::foundation`]) fitted and tested on the data
//! the state's chosen corrections (runout, delays, table) correct.

use super::backward::Chosen;
use super::correct::{
    carrying_noise, corrected, corrected_on, corrections_only, mixes_channels, residual_noise,
};
use super::criterion::{chi2_sf, Evidence};
use super::data::Prepared;
use super::forward::StepOutcome;
use super::foundation::{self, FoundationFit};
use super::gap::Prediction;
use super::model::{Model, Nonlinear, Params, Term};
use super::state::{base_model, State};
use super::workflow::Options;
use anyhow::Result;
use nalgebra::{DMatrix, DVector};
use plinth_shared::regression::Parameter;

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

/// Candidates refitted with the base after the screening of
/// [`correction_on_base`].
const REFIT_BEST: usize = 2;

/// The best correction on top of a chosen base: every library candidate of
/// `outcome` that corrects the data (probe runout, sensor delay, a table's
/// clearance, pedestal cross-coupling: [`corrections_only`]) re-estimated
/// on the base ([`tuned_on_base`]: the rigid-ground values absorb the
/// base) and screened by the drop of the base's χ² with the base held;
/// the [`REFIT_BEST`] best significant ones are then estimated jointly with
/// the base ([`settled_on_base`]) and tested by the
/// drop of the refitted base's χ² against χ²(q), Bonferroni over every
/// candidate screened, Schwarz penalty. The held-base drop is at most the
/// refitted one, so the screening loses no candidate the test would pass.
///
/// The reference is the current model settled once more the same way
/// (the null, [`settled_on_base`] from the current corrections and base):
/// settling alternates between the corrections and the base and need not
/// have converged, and a candidate given another settling would otherwise
/// be credited with what that settling gains (a runout of 1e-10 m ± 1e-8
/// "lowering" the χ² by 38 after a base and a cross-coupling). Every
/// candidate starts from the null's values of the corrections it shares
/// with it.
///
/// Returns the number screened, the winner (its index in
/// `outcome.ranked`, its state, the refitted base and the evidence; `None`
/// when no candidate is significant) and the null when settling it lowered
/// the base's χ² (the current model to go on from).
#[allow(clippy::type_complexity)]
pub(super) fn correction_on_base(
    prep: &Prepared,
    state: &State,
    base: &BaseOn,
    outcome: &StepOutcome,
    opts: &Options,
) -> (
    usize,
    Option<(usize, State, BaseOn, Evidence)>,
    Option<(State, BaseOn)>,
) {
    let null = settled_on_base(prep, state, &base.fit, opts).filter(|(_, on)| on.chi2 < base.chi2);
    let (state, base) = match &null {
        Some((s, on)) => (s, on),
        None => (state, base),
    };
    let n = base.fit.prediction.chi2(&base.prep).1;
    // The null's corrections tuned on its base, held: the settling ends
    // with a base refit, after which the corrections it has are no longer
    // at their best; what tuning them gains is the null's, not a
    // candidate's. The null's χ² is the lower of the two.
    let (state, null_chi2) = match tuned_on_base(prep, state, &base.fit, opts) {
        (t, c) if c < base.chi2 => (t, c),
        _ => (state.clone(), base.chi2),
    };
    let state = &state;
    let tried: Vec<usize> = (0..outcome.ranked.len())
        .filter(|&i| corrections_only(&outcome.ranked[i].candidate.model))
        .collect();
    let q_of = |i: usize| outcome.ranked[i].candidate.null.len();
    let significant = |ev: &Evidence| ev.delta_bic > 0.0 && ev.p_adjusted < opts.alpha;
    let mut screened: Vec<(usize, State, Evidence)> = tried
        .iter()
        .filter_map(|&i| {
            let e = &outcome.ranked[i];
            let mut cstate = State {
                model: e.candidate.model.clone(),
                params: e.params.clone(),
                weights: state.weights.clone(),
            };
            carry_corrections(&mut cstate, state);
            let (tuned, chi2) = tuned_on_base(prep, &cstate, &base.fit, opts);
            let ev = lr_evidence(null_chi2 - chi2, q_of(i), tried.len(), n);
            significant(&ev).then_some((i, tuned, ev))
        })
        .collect();
    screened.sort_by(|a, b| b.2.delta_bic.total_cmp(&a.2.delta_bic));
    let mut best: Option<(usize, State, BaseOn, Evidence)> = None;
    for (i, tuned, _) in screened.into_iter().take(REFIT_BEST) {
        let Some((tuned, on)) = settled_on_base(prep, &tuned, &base.fit, opts) else {
            continue;
        };
        let ev = lr_evidence(null_chi2 - on.chi2, q_of(i), tried.len(), n);
        if significant(&ev) && best.as_ref().is_none_or(|b| ev.delta_bic > b.3.delta_bic) {
            best = Some((i, tuned, on, ev));
        }
    }
    (tried.len(), best, null)
}

/// The values of `from`'s corrections copied into the same corrections of
/// `to` (its other parameters kept).
fn carry_corrections(to: &mut State, from: &State) {
    for s in correction_slots(to) {
        let shared = match s {
            Slot::Term(i) => from
                .model
                .terms
                .iter()
                .position(|u| *u == to.model.terms[i])
                .map(Slot::Term),
            Slot::Nonlinear(k) => from
                .model
                .nonlinear
                .iter()
                .position(|q| *q == to.model.nonlinear[k])
                .map(Slot::Nonlinear),
        };
        if let Some(f) = shared {
            set_slot(to, s, slot_value(from, f));
        }
    }
}

/// Rounds of [`settled_on_base`], and the χ² drop [-] below which it stops.
const SETTLE_ROUNDS: usize = 4;
const SETTLE_DROP: f64 = 0.5;

/// The corrections of `state` and the base `fit` estimated jointly:
/// corrections re-estimated with the base held ([`tuned_on_base`]), the
/// base refitted on the data they correct, in turn, until the base's χ²
/// drops by less than [`SETTLE_DROP`]. A state compared before it settles
/// would credit the next correction with what settling gains. `None` when
/// the base cannot be refitted (or ends non-physical).
pub(super) fn settled_on_base(
    prep: &Prepared,
    state: &State,
    fit: &FoundationFit,
    opts: &Options,
) -> Option<(State, BaseOn)> {
    let (mut cur, _) = tuned_on_base(prep, state, fit, opts);
    let mut on = BaseOn::refit(prep, &cur, fit, opts)?;
    for _ in 1..SETTLE_ROUNDS {
        let (next, chi2) = tuned_on_base(prep, &cur, &on.fit, opts);
        if chi2.is_nan() || chi2 >= on.chi2 - SETTLE_DROP {
            break;
        }
        let Some(next_on) = BaseOn::refit(prep, &next, &on.fit, opts) else {
            break;
        };
        let settled = next_on.chi2 > on.chi2 - SETTLE_DROP;
        if next_on.chi2 < on.chi2 {
            cur = next;
            on = next_on;
        }
        if settled {
            break;
        }
    }
    Some((cur, on))
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
        let Some((without, on)) = settled_on_base(prep, &without, &base.fit, opts) else {
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

/// A parameter of a state that corrects the data: a linear term (runout,
/// cross-coupling) or a nonlinear scalar (a delay, a table's clearance).
#[derive(Clone, Copy, Debug)]
enum Slot {
    Term(usize),
    Nonlinear(usize),
}

/// The correcting parameters of `state` ([`super::correct::corrected`]).
fn correction_slots(state: &State) -> Vec<Slot> {
    let terms = state
        .model
        .terms
        .iter()
        .enumerate()
        .filter(|(_, t)| matches!(t, Term::Runout { .. } | Term::CrossStiffness { .. }))
        .map(|(i, _)| Slot::Term(i));
    let nl = state
        .model
        .nonlinear
        .iter()
        .enumerate()
        .filter(|(_, p)| {
            matches!(
                p,
                Nonlinear::Delay { .. }
                    | Nonlinear::Clearance { .. }
                    | Nonlinear::StiffnessRatio { .. }
            )
        })
        .map(|(k, _)| Slot::Nonlinear(k));
    terms.chain(nl).collect()
}

fn slot_value(state: &State, s: Slot) -> f64 {
    match s {
        Slot::Term(i) => state.params.beta[i],
        Slot::Nonlinear(k) => state.params.nl[k],
    }
}

fn set_slot(state: &mut State, s: Slot, v: f64) {
    match s {
        Slot::Term(i) => state.params.beta[i] = v,
        Slot::Nonlinear(k) => state.params.nl[k] = v,
    }
}

/// Finite-difference step of a correcting parameter: 1 % of its value,
/// at least a floor in its own unit (runout: 1e-3 of the largest runout
/// value [m]; cross-stiffness 1e3 N/m; delay 1e-6 s; a table's δ 1e-3).
fn slot_step(state: &State, s: Slot, runout_scale: f64) -> f64 {
    let v = slot_value(state, s).abs();
    let floor = match s {
        Slot::Term(i) => match state.model.terms[i] {
            Term::Runout { .. } => 1e-3 * runout_scale.max(1e-12),
            _ => 1e3,
        },
        Slot::Nonlinear(k) => match state.model.nonlinear[k] {
            Nonlinear::Delay { .. } => 1e-6,
            _ => 1e-3,
        },
    };
    (1e-2 * v).max(floor)
}

/// The pedestal-level χ² of the chosen base `fit`, its values held, on the
/// data `state` corrects ([`Prediction::chi2`]; ∞ when it cannot predict).
fn held_base_chi2(prep: &Prepared, state: &State, fit: &FoundationFit, opts: &Options) -> f64 {
    held_prediction(prep, state, fit, opts).map_or(f64::INFINITY, |(c, p)| p.chi2(&c).0)
}

/// The chosen base `fit`, its values held, predicting the pedestals on the
/// data `state` corrects on it, with each residual's noise carried through
/// the corrections when they mix the channels ([`residual_noise`]): the
/// corrected data and the prediction; `None` when it cannot predict.
fn held_prediction(
    prep: &Prepared,
    state: &State,
    fit: &FoundationFit,
    opts: &Options,
) -> Option<(Prepared, Prediction)> {
    let rigid = |c: &Prepared| rigid_prediction(c, state, &opts.base);
    let cprep = corrected_on(prep, state, Some(fit));
    if !mixes_channels(state) {
        let pred = fit.predict_on(&cprep, &rigid(&cprep))?;
        return Some((cprep, pred));
    }
    // The noise is carried from the measured numbers: the motion alone.
    let predict = |c: &Prepared| fit.motion_on(c, &rigid);
    let mut pred = predict(&cprep)?;
    pred.noise_var = residual_noise(prep, state, Some(fit), &predict)?;
    Some((cprep, pred))
}

/// Newton iterations of [`tuned_on_base`].
const TUNE_ITERATIONS: usize = 4;

/// The corrections of `state` re-estimated on a chosen base: the values the
/// rigid-ground fit gives them absorb what the base explains (a runout
/// fitted without the base bends to mimic the base's motion), so they are
/// moved to the minimum of the base's pedestal-level χ² with the base's
/// values held. Newton steps on a finite-difference gradient and Hessian
/// (exact for runout, in which the χ² is quadratic; nearly so for
/// cross-coupling, whose value also moves the residuals' noise,
/// [`residual_noise`]), each halved until the χ² falls. Returns the state and its χ².
pub(super) fn tuned_on_base(
    prep: &Prepared,
    state: &State,
    fit: &FoundationFit,
    opts: &Options,
) -> (State, f64) {
    let slots = correction_slots(state);
    let mut cur = state.clone();
    let mut f0 = held_base_chi2(prep, &cur, fit, opts);
    if slots.is_empty() || !f0.is_finite() {
        return (cur, f0);
    }
    let runout_scale = slots
        .iter()
        .filter(
            |s| matches!(s, Slot::Term(i) if matches!(state.model.terms[*i], Term::Runout { .. })),
        )
        .map(|&s| slot_value(state, s).abs())
        .fold(0.0, f64::max);
    let n = slots.len();
    for _ in 0..TUNE_ITERATIONS {
        let h: Vec<f64> = slots
            .iter()
            .map(|&s| slot_step(&cur, s, runout_scale))
            .collect();
        let eval = |moves: &[(usize, f64)]| {
            let mut s = cur.clone();
            for &(i, d) in moves {
                set_slot(&mut s, slots[i], slot_value(&cur, slots[i]) + d);
            }
            held_base_chi2(prep, &s, fit, opts)
        };
        let plus: Vec<f64> = (0..n).map(|i| eval(&[(i, h[i])])).collect();
        let minus: Vec<f64> = (0..n).map(|i| eval(&[(i, -h[i])])).collect();
        let mut g = DVector::zeros(n);
        let mut hess = DMatrix::zeros(n, n);
        for i in 0..n {
            g[i] = (plus[i] - minus[i]) / (2.0 * h[i]);
            hess[(i, i)] = (plus[i] - 2.0 * f0 + minus[i]) / (h[i] * h[i]);
            for j in 0..i {
                let both = eval(&[(i, h[i]), (j, h[j])]);
                let v = (both - plus[i] - plus[j] + f0) / (h[i] * h[j]);
                hess[(i, j)] = v;
                hess[(j, i)] = v;
            }
        }
        if !g.iter().chain(hess.iter()).all(|v| v.is_finite()) {
            break;
        }
        // A Newton step where the Hessian is positive definite, else a
        // gradient step scaled by its diagonal.
        let dx = match hess.clone().cholesky() {
            Some(ch) => -ch.solve(&g),
            None => DVector::from_iterator(
                n,
                (0..n).map(|i| -g[i] / hess[(i, i)].abs().max(f64::MIN_POSITIVE)),
            ),
        };
        let mut t = 1.0;
        let mut moved = false;
        for _ in 0..8 {
            let mut s = cur.clone();
            for (i, &sl) in slots.iter().enumerate() {
                set_slot(&mut s, sl, slot_value(&cur, sl) + t * dx[i]);
            }
            let f = held_base_chi2(prep, &s, fit, opts);
            if f < f0 {
                let gain = f0 - f;
                cur = s;
                f0 = f;
                moved = gain > 1e-3;
                break;
            }
            t *= 0.5;
        }
        if !moved {
            break;
        }
    }
    (cur, f0)
}
