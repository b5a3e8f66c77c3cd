//! "Never confidently wrong" (issue 17, identify's side): a pedestal on its
//! own soft sub-base (the simulator's base element under one pedestal, its
//! motion not measured) is untrusted for lack of fit; speeds where one
//! bearing's phasors are flipped by 180° are listed; pedestal pick-ups in µm
//! against probes in m are named; clean runs (digits 2/3/12, 1 % noise on
//! the undamped paper machine) are flagged by no rule. Faults are made in
//! the data here (negation, scaling), independently of Plinth's own
//! corrections. The Monte-Carlo rates are in scripts/bench-trust.sh.

use plinth::identify::physical::NotPhysical;
use plinth::identify::{Identification, WarningKind};
use plinth_tests::rundown::{self, identify, machine, run};

/// The trust rules (untrusting or exit 2) this file checks.
const RULES: &[WarningKind] = &[
    WarningKind::LackOfFit,
    WarningKind::PhysicallyImpossible,
    WarningKind::SuspectedConventionError,
    WarningKind::Implausible,
];

/// The trust rules that fired on `id`.
fn flags(id: &Identification) -> Vec<String> {
    rundown::flags(id, RULES)
}

#[test]
fn a_pedestal_on_its_own_sub_base_is_untrusted_for_lack_of_fit() {
    let m = machine("tests/machines/three-bearing-sub-base.toml");
    // At 1 % noise the detection rate is measured by scripts/bench-trust.sh.
    for (noise, digits) in [(None, Some(3)), (None, Some(2))] {
        let id = identify(&run(&m, noise, digits));
        for p in &id.pedestals {
            let lof = p.warnings.iter().find(|w| w.kind == WarningKind::LackOfFit);
            if p.bearing == "mid" {
                let w = lof.unwrap_or_else(|| panic!("{noise:?} {digits:?}: mid not flagged"));
                assert!(!p.trusted);
                assert!(w.message.contains("plinth diagnose"), "{}", w.message);
                assert!(
                    w.message.contains("exclude this model error"),
                    "{}",
                    w.message
                );
            } else {
                assert!(lof.is_none(), "{}: {:?}", p.bearing, p.warnings);
            }
        }
        let json = serde_json::to_value(&id).expect("json");
        assert!(json["noise"]["mid"]["lack_of_fit"]["level_ratio"].is_number());
    }
}

#[test]
fn the_undamped_paper_machine_with_noise_is_not_flagged() {
    // The case: 4 of 20 seeds exited 2 under the old one-sided 2σ
    // rule. Six seeds here; twenty and more in scripts/bench-trust.sh.
    let m = machine("examples/feng-hahn-1997.toml");
    for seed in 1..=6 {
        let id = identify(&run(&m, Some((0.01, seed)), Some(6)));
        assert!(flags(&id).is_empty(), "seed {seed}: {:?}", flags(&id));
        assert!(NotPhysical::of(&id).is_none());
    }
}

#[test]
fn clean_digits_are_not_flagged() {
    let m = machine("tests/machines/three-bearing-tabulated.toml");
    for digits in [2, 3, 12] {
        let id = identify(&run(&m, None, Some(digits)));
        assert!(flags(&id).is_empty(), "{digits} digits: {:?}", flags(&id));
    }
}

/// The speeds identify lists as bad for `bearing` (`noise.<b>.outlier_speeds_hz`).
fn listed(id: &Identification, bearing: &str) -> Vec<f64> {
    id.noise
        .get(bearing)
        .map(|n| n.outlier_speeds_hz.clone())
        .unwrap_or_default()
}

/// `r` with every channel of `bearing` negated at the speeds `flipped` [Hz]
/// (a keyphasor that triggered half a revolution off).
fn flip(r: &mut plinth::rundir::RunDir, bearing: &str, flipped: &[f64]) {
    for row in &mut r.measurements {
        if row.bearing == bearing && flipped.contains(&row.speed_hz) {
            for z in row.rel.iter_mut().chain(row.ped.iter_mut()) {
                *z = -*z;
            }
        }
    }
}

