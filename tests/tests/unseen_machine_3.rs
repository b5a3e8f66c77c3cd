//! Issue 17 on a third machine nobody tuned to, different in kind from the
//! first two: a motor-pump train modelled as one long flexible shaft on
//! three bearings (tests/data/ross-unseen-3/unseen-train.toml: B1 a
//! cross-coupled sleeve table on a pedestal ten times stiffer than its
//! bearing, B2 an oil film, B3 a stiff lightly damped table on a soft
//! bracket with the impeller overhung beyond it), run UP at constant
//! acceleration (dense at high speed) with the band 38-46 Hz skipped, noise
//! of a different style per kind of sensor (pedestal pick-ups 2 % of each
//! phasor, proximity probes a constant floor), and a digits case with B1 at
//! 2 significant digits, B2 at 3, B3 at 4. Every phasor and the truth are
//! ROSS 2.3.0's and scripts/ross_unseen.py's (`--machine unseen-train`),
//! seed 1 of each case kept in tests/data/ross-unseen-3/<case>/; only the
//! reading is Plinth's. The rates over several seeds are measured by
//! `scripts/bench-unseen.sh --machine unseen-train` (docs/unseen-train.md). What
//! does not work yet is written with the right assertion and ignored with
//! the measured rate, so it can be un-ignored when fixed.

use plinth::diagnose::diagnose;
use plinth::diagnose::report::Diagnosis;
use plinth::identify::WarningKind;
use plinth::rundir::RunDir;
use plinth_tests::rundown::identify;
use plinth_tests::unseen::{
    self, assert_ok_means_right, listed, named, ok_but_wrong, suspected, untrusted,
};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-3");
const BEARINGS: [&str; 3] = ["B1", "B2", "B3"];

/// The stored run directory of `case` (seed 1).
fn stored(case: &str) -> RunDir {
    unseen::stored(DATA, case)
}

/// `plinth diagnose RUN --machine unseen-train.toml` as the command line
/// runs it: the search with the file's oil-film geometry, then the
/// machine-level check applied to the verdict.
fn diagnosis(run: &RunDir) -> Diagnosis {
    unseen::diagnosis_with_machine_check(DATA, "unseen-train.toml", run)
}

/// Clean data with a noise style the first two machines did not have: the
/// pick-ups' 2 % of each phasor with the probes' constant floor, no noise
/// columns.
#[test]
fn clean_per_sensor_noise_is_flagged_by_nothing_and_ok_means_right() {
    let run = stored("clean-p2");
    let id = identify(&run);
    assert!(untrusted(&id).is_empty(), "{:?}", untrusted(&id));
    for b in BEARINGS {
        assert!(listed(&id, b).is_empty(), "{b} lists {:?}", listed(&id, b));
    }
    assert_ok_means_right(&run, &id, "clean-p2");
    let d = diagnosis(&run);
    assert!(named(&d).is_empty(), "{}", d.to_text());
    assert!(d.trusted, "{:?}\n{}", d.trust_reasons, d.to_text());
}

/// A clean run-up names no keyphasor flip at its first speeds. Seeds 717
/// and 356 of clean-p2c (`python3 scripts/ross_unseen.py --machine
/// unseen-train tests/data/ross-unseen-3 clean-p2c 717`): the test across
/// bearings named B1 flipped at 5 Hz, the first speed, where the window's
/// subspace is an extrapolation (two of 10 such runs in 1000,
/// docs/trust-bad-speeds.md "Session 37"). Seed 717: Σ r/s 84.7 against its limit
/// 43.5, and negating B1, B2 or B3 each passed every condition: the data
/// do not say which bearing flipped, and nothing is named. Seed 356: only
/// B1's negation passed, but the studentised r/((1 + ℓ)s′) that an
/// extrapolated subspace calls for is 28.4, within the limit. identify
/// lists nothing and trusts every pedestal, and diagnose's flip search
/// (`Prepared::from_run`) names no flip either.
#[test]
fn a_clean_run_up_names_no_flip_at_its_first_speeds() {
    for case in ["clean-p2c-717", "clean-p2c-356"] {
        let run = stored(case);
        let id = identify(&run);
        for b in BEARINGS {
            assert!(
                listed(&id, b).is_empty(),
                "{case}: {b} lists {:?}",
                listed(&id, b)
            );
        }
        assert!(untrusted(&id).is_empty(), "{case}: {:?}", untrusted(&id));
        let prepared = plinth::diagnose::data::Prepared::from_run(&run).expect("prepared");
        assert!(
            prepared.flipped_speeds_hz.iter().all(Vec::is_empty),
            "{case}: {:?}",
            prepared.flipped_speeds_hz
        );
    }
}

