//! Issue 17 on a tenth machine nobody tuned to (session 50, helper
//! unseen10): a two-pole induction motor on a variable-frequency drive
//! (tests/data/ross-unseen-10/unseen-ten.toml), the first symmetric machine:
//! a 150 kg rotor core between two deep-groove ball bearings (isotropic
//! tables, no cross-coupling, almost no damping: ΩC_b at most 0.2 % of
//! K_b), the end shields as pedestals, nearly isotropic (k_z 6-7 % below
//! k_y), their resonances (76-87 Hz) and the rotor's modes (40, 62-66 Hz)
//! inside the drive's ramp-down from 100 Hz to 10 Hz, a vector every 2 Hz
//! (46 speeds); near-circular forward orbits; probes 0.5 % of |phasor| +
//! 0.03 µm, velocity pick-ups 1 % + 2 µm/s. Every phasor and the truth are
//! ROSS 2.3.0's and scripts/ross_unseen.py's (`--machine unseen-ten`), made
//! by `python3 scripts/ross_unseen.py --machine unseen-ten
//! tests/data/ross-unseen-10 clean-v1c,clean-d2,cross,probe-gain,sub-base,table-scale 9500`;
//! only the reading is Plinth's. The rates over seeds are measured by
//! `scripts/bench_unseen.py --machine unseen-ten` (docs/unseen-ten.md).

use plinth::rundir::RunDir;
use plinth_tests::rundown::identify;
use plinth_tests::unseen::{self, named, ok_but_wrong, untrusted};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-10");

/// The machine file a user would have, beside the runs: `plinth diagnose
/// RUN --machine unseen-ten.toml` is what these tests judge.
const MACHINE: &str = "unseen-ten.toml";

/// The stored run directory of `case`.
fn stored(case: &str) -> RunDir {
    unseen::stored(DATA, case)
}

/// Clean data with the noise columns: identify untrusts nothing, lists no
/// speed, every value it prints `ok` (the dampings too) is within 3 of its
/// ± of ROSS's; diagnose names nothing, is trusted, its final pedestals
/// within 3 ±. Over fresh seeds identify flags 0 of the clean runs
/// (docs/unseen-ten.md).
#[test]
fn clean_run_is_flagged_by_nothing_and_ok_means_right() {
    unseen::assert_clean_run_right(DATA, MACHINE, "clean-v1c-9500");
}

/// No noise, two significant digits (the coarsest rounding a user's table
/// has): flagged by nothing, `ok` means right.
#[test]
fn two_digit_run_is_flagged_by_nothing_and_ok_means_right() {
    unseen::assert_clean_run_right(DATA, MACHINE, "clean-d2-9500");
}

/// Pedestal cross-coupling at B1 (k_yz = k_zy = 0.2 √(k_y k_z)), on a
/// machine whose orbits are near circles (where a cross-coupled stiffness
/// reads much like a damping of opposite sign in y and z): identify
/// untrusts B1 and only B1; diagnose names exactly that effect at B1,
/// trusted, its final pedestals within 3 ±.
#[test]
fn cross_coupling_at_b1_is_named_there_and_right() {
    unseen::assert_one_effect_named_right(
        DATA,
        MACHINE,
        "cross-9500",
        "pedestal_cross_coupling",
        "B1",
    );
}

/// B2's horizontal probe reads 5 % low (calibrated on another steel): on
/// this machine identify's y/z sensitivity-ratio test untrusts B2, and B1
/// (the bearing without the error) keeps its `ok` values within 3 ±.
#[test]
fn one_probe_read_five_percent_low_untrusts_its_bearing_only() {
    let run = stored("probe-gain-9500");
    let id = identify(&run);
    assert_eq!(untrusted(&id), ["B2"]);
    let wrong = ok_but_wrong(&run, &id, false);
    assert!(wrong.is_empty(), "{wrong:?}");
}

/// B2's end shield on its own sub-base (80 kg on 40/25 MN/m, y/z: its own
/// modes 113 Hz y, above the run, and 89 Hz z, inside it): identify
/// untrusts B2 and only B2, B1's `ok` values within 3 ±; diagnose names
/// `pedestal_sub_base` at B2 and nothing else (what it then trusts is
/// finding 1's test below).
#[test]
fn sub_base_at_b2_is_untrusted_by_identify_and_named_by_diagnose() {
    let run = stored("sub-base-9500");
    let id = identify(&run);
    assert_eq!(untrusted(&id), ["B2"]);
    let wrong = ok_but_wrong(&run, &id, true);
    assert!(wrong.is_empty(), "{wrong:?}");
    let d = unseen::diagnosis_with_machine_check(DATA, MACHINE, &run);
    assert_eq!(
        named(&d),
        [("pedestal_sub_base".to_string(), "B2".to_string())],
        "{}",
        d.to_text()
    );
}

