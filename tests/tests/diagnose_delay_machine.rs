//! Issue 17: a sensor delay named right must not fail the machine-level
//! check for a reason that is not the delay's. The base model is
//! `plinth identify`'s maximum-likelihood fit; every step's joint refit is
//! the weighted fit of the pedestal equations, so between the base model
//! and step 1 every pedestal moves by the change of estimator (a fraction
//! of its ±), also those the step does not act on. On the third unseen
//! machine B3's soft, lightly damped bracket magnifies that in the
//! open-loop re-simulation more than the delay at B2 lowers it: step 1
//! "did not lower the machine-level gap" (seed 63: 0.0462 → 0.0501) and a
//! right delay, τ within its ±, was untrusted on 7 of 15 fresh seeds. Step
//! 1 is now judged against the base model refitted as the steps are
//! (`plinth::diagnose::machine::refitted_base`; seed 63: 0.0523 → 0.0501).
//!
//! Runs made by ROSS 2.3.0 with scripts/ross_unseen.py (`--machine
//! unseen-train`, case `delay`: τ = 150 µs on B2's rel probes; seed 63
//! kept under tests/data/ross-unseen-3/delay-63, and the stored `delay`
//! run, seed 1; seed 74 kept under tests/data/ross-unseen-3/delay-74,
//! `python3 scripts/ross_unseen.py --machine unseen-train DIR delay 74`);
//! only the reading is Plinth's.

use plinth::diagnose::report::Diagnosis;
use plinth_tests::unseen::{self, named};

const TRAIN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-3");

/// The train's stored run `case` diagnosed with `--machine`: exactly
/// `sensor_delay` at B2, τ within 3 standard errors of the true delay, the
/// machine-level gap lowered by the step, trusted.
fn delay_trusted(case: &str) -> Diagnosis {
    let run = unseen::stored(TRAIN, case);
    let d = unseen::diagnosis_with_machine_check(TRAIN, "unseen-train.toml", &run);
    assert_eq!(
        named(&d),
        vec![("sensor_delay".to_string(), "B2".to_string())],
        "{}",
        d.to_text()
    );
    unseen::assert_delay_in_its_error(&run, &d, 0);
    let s = &d.steps[0];
    let (Some(before), Some(after)) = (s.machine_gap_before, s.machine_gap_after) else {
        panic!("step 1 has no machine-level gaps: {}", d.to_text());
    };
    assert!(after < before, "machine-level gap {before:.4} → {after:.4}");
    assert!(d.trusted, "{:?}\n{}", d.trust_reasons, d.to_text());
    d
}

#[test]
fn a_fresh_train_delay_lowers_the_machine_level_gap_and_is_trusted() {
    delay_trusted("delay-63");
}

#[test]
fn the_stored_train_delay_is_trusted() {
    delay_trusted("delay");
}

/// The text report shows two machine-level "before" figures on a run with
/// a step: the overall one (the base model as `plinth identify` fits it,
/// JSON `machine_gap_before`) and step 1's (the base model refitted as the
/// steps fit it, what the step is judged against). On the stored delay run
/// they differ (0.0288 and 0.0347); each is printed with its own label.
#[test]
fn the_two_machine_level_befores_are_labelled_in_the_text() {
    use plinth::diagnose::report::{BASE_AS_IDENTIFY, BASE_AS_STEPS};
    let d = delay_trusted("delay");
    let text = d.to_text();
    let (Some(overall), Some(step1)) = (d.machine_gap_before, d.steps[0].machine_gap_before) else {
        panic!("no machine-level gaps: {text}");
    };
    assert!(
        (overall - step1).abs() > 1e-4,
        "the two befores coincide: {text}"
    );
    assert!(
        line_with(&text, overall).contains(BASE_AS_IDENTIFY),
        "{text}"
    );
    assert!(line_with(&text, step1).contains(BASE_AS_STEPS), "{text}");
}

/// The first line of `text` that prints the machine-level gap `figure` [-]
/// (to 4 decimals).
fn line_with(text: &str, figure: f64) -> &str {
    let f = format!("machine-level gap {figure:.4}");
    text.lines()
        .find(|l| l.contains(&f))
        .unwrap_or_else(|| panic!("no line with {f}: {text}"))
}

/// Seed 74 of the same case (τ = 150 µs at B2 only). Until session 36 the
/// search named the delay at B2, then a second, wrong `sensor_delay` (ped_y)
/// at B1, 410 ± 75 µs, passed by the Wald form of its test where the delay
/// trades against B1's damping (c_y turned negative), untrusted. A profiled
/// scalar is now tested by its likelihood ratio (docs/diagnose.md "Session
/// 36"): exactly the delay at B2, trusted, nothing at B1.
#[test]
fn no_wrong_second_delay_at_the_stiff_block() {
    let d = delay_trusted("delay-74");
    let text = d.to_text();
    assert!(
        d.steps
            .iter()
            .all(|s| s.bearing != "B1" || s.dropped.is_some()),
        "a step kept at B1: {text}"
    );
}