/// Each bearing at its own number of digits (B1 2, B2 3, B3 4): nothing
/// untrusted, every `ok` right (identify only: diagnose takes about a
/// minute on these runs).
#[test]
fn digits_per_bearing_untrust_nothing_and_ok_means_right() {
    let run = stored("clean-dmix");
    let id = identify(&run);
    assert!(untrusted(&id).is_empty(), "{:?}", untrusted(&id));
    assert_ok_means_right(&run, &id, "clean-dmix");
}

/// Each bearing written with its own digits: none lists a clean speed.
/// The digits were counted per column of measurements.csv over every
/// bearing, so B1 (2 digits) and B2 (3) were given B3's 4-digit floor, it
/// did not fit, their noise fell back to one scatter level per channel, and
/// B2's 3-digit rounding at the rotor's 78 Hz peak was listed as outliers
/// (16/30 runs). Counted per bearing (`ColumnDigits::of_rows`): a clean
/// speed listed in 0/30 runs (identify only, `plinth identify --json` over
/// seeds 1-30 of `scripts/ross_unseen.py --machine unseen-train DIR
/// clean-dmix`); an `ok` value more than 3 ± off in 1/30 (B1 3.2 ±), as
/// before (1/30, B1 3.0 ±).
#[test]
fn digits_per_bearing_list_no_clean_speed() {
    let id = identify(&stored("clean-dmix"));
    for b in BEARINGS {
        assert!(listed(&id, b).is_empty(), "{b} lists {:?}", listed(&id, b));
    }
}

/// B3's bearing is stiff and nearly undamped (ΩC_b is under 1 % of K_b), so
/// reading the speeds as rpm (Ω/60, the table's speeds too) changes only
/// B3's tiny bearing damping force and scales m by 3600 and c by 60: the
/// two readings fit alike, and which one wins is the noise's choice. The
/// rule compared them by ν·ln(r_b/r_a) of the unweighted relative residual
/// alone, a likelihood ratio only when every speed's equation error has the
/// same variance; with the pick-ups' 2 % proportional noise a few resonance
/// speeds carry the sum and a 4 % smaller r (1.46e-2 against 1.52e-2 on the
/// stored run, whose noise-whitened χ²/ν is WORSE under rpm: 1.028 against
/// 0.994) passed for decisive: B3 untrusted with "suspected convention
/// error speed_in_rpm" (m = 3.06e5 kg) in 13/30 clean runs with noise
/// columns and 7/30 without. Now the noise-weighted ratio ν·ln(χ²_b/χ²_a)
/// must be decisive too and the named reading's χ² no worse than the data
/// as found (identify::convention::decide): 0/30 and 0/30, identify on the
/// runs of `UNSEEN_RUNS=DIR scripts/bench-unseen.sh --machine unseen-train
/// 30 clean-p2c clean-p2`.
#[test]
fn a_nearly_undamped_bearing_is_not_taken_for_speeds_in_rpm() {
    for case in ["clean-p2c", "runout"] {
        let id = identify(&stored(case));
        let named = suspected(&id);
        assert!(named.is_empty(), "{case}: {named:?}");
    }
}

/// Every effect untrusts exactly the bearing(s) it acts on, and the other
/// bearings' `ok` values are right.
#[test]
fn each_effect_untrusts_exactly_its_bearings_in_identify() {
    for (case, bearings) in [
        ("table-film", &["B2"][..]),
        ("cross", &["B3"]),
        ("delay", &["B2"]),
        ("base-runout", &["B1", "B2", "B3"]),
    ] {
        let run = stored(case);
        let id = identify(&run);
        assert_eq!(untrusted(&id), bearings, "{case}");
        assert_ok_means_right(&run, &id, case);
    }
    let id = identify(&stored("table-film"));
    let b2 = id.pedestal("B2").expect("B2");
    assert!(b2.has_warning(WarningKind::LackOfFit));
}

