//! Session 44: a pedestal damping held at zero within the noise, in a
//! group without a table. The held fit's ± are conditional on the damping
//! being zero exactly; where the band lies far above the pedestal's
//! resonance k and m trade with it, and the hold's ± were far too narrow.
//! Every group that keeps such a hold now reports its ± with the damping
//! unknown (`ml_final::held_free`, `HeldUnknown`; docs/unseen.md "Session
//! 44 (sweep17b)").

use plinth_tests::unseen::{assert_trusted_means_right, diagnosis_with_machine_check};

const FOUR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen");

/// unseen-four `base-runout-d3` seed 2901 (ROSS; a 350 kg frame under B1
/// and B2 and a probe runout at B2; 3 digits; the seed shifts the grid to
/// 403-523 Hz, where B2's k_y is 2 % of Ω²m). Main 76899fa named the
/// runout, held B2's c_z at zero (truth 1200 N·s/m) and printed the run
/// trusted with B2 k_y 16.4 ± 4.2 MN/m (truth 34.0, 4.2 ± off), k_z 6.9 ±
/// 4.2 (truth 25.0, 4.3 ±), m 237.4 ± 0.60 kg (truth 240, 4.3 ±). With
/// c_z unknown the ± are about 3.2 times wider. A trusted verdict's
/// pedestals must be within 3 of their ± of the truth.
#[test]
fn a_damping_held_within_the_noise_is_counted_unknown_in_the_error() {
    let run = plinth_tests::unseen::stored(FOUR, "base-runout-d3-2901");
    let d = diagnosis_with_machine_check(FOUR, "unseen-four.toml", &run);
    assert_trusted_means_right(&run, &d);
    if let Some(b2) = d.pedestals_after.iter().find(|p| p.bearing == "B2") {
        if !b2.std_err.contains_key("c_z") {
            // Still held: its ± must count the held damping as unknown.
            assert!(
                b2.std_err["m"] > 1.2,
                "B2 m ± {} kg with c_z held: conditional on c_z = 0\n{}",
                b2.std_err["m"],
                d.to_text()
            );
        }
    }
}
