//! Issue 17 on a ninth machine nobody tuned to (session 48, helper nine17):
//! a large turbocharger (tests/data/ross-unseen-9/unseen-nine.toml): a short
//! stiff rotor with both wheels overhung outboard of two floating-ring
//! journals (a table: stiffness rising 3.4-fold and damping falling 2.7-fold
//! with speed, strongly cross-coupled, k_yz = −k_zy about 0.35 k_yy), strong
//! gyroscopic coupling; B1's housing end light and stiff (resonances
//! 650-840 Hz, above the run), B2's (the hot turbine end) softer, its
//! resonances (275, 367 Hz) inside an exponential coast-down from 500 Hz to
//! 100 Hz (90 speeds, a vector a second); probes 0.5 % of |phasor| +
//! 0.01 µm, casing accelerometers 1 % + 2 mm/s². Every phasor and the truth
//! are ROSS 2.3.0's and scripts/ross_unseen.py's (`--machine unseen-nine`):
//! seed 1 of `clean-r1c` and `cross` (`--repo`), and seed 8210 of two
//! departures no machine had (`python3 scripts/ross_unseen.py --machine
//! unseen-nine tests/data/ross-unseen-9 ped-drift,probe-gain 8210`); only the
//! reading is Plinth's. The rates over seeds are measured by
//! `scripts/bench_unseen.py --machine unseen-nine` (docs/unseen-nine.md).

use plinth::rundir::RunDir;
use plinth_tests::rundown::identify;
use plinth_tests::unseen::{self, ok_but_wrong, untrusted};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-9");

/// The stored run directory of `case`.
fn stored(case: &str) -> RunDir {
    unseen::stored(DATA, case)
}

/// The machine file a user would have, beside the runs: `plinth diagnose
/// RUN --machine unseen-nine.toml` (the search, then the machine-level
/// check applied to the verdict) is what these tests judge.
const MACHINE: &str = "unseen-nine.toml";

/// Clean data with the noise columns: identify untrusts nothing, lists no
/// speed, and every value it prints `ok` (k_y, k_z, m and the dampings) is
/// within 3 of its ± of ROSS's; diagnose names nothing, is trusted, and its
/// final pedestals are within 3 ± too. Over fresh seeds: identify flags
/// 0 of 46 clean runs with noise (docs/unseen-nine.md).
#[test]
fn clean_run_is_flagged_by_nothing_and_ok_means_right() {
    unseen::assert_clean_run_right(DATA, MACHINE, "clean-r1c");
}

/// Pedestal cross-coupling at B2 (k_yz = k_zy = 0.2 √(k_y k_z), the
/// library's `pedestal_cross_coupling`), on the soft turbine-end housing
/// whose resonances lie inside the run: identify untrusts B2 and only B2,
/// B1's `ok` values within 3 ±; diagnose names exactly that effect at B2,
/// trusts its verdict, and its final pedestals are within 3 ± of ROSS's.
#[test]
fn cross_coupling_at_b2_is_named_there_and_right() {
    unseen::assert_one_effect_named_right(DATA, MACHINE, "cross", "pedestal_cross_coupling", "B2");
}

/// Finding 1 (docs/unseen-nine.md): B2's pedestal stiffness rises 4 %
/// over the coast-down (the turbine end cooling; the truth's k is the value
/// half way through the cooling, k_y 156.8-163.2 MN/m, k_z 88.2-91.8 MN/m
/// over the run, m 30 kg throughout). In a run-down time and speed go
/// together, so a stiffness that rises as the speed falls reads as mass:
/// identify prints B2 `ok` with m +1.8 % (about +16 ±) and k_z +2.1 %
/// (+18 ±) on seed 8210, 19 of 20 seeds alike.
///
/// Re-stated in session 49 (drift17): the earlier assertion (no value
/// printed `ok` beyond 3 ±) cannot be met by one run: the drift is, to the
/// fit, a mass term with a perfect fit, and each half of the run is biased
/// alike (docs/unseen-nine.md). What the output must say instead is the
/// condition with its numbers: identify's "Conditional on" states, for B2,
/// how far a 1 % drift of its support over the run would move m, k_y, k_z,
/// and that a drift well below this run's 4 % moves a value by its ± (on
/// main nothing is said). The test one run cannot make is `plinth
/// compare` with a run-up (tests/tests/compare_runs.rs).
#[test]
fn pedestal_stiffness_drifting_over_the_run_is_stated_as_a_condition_with_its_size() {
    let run = stored("ped-drift-8210");
    let id = identify(&run);
    let c = plinth::identify::conditional::of(&run, &id, None);
    let b2 = c
        .support_drift
        .iter()
        .find(|d| d.bearing == "B2")
        .expect("B2's drift sensitivity");
    assert!(b2.matters(), "{b2:?}");
    // The drift that moves one of B2's values by its ± lies far below the
    // 4 % of this run (0.27 % here: m).
    assert!(b2.drift_at_one_std_err < 0.01, "{b2:?}");
    // m read high under a stiffness rising as the speed falls, as measured.
    assert!(
        b2.shift_relative.m > 0.0 && b2.shift_in_std_err.m > 1.0,
        "{b2:?}"
    );
    let text = c.to_text();
    assert!(
        text.contains("B2: a support whose stiffness") && text.contains("plinth compare"),
        "{text}"
    );
    let json = serde_json::to_value(&c).expect("json");
    assert!(json["support_drift"]
        .as_array()
        .is_some_and(|a| !a.is_empty()));
}

/// Finding 2 (docs/unseen-nine.md): B1's vertical proximity probe reads 5 %
/// low (calibrated on another steel than the journal's: a sensitivity error
/// of one channel). identify prints B1 `ok` with k_y −4.7 % (−21 ±) on seed
/// 8210, 17 of 20 seeds alike; diagnose `--machine` trusts values as far
/// off (9 of 9) and names a `probe_runout` (5 of 6 re-runs) or a
/// `pedestal_cross_coupling` at B1 that is not there. The text's condition speaks of one scale on every rel
/// reading, not of one channel's. What an engineer expects: not `ok`
/// beyond 3 ±, or the condition stated for each channel's sensitivity.
/// Since session 49 (gain17) identify tests each bearing's y/z sensitivity
/// ratios and untrusts B1 here (rel_y about −5 % against rel_z;
/// docs/trust.md, Session 49 (gain17)).
#[test]
fn one_probe_read_five_percent_low_is_not_printed_ok_when_off() {
    let run = stored("probe-gain-8210");
    let id = identify(&run);
    let wrong = ok_but_wrong(&run, &id, false);
    assert!(
        wrong.is_empty(),
        "probe-gain-8210 (untrusted {:?}): {wrong:?}",
        untrusted(&id)
    );
}
