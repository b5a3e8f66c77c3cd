//! [`freed_held`] on ROSS 2.3.0's runs (tests/data, not this crate's
//! model): a 150 µs delay on a bearing's rel probes, which reads as a
//! damping −τ·k, so the base fit's dampings there come out impossible.

use super::*;
use crate::diagnose::test_runs::stored;
use crate::effects::EffectKind;
use plinth_shared::regression::Parameter;

/// The base state of `prep`, bearing `name`'s index and its dampings,
/// checked impossible on the base fit (what makes the search hold them).
fn base_with_impossible(prep: &Prepared, name: &str) -> (State, usize, Vec<Term>) {
    let before = State::base(prep, Parameter::ALL.as_slice()).expect("base state");
    let b = prep.bearing_index(name).expect("bearing");
    let dampings: Vec<Term> = (0..2)
        .map(|dir| Term::Damping { bearing: b, dir })
        .collect();
    let impossible = non_physical_dampings(prep, &before);
    assert!(
        dampings.iter().all(|t| impossible.contains(t)),
        "the delay should read as impossible dampings: {impossible:?}"
    );
    (before, b, dampings)
}

/// The joint refit with the rel delay at `left`, its dampings held at zero
/// (the step's held variant, as `library_winner` refits it).
fn held_delay(prep: &Prepared, before: &State, left: usize, held: &[Term]) -> State {
    let cand = library(&before.model, prep.bearings.len())
        .into_iter()
        .find(|c| {
            c.effect == EffectKind::SensorDelay
                && c.bearing == left
                && c.variant.as_deref() == Some("rel")
        })
        .expect("the rel delay candidate");
    let cand = held_at_zero(&cand, held).expect("its held variant");
    let e = evaluate(prep, before, cand, 1, prep.real_equations()).expect("evaluated");
    State::fit(prep, e.candidate.model.clone(), e.params.nl.clone()).expect("joint refit")
}

fn damping(state: &State, t: Term) -> Option<f64> {
    let i = state.model.terms.iter().position(|u| *u == t)?;
    state.params.beta.get(i).copied()
}

/// Third unseen machine, seed 51 (B2: c_y 6000, c_z 4000 N·s/m, c/k 43
/// and 50 µs): freed, the dampings are physical and supported, and τ
/// (held: a lower bound, 65 µs) comes back to the truth.
#[test]
fn a_physical_supported_damping_is_freed() {
    let prep = stored("ross-unseen-3/delay-51");
    let (before, b, held) = base_with_impossible(&prep, "B2");
    let next = held_delay(&prep, &before, b, &held);
    let tau_held = next.params.nl.first().copied().expect("tau");
    let out = freed_held(&prep, &before, next, b, 1e-3);
    for (t, truth) in held.iter().zip([6000.0, 4000.0]) {
        let v = damping(&out, *t).expect("the damping freed");
        assert!(v > 0.0 && (v - truth).abs() < 0.5 * truth, "{t:?}: {v}");
    }
    let tau = out.params.nl.first().copied().expect("tau");
    assert!(
        tau_held < 100e-6 && (tau - 150e-6).abs() < 30e-6,
        "tau {tau_held} -> {tau}"
    );
}

/// Fourth unseen machine's stiff block (B1: c/k 10 and 12.5 µs): freed,
/// the dampings are physical but only trade against τ (−τ·k is collinear
/// with c), the data do not support them: the held fit stands.
#[test]
fn a_physical_unsupported_damping_stays_held() {
    let prep = stored("ross-unseen-4/delay-runout");
    let (before, b, held) = base_with_impossible(&prep, "B1");
    let next = held_delay(&prep, &before, b, &held);
    let mut model = next.model.clone();
    model.terms.extend(held.iter().copied());
    let freed = State::fit(&prep, model, next.params.nl.clone()).expect("freed");
    let impossible = non_physical_dampings(&prep, &freed);
    assert!(
        held.iter().all(|t| !impossible.contains(t)),
        "{impossible:?}"
    );
    let out = freed_held(&prep, &before, next.clone(), b, 1e-3);
    assert_eq!(out.model.terms, next.model.terms);
    assert_eq!(out.params.beta, next.params.beta);
}

/// A winner that holds the dampings without explaining the delay: freed,
/// they are the base fit's impossible ones again, and stay held.
#[test]
fn an_impossible_damping_stays_held() {
    let prep = stored("ross-unseen-3/delay-51");
    let (before, b, held) = base_with_impossible(&prep, "B2");
    let mut model = before.model.clone();
    model.terms.retain(|t| !held.contains(t));
    let next = State::fit(&prep, model, Vec::new()).expect("held refit");
    let out = freed_held(&prep, &before, next.clone(), b, 1e-3);
    assert_eq!(out.model.terms, next.model.terms);
    assert!(held.iter().all(|t| damping(&out, *t).is_none()));
}