/// Finding 1 (docs/unseen-ten.md): the sub-base above is fitted in z only
/// (its y mode, 113 Hz, lies above the 100 Hz top speed: `not_detected`),
/// so B2's y values after the step are still the support's apparent ones
/// (the pedestal in series with the sub-base's spring, their masses
/// lumped), yet the verdict is trusted: k_y −18.8 % (−35 ±), m +16 %
/// (+19 ±), k_z −7 % (−6 ±) on seed 9500; 3 of 17 seeds alike. What a
/// user must get: a trusted verdict only where the final values are right
/// within 3 ±. Since session 50 (halfsub50) such a one-direction sub-base
/// untrusts the verdict (`diagnose/trust/support.rs`).
#[test]
fn sub_base_detected_in_one_direction_only_is_not_trusted_when_off() {
    let run = stored("sub-base-9500");
    let d = unseen::diagnosis_with_machine_check(DATA, MACHINE, &run);
    unseen::assert_trusted_means_right(&run, &d);
}

/// B1's table 25 % stiffer than the ball bearing (`table-scale`: the
/// table's stiffness × 1.25, its damping right). A ball bearing's force is
/// almost all stiffness (ΩC_b at most 0.2 % of K_b), so a stiffness error
/// of the table alone scales B1's k, c, m alike with a perfect fit:
/// identify prints B1 `ok` 25 % high (+40 ±, 20 of 20 seeds) and says so
/// in its conditions (this bearing's line); `plinth diagnose --machine`
/// sees it at the machine level and does not trust the verdict, giving
/// B1's table × 0.80 (or B1's rel readings ÷ 1.29) as what reproduces the
/// machine.
#[test]
fn a_ball_bearing_table_too_stiff_is_stated_by_identify_and_untrusted_by_diagnose() {
    let run = stored("table-scale-9500");
    let id = identify(&run);
    let c = plinth::identify::conditional::of(&run, &id, None);
    let text = c.to_text();
    assert!(
        text.contains("B1: its bearing force is almost all stiffness"),
        "{text}"
    );
    let d = unseen::diagnosis_with_machine_check(DATA, MACHINE, &run);
    assert!(!d.trusted, "{}", d.to_text());
    assert!(
        d.trust_reasons
            .iter()
            .any(|r| r.contains("B1's bearing table ×")),
        "{:?}",
        d.trust_reasons
    );
}

/// Finding 2 (docs/unseen-ten.md): the table-scale run above. The issue's
/// Done-when: a wrong bearing table is named `bearing_coefficients` at its
/// bearing, the pedestal values after the correction within 2 % (k, m).
/// Today diagnose names nothing (the pedestal-level search cannot see a
/// common scale; the machine-level check finds B1's table × 0.796 but
/// cannot tell it from a scale on B1's rel readings, and calls that factor
/// "the common unit factor ×√2" though √2 lies 13 of its ± away).
#[test]
#[ignore = "finding 2 of docs/unseen-ten.md: a ball-bearing table 25 % too stiff is not named bearing_coefficients (untrusted, nothing named; the machine-level check cannot tell it from a rel unit scale)"]
fn a_ball_bearing_table_too_stiff_is_named_bearing_coefficients() {
    let run = stored("table-scale-9500");
    let d = unseen::diagnosis_with_machine_check(DATA, MACHINE, &run);
    assert_eq!(
        named(&d),
        [("bearing_coefficients".to_string(), "B1".to_string())],
        "{}",
        d.to_text()
    );
    let truth = unseen::truth_of(&run, "B1");
    let after = d
        .pedestals_after
        .iter()
        .find(|p| p.bearing == "B1")
        .expect("B1 after");
    for (key, t) in [("k_y", truth.k_y), ("k_z", truth.k_z), ("m", truth.m)] {
        let v = after.values[key];
        assert!(
            (v / t - 1.0).abs() < 0.02,
            "B1 {key}: {v:.6e}, truth {t:.6e}"
        );
    }
}
