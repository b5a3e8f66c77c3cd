//! Sessions 44-45 (reliab17, baserun17b): a shared base a kept probe runout
//! may have taken for itself (`diagnose::trust::confounded`). Above the
//! base's modes its motion is a nearly constant phasor per bearing, as a
//! runout is; the runout is named, the base never, and main reported the
//! pedestals on it with ± that hold the base known to be absent. Every
//! shared base under the runout's bearing is judged, whichever grouping the
//! base model's trial favoured.

use plinth_tests::unseen::{assert_trusted_means_right, diagnosis_with_machine_check, named};

const FOUR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen");

/// The stored unseen-four `base-runout-d3` run `name` (ROSS: a 350 kg frame
/// under B1 and B2, modes 34 and 40 Hz; probe runout at B2; 3 digits, no
/// other noise; made by `scripts/ross_unseen.py --machine unseen-four DIR
/// base-runout-d3 SEED`): the runout named at B2, the base judged (the
/// verdict says it is neither found nor excluded), and a trusted verdict's
/// final pedestals within 3 of their ± of the truth.
fn a_base_the_runout_can_take_is_counted(name: &str) {
    let run = plinth_tests::unseen::stored(FOUR, name);
    let d = diagnosis_with_machine_check(FOUR, "unseen-four.toml", &run);
    assert!(
        named(&d).contains(&("probe_runout".to_string(), "B2".to_string())),
        "{}",
        d.to_text()
    );
    assert!(
        d.verdict.contains("neither found nor excluded"),
        "no shared base under B2 judged\n{}",
        d.to_text()
    );
    assert_trusted_means_right(&run, &d);
}

/// Seed 1602 (grid 225-345 Hz). Main: trusted, runout at B2, B1 k_y
/// 9.379e6 ± 5.17e4 against the truth 9.0e6 (7.3 ±).
#[test]
fn a_base_a_runout_can_take_is_counted_in_the_pedestals_on_it() {
    a_base_the_runout_can_take_is_counted("base-runout-d3-1602");
}

/// Seed 1852 (grid 259-379 Hz), where the base model's trial favoured
/// B1+B4, a grouping without B2, so session 44's rule (the trial's grouping
/// only) did not judge the base. Main: trusted, runout at B2, B1 k_y 3.3 ±
/// off.
#[test]
fn a_base_the_base_trial_did_not_group_with_the_runout_is_counted() {
    a_base_the_runout_can_take_is_counted("base-runout-d3-1852");
}
