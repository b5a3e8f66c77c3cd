//! Probes mounted at an angle and written as they read (issue 17, session
//! 48, helper mount17; docs/trust.md "Session 48 (mount17)"): a bearing's
//! two proximity probes at ±45° from the vertical (the X-Y pair of API 670)
//! written as `rel_y` and `rel_z` instead of resolved to y (vertical) and z
//! (horizontal). identify names the turned pair at its bearing with the
//! angle (`rel_rotated`), and the pedestal it gives with the pair resolved
//! back is the machine's.
//!
//! Data from paths independent of Plinth (tests/data/ross-probe-axes/):
//! - `probe-axes-7900`: ROSS 2.3.0, `python3 scripts/ross_unseen.py
//!   --machine unseen-eight DIR probe-axes 7900` (both bearings' probes at
//!   45°, made by the script's `add_probe_axes`);
//! - `b1-rel-minus30-7906`: ROSS's clean run `clean-g1c` seed 7906 of the
//!   same machine with only B1's probes turned by −30° (a general angle, no
//!   field arrangement), by the Python of docs/trust.md's appendix
//!   (`rotate_pair.py DIR/clean-g1c-7906 OUT B1 rel -30`).
//!
//! The clean control is tests/data/ross-unseen-8/clean-g1c (nothing named).

use plinth::estimate::noise::RunNoise;
use plinth::identify::convention::{self, Angle, Convention};
use plinth::identify::{Identification, Options};
use plinth::rundir::RunDir;
use plinth_tests::rundown::identify;
use plinth_tests::unseen::{self, truth_of};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-probe-axes");
const EIGHT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-8");

/// The convention each pedestal of `id` is suspected of, by bearing.
fn suspected(id: &Identification) -> Vec<(String, Option<Convention>)> {
    id.pedestals
        .iter()
        .map(|p| (p.bearing.clone(), p.suspected_convention_error))
        .collect()
}

/// The pedestals identify gives with the named mistakes undone, against
/// ROSS's truth: every k_y, k_z and m within `tolerance` (relative).
fn corrected_within(run: &RunDir, id: &Identification, tolerance: f64) {
    let options = Options::default();
    let noise = RunNoise::estimate(run, options.quantisation);
    let findings = convention::diagnose(run, id, &noise, &options);
    assert!(!findings.is_empty());
    for f in findings {
        let t = truth_of(run, &f.bearing);
        let p = &f.corrected_fit.pedestal;
        for (name, got, want) in [
            ("k_y", p.k_y, t.k_y),
            ("k_z", p.k_z, t.k_z),
            ("m", p.m, t.m),
        ] {
            let e = (got - want).abs() / want;
            assert!(
                e <= tolerance,
                "{} {name}: {got:.4e} against ROSS's {want:.4e} ({:.2} %)",
                f.bearing,
                100.0 * e
            );
        }
    }
}

/// Both bearings' probes at 45° (ROSS, unseen-eight): each bearing is
/// named `rel_rotated 45°` and untrusted, the message says what to check
/// and how to resolve the pair, and with the pair resolved back each
/// pedestal's k and m are within 2 % of ROSS's. On main: no convention is
/// suspected (the run is read as a sensor delay and model error).
#[test]
fn probes_at_45_degrees_are_named_with_their_angle() {
    let run = unseen::stored(DATA, "probe-axes-7900");
    let id = identify(&run);
    let turned = Some(Convention::RelRotated(Angle::from_deg(45.0)));
    assert_eq!(
        suspected(&id),
        vec![("B1".to_string(), turned), ("B2".to_string(), turned)]
    );
    for p in &id.pedestals {
        assert!(!p.trusted, "{}", p.bearing);
        let w = p
            .warnings
            .iter()
            .find(|w| {
                w.message
                    .contains("suspected convention error `rel_rotated 45°`")
            })
            .expect("the suspicion's warning");
        assert!(w.message.contains("Were they written as they read?"));
        assert!(w.message.contains("y = cos a·rel_y + sin a·rel_z"));
    }
    corrected_within(&run, &id, 0.02);
}

/// Only B1's probes turned, by −30° (no field arrangement: the angle is
/// estimated): B1 is named `rel_rotated −30°` and nothing is suspected at
/// B2, whose data are as ROSS made them; the corrected B1 is within 2 %.
#[test]
fn one_bearing_turned_by_a_general_angle_is_named_there_only() {
    let run = unseen::stored(DATA, "b1-rel-minus30-7906");
    let id = identify(&run);
    let s = suspected(&id);
    assert_eq!(s[1], ("B2".to_string(), None), "{s:?}");
    match s[0].1 {
        Some(Convention::RelRotated(a)) => {
            assert!((a.deg() + 30.0).abs() <= 1.0, "B1 turned by {a}, not −30°")
        }
        other => panic!("B1: {other:?}"),
    }
    corrected_within(&run, &id, 0.02);
}

/// The same machine's clean run with the noise columns: no turned pair
/// (and no other mistake) is suspected.
#[test]
fn clean_run_suspects_no_turned_pair() {
    let run = unseen::stored(EIGHT, "clean-g1c");
    let id = identify(&run);
    assert!(
        id.pedestals
            .iter()
            .all(|p| p.suspected_convention_error.is_none()),
        "{:?}",
        suspected(&id)
    );
}
