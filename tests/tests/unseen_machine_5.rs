//! Issue 17 on a fifth machine nobody tuned to (session 38): a fan rotor
//! with a 170 kg wheel overhung beyond B2 (tests/data/ross-unseen-5/
//! unseen-five.toml) on two PLAIN bearings with strong cross-coupling (B1 a
//! lightly loaded short sleeve bearing, k_yz 1.4-5.2 times k_yy; B2 a skew
//! cross-coupled table), on pedestals four times stiffer vertically than
//! horizontally whose horizontal resonances (36 and 29 Hz) lie inside the
//! run; a COARSE run-down table (one speed every 1.5 Hz, 56.1 down to
//! 9.6 Hz: 32 speeds, below the machine's oil-whip onset at 59 Hz) and the
//! largest noise of the five machines (3 % of |phasor| plus 0.3 % of the
//! channel's RMS). Every phasor and the truth are ROSS 2.3.0's and
//! scripts/ross_unseen.py's (`--machine unseen-five`), seed 1 of each case
//! kept in tests/data/ross-unseen-5/<case>/; only the reading is Plinth's.
//! The rates over seeds are measured by `scripts/bench_unseen.py --machine
//! unseen-five` (docs/unseen-five.md). What does not work yet is written
//! with the right assertion and ignored with the measured rate.

use plinth::diagnose::report::Diagnosis;
use plinth::rundir::RunDir;
use plinth_tests::rundown::identify;
use plinth_tests::unseen::{self, assert_ok_means_right, named, untrusted};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-5");

/// The stored run directory of `case` (seed 1).
fn stored(case: &str) -> RunDir {
    unseen::stored(DATA, case)
}

/// `plinth diagnose RUN --machine unseen-five.toml` as the command line
/// runs it: the search, then the machine-level check applied to the
/// verdict.
fn diagnosis(run: &RunDir) -> Diagnosis {
    unseen::diagnosis_with_machine_check(DATA, "unseen-five.toml", run)
}

/// Clean data, with and without the noise columns: nothing untrusted, no
/// speed listed, every `ok` within 3 of its ± (identify); nothing named and
/// trusted (diagnose). Measured (`BENCH_JOBS=1 python3
/// scripts/bench_unseen.py --machine unseen-five PLINTH DIR 1-10 CASE`):
/// identify untrusted 0/230 (clean-n3 and clean-n3c seeds 1-110, clean-d3
/// seeds 1-10), an `ok` beyond 3 ± on 6/110 clean-n3 and 2/110 clean-n3c
/// runs (not seed 1); diagnose named something on 1/130 (clean-n3 and
/// clean-d3 seeds 1-10, clean-n3c 1-110; clean-n3c seed 2: a
/// `sensor_delay` at B1, trusted; docs/unseen.md "Session 38 (2026-12-04, helper unseen5)").
#[test]
fn clean_runs_are_flagged_by_nothing_and_ok_means_right() {
    for case in ["clean-n3", "clean-n3c"] {
        let run = stored(case);
        let id = identify(&run);
        unseen::assert_flagged_by_nothing(&run, &id, &diagnosis(&run), case);
    }
}

/// Pedestal cross-coupling 0.2·√(k_y k_z) at B1 (the pedestal under the
/// strongly cross-coupled sleeve bearing, its z resonance inside the run):
/// identify untrusts B1 and only B1, B2's `ok` values are right, and
/// diagnose names `pedestal_cross_coupling` at B1 and nothing else.
/// Measured over seeds 1-10: identify B1 untrusted 10/10, B2 0/10;
/// diagnose named right 10/10, trusted.
#[test]
fn cross_coupling_at_the_cross_coupled_bearing_is_found_there() {
    let run = stored("cross");
    let id = identify(&run);
    assert_eq!(untrusted(&id), ["B1"]);
    assert_ok_means_right(&run, &id, "cross");
    let d = diagnosis(&run);
    assert_eq!(
        named(&d),
        [("pedestal_cross_coupling".to_string(), "B1".to_string())],
        "{}",
        d.to_text()
    );
}

/// B2's pedestal (300 kg, 40/10 MN/m) on a sub-base (250 kg, 150/60 MN/m,
/// its own resonances 123/78 Hz, above the 56 Hz top speed). Over the run
/// the support moves as its series stiffness and apparent mass, with an
/// Ω⁴ fall of 0.7 % (y) and 3.3 % (z) of the stiffness at the top speed:
/// below what 3 % noise on 32 speeds shows. What identify prints for B2 is
/// that apparent support (its "Conditional on" line says so): k_y and k_z
/// within 4 % of the series stiffnesses k·k_s/(k + k_s), m within 3 % of
/// the apparent mass m + m_s·(k/(k + k_s))² of the y direction.
#[test]
fn a_sub_base_above_the_range_reads_as_the_apparent_support() {
    let run = stored("sub-base");
    let id = identify(&run);
    let b2 = id.pedestals.iter().find(|p| p.bearing == "B2").expect("B2");
    let series = |k: f64, ks: f64| k * ks / (k + ks);
    let apparent_m = 300.0 + 250.0 * (4.0e7_f64 / (4.0e7 + 1.5e8)).powi(2);
    for (name, got, want, tol) in [
        ("k_y", b2.pedestal.k_y, series(4.0e7, 1.5e8), 0.04),
        ("k_z", b2.pedestal.k_z, series(1.0e7, 6.0e7), 0.04),
        ("m", b2.pedestal.m, apparent_m, 0.03),
    ] {
        assert!(
            (got / want - 1.0).abs() < tol,
            "B2 {name} = {got:.6e}, apparent support {want:.6e}"
        );
    }
    let b1 = id.pedestals.iter().find(|p| p.bearing == "B1").expect("B1");
    assert!(b1.trusted, "B1 untrusted on the sub-base run");
    let wrong: Vec<String> = unseen::ok_but_wrong(&run, &id, false)
        .into_iter()
        .filter(|w| w.starts_with("B1 "))
        .collect();
    assert!(wrong.is_empty(), "sub-base: {wrong:?}");
}

/// What should hold and does not yet: B2 on its sub-base is untrusted (its
/// printed values are 21 % (k_y) and 12 % (k_z) below the pedestal's own,
/// 40-55 of their ± away). Measured over seeds 1-10 (`BENCH_JOBS=1 python3
/// scripts/bench_unseen.py --machine unseen-five PLINTH DIR 1-10
/// sub-base`): B2 untrusted 1/10 (3/50 on seeds 11-60), diagnose named
/// `pedestal_sub_base` 1/10 and was trusted with nothing named 9/10. With
/// the same runs' noise scaled (docs/unseen.md "Session 38 (2026-12-04, helper unseen5)"): 1 % noise 5/5
/// untrusted, 1.5 % 6/10, 2.1 % 2/10, 3 % 1/10: a limit of the data's
/// power, not a bias.
#[test]
#[ignore = "B2 on its sub-base is trusted in 9/10 runs at 3 % noise (docs/unseen.md, Session 38, helper unseen5)"]
fn a_sub_base_under_b2_is_untrusted() {
    let run = stored("sub-base");
    let id = identify(&run);
    assert_eq!(untrusted(&id), ["B2"]);
}
