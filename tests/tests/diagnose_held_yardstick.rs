//! Issue 17: a held variant (an effect fitted with a pedestal's impossible
//! dampings held at zero) is tested against its own null, the base model
//! with those dampings at zero, which fits worse than the state it would
//! replace. A table correction so held passed that test first on the third
//! unseen machine's 150 µs delay at B2 while its refit fitted worse than the
//! state (χ² 1819 against 1691 on this run): a delay named `bearing_
//! coefficients` (clearance ratio 0.975), then mass anisotropy and a 16 µs
//! delay, untrusted. A held winner must now also beat the state on the
//! search's one yardstick (the pedestal-level χ² with the BIC's penalty).
//!
//! Run made by ROSS 2.3.0 with scripts/ross_unseen.py (`--machine
//! unseen-train DIR delay 55`), kept under tests/data/ross-unseen-3/delay-55;
//! only the reading is Plinth's.

use plinth_tests::unseen::{self, named};

const TRAIN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-3");

#[test]
fn train_delay_beats_a_held_table_correction() {
    let run = unseen::stored(TRAIN, "delay-55");
    let d = unseen::diagnosis_with_machine_check(TRAIN, "unseen-train.toml", &run);
    assert_eq!(
        named(&d),
        vec![("sensor_delay".to_string(), "B2".to_string())],
        "{}",
        d.to_text()
    );
    let truth = run
        .truth
        .as_ref()
        .expect("truth")
        .effect_details
        .iter()
        .find(|e| e.name == "sensor_delay")
        .and_then(|e| e.parameters.get("tau_s").copied())
        .expect("true delay");
    let tau = d.steps[0]
        .parameters
        .iter()
        .find(|p| p.name == "tau")
        .expect("tau");
    assert!(
        (tau.value - truth).abs() < 3.0 * tau.std_err,
        "tau {:.3e} ± {:.1e} s, true {truth:.3e} s",
        tau.value,
        tau.std_err
    );
    assert!(d.trusted, "{}", d.to_text());
}
