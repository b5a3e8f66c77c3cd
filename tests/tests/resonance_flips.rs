//! A lightly damped rotor critical between two logged speeds is not a
//! keyphasor flip (docs/trust-flips.md, Session 46 (flipcrit17)). On the seventh unseen
//! machine (tests/data/ross-unseen-7/unseen-seven.toml, a turbine-generator
//! set) the first critical sits at 17.2 Hz with a log dec of 0.06: its
//! half-power band (0.33 Hz) is narrower than the 0.75 Hz logging step, so
//! the reading at 17.0 Hz catches the mode near its peak and its neighbours
//! do not. At B1, near that mode's node, every channel turns by most of
//! 180° against the neighbouring speeds, and the test in speed names a
//! flip; the other bearings turn with it and agree with B1 as read, so
//! nothing is flipped. The run is ROSS 2.3.0's, `python3
//! scripts/ross_unseen.py --machine unseen-seven DIR clean-t1c 5400`
//! (python3 the ROSS venv's), kept in
//! tests/data/ross-unseen-7/clean-t1c-5400. Main (729c571) lists 17.0 Hz
//! at B1 with a `keyphasor_flip` warning in identify, and diagnose leaves it
//! out as flipped.

use plinth::diagnose::data::Prepared;
use plinth::identify::WarningKind;
use plinth::rundir::RunDir;
use plinth_tests::rundown::identify;
use std::path::Path;

const RUN: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/data/ross-unseen-7/clean-t1c-5400"
);

/// identify lists no speed of the clean run and warns of no flip; diagnose
/// finds no flipped speed (one definition: `identify::flips`).
#[test]
fn a_critical_between_two_logged_speeds_is_not_named_a_flip() {
    let run = RunDir::read(Path::new(RUN)).expect("stored run directory");
    let id = identify(&run);
    for (bearing, report) in &id.noise {
        assert!(
            report.outlier_speeds_hz.is_empty(),
            "{bearing}: {:?}",
            report.outlier_speeds_hz
        );
    }
    for p in &id.pedestals {
        assert!(
            !p.has_warning(WarningKind::KeyphasorFlip),
            "{}: {:?}",
            p.bearing,
            p.warnings
        );
    }
    let prepared = Prepared::from_run(&run).expect("diagnose's data");
    assert!(
        prepared.flipped_speeds_hz.iter().all(Vec::is_empty),
        "{:?}",
        prepared.flipped_speeds_hz
    );
}
