//! Issue 17: a pedestal damping the search held at zero to let an effect
//! in is the base model's own parameter, not an effect. When a runout or a
//! delay the base model lacks makes a pedestal's free damping impossible,
//! the step's winner is fitted with that damping held at zero (the passive
//! bound); once the effect is in, the damping is freed again in the same
//! refit if its value is physical and the data support it, instead of
//! being named by the next step as a `pedestal_damping` effect (which also
//! left a delay fitted with the damping at zero: τ a lower bound, less than
//! half the true one).
//!
//! Runs made by ROSS 2.3.0 with scripts/ross_unseen.py (seeds 52, 51 and
//! 55, kept under tests/data/ross-unseen-2/runout-52 and
//! tests/data/ross-unseen-3/delay-51, delay-55); only the reading is
//! Plinth's.

use plinth::diagnose::report::Diagnosis;
use plinth::rundir::RunDir;
use plinth_tests::unseen::{self, named};

const OVERHUNG: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-2");
const TRAIN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-3");

/// `plinth diagnose` on the stored run `case` under `data` with the
/// machine file `file`, and the run.
fn diagnosed(data: &str, file: &str, case: &str) -> (RunDir, Diagnosis) {
    let run = unseen::stored(data, case);
    let d = unseen::diagnosis_with_machine_check(data, file, &run);
    (run, d)
}

/// (effect, bearing) pairs as owned strings.
fn pairs(v: &[(&str, &str)]) -> Vec<(String, String)> {
    v.iter()
        .map(|(e, b)| (e.to_string(), b.to_string()))
        .collect()
}

#[test]
fn overhung_runout_is_named_alone_and_trusted() {
    let (run, d) = diagnosed(OVERHUNG, "unseen-overhung.toml", "runout-52");
    assert_eq!(
        named(&d),
        pairs(&[("probe_runout", "B2")]),
        "{}",
        d.to_text()
    );
    assert!(d.trusted, "{}", d.to_text());
    plinth_tests::simulated::assert_pedestals_near_truth(
        &run,
        &d.pedestals_after,
        0.02,
        "runout-52",
    );
}

#[test]
fn train_delay_is_named_alone_with_its_delay_in_its_error() {
    train_delay_named_alone("delay-51");
}

/// The train's stored run `case` diagnosed: exactly `sensor_delay` at B2
/// named, the first step's τ within 3 standard errors of the true delay.
fn train_delay_named_alone(case: &str) -> Diagnosis {
    let (run, d) = diagnosed(TRAIN, "unseen-train.toml", case);
    assert_eq!(
        named(&d),
        pairs(&[("sensor_delay", "B2")]),
        "{}",
        d.to_text()
    );
    unseen::assert_delay_in_its_error(&run, &d, 0);
    d
}

/// A held variant is tested against its own null, the base model with the
/// held dampings at zero, which fits worse than the state it would
/// replace. On this run (seed 55) a table correction so held passed that
/// test first while its refit fitted worse than the state (pedestal-level
/// χ² 1819 against 1691): the delay was named `bearing_coefficients`
/// (clearance ratio 0.975), then a 16 µs delay and mass anisotropy,
/// untrusted. A held winner must now also beat the state on the search's
/// one yardstick (χ² with the BIC's penalty): the delay alone, τ in its
/// error, trusted; the table correction, ranked above it, is said to be
/// passed over and why (in the JSON and the text).
#[test]
fn train_delay_beats_a_held_table_correction() {
    let d = train_delay_named_alone("delay-55");
    assert!(d.trusted, "{}", d.to_text());
    let passed = &d.steps[0].passed_over;
    assert!(
        passed.iter().any(|p| p.effect == "bearing_coefficients"
            && p.bearing == "B2"
            && p.reason.contains("fits worse")),
        "{passed:?}"
    );
    assert!(d
        .to_text()
        .contains("passed over: bearing_coefficients at B2"));
}
