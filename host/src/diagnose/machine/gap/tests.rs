//! [`refitted_base`] on ROSS 2.3.0's run of the third unseen machine
//! (tests/data/ross-unseen-3/delay-55: a 150 µs delay on B2's rel probes),
//! not this crate's model.

use super::*;
use crate::diagnose::model::{DelayChannels, Nonlinear, Term};
use crate::diagnose::test_runs::stored;
use plinth_shared::regression::Parameter;

/// The pedestal terms (k, m, c) of bearing `b` in `state`, by term.
fn pedestal_of(state: &State, b: usize) -> Vec<(Term, f64)> {
    state
        .model
        .terms
        .iter()
        .zip(&state.params.beta)
        .filter(|(t, _)| t.is_pedestal() && t.bearings() == [Some(b), None])
        .map(|(t, v)| (*t, *v))
        .collect()
}

/// A step acting at B2 (the rel delay, its joint refit as the search makes
/// it, `State::fit`) leaves the pedestals of B1 and B3 exactly as the refitted base
/// model has them, where the base model's own (maximum-likelihood) values
/// differ: step 1's machine-level change is then the effect's alone.
#[test]
fn the_refitted_base_differs_from_a_step_only_where_the_step_acts() {
    let prep = stored("ross-unseen-3/delay-55");
    let base = State::base(&prep, Parameter::ALL.as_slice()).expect("base state");
    let refitted = refitted_base(&prep, &base).expect("refitted base");
    let b2 = prep.bearing_index("B2").expect("bearing B2");
    let mut model = base.model.clone();
    model.nonlinear.push(Nonlinear::Delay {
        bearing: b2,
        channels: DelayChannels {
            rel: [true; 2],
            ped: [false; 2],
        },
    });
    let step = State::fit(&prep, model, vec![150e-6]).expect("joint refit with the delay");
    let mut moved = 0.0f64;
    for b in (0..prep.bearings.len()).filter(|&b| b != b2) {
        let (r, s, m) = (
            pedestal_of(&refitted, b),
            pedestal_of(&step, b),
            pedestal_of(&base, b),
        );
        assert_eq!(r.len(), 5);
        assert_eq!(r, s, "bearing {}: the step changed it", prep.bearings[b]);
        for ((_, v), (_, w)) in r.iter().zip(&m) {
            moved = moved.max(((v - w) / w).abs());
        }
    }
    assert!(
        moved > 1e-6,
        "the maximum-likelihood base should differ from the weighted refit"
    );
}
