//! A found scale is named a unit mistake only when the machine-level fit
//! tells it from 1 by its own ± and it lies beyond a transducer's
//! calibration tolerance (session 42, docs/robustness-hostile.md, Session 42 (unitscale17d);
//! `plinth::diagnose::machine::unit_scale::evidence`).

use plinth::diagnose::diagnose;
use plinth::diagnose::machine::unit_scale::{evidence, Kind, Reading};
use plinth::diagnose::machine::MachineCheck;
use plinth_tests::unseen;

/// unseen-train's clean run, seed 825 (`python3 scripts/ross_unseen.py
/// --machine unseen-train OUT clean-p2c 825`, ROSS 2.3.0): the final model
/// fails the machine-level check on clean data (gap 0.145, limit 0.128:
/// the check's own false alarm), and main (296e18c) then named B3's `rel`
/// × 1.0072 a unit or scale mistake (with B3's table × 0.9933 as its twin):
/// a scale of 0.7 %, no unit factor and within a transducer's calibration
/// tolerance. Now nothing is named: the diagnosis stays untrusted with the
/// machine-file reason.
#[test]
fn a_noise_sized_scale_on_a_clean_run_is_not_named() {
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-3");
    let run = unseen::stored(data, "clean-p2c-825");
    let (machine, options) = unseen::machine_and_options(data, "unseen-train.toml");
    let out = diagnose(&run, &options).expect("diagnose");
    // The scale main named, with its ± from the machine-level fit (printed
    // for the session's docs).
    let first = out.states.first().expect("a base model");
    let b3 = Reading::bearing(Kind::Rel, 2);
    let sd = evidence::log_sd(&machine, &out.prep, first, b3, 1.0072).expect("the scale's ±");
    println!("B3 rel × 1.0072: sd of ln s = {sd}");
    assert!(!evidence::named(1.0072, sd));
    let check = MachineCheck::of(&machine, &out).expect("machine check");
    let mut d = out.diagnosis;
    check.apply(&mut d);
    let v = serde_json::to_value(&d).expect("diagnosis as JSON");
    assert!(
        v.get("unit_scale").is_none(),
        "a unit mistake named on a clean run: {}",
        v["unit_scale"]
    );
    assert!(!d.trusted, "the check's own false alarm stays untrusted");
    assert!(
        d.trust_reasons
            .iter()
            .any(|r| r.contains("does not describe the machine of this run")),
        "{:?}",
        d.trust_reasons
    );
}
