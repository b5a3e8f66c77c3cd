//! Issue 17 on a second machine nobody tuned to, different in kind from
//! unseen_machine.rs's: an overhung single-stage compressor on two bearings
//! (tests/data/ross-unseen-2/unseen-overhung.toml: a 110 kg impeller
//! overhung beyond B2, B1 a tilting-pad-like table whose stiffness and
//! damping rise with speed, B2 a short-bearing oil film, pedestals with
//! k_z = 0.3 k_y), run down on a coast-down speed grid (geometric, dense at
//! low speed) with heteroscedastic noise (1 % of each phasor's amplitude
//! plus a floor). Every phasor and the truth are ROSS 2.3.0's and
//! scripts/ross_unseen.py's (`--machine unseen-overhung`), seed 1 of each
//! case kept in tests/data/ross-unseen-2/<case>/; only the reading is
//! Plinth's. The rates over several seeds are measured by
//! `scripts/bench-unseen.sh --machine unseen-overhung` (docs/unseen-overhung.md).
//! What does not work yet is written with the right assertion and ignored
//! with the measured rate, so it can be un-ignored when fixed.

use plinth::diagnose::report::Diagnosis;
use plinth::identify::WarningKind;
use plinth::rundir::RunDir;
use plinth_tests::rundown::identify;
use plinth_tests::unseen::{self, assert_ok_means_right, listed, named, ok_but_wrong, untrusted};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-2");

/// The stored run directory of `case` (seed 1).
fn stored(case: &str) -> RunDir {
    unseen::stored(DATA, case)
}

/// `plinth diagnose RUN --machine unseen-overhung.toml` as the command line
/// runs it: the search with the file's oil-film geometry, then the
/// machine-level check applied to the verdict.
fn diagnosis(run: &RunDir) -> Diagnosis {
    unseen::diagnosis_with_machine_check(DATA, "unseen-overhung.toml", run)
}

/// (effect, bearing) pairs as owned strings, sorted.
fn pairs(v: &[(&str, &str)]) -> Vec<(String, String)> {
    let mut v: Vec<(String, String)> = v
        .iter()
        .map(|(e, b)| (e.to_string(), b.to_string()))
        .collect();
    v.sort();
    v
}

/// The speeds the truth lists for `bearing` under `effect` (flipped or
/// outlier speeds), sorted.
fn truth_speeds(run: &RunDir, effect: &str, bearing: &str) -> Vec<f64> {
    let mut v: Vec<f64> = run
        .truth
        .as_ref()
        .expect("truth")
        .effect_details
        .iter()
        .filter(|d| d.name == effect && d.bearing == bearing)
        .flat_map(|d| d.parameters.values().copied())
        .collect();
    v.sort_by(f64::total_cmp);
    v
}

/// Diagnose names exactly `want` (a base at any bearing: "" matches all),
/// and the pedestals after it lie within 2 % of ROSS's (k, m).
fn assert_named(case: &str, want: &[(&str, &str)]) -> Diagnosis {
    let run = stored(case);
    let d = diagnosis(&run);
    let got: Vec<(String, String)> = named(&d)
        .into_iter()
        .map(|(e, b)| {
            let any = want.iter().any(|(we, wb)| *we == e && wb.is_empty());
            (e, if any { String::new() } else { b })
        })
        .collect();
    assert_eq!(got, pairs(want), "{case}: {}", d.to_text());
    plinth_tests::simulated::assert_pedestals_near_truth(&run, &d.pedestals_after, 0.02, case);
    d
}

#[test]
fn clean_runs_are_flagged_by_nothing_and_ok_means_right() {
    for case in ["clean-h1c", "clean-d3"] {
        let run = stored(case);
        let id = identify(&run);
        unseen::assert_flagged_by_nothing(&run, &id, &diagnosis(&run), case);
    }
}

/// Heteroscedastic noise (1 % of each phasor plus a floor) without the
/// noise columns is clean data too. Measured over 30 seeds
/// (`scripts/bench-unseen.sh --machine unseen-overhung 30 clean-h1`,
/// session 24): identify prints no k or m `ok` more than 3 of its ± off
/// (session 23: 22/30 before the variance function), but untrusts B1 for
/// lack of fit in 4/30 and lists a speed (77.1 Hz) in 6/30 (docs/trust-noise-law.md,
/// "Session 24"); diagnose names nothing in 30/30, all trusted (session 23:
/// 21/30 named). The stored seed 1 is one of the clean 26.
#[test]
fn clean_heteroscedastic_noise_without_columns_is_flagged_by_nothing() {
    let run = stored("clean-h1");
    let id = identify(&run);
    assert!(untrusted(&id).is_empty(), "{:?}", untrusted(&id));
    for b in ["B1", "B2"] {
        assert!(listed(&id, b).is_empty(), "{b} lists {:?}", listed(&id, b));
    }
    let wrong = ok_but_wrong(&run, &id, true);
    assert!(wrong.is_empty(), "{wrong:?}");
    let d = diagnosis(&run);
    assert!(named(&d).is_empty(), "{}", d.to_text());
}

