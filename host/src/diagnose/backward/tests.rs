//! The backward check's test of a chosen profiled scalar on ROSS 2.3.0's
//! run of the fourth machine (tests/data, not this crate's model): the
//! clean run `clean-n1c-382`, whose B1 (a block 30-50 times stiffer than
//! its bearing) has no delay, but where a delay on the ped_y probe trades
//! against the damping (−τ·k) and the Wald form at τ̂ overstates how much
//! it lowers the criterion (docs/diagnose.md, "Session 36").

use super::*;
use crate::diagnose::candidates::library;
use crate::diagnose::forward::evaluate;
use crate::diagnose::test_runs::stored;
use crate::effects::EffectKind;
use plinth_shared::regression::Parameter;

/// The B1 ped_y delay chosen on the base model and fitted jointly: the
/// backward check tests it by the statistic the forward step chose it by
/// (the likelihood ratio, `scalar_drop`), not by the Wald form at τ̂,
/// which on this run is several times larger (main before session 37:
/// `evidence_against` returned the Wald form).
#[test]
fn a_chosen_delay_is_tested_by_the_forward_steps_likelihood_ratio() {
    let prep = stored("ross-unseen-4/clean-n1c-382");
    let n_total = prep.real_equations();
    let before = State::base(&prep, Parameter::ALL.as_slice()).expect("base state");
    let b1 = prep.bearing_index("B1").expect("B1");
    let cand = library(&before.model, prep.bearings.len())
        .into_iter()
        .find(|c| {
            c.effect == EffectKind::SensorDelay
                && c.bearing == b1
                && c.variant.as_deref() == Some("ped_y")
        })
        .expect("the ped_y delay candidate at B1");
    let forward = evaluate(&prep, &before, cand, 1, n_total).expect("evaluated");
    let next = State::fit(
        &prep,
        forward.candidate.model.clone(),
        forward.params.nl.clone(),
    )
    .expect("joint refit");
    let chosen = Chosen::of(&forward.candidate, 0);
    let backward = chosen
        .evidence(&prep, &next, 1, n_total)
        .expect("backward evidence");
    // The Wald form of the same constraint at the joint fit (what the
    // backward check used before).
    let (_, inf, c) = constraints(&prep, &next, b1, &chosen.null).expect("constraints");
    let wald = inf.evidence(&c, 1, n_total).expect("wald");
    println!(
        "forward {:?}\nbackward {:?}\nwald {:?}",
        forward.evidence, backward, wald
    );
    let (f, b) = (forward.evidence.wald_floor, backward.wald_floor);
    assert!(
        f > 0.0 && (b - f).abs() < 0.25 * f,
        "backward floor statistic {b} against the forward step's {f}"
    );
    assert!(
        wald.wald_floor > 2.0 * b,
        "the Wald form {} does not overstate the drop {b} here",
        wald.wald_floor
    );
}
