//! Session 41 (lead): a pedestal fitted beside its own dampings held at
//! zero (the passive bound, where the base model's free dampings came out
//! impossible) reported ± conditional on c = 0 exactly, a value no data
//! gave. diagnose now reports every parameter of such a group with the
//! larger of its held ± and its ± with the held dampings free
//! (`diagnose::ml_final::held_delay::freed_std_errs`), as it did for a
//! sensor delay since session 38.

use plinth_tests::unseen::{diagnosis_with_machine_check, named, truth_of};

const FOUR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen");

/// unseen-four `runout-d3` seed 1201 (ROSS, a probe runout at B3, 3
/// digits rounded, no noise, 170-290 Hz: far above every pedestal's
/// resonance, where a damping is a small share of the inertia and trades
/// with the runout): `probe_runout` at B3 is named with B3's dampings held
/// at zero; main printed it trusted with B3's k_y 6.8 % = 9.7 ± off. A
/// trusted verdict's pedestals must be within 3 of their ± of the truth.
#[test]
fn a_pedestal_fitted_beside_held_dampings_carries_their_uncertainty() {
    let run = plinth_tests::unseen::stored(FOUR, "runout-d3-1201");
    let d = diagnosis_with_machine_check(FOUR, "unseen-four.toml", &run);
    assert_eq!(
        named(&d),
        vec![("probe_runout".to_string(), "B3".to_string())],
        "{}",
        d.to_text()
    );
    if !d.trusted {
        return;
    }
    for after in &d.pedestals_after {
        let truth = truth_of(&run, &after.bearing);
        for (key, t) in [("k_y", truth.k_y), ("k_z", truth.k_z), ("m", truth.m)] {
            let (v, se) = (after.values[key], after.std_err[key]);
            assert!(
                ((v - t) / se).abs() < 3.0,
                "{} {key}: {v:.6e} ± {se:.2e}, truth {t:.6e} ({:.1} ±), trusted",
                after.bearing,
                (v - t) / se
            );
        }
    }
}
