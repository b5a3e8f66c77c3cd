//! Issue 17 on a sixth machine nobody tuned to (session 45, helper six17):
//! a centrifugal fan line shaft on THREE bearings (tests/data/ross-unseen-6/
//! unseen-six.toml): B1 and B3 rolling-element bearings (a nearly constant
//! table, y stiffer than z, no cross-coupling, little damping), B2 a short
//! sleeve steady bearing, the 140 kg wheel between B2 and B3; LIGHT soft
//! pedestals (30-60 kg, six times stiffer vertically than horizontally)
//! that move ten times more than the shaft in them, with every horizontal
//! pedestal resonance (45, 22, 38 Hz) and B2's vertical one (52 Hz) INSIDE
//! the run-down (58 uneven speeds, 62 down to 4 Hz); its noise per channel
//! (each sensor its own floor, z worse than y) with a term growing as
//! √speed. Every phasor and the truth are ROSS 2.3.0's and
//! scripts/ross_unseen.py's (`--machine unseen-six`), seed 1 of each case
//! kept in tests/data/ross-unseen-6/<case>/; only the reading is Plinth's.
//! The rates over seeds are measured by `scripts/bench_unseen.py --machine
//! unseen-six` (docs/unseen-six.md).

use plinth::diagnose::report::Diagnosis;
use plinth::rundir::RunDir;
use plinth_tests::rundown::identify;
use plinth_tests::unseen::{self, named, ok_but_wrong, truth_of, untrusted};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-6");

/// The stored run directory of `case` (seed 1).
fn stored(case: &str) -> RunDir {
    unseen::stored(DATA, case)
}

/// `plinth diagnose RUN --machine unseen-six.toml` as the command line
/// runs it: the search, then the machine-level check applied to the
/// verdict.
fn diagnosis(run: &RunDir) -> Diagnosis {
    unseen::diagnosis_with_machine_check(DATA, "unseen-six.toml", run)
}

/// Clean data with the noise columns: identify untrusts nothing, lists no
/// speed, and every value it prints `ok` (k_y, k_z, m and the dampings) is
/// within 3 of its ± of ROSS's; diagnose names nothing, is trusted, and its
/// final pedestals are within 3 ± too. Measured (`BENCH_JOBS=1 python3
/// scripts/bench_unseen.py --machine unseen-six PLINTH DIR 3631-3670
/// clean-s1 clean-s1c`, and seeds 3601-3603, 3611-3630; docs/unseen-six.md):
/// 0/175 clean runs flagged by identify or diagnose; with the noise columns
/// 0/63 trusted runs with a final value beyond 3 ± (without them 8/63:
/// finding 2 there).
#[test]
fn clean_run_is_flagged_by_nothing_and_ok_means_right() {
    let run = stored("clean-s1c");
    let id = identify(&run);
    let d = diagnosis(&run);
    unseen::assert_flagged_by_nothing(&run, &id, &d, "clean-s1c");
    let wrong = ok_but_wrong(&run, &id, true);
    assert!(wrong.is_empty(), "clean-s1c, dampings too: {wrong:?}");
    unseen::assert_trusted_means_right(&run, &d);
}

/// Pedestal cross-coupling 0.2·√(k_y k_z) at B1 (its horizontal resonance,
/// 45 Hz, inside the run): identify untrusts B1 and only B1, B2's and B3's
/// `ok` values are right; diagnose names `pedestal_cross_coupling` at B1
/// and nothing else, trusted, with k_yz within 3 of its ± of the truth and
/// every final pedestal within 3 ± of ROSS's. Measured over seeds 3601-3603:
/// identify B1 untrusted 3/3 (B2, B3 0/3), diagnose named right and
/// trusted 3/3, no final value beyond 3 ±.
#[test]
fn cross_coupling_at_b1_is_found_there() {
    let run = stored("cross");
    let id = identify(&run);
    assert_eq!(untrusted(&id), ["B1"]);
    unseen::assert_ok_means_right(&run, &id, "cross");
    let d = diagnosis(&run);
    assert_eq!(
        named(&d),
        [("pedestal_cross_coupling".to_string(), "B1".to_string())],
        "{}",
        d.to_text()
    );
    assert!(d.trusted, "{:?}\n{}", d.trust_reasons, d.to_text());
    let k_yz = d.steps[0]
        .parameters
        .iter()
        .find(|p| p.name == "k_yz")
        .expect("k_yz of the cross-coupling step");
    let t = truth_of(&run, "B1");
    let want = 0.2 * (t.k_y * t.k_z).sqrt();
    assert!(
        ((k_yz.value - want) / k_yz.std_err).abs() < 3.0,
        "k_yz = {:.6e} ± {:.2e}, truth {want:.6e}",
        k_yz.value,
        k_yz.std_err
    );
    unseen::assert_trusted_means_right(&run, &d);
}
