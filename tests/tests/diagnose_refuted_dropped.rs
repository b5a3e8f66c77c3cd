//! Issue 17 ("Done when": every effect named at the right bearing, nothing
//! else named): a step the machine-level check refutes is dropped, with
//! every step chosen after it (`plinth::diagnose::refute`, session 50,
//! docs/diagnose-verdict.md "Session 50 (refute50)"). Until then diagnose
//! kept it named after the right one: on unseen-nine `runout-drift` (B2's
//! probe runout growing 1.8-fold and turning 40° over the run)
//! `probe_runout` at B2 (right), then `sensor_delay` at B2, which raised
//! the re-simulated machine's gap by 13 times the change's own noise.
//!
//! The run: `tests/data/diagnose-refuted/runout-drift-9201-every3`, made by
//! ROSS 2.3.0 (`python3 scripts/ross_unseen.py --machine unseen-nine DIR
//! runout-drift 9201`) and cut to every third speed (the rows of the
//! speeds whose rank in the run is a multiple of 3, ranks from 0: 30 of 90
//! speeds, so that the two searches fit the time a test may take), only
//! the reading is Plinth's. On main (d908e34): named `probe_runout` and
//! `sensor_delay` at B2, the delay's machine-level gap 0.0610 → 0.0900
//! (12.8 times its noise), untrusted.

use plinth::diagnose::refute::diagnose_checked;
use plinth_tests::unseen::{self, named};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/diagnose-refuted");
const NINE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-9");

#[test]
fn a_delay_the_machine_level_check_refutes_is_dropped_and_the_runout_kept() {
    let run = unseen::stored(DATA, "runout-drift-9201-every3");
    let (machine, options) = unseen::machine_and_options(NINE, "unseen-nine.toml");
    let (out, check) = diagnose_checked(&run, &options, &machine).expect("diagnose --machine");
    let mut d = out.diagnosis;
    check.apply(&mut d);
    let text = d.to_text();
    let names = named(&d);
    // The right effect is named, and only it.
    assert_eq!(
        names,
        [("probe_runout".to_string(), "B2".to_string())],
        "{text}"
    );
    // The refuted delay is dropped, said with the gaps that refute it.
    let r = d
        .refuted_steps
        .iter()
        .find(|r| r.effect == "sensor_delay" && r.bearing == "B2")
        .unwrap_or_else(|| panic!("the delay at B2 not dropped: {text}"));
    assert!(r.refuted, "{r:?}");
    let (Some(before), Some(after)) = (r.machine_gap_before, r.machine_gap_after) else {
        panic!("no machine-level gaps: {r:?}");
    };
    assert!(after > before, "{r:?}");
    assert!(
        !names.iter().any(|(e, b)| d
            .refuted_steps
            .iter()
            .any(|r| &r.effect == e && &r.bearing == b)),
        "a dropped step is named again: {names:?}"
    );
    assert!(
        text.contains("Dropped by the machine-level check"),
        "{text}"
    );
    // Still untrusted: what the delay was chosen on is unexplained.
    assert!(!d.trusted, "{text}");
    assert!(
        d.trust_reasons
            .iter()
            .any(|w| w.starts_with("sensor_delay") && w.contains("dropped")),
        "{:?}",
        d.trust_reasons
    );
}