/// Every effect untrusts exactly the bearing(s) it acts on, for lack of
/// fit, and the other bearing's `ok` is right.
#[test]
fn each_effect_untrusts_exactly_its_bearings_in_identify() {
    for (case, bearings) in [
        ("sub-base", &["B1"][..]),
        ("table-film", &["B2"]),
        ("table-scale", &["B1"]),
        ("cross", &["B1"]),
        ("runout", &["B2"]),
        ("delay", &["B1"]),
        ("base-runout-delay", &["B1", "B2"]),
        ("cross-runout", &["B1", "B2"]),
    ] {
        let run = stored(case);
        let id = identify(&run);
        assert_eq!(untrusted(&id), bearings, "{case}");
        for b in bearings {
            let p = id.pedestal(b).expect("pedestal");
            assert!(p.has_warning(WarningKind::LackOfFit), "{case}: {b}");
        }
        assert_ok_means_right(&run, &id, case);
    }
}

#[test]
fn the_sub_base_is_named_at_its_bearing() {
    let d = assert_named("sub-base", &[("pedestal_sub_base", "B1")]);
    assert!(d.trusted, "{:?}", d.trust_reasons);
}

#[test]
fn a_worn_oil_film_is_named_as_bearing_coefficients_at_its_bearing() {
    let d = assert_named("table-film", &[("bearing_coefficients", "B2")]);
    assert!(d.trusted, "{:?}", d.trust_reasons);
}

/// A tabulated bearing (B1) whose table is 25 % too stiff, its damping
/// right. Measured: named `bearing_coefficients` at B1 alone and trusted
/// 5/5, k_scale 0.80, worst pedestal k/m error after 0.81 %
/// (`scripts/bench-unseen.sh --machine unseen-overhung 5 table-scale`).
#[test]
fn a_wrong_table_scale_is_named_as_bearing_coefficients_at_its_bearing() {
    let d = assert_named("table-scale", &[("bearing_coefficients", "B1")]);
    assert!(d.trusted, "{:?}", d.trust_reasons);
}

#[test]
fn cross_coupling_runout_and_a_sensor_delay_are_named_at_their_bearing() {
    for (case, effect, bearing) in [
        ("cross", "pedestal_cross_coupling", "B1"),
        ("runout", "probe_runout", "B2"),
        ("delay", "sensor_delay", "B1"),
    ] {
        let d = assert_named(case, &[(effect, bearing)]);
        assert!(d.trusted, "{case}: {:?}", d.trust_reasons);
    }
}

#[test]
fn a_base_with_runout_and_a_delay_are_all_named() {
    let d = assert_named(
        "base-runout-delay",
        &[
            ("foundation_coupling", ""),
            ("probe_runout", "B1"),
            ("sensor_delay", "B2"),
        ],
    );
    assert!(d.trusted, "{:?}", d.trust_reasons);
}

#[test]
fn two_effects_at_two_bearings_are_both_named() {
    let d = assert_named(
        "cross-runout",
        &[("pedestal_cross_coupling", "B2"), ("probe_runout", "B1")],
    );
    assert!(d.trusted, "{:?}", d.trust_reasons);
}

/// One keyphasor for the machine: every channel of both bearings negated at
/// three speeds. What holds: no speed that was not flipped is listed, the
/// flip is named, the pedestals stay right, diagnose names nothing.
#[test]
fn flips_of_every_bearing_list_no_wrong_speed_and_keep_the_pedestals_right() {
    let run = stored("flips");
    let id = identify(&run);
    assert!(untrusted(&id).is_empty(), "{:?}", untrusted(&id));
    for b in ["B1", "B2"] {
        let want = truth_speeds(&run, "keyphasor_flip", b);
        let got = listed(&id, b);
        assert!(!got.is_empty(), "{b}: nothing listed");
        assert!(
            got.iter().all(|s| want.contains(s)),
            "{b}: {got:?} not in {want:?}"
        );
        assert!(
            id.pedestal(b)
                .expect(b)
                .has_warning(WarningKind::KeyphasorFlip),
            "{b}"
        );
    }
    assert_ok_means_right(&run, &id, "flips");
    let d = diagnosis(&run);
    assert!(named(&d).is_empty(), "{}", d.to_text());
}

#[test]
#[ignore = "issue 17: keyphasor flips of every bearing at three speeds are listed exactly at \
            both bearings in 1/5 runs (the stored seed 1 lists 2 of 3 at B1, 1 of 3 at B2; never \
            a speed that was not flipped)"]
fn flips_of_every_bearing_are_listed_exactly() {
    let run = stored("flips");
    let id = identify(&run);
    for b in ["B1", "B2"] {
        assert_eq!(
            listed(&id, b),
            truth_speeds(&run, "keyphasor_flip", b),
            "{b}"
        );
    }
}

#[test]
fn one_outlier_speed_is_listed_exactly_and_nothing_is_named() {
    let run = stored("outlier");
    let id = identify(&run);
    assert!(untrusted(&id).is_empty(), "{:?}", untrusted(&id));
    assert_eq!(listed(&id, "B2"), truth_speeds(&run, "outlier_speed", "B2"));
    assert!(
        listed(&id, "B1").is_empty(),
        "B1 lists {:?}",
        listed(&id, "B1")
    );
    assert_ok_means_right(&run, &id, "outlier");
    let d = diagnosis(&run);
    assert!(named(&d).is_empty(), "{}", d.to_text());
}