/// Whether `id` lists exactly `flipped` for `mid` (with a `keyphasor_flip`
/// warning) and nothing for the other bearings.
fn listed_exactly(id: &Identification, flipped: &[f64]) -> bool {
    let mid = id.pedestal("mid").expect("mid");
    listed(id, "mid") == flipped
        && mid.has_warning(WarningKind::KeyphasorFlip)
        && ["drive", "outboard"]
            .iter()
            .all(|other| listed(id, other).is_empty())
}

#[test]
fn speeds_with_one_bearing_flipped_are_listed() {
    // Two adjacent flips next to `mid`'s pedestal resonance, one far away.
    // The local model in speed cannot judge 40/42.5 Hz (the 2.5 Hz steps
    // resolve none of the modes at 35-50 Hz); the other bearings at the
    // same speeds do (robust::cross_bearing_flips).
    let m = machine("tests/machines/three-bearing-tabulated.toml");
    let mut r = run(&m, Some((0.01, 3)), Some(6));
    let flipped = [40.0, 42.5, 120.0];
    flip(&mut r, "mid", &flipped);
    let id = identify(&r);
    assert!(
        listed_exactly(&id, &flipped),
        "mid {:?}, drive {:?}, outboard {:?}",
        listed(&id, "mid"),
        listed(&id, "drive"),
        listed(&id, "outboard")
    );
}

#[test]
fn three_random_flipped_speeds_are_listed_exactly() {
    // The protocol of scripts/bench-flips.sh: three speeds of `mid` drawn
    // from 25-192.5 Hz, 1 % noise, 20 seeds; the speeds drawn here by a
    // simple LCG (not the estimator's generator).
    let m = machine("tests/machines/three-bearing-tabulated.toml");
    let grid: Vec<f64> = (8..76).map(|i| 5.0 + 2.5 * i as f64).collect();
    let mut misses = Vec::new();
    for seed in 1..=20u64 {
        let mut state = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let mut flipped = Vec::new();
        while flipped.len() < 3 {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let s = grid[((state >> 33) % grid.len() as u64) as usize];
            if !flipped.contains(&s) {
                flipped.push(s);
            }
        }
        flipped.sort_by(f64::total_cmp);
        let mut r = run(&m, Some((0.01, 100 + seed)), Some(6));
        flip(&mut r, "mid", &flipped);
        let id = identify(&r);
        if !listed_exactly(&id, &flipped) {
            misses.push(format!(
                "seed {seed}: {flipped:?} listed {:?}",
                listed(&id, "mid")
            ));
        }
    }
    eprintln!("{} of 20 missed: {misses:?}", misses.len());
    assert!(
        misses.len() <= 2,
        "{} of 20 missed: {misses:?}",
        misses.len()
    );
}

#[test]
fn every_bearing_flipped_is_listed_at_every_bearing_with_the_note() {
    // The machine's keyphasor flips every channel of every bearing: the
    // cross-bearing test is blind to it (a subspace holds −y with y), the
    // test in speed finds it at each bearing where the speed steps follow
    // the response (away from the modes at 35-50 Hz; at random speeds
    // scripts/bench-flips.sh, section `every`, measured 13/40), and the
    // speeds every bearing lists get the note naming the machine's keyphasor.
    let m = machine("tests/machines/three-bearing-tabulated.toml");
    let mut r = run(&m, Some((0.01, 5)), Some(6));
    let flipped = [120.0, 150.0];
    for bearing in ["drive", "mid", "outboard"] {
        flip(&mut r, bearing, &flipped);
    }
    let id = identify(&r);
    for p in &id.pedestals {
        assert_eq!(listed(&id, &p.bearing), flipped, "{}", p.bearing);
        assert!(
            p.warnings
                .iter()
                .any(|w| w.kind == WarningKind::KeyphasorFlip
                    && w.message.contains("every bearing lists 120, 150 Hz")),
            "{}: {:?}",
            p.bearing,
            p.warnings
        );
    }
}

