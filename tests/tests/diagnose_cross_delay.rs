//! Session 47 (xdelay17): a sensor delay the search rejects at one bearing
//! while it names an effect at another. unseen-seven `cross-delay`: a
//! pedestal cross-coupling at B3 (k_yz 22 MN/m) and 150 µs on B1's `rel`
//! probes. B1's horizontal resonance (79 Hz) lies above the 5-50 Hz run, so
//! over the run k − Ω²m is nearly k and the delay reads as a damping
//! c − τ·(k − Ω²m), 30 000 N·s/m at 150 µs against B1's c_y of 24 000.
//! The search names the cross-coupling at B3 in every run and the delay at
//! B1 in 8 of 20 (seeds 6800-6819): its own σ_τ for the delay is 35 µs,
//! the final ML refit's 20 µs (docs/trust.md, Session 47 (xdelay17)). Where
//! the delay is not named, B1's final ± must count it as unknown
//! (`diagnose::ml_final::delay_unknown`, the group's own refit beside the
//! named effect elsewhere).

use plinth_tests::unseen::{
    assert_trusted_dampings_right_too, diagnosis_with_machine_check, named, stored,
};

const SEVEN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-7");

/// unseen-seven `cross-delay` seed 6803 (ROSS 2.3.0; made by
/// `python3 scripts/ross_unseen.py --machine unseen-seven DIR cross-delay
/// 6803`; truth B1 c_y 24 000 N·s/m). The search names the cross-coupling
/// at B3 and rejects the delay at B1 (τ 88 ± 35 µs, adjusted p 0.44 against
/// 0.001); the final refit's linearisation puts it at τ̂ 132 ± 20 µs. Main
/// 840c9e1 (before session 46's pdelay17, which formed both fits' ± from
/// the residual after the step) printed the run trusted with B1 c_y
/// 4.1e3 ± 3.5e3 N·s/m (5.7 ± off); main 48c03f6 counts the delay in B1's
/// ± (c_y ± ×4.9). A trusted verdict's final pedestal values, dampings
/// included, are within 3 of their ± of the truth, and where the delay at
/// B1 is not named the verdict says that B1's ± count it.
#[test]
fn a_delay_beside_an_effect_named_elsewhere_is_counted_in_its_bearings_error() {
    let run = stored(SEVEN, "cross-delay-6803");
    let d = diagnosis_with_machine_check(SEVEN, "unseen-seven.toml", &run);
    let names = named(&d);
    // The effect elsewhere is what this test is about: without it named,
    // B1's group would be the base model's and a different path.
    assert!(
        names.contains(&("pedestal_cross_coupling".to_string(), "B3".to_string())),
        "{names:?}\n{}",
        d.to_text()
    );
    if !d.trusted {
        return;
    }
    assert_trusted_dampings_right_too(&run, &d, "cross-delay-6803");
    let delay_named = names.contains(&("sensor_delay".to_string(), "B1".to_string()));
    assert!(
        delay_named
            || d.verdict
                .contains("At bearing B1 the data do not exclude a sensor delay on `rel`"),
        "{}",
        d.verdict
    );
}