/// B2's pedestal on a stiff sub-base (150 kg, 200/120 MN/m: its own
/// resonance near 180 Hz, the pedestal's 137/103 Hz, both above the
/// 85 Hz top speed). Below both resonances the two masses move nearly as
/// one: the support seen at the bearing is a single pedestal of the series
/// stiffness k·k_s/(k + k_s) (82.4/48.0 MN/m) and a mass m + m_s·(k/(k +
/// k_s))² (215 kg), and it fits the data to the noise (χ²/ν about 1):
/// identify fits k_y 83.1 ± 0.1 MN/m against the pedestal element's 140
/// (−41 %), m 222 kg against 190. What is left is the Ω⁴ term of the
/// two-mass support (Ω⁴Q 1-3 % of the stiffness at the top speed), which
/// the support-mode test looks for; being positive for any support below
/// its second mode, it is tested one-sided (session 29): on seed 2 the
/// two-sided χ²(2) p was 5.9e-4 against its 3.3e-4 limit and B2 was printed
/// `ok` 41 % off. Seeds 1 (`sub-base`) and 2 (`sub-base-2`), both stored
/// ROSS runs (`python3 scripts/ross_unseen.py --machine unseen-train DIR
/// sub-base 1 2`): B2 untrusted, nothing printed `ok` is wrong. Measured
/// 5/5 untrusted (`python3 scripts/bench_unseen.py --machine unseen-train
/// PLINTH DIR 5 sub-base`; 4/5 before). Seed 93 (`sub-base-93`, stored the
/// same way): T̄ 12.0, p 1.26e-3, printed `ok` with k −40 % under the
/// support rule's former 0.001 per run (limit 3.3e-4) and untrusted at its
/// 0.005 (limit 1.7e-3; the rate's clean false-alarm rate measured in
/// docs/trust-support-mode.md, session 36).
#[test]
fn a_sub_base_above_the_range_is_not_printed_ok() {
    for case in ["sub-base", "sub-base-2", "sub-base-93"] {
        let run = stored(case);
        let id = identify(&run);
        assert_eq!(untrusted(&id), ["B2"], "{case}");
        let wrong = ok_but_wrong(&run, &id, false);
        assert!(wrong.is_empty(), "{case}: {wrong:?}");
    }
}

/// The same sub-base named by diagnose (session 31). Its Ω⁴ term is a few
/// standard errors (the support-mode test's T̄ 14.9 on seed 2, limit
/// 3.3e-4 reached at p = 3.0e-4): the library's criterion for the
/// above-range candidate (two-sided Wald over 36 candidates, ΔBIC > 0 on
/// two parameters) missed it on seeds 2, 4, 5 (candidate's Wald 9.6-14.8)
/// and the diagnosis said only that B2's support falls as Ω⁴. Now a
/// bearing the support-mode test flags, at which no step acts when no
/// library candidate is significant, is given the above-range candidate
/// (`diagnose::foundation::sub_base::above_range`): `pedestal_sub_base` at
/// B2 and nothing else, untrusted (pedestal and sub-base not separable),
/// with q_y, q_z positive and within 3 of their ± of the ROSS chain's Ω⁴
/// coefficient k²M_s²/(k + K_s)³ per direction. Seeds 1 (`sub-base`) and 2
/// (`sub-base-2`, nothing named before), and 93 (`sub-base-93`: trusted with
/// nothing named at the support rule's former 0.001 per run; named at its
/// 0.005, session 36).
#[test]
fn a_sub_base_above_the_range_is_named_at_its_bearing() {
    for case in ["sub-base", "sub-base-2", "sub-base-93"] {
        let run = stored(case);
        let d = diagnosis(&run);
        let want = vec![("pedestal_sub_base".to_string(), "B2".to_string())];
        assert_eq!(named(&d), want, "{case}: {}", d.to_text());
        assert!(!d.trusted, "{case}: {}", d.to_text());
        let step = d.steps.iter().find(|s| s.dropped.is_none()).expect("step");
        assert_eq!(step.channels.as_deref(), Some("above_range"), "{case}");
        let truth = run.truth.as_ref().expect("truth");
        let base = truth
            .bases
            .iter()
            .find(|b| b.bearings == ["B2"])
            .expect("sub-base");
        let ped = unseen::truth_of(&run, "B2");
        for (name, k, k_s, m_s) in [
            ("q_y", ped.k_y, base.k_y, base.m_y),
            ("q_z", ped.k_z, base.k_z, base.m_z),
        ] {
            let q = step.parameters.iter().find(|e| e.name == name).expect(name);
            let want = k * k * m_s * m_s / (k + k_s).powi(3);
            assert!(q.value > 0.0, "{case} {name}: {q:?}");
            assert!(
                (q.value - want).abs() < 3.0 * q.std_err,
                "{case} {name}: {q:?} against {want:.3e}"
            );
        }
    }
}

// B3's table 25 % stiffer than its bearing (the stored table-scale run):
// k, m, c all +25 % with a perfect fit (the pedestal equations are
// homogeneous in a nearly undamped bearing's force). identify now says B3's
// values scale with its table and `--table-uncertainty` carries the table's
// doubt into the ±: tested in
// `identify_conditional::a_stiff_undamped_table_is_said_to_scale_and_its_doubt_covers_its_error`.