#[test]
fn an_outlier_speed_is_left_out_and_listed() {
    let m = machine("tests/machines/three-bearing-tabulated.toml");
    let clean = run(&m, Some((0.01, 4)), Some(6));
    let reference = identify(&clean);
    let mut r = clean.clone();
    // A bad reading of drive's pedestal pick-ups at 100 Hz only.
    for row in &mut r.measurements {
        if row.bearing == "drive" && row.speed_hz == 100.0 {
            row.ped[0] *= 1.5;
            row.ped[1] *= num_complex::Complex::from_polar(1.0, 0.7);
        }
    }
    let id = identify(&r);
    let drive = id.pedestal("drive").expect("drive");
    assert_eq!(listed(&id, "drive"), vec![100.0]);
    assert!(drive.has_warning(WarningKind::OutlierSpeeds));
    let before = reference.pedestal("drive").expect("drive");
    // The fit without it stays within 3σ of the clean fit.
    for (a, (b, s)) in drive
        .pedestal
        .theta()
        .iter()
        .zip(before.pedestal.theta().iter().zip(before.std_err.theta()))
    {
        assert!((a - b).abs() < 3.0 * s, "{a} vs {b} ± {s}");
    }
    for p in &reference.pedestals {
        assert!(
            listed(&reference, &p.bearing).is_empty(),
            "clean {}",
            p.bearing
        );
        if p.bearing != "drive" {
            assert!(listed(&id, &p.bearing).is_empty(), "{}", p.bearing);
        }
    }
}

#[test]
fn micrometres_against_metres_are_named() {
    let m = machine("examples/feng-hahn-1997-damped.toml");
    let mut r = run(&m, None, Some(12));
    for row in &mut r.measurements {
        for z in &mut row.ped {
            *z *= 1e6;
        }
    }
    let id = identify(&r);
    for p in &id.pedestals {
        assert!(!p.trusted);
        let w = p
            .warnings
            .iter()
            .find(|w| w.kind == WarningKind::Implausible)
            .expect("implausible");
        assert!(w.message.contains("ped in µm, rel in m"), "{}", w.message);
    }
    assert!(NotPhysical::of(&id).is_some());
}

#[test]
fn a_local_model_error_inside_the_level_limit_is_found_by_the_scan() {
    // ROSS reference machine d, B1 on its own sub-base (motion not
    // measured), 1.5 % noise: the fit leaves 1.5-4 times the variance of its
    // noise, inside the level rule's limit of 4, and the model error is
    // local in speed (the sub-base's resonance). The scan over windows of
    // speed finds it where the level rule cannot. Measured (2026-12-02,
    // session 27, `plinth simulate tests/reference/ross/machine-d.toml
    // --speeds 5:200:2.5 --noise 0.015 --seed S --digits 6`, S = 1..20):
    // 16/20 by the scan alone, 17/20 untrusted, no other bearing flagged.
    // At 1 % noise (this test's level before session 27) the scatter now
    // measures the noise itself (quartic local fits), so B1 leaves 12-25
    // times it in 18/20 runs and the level rule alone untrusts it: 20/20,
    // and the scan is no longer what finds it there (seeds 1, 2 only).
    let m = machine("tests/reference/ross/machine-d.toml");
    let mut by_structure = Vec::new();
    for seed in 1..=20 {
        let id = identify(&run(&m, Some((0.015, seed)), Some(6)));
        for p in &id.pedestals {
            let mut lof = p
                .warnings
                .iter()
                .filter(|w| w.kind == WarningKind::LackOfFit);
            if p.bearing != "B1" {
                assert!(
                    lof.next().is_none(),
                    "seed {seed} {}: {:?}",
                    p.bearing,
                    p.warnings
                );
                continue;
            }
            // (Session 31: the run of outlier speeds at the resonance is a
            // lack-of-fit warning of its own; the scan's is another.)
            let level = id.noise["B1"].lack_of_fit.map(|l| l.level_ratio);
            if lof.any(|w| w.message.contains("scan score")) && level.is_some_and(|l| l <= 4.0) {
                by_structure.push(seed);
            }
        }
    }
    // Measured at 1 % before session 27 (2026-11-28): seeds 2, 4, 10, 11,
    // 13, 16, 17, 18, 20; the whole-run polynomial before the scan: 10, 11.
    assert!(
        by_structure.len() >= 6,
        "found by the scan alone: {by_structure:?}"
    );
}

