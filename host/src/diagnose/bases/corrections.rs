//! Corrections on top of a chosen base: screened with the base held,
//! settled jointly with its refit, tested by the drop of the refitted
//! base's χ², and checked backward the same way.

use super::held::{correction_slots, set_slot, slot_value, tuned_on_base, Slot};
use super::{carried_nonlinear, BaseOn};
use crate::diagnose::backward::Chosen;
use crate::diagnose::correct::corrections_only;
use crate::diagnose::criterion::{chi2_sf, Evidence};
use crate::diagnose::data::Prepared;
use crate::diagnose::forward::StepOutcome;
use crate::diagnose::foundation::FoundationFit;
use crate::diagnose::state::State;
use crate::diagnose::workflow::Options;

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
pub(in crate::diagnose) fn lr_test(tried: usize) -> String {
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
pub(in crate::diagnose) fn correction_on_base(
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
fn settled_on_base(
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
pub(in crate::diagnose) fn weakest_on_base(
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
