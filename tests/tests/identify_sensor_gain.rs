//! One channel's sensitivity off (issue 17; unseen-nine's finding 2,
//! docs/unseen-nine.md; docs/trust.md, Session 49 (gain17)): identify
//! tests each bearing's y/z sensitivity ratios (rel_y against rel_z, ped_y
//! against ped_z), states in "Conditional on" how far a 1 % error of each
//! channel moves each value, and `--sensor-uncertainty` carries a stated
//! calibration uncertainty into the ±.
//!
//! Data: ROSS 2.3.0 runs of the ninth unseen machine (a turbocharger on
//! floating-ring bearings, k_yz = −k_zy = 0.35 k_yy), made by
//! scripts/ross_unseen.py, never by Plinth: `probe-gain-8210` (B1's
//! vertical probe reading 5 % low; `python3 scripts/ross_unseen.py
//! --machine unseen-nine tests/data/ross-unseen-9 ped-drift,probe-gain
//! 8210`) and `clean-r1c` (seed 1, `--repo`), both with noise columns.

use plinth::identify::conditional::sensor::{self, SensorUncertainty};
use plinth::identify::WarningKind;
use plinth::rundir::RunDir;
use plinth_tests::rundown::{identify, pedestal};
use plinth_tests::unseen::{self, ok_but_wrong};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-9");

fn stored(case: &str) -> RunDir {
    unseen::stored(DATA, case)
}

/// B1's rel_y reads 5 % low: B1 is untrusted with the channel named and
/// its ratio within 3 of its ± of −5 %; B2 is not flagged for it. On main
/// (e805765) B1 was printed `ok` with k_y −4.7 % (−21 ±).
#[test]
fn one_probe_five_percent_low_is_named_and_untrusted() {
    let run = stored("probe-gain-8210");
    let id = identify(&run);
    let b1 = pedestal(&id, "B1");
    assert!(!b1.trusted, "B1 trusted: {:?}", b1.warnings);
    let w = b1
        .warnings
        .iter()
        .find(|w| w.kind == WarningKind::SensorGain)
        .expect("a sensor_gain warning at B1");
    assert!(
        w.message.contains("B1 rel_y reads about -") && w.message.contains("relative to rel_z"),
        "{}",
        w.message
    );
    let e = id
        .sensor_gain
        .iter()
        .find(|e| e.bearing == "B1")
        .expect("B1 judged");
    assert!(
        (e.ratio[0] + 0.05).abs() < 3.0 * e.ratio_std_err[0],
        "rel_y/rel_z − 1 = {} ± {}",
        e.ratio[0],
        e.ratio_std_err[0]
    );
    let b2 = pedestal(&id, "B2");
    assert!(
        b2.warnings
            .iter()
            .all(|w| w.kind != WarningKind::SensorGain),
        "{:?}",
        b2.warnings
    );
}

/// Clean data with noise columns: nothing flagged for a sensitivity, every
/// bearing judged, and the per-channel condition stated: at B1 (its
/// pedestal resonating above the run) the channel that moves a value most
/// is one of its own with a move of the order of 1 % per 1 %, many ±.
#[test]
fn clean_run_is_not_flagged_and_each_channel_is_stated() {
    let run = stored("clean-r1c");
    let id = identify(&run);
    for p in &id.pedestals {
        assert!(
            p.warnings.iter().all(|w| w.kind != WarningKind::SensorGain),
            "{}: {:?}",
            p.bearing,
            p.warnings
        );
    }
    assert_eq!(id.sensor_gain.len(), 2, "{:?}", id.sensor_gain);
    assert!(ok_but_wrong(&run, &id, false).is_empty());
    let stated = sensor::of(&id);
    let b1 = stated
        .iter()
        .find(|s| s.bearing == "B1")
        .expect("B1 stated");
    assert!(
        (0.3..=1.5).contains(&b1.largest_percent.abs()) && b1.largest_std_errs.abs() > 2.0,
        "{b1:?}"
    );
    assert!(
        b1.message().starts_with("a 1 % error in B1 "),
        "{}",
        b1.message()
    );
    assert_eq!(b1.channels.len(), 4);
}

/// `--sensor-uncertainty 5`: every pedestal's ± carries a 5 % sensitivity
/// uncertainty per channel, and B1's k_y, k_z, m on `probe-gain-8210` are
/// within 3 of the widened ± (−4.7 % was −21 noise-only ±).
#[test]
fn a_stated_sensitivity_uncertainty_covers_the_gain() {
    let run = stored("probe-gain-8210");
    let mut id = identify(&run);
    let before = pedestal(&id, "B1").std_err;
    sensor::widen(
        &mut id,
        SensorUncertainty {
            rel: 0.05,
            ped: 0.05,
        },
    );
    let b1 = pedestal(&id, "B1");
    assert!(b1.std_err.k_y > 4.0 * before.k_y, "{:?}", b1.std_err);
    // Judged as printed ok: the widened ± must cover the truth.
    for p in &mut id.pedestals {
        p.trusted = true;
    }
    let wrong = ok_but_wrong(&run, &id, false);
    assert!(wrong.is_empty(), "{wrong:?}");
}
