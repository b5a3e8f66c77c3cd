//! Issue 17: a right step whose re-simulated machine-level gap rises
//! within the change's own noise must not untrust the diagnosis. The rule
//! (`plinth::diagnose::trust::judge_steps`) untrusts a kept step whose
//! machine-level gap rose by more than `MACHINE_STEP_NOISE_SD` standard
//! deviations of the step's change (`Step::machine_gap_change_sd`: two
//! nested fits to the same data, the change's variance from the step's
//! own parameters, `plinth::diagnose::machine`'s `change` module); until
//! session 39 any rise did (a loss of power on right names).
//!
//! Runs made by ROSS 2.3.0 with scripts/ross_unseen.py; only the reading
//! is Plinth's:
//! - `ross-unseen-4/delay-runout-141` (`--machine unseen-flex DIR
//!   delay-runout 141`: τ = 150 µs on B1's probes, a probe runout at B2):
//!   step 1, the runout at B2 with the delay not yet in the model, raises
//!   the gap 0.0404 → 0.0455 (2.0 sd of its change).
//! - `ross-unseen-3/cross-delay-151` (`--machine unseen-train DIR
//!   cross-delay 151`: a pedestal cross-coupling at B2, a delay at B3):
//!   step 2, the delay at B3, 0.1112 → 0.1113 (0.1 sd; session 46:
//!   0.1106, within 1 % of where it was).
//! - `ross-unseen-4/delay-runout-340` (as 141, seed 340; session 40):
//!   step 1, the runout at B2, raises the gap 0.0556 → 0.0649. Its change
//!   sd with the gap's gradient at one end only (session 39) was 0.0030, a
//!   rise of 3.1 sd (untrusted); the gap bends between the two models, and
//!   with its gradient at both ends (and the measurements' own noise,
//!   `machine::change::change_sd`) the sd is about 0.006, the rise 1.5 sd.
//! - `ross-unseen-4/delay-runout-920` (as 141, seed 920; session 41,
//!   docs/diagnose-verdict.md, Session 41 (stepsd17b)): step 2, the delay at B1 with B1's
//!   dampings held at zero, raises the gap 0.0283 → 0.0386. Counting only
//!   the bearing whose parameters the step changes (session 40) its change
//!   sd was 0.0013, a rise of 7.9 sd (untrusted); the other bearings'
//!   estimates are the same in both models but the gap's gradient along
//!   them is not, and with their noise counted the sd is about 0.019, the
//!   rise 0.5 sd.

use plinth::diagnose::report::Diagnosis;
use plinth::diagnose::trust::MACHINE_STEP_NOISE_SD;
use plinth_tests::unseen::{self, named};

const FLEX: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-4");
const TRAIN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-3");

/// The diagnosis of `case` names exactly `want` (in any order), step
/// `rising` (0-based) raises the machine-level gap by less than
/// `MACHINE_STEP_NOISE_SD` times its change's noise, and it is trusted.
fn right_and_trusted(
    data: &str,
    file: &str,
    case: &str,
    want: &[(&str, &str)],
    rising: usize,
) -> Diagnosis {
    let run = unseen::stored(data, case);
    let d = unseen::diagnosis_with_machine_check(data, file, &run);
    let mut got = named(&d);
    got.sort();
    let mut want: Vec<(String, String)> = want
        .iter()
        .map(|(e, b)| (e.to_string(), b.to_string()))
        .collect();
    want.sort();
    assert_eq!(got, want, "{}", d.to_text());
    let s = &d.steps[rising];
    let (Some(before), Some(after)) = (s.machine_gap_before, s.machine_gap_after) else {
        panic!(
            "step {} has no machine-level gaps: {}",
            rising + 1,
            d.to_text()
        );
    };
    // The run tests the rule where the gap rises; cross-delay-151's step 2
    // left it where it was (0.1112 → 0.1113) and since session 46 lowers it
    // by 0.5 % (0.1106; which of session 46's changes moved it is not
    // traced: its noise comes from columns, so not the REML law), and
    // a lowered gap carries no change noise (nothing to judge): there the
    // gap must stay within 1 % of where it was, names and trust as before.
    if after < before {
        assert!(
            before - after <= 0.01 * before,
            "step {} lowers the gap by more than 1 % now ({before:.4} → {after:.4}): the run no longer tests the rule",
            rising + 1
        );
    } else {
        let sd = s
            .machine_gap_change_sd
            .unwrap_or_else(|| panic!("step {}: no change noise: {}", rising + 1, d.to_text()));
        assert!(
            after - before <= MACHINE_STEP_NOISE_SD * sd,
            "rise {:.4} against {MACHINE_STEP_NOISE_SD} × {sd:.4}",
            after - before
        );
    }
    assert!(d.trusted, "{:?}\n{}", d.trust_reasons, d.to_text());
    d
}

#[test]
fn a_right_runout_that_raises_the_machine_gap_within_its_noise_is_trusted() {
    right_and_trusted(
        FLEX,
        "unseen-flex.toml",
        "delay-runout-141",
        &[("probe_runout", "B2"), ("sensor_delay", "B1")],
        0,
    );
}

#[test]
fn a_right_delay_that_leaves_the_machine_gap_where_it_was_is_trusted() {
    right_and_trusted(
        TRAIN,
        "unseen-train.toml",
        "cross-delay-151",
        &[("pedestal_cross_coupling", "B2"), ("sensor_delay", "B3")],
        1,
    );
}

#[test]
fn a_right_runout_whose_gap_bends_between_the_two_models_is_trusted() {
    right_and_trusted(
        FLEX,
        "unseen-flex.toml",
        "delay-runout-340",
        &[("probe_runout", "B2"), ("sensor_delay", "B1")],
        0,
    );
}

#[test]
fn a_right_held_damping_delay_whose_other_bearings_bend_the_gap_is_trusted() {
    right_and_trusted(
        FLEX,
        "unseen-flex.toml",
        "delay-runout-920",
        &[("probe_runout", "B2"), ("sensor_delay", "B1")],
        1,
    );
}
