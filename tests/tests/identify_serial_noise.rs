//! Noise correlated along the run (docs/estimation-scatter.md, Session 48
//! (corr17); docs/unseen-eight.md finding 1): identify measures the lag-one
//! correlation of each bearing's whitened residuals along the run and, where
//! it is beyond what white noise gives, widens the ± by the long-run
//! covariance of that AR(1) noise. Every run here is ROSS 2.3.0's
//! (`scripts/ross_unseen.py`, the stored runs of tests/data/ross-unseen*/,
//! each made by the line in its own docs page); only the reading is Plinth's.

use plinth::identify::Identification;
use plinth::identify::WarningKind;
use plinth_tests::rundown::{identify, identify_dir};
use plinth_tests::unseen::{ok_but_wrong, stored};
use std::path::PathBuf;

fn data(dir: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/data")).join(dir)
}

/// The bearings whose ± identify widened for a correlation along the run.
fn widened(id: &Identification) -> Vec<String> {
    id.noise
        .iter()
        .filter(|(_, n)| n.serial_correlation.is_some())
        .map(|(b, _)| b.clone())
        .collect()
}

/// Clean runs of seven machines, white noise (with and without noise
/// columns) and 2-3 digits: the rule never fires, so no ± moves (each
/// bearing's white limit is its 1 % quantile: over these 24 bearings about
/// one firing in four such sets would be chance; none fires on these).
/// Fails if the correlation rule fires on white noise.
#[test]
fn white_noise_runs_keep_their_plus_minus() {
    for dir in [
        "ross-unseen/clean-w1c",
        "ross-unseen-2/clean-h1",
        "ross-unseen-2/clean-h1c",
        "ross-unseen-2/clean-d3",
        "ross-unseen-3/clean-p2",
        "ross-unseen-3/clean-p2c",
        "ross-unseen-4/clean-n1",
        "ross-unseen-5/clean-n3c",
        "ross-unseen-6/clean-s1c",
        "ross-unseen-7/clean-t1c",
        "ross-unseen-8/clean-g1c",
    ] {
        let id = identify_dir(&data(dir));
        assert!(widened(&id).is_empty(), "{dir}: {:?}", widened(&id));
        for p in &id.pedestals {
            assert!(
                !p.warnings
                    .iter()
                    .any(|w| w.message.contains("correlated along the run")),
                "{dir} {}",
                p.bearing
            );
        }
    }
}

/// The eighth machine's `corr-noise` run (ρ = 0.80 between stored vectors):
/// both bearings' correlation measured near it and their ± widened about
/// √((1 + ρ)/(1 − ρ)) = 3 times, said in the warnings; no bearing is taken
/// for model error (on main 49d143f: B1 untrusted for lack of fit, B2 `ok`
/// 6-7.6 ± off).
#[test]
fn correlated_noise_is_measured_and_the_plus_minus_widened() {
    let id = identify_dir(&data("ross-unseen-8/corr-noise-7325"));
    assert_eq!(widened(&id), ["B1", "B2"]);
    for (b, n) in &id.noise {
        let s = n.serial_correlation.expect("measured");
        assert!((0.65..0.9).contains(&s.lag_one), "{b}: {s:?}");
        // k_y, k_z, m: parameters the whole run carries.
        for f in &s.widening[..3] {
            assert!((2.2..3.2).contains(f), "{b}: {s:?}");
        }
    }
    for p in &id.pedestals {
        assert!(p.trusted, "{}: {:?}", p.bearing, p.warnings);
        assert!(
            p.warnings
                .iter()
                .any(|w| w.message.contains("correlated along the run")),
            "{}",
            p.bearing
        );
    }
}

/// A fresh `corr-noise` run of the eighth machine (seed 9068, ROSS; made by
/// `python3 scripts/ross_unseen.py --machine unseen-eight DIR corr-noise
/// 9068`), chosen among 40 fresh seeds 9040-9079 as one where main e805765
/// prints a value `ok` beyond 3 ± (three there: 9041 B1 k_y −3.05, 9061 B2
/// k_y +3.7, this one's B1 k_z +3.06; docs/estimation-scatter.md, Session 49
/// (corr17b)). The measured ρ̂ (B1 0.78, B2 0.75) is biased low by the
/// detrending, and main widened by it; the AR(1)'s ρ it implies (0.80,
/// 0.77) is used here: every value printed `ok` (dampings too) within 3 of
/// its ±, both bearings trusted, and the ρ used above ρ̂. Fails on main (a
/// margin of 6 %: what the bias costs; 9061 stays at +3.5 ±, what is left).
#[test]
fn the_detrending_bias_of_the_correlation_is_removed() {
    let run = stored(&data("ross-unseen-8").to_string_lossy(), "corr-noise-9068");
    let id = identify(&run);
    let wrong = ok_but_wrong(&run, &id, true);
    assert!(wrong.is_empty(), "{wrong:?}");
    for (b, n) in &id.noise {
        let s = n.serial_correlation.expect("measured");
        assert!(s.ar1_rho > s.lag_one + 0.01, "{b}: {s:?}");
        assert!((0.72..0.9).contains(&s.ar1_rho), "{b}: {s:?}");
    }
    for p in &id.pedestals {
        assert!(p.trusted, "{}: {:?}", p.bearing, p.warnings);
    }
}

/// The delay rule under the same correlation: its likelihood ratio is
/// taken on the equations prewhitened by the AR(1) measured, so the noise's
/// slow wander is not read as a sensor delay. On main e805765 the gate
/// opened on 7325's B2 (τ̂ −2.6 of its white-noise ±) and widened its
/// dampings' ± ×13.9 and ×9.5 (and on 24 of 32 bearings of the fresh seeds
/// 9000-9015, ×7-39). Here the delay is not counted on these two runs'
/// four bearings (τ̂ within 1 of its ± under the AR(1); the gate's chance
/// rate under its null is 4.6 % per bearing). Fails on main.
#[test]
fn correlated_noise_is_not_read_as_a_sensor_delay() {
    for case in ["corr-noise-7325", "corr-noise-9068"] {
        let id = identify_dir(&data("ross-unseen-8").join(case));
        for p in &id.pedestals {
            assert!(
                !p.has_warning(WarningKind::DelayNotExcluded),
                "{case} {}: {:?}",
                p.bearing,
                p.warnings
            );
        }
    }
}
