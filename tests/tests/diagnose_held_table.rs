//! Session 43 (heldtable17): a bearing table's correction named beside a
//! pedestal damping held at zero. `bearing_table::refine` refits a table's
//! pedestal over its five base terms only and `ml_final::refit` skipped
//! every group with a table scalar, so such a group kept the search's
//! held-weights least-squares values and its hold was never judged. Now
//! `ml_final::refit` refits it by ML with its scalar and `free_held` judges
//! the hold (the table's δ and the damping trade: a clearance moves the
//! bearing's damping too).

use plinth_tests::unseen::{assert_trusted_means_right, diagnosis_with_machine_check, named};

const FOUR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen");

/// unseen-four `table-d3` seed 1602 (ROSS, B2's bearing at 1/0.85 of its
/// drawn clearance, 3 digits rounded, no noise; the seed shifts the grid
/// to 225-346 Hz, above every pedestal resonance). Main named the
/// clearance at B2 right with B2's c_y held at zero and printed the run
/// trusted with B2 m 244.90 ± 0.23 kg (truth 240, 21.7 ± off), k_y 37.16 ±
/// 0.49 MN/m (truth 34.0, 6.4 ±), clearance ratio 1.16924 ± 0.00036
/// (truth 1.17647, 20 ±). The ML refit with c_y free finds it physical
/// (1895 N·s/m, truth 1800): freed, B2 and the ratio within their ±. A
/// trusted verdict's pedestals and ratio must be within 3 of their ± of
/// the truth.
#[test]
fn a_table_named_beside_a_held_damping_is_not_confidently_wrong() {
    let run = plinth_tests::unseen::stored(FOUR, "table-d3-1602");
    let d = diagnosis_with_machine_check(FOUR, "unseen-four.toml", &run);
    assert_eq!(
        named(&d),
        vec![("bearing_coefficients".to_string(), "B2".to_string())],
        "{}",
        d.to_text()
    );
    assert_trusted_means_right(&run, &d);
    if !d.trusted {
        return;
    }
    let truth = run.truth.as_ref().expect("truth");
    let ratio = truth
        .effect_details
        .iter()
        .find(|e| e.name == "bearing_coefficients")
        .and_then(|e| e.parameters.get("clearance_ratio"))
        .copied()
        .expect("the truth's clearance ratio");
    let e = d.steps[0]
        .parameters
        .iter()
        .find(|e| e.name == "clearance_ratio")
        .expect("clearance_ratio reported");
    assert!(
        ((e.value - ratio) / e.std_err).abs() < 3.0,
        "clearance_ratio {} ± {}, truth {ratio}, trusted\n{}",
        e.value,
        e.std_err,
        d.to_text()
    );
}
