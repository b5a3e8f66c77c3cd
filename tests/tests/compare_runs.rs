//! `plinth compare RUN_A RUN_B` (session 49, helper drift17): two runs of
//! one machine identified and each pedestal's values tested for agreement,
//! the test one run cannot make of a support whose stiffness drifts over
//! the run (docs/unseen-nine.md finding 1; docs/trust-lack-of-fit.md,
//! session 49).
//!
//! Stored ROSS runs of unseen-nine (tests/data/ross-unseen-9), made by
//! `python3 scripts/ross_unseen.py --machine unseen-nine
//! tests/data/ross-unseen-9 ped-drift,ped-drift-up,clean-r1c 8700`:
//! `ped-drift-8700` (the coast-down, B2's pedestal stiffness rising 4 % as
//! the turbine end cools), `ped-drift-up-8700` (the same machine run up, the
//! stiffness again rising 4 % over the run, following time, so now rising
//! with speed) and `clean-r1c-8700` (clean, another seed of `clean-r1c`,
//! stored from seed 1). Every phasor is ROSS 2.3.0's; only the reading is
//! Plinth's. Rates over seeds (detection 15/15 pairs, false alarms 0 of
//! 100 clean pairs on three machines) are in the docs.

use plinth::compare::{self, comparison};
use plinth::identify::physical::{exit_code, EXIT_NOT_PHYSICAL};
use std::path::{Path, PathBuf};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-9");

fn run(case: &str) -> PathBuf {
    Path::new(DATA).join(case)
}

fn args(a: &Path, b: &Path) -> compare::Args {
    compare::Args {
        run_a: a.to_path_buf(),
        run_b: b.to_path_buf(),
        json: true,
    }
}

/// A run-down and a run-up of the machine whose B2 support stiffens 4 %
/// over each run: each run alone prints B2 with m 1.5-1.8 % off (10-20 ±),
/// the two disagree at B2 by far more than their ± (χ² about 1000 on 5
/// over 15 seeds), and at B2 only; the verdict names B2, the parameters
/// that differ and says neither run's B2 is to be trusted alone; exit code
/// 2. Fails on main (no `compare`).
#[test]
fn a_run_down_and_a_run_up_of_a_drifting_support_disagree_at_b2_only() {
    let (a, b) = (run("ped-drift-8700"), run("ped-drift-up-8700"));
    let c = comparison(&a, &b).expect("compare");
    let flagged: Vec<&str> = c.disagreeing().map(|p| p.bearing.as_str()).collect();
    assert_eq!(flagged, ["B2"], "{:#?}", c.pedestals);
    let b2 = c.pedestals.iter().find(|p| p.bearing == "B2").expect("B2");
    assert!(b2.chi2 > 100.0, "B2 χ² {}", b2.chi2);
    let m = b2.parameters.iter().find(|q| q.name == "m").expect("m");
    // The run-down reads m high, the run-up low: B − A well below zero.
    assert!(m.z < -5.0 && m.difference_relative < -0.01, "{m:?}");
    assert!(
        b2.message.contains("m differs by") && b2.message.contains("neither run's B2"),
        "{}",
        b2.message
    );
    let e = compare::run(&args(&a, &b)).expect_err("disagreement");
    assert_eq!(exit_code(&e), EXIT_NOT_PHYSICAL, "{e}");
    assert!(e.to_string().contains("`B2`"), "{e}");
}

/// Two clean run-downs of the machine (seeds 1 and 8700): no pedestal
/// disagrees (each χ² within its 99.5 % quantile, 16.7 on 5), exit 0.
#[test]
fn two_clean_runs_agree() {
    let (a, b) = (run("clean-r1c"), run("clean-r1c-8700"));
    let c = comparison(&a, &b).expect("compare");
    assert_eq!(c.disagreeing().count(), 0, "{:#?}", c.pedestals);
    assert!(c.pedestals.iter().all(|p| p.dof == 5 && p.chi2 < 16.7));
    compare::run(&args(&a, &b)).expect("agree: exit 0");
}

/// Bad inputs: each an error naming the run (or its file) and the reason.
#[test]
fn bad_inputs_are_errors_that_name_the_run_and_the_reason() {
    let clean = run("clean-r1c");
    let text = |a: &Path, b: &Path| {
        let e = comparison(a, b).expect_err("an error");
        assert_eq!(exit_code(&e), 1);
        plinth::error_text(&e)
    };
    // A run directory that does not exist.
    let missing = Path::new(DATA).join("no-such-run");
    let t = text(&clean, &missing);
    assert!(
        t.contains("no-such-run") && t.contains("no such run directory"),
        "{t}"
    );
    // The same run twice.
    let t = text(&clean, &clean);
    assert!(t.contains("given twice"), "{t}");
    // Another machine: other bearings.
    let other = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/three-bearing/noise-1");
    let t = text(&clean, &other);
    assert!(
        t.contains("not of the same machine")
            && t.contains("B1, B2")
            && t.contains("measurements.csv"),
        "{t}"
    );
    // A broken measurements.csv: the file, the line and what is wrong.
    let dir = tempfile::tempdir().expect("temp dir");
    for f in ["measurements.csv", "bearings.csv"] {
        std::fs::copy(clean.join(f), dir.path().join(f)).expect("copy");
    }
    let csv = std::fs::read_to_string(clean.join("measurements.csv")).expect("read");
    let broken: Vec<String> = csv
        .lines()
        .enumerate()
        .map(|(i, l)| {
            let mut f: Vec<&str> = l.split(',').collect();
            if i == 3 {
                f[2] = "x1.0";
            }
            f.join(",")
        })
        .collect();
    std::fs::write(
        dir.path().join("measurements.csv"),
        broken.join("\n") + "\n",
    )
    .expect("write");
    let t = text(&clean, dir.path());
    assert!(
        t.contains("run B") && t.contains("measurements.csv:4"),
        "{t}"
    );
}