#[test]
fn a_resonance_left_out_as_outlier_speeds_is_a_lack_of_fit() {
    // ROSS reference machine d, B1 on its own sub-base (motion not
    // measured): the sub-base's resonance at 75-82.5 Hz is narrower than
    // the scan's windows, and the outlier test takes its 3-4 speeds out as
    // outliers; the fit without them is clean, and B1 was printed `ok` in
    // 3/20 runs at 1.5 % noise and 13/20 at 3 % (main e51e245: untrusted
    // 17/20 and 7/20). Neighbouring outlier speeds are a lack of fit
    // (`identify::trust::ADJACENT_OUTLIERS`). Measured (2026-12-03, session
    // 31, `plinth simulate tests/reference/ross/machine-d.toml --speeds
    // 5:200:2.5 --noise N --seed S --digits 6`, S = 1..20): untrusted 20/20
    // and 19/20, no other bearing flagged.
    let m = machine("tests/reference/ross/machine-d.toml");
    for (noise, least) in [(0.015, 20), (0.03, 18)] {
        let mut untrusted = Vec::new();
        for seed in 1..=20 {
            let id = identify(&run(&m, Some((noise, seed)), Some(6)));
            for p in &id.pedestals {
                let lof = p.warnings.iter().any(|w| w.kind == WarningKind::LackOfFit);
                if p.bearing == "B1" {
                    if lof && !p.trusted {
                        untrusted.push(seed);
                    }
                } else {
                    assert!(
                        !lof,
                        "noise {noise} seed {seed} {}: {:?}",
                        p.bearing, p.warnings
                    );
                }
            }
        }
        assert!(
            untrusted.len() >= least,
            "noise {noise}: B1 untrusted in {untrusted:?}"
        );
    }
}

#[test]
fn a_pedestal_on_its_own_sub_base_is_untrusted_at_one_percent_noise() {
    // The sub-base machine (the simulator's base element under `mid`, its
    // motion not measured), 1 % noise, seeds 1-20: every bearing takes its
    // noise from the scatter, so all three are judged, but only `mid`
    // leaves more than its level and can be flagged for structure; the
    // structure rule's share of the run's 1 % is spent over the bearings
    // it can flag (identify::trust). Measured (2026-11-28, session 22):
    // 20/20. On the bench's runs (scripts/bench-trust.sh: every digit kept)
    // 17/20 with the share over every judged bearing before the mean test,
    // 7/20 with it and the mean's Bonferroni, 20/20 now. Other pedestals
    // are never flagged.
    let m = machine("tests/machines/three-bearing-sub-base.toml");
    let mut untrusted = Vec::new();
    for seed in 1..=20 {
        let id = identify(&run(&m, Some((0.01, seed)), Some(6)));
        for p in &id.pedestals {
            let lof = p.warnings.iter().any(|w| w.kind == WarningKind::LackOfFit);
            if p.bearing == "mid" {
                if lof && !p.trusted {
                    untrusted.push(seed);
                }
            } else {
                assert!(!lof, "seed {seed} {}: {:?}", p.bearing, p.warnings);
            }
        }
    }
    eprintln!("mid untrusted in {}/20: {untrusted:?}", untrusted.len());
    assert!(untrusted.len() >= 19, "mid untrusted in {untrusted:?}");
}