/// One outlier speed at B3 (seed 1: 54.077 Hz). identify lists exactly
/// that speed at B3, 5/5 runs. diagnose did not leave it out (it did for
/// keyphasor flips), the gap at that one speed was taken for model error and
/// `pedestal_sub_base` at B3 was named with the verdict trusted (gap 0.054 →
/// 0.032) in 1/5 runs, seed 1, in ~4 min. Now the speeds the base model's
/// robust fit lists are left out of the search and tested again under the
/// model it chose (`diagnose::outliers`): nothing named, the speed listed
/// in `outlier_speeds_hz`, 5/5 (`scripts/bench-unseen.sh --machine
/// unseen-train 5 outlier`), ~1 s.
#[test]
fn one_outlier_speed_names_nothing_in_diagnose() {
    let run = stored("outlier");
    let id = identify(&run);
    assert_eq!(listed(&id, "B3").len(), 1, "{:?}", listed(&id, "B3"));
    let d = diagnosis(&run);
    assert!(named(&d).is_empty(), "{}", d.to_text());
    assert_eq!(
        d.outlier_speeds_hz["B3"],
        listed(&id, "B3"),
        "{}",
        d.to_text()
    );
    assert!(
        d.to_text().contains("OUTLIER SPEEDS at B3"),
        "{}",
        d.to_text()
    );
}

/// The re-test that decides whether a listed speed is put back has power:
/// under the model the search chose (the base model: nothing named) the
/// outlier reading at B3 is far outside its noise (χ² with 4 degrees of
/// freedom: over 100 asserted, the 1e-3 level is 18.5), so it stays
/// out, while B3's other readings are within their noise in bulk (median
/// χ² under 6; 3.36 is χ²(4)'s median).
#[test]
fn the_outlier_reading_stays_an_outlier_under_the_chosen_model() {
    let run = stored("outlier");
    let (_, options) = unseen::machine_and_options(DATA, "unseen-train.toml");
    let out = diagnose(&run, &options).expect("diagnose");
    let all = plinth::diagnose::data::Prepared::from_run(&run).expect("prepared");
    let b3 = all.bearing_index("B3").expect("B3");
    let listed = all.outlier_speeds_hz.clone();
    assert_eq!(listed[b3].len(), 1, "{listed:?}");
    let chi2 = plinth::diagnose::outliers::chi2_of_listed(&all, &out, &options, &listed);
    let (_, c) = chi2[b3][0];
    assert!(c.is_some_and(|c| c > 100.0), "{c:?}");
    // Clean readings of B3 under the same model: their median χ² (4 dof).
    let clean: Vec<Vec<f64>> = (0..all.bearings.len())
        .map(|b| {
            if b == b3 {
                all.speeds_hz
                    .iter()
                    .copied()
                    .filter(|s| !listed[b3].contains(s))
                    .collect()
            } else {
                Vec::new()
            }
        })
        .collect();
    let mut c: Vec<f64> = plinth::diagnose::outliers::chi2_of_listed(&all, &out, &options, &clean)
        [b3]
        .iter()
        .filter_map(|(_, c)| *c)
        .collect();
    c.sort_by(f64::total_cmp);
    let median = c[c.len() / 2];
    assert!(median < 6.0, "median χ² of the clean readings {median}");
}

/// Noise-free ROSS phasors at 12 digits (clean-d12, seed 141:
/// `python3 scripts/ross_unseen.py --machine unseen-train
/// tests/data/ross-unseen-3 clean-d12 141`): ROSS's chain leaves B1 and B2
/// a model error of a few parts in 10⁷ (B3 matches to 10⁻¹³). identify
/// sees it (B1's fit 57.5 times the variance the scatter between
/// neighbouring speeds allows, B2 7.3) and untrusts them; diagnose's gap
/// and floor, both on the pedestal-level prediction with the noise taken
/// from the fit's scatter, put it within 3 floors, named nothing and
/// printed trusted with B2's k_y 3.7 ± from the truth (session 38). The
/// lack-of-fit findings of the base fits are diagnose's reasons too, where
/// no effect acts (`diagnose::trust::lack_of_fit_reasons`).
#[test]
fn model_error_identify_sees_is_not_trusted_by_diagnose() {
    let run = stored("clean-d12-141");
    let id = identify(&run);
    let mut flagged = untrusted(&id);
    flagged.sort();
    assert_eq!(flagged, ["B1", "B2"], "identify untrusts {flagged:?}");
    let d = diagnosis(&run);
    assert!(!d.trusted, "{}", d.to_text());
    for b in ["B1", "B2"] {
        assert!(
            d.trust_reasons
                .iter()
                .any(|r| r.starts_with(&format!("bearing {b}: its base model's fit"))),
            "{b}: {:?}",
            d.trust_reasons
        );
    }
    assert!(
        !d.trust_reasons.iter().any(|r| r.starts_with("bearing B3")),
        "{:?}",
        d.trust_reasons
    );
}
