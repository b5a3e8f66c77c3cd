//! Session 42 (heldpm17b): a pedestal damping held at zero in the search
//! (the passive bound, where the held-weights fit's free damping came out
//! impossible) is judged again by the final maximum-likelihood refit with
//! it free (`diagnose::ml_final::held_free`): freed where the refit finds
//! it physical and supported, the diagnosis untrusted where it is still
//! impossible beyond `plinth identify`'s family-wise rule
//! (`diagnose::trust::held`), the hold kept where it is within the noise.

use plinth_tests::unseen::{assert_trusted_means_right, diagnosis_with_machine_check, named};

const FOUR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen");

/// unseen-four `runout-d3` seed 1201 (ROSS, a probe runout at B3, 3
/// digits rounded, no noise, 170-290 Hz: far above every pedestal's
/// resonance): `probe_runout` at B3 is named with B3's dampings held at
/// zero by the search. Main printed it trusted with B3's k_y 6.8 % = 9.7 ±
/// off. The ML refit with the runout and the dampings free gives c_y
/// 981 ± 284, c_z 1066 ± 265 N·s/m (truth 900, 1100): freed, and B3's k,
/// m within their ±. A trusted verdict's pedestals must be within 3 of
/// their ± of the truth.
#[test]
fn held_dampings_the_final_fit_supports_are_freed_and_the_pedestals_are_right() {
    let run = plinth_tests::unseen::stored(FOUR, "runout-d3-1201");
    let d = diagnosis_with_machine_check(FOUR, "unseen-four.toml", &run);
    assert_eq!(
        named(&d),
        vec![("probe_runout".to_string(), "B3".to_string())],
        "{}",
        d.to_text()
    );
    let b3 = d
        .pedestals_after
        .iter()
        .find(|p| p.bearing == "B3")
        .expect("B3");
    for c in ["c_y", "c_z"] {
        let se = b3.std_err.get(c).copied().unwrap_or(0.0);
        assert!(se > 0.0, "B3 {c} still held: {}", d.to_text());
    }
    assert!(d.steps[0].held.is_none(), "{}", d.to_text());
    assert_trusted_means_right(&run, &d);
}

/// A control: unseen-four `cross` (stored run; a cross stiffness at B4,
/// whose pedestal is truly undamped). The search holds B4's c_y at zero;
/// the ML refit with it free gives −27 ± 52 N·s/m (zero plus noise, 0.5
/// standard errors below zero, the likelihood ratio 0.3): within the
/// noise, so the hold stays, no trust reason about it, the verdict
/// trusted (as on main).
#[test]
fn a_truly_zero_damping_held_within_its_noise_stays_held_and_trusted() {
    let run = plinth_tests::unseen::stored(FOUR, "cross");
    let d = diagnosis_with_machine_check(FOUR, "unseen-four.toml", &run);
    assert_eq!(
        named(&d),
        vec![("pedestal_cross_coupling".to_string(), "B4".to_string())],
        "{}",
        d.to_text()
    );
    let held = d.steps[0].held.as_ref().expect("B4's damping held");
    assert_eq!(held.dampings, vec!["c_y".to_string()]);
    assert!(
        !d.trust_reasons.iter().any(|r| r.contains("held at 0")),
        "{:?}",
        d.trust_reasons
    );
    assert!(d.trusted, "{}", d.to_text());
}
