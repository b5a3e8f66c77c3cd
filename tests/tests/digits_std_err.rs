//! The ± `plinth diagnose` reports for pedestals on rigid ground when the
//! data are written with few digits and no noise mean what they say.
//!
//! The workflow takes digits as truncated (mean square ulp²/3), four times a
//! rounding's variance, on purpose: a truncation bias must not pass for an
//! effect. Its reported ± followed that upper bound, so on ROSS runs at 3
//! digits the final pedestals were 2-4 times closer to the truth than their
//! ± said (RMS z 0.15-0.6 per parameter, docs/diagnose-accuracy.md ("Session 39")). The
//! reported ± now follow the residuals where they scatter significantly
//! less than the noise model says (`NoiseLevel::reported_scale`, the rule
//! the base pedestals are reported by too). They are still about 1.6 times
//! wider than `plinth identify`'s (the search's weighted-fit covariance, not
//! the likelihood's; left, in the same doc).
//!
//! Data: ROSS 2.3.0 runs made by scripts/ross_unseen.py, stored by earlier
//! sessions (seed 1 of each case): unseen-four and unseen-overhung at 3
//! digits, unseen-flex at 2 digits.

use plinth::diagnose::report::Diagnosis;
use plinth::rundir::RunDir;
use plinth_tests::unseen::{self, truth_of};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data");

/// (data folder, machine file, case) of the stored few-digit clean runs.
const RUNS: [(&str, &str, &str); 3] = [
    ("ross-unseen", "unseen-four.toml", "clean-d3"),
    ("ross-unseen-2", "unseen-overhung.toml", "clean-d3"),
    ("ross-unseen-4", "unseen-flex.toml", "clean-d2"),
];

/// (value − truth)/± of k_y, k_z, m, c_y and c_z of every final pedestal of
/// `d` against `run`'s truth, labelled "bearing parameter".
fn z_scores(run: &RunDir, d: &Diagnosis) -> Vec<(String, f64)> {
    let mut out = Vec::new();
    for p in &d.pedestals_after {
        let truth = truth_of(run, &p.bearing);
        for (name, want) in [
            ("k_y", truth.k_y),
            ("k_z", truth.k_z),
            ("m", truth.m),
            ("c_y", truth.c_y),
            ("c_z", truth.c_z),
        ] {
            let (Some(v), Some(se)) = (p.values.get(name), p.std_err.get(name)) else {
                continue;
            };
            assert!(*se > 0.0 && se.is_finite(), "{} {name}: ± {se}", p.bearing);
            out.push((format!("{} {name}", p.bearing), (v - want) / se));
        }
    }
    out
}

/// Over the stored runs the RMS of z is at least 0.45 (main at c0eccc6:
/// 0.32 over these 40 values; this branch 0.62) and no value is more than
/// 4 of its ± off (the ± not too narrow).
#[test]
fn rigid_ground_std_errs_at_few_digits_mean_what_they_say() {
    let mut all = Vec::new();
    for (folder, file, case) in RUNS {
        let data = format!("{DATA}/{folder}");
        let run = unseen::stored(&data, case);
        let d = unseen::diagnosis_with_machine_check(&data, file, &run);
        assert!(
            unseen::named(&d).is_empty() && d.trusted,
            "{folder}/{case}: {}",
            d.to_text()
        );
        for (label, z) in z_scores(&run, &d) {
            all.push((format!("{folder}/{case} {label}"), z));
        }
    }
    assert!(all.len() >= 30, "{} values", all.len());
    let rms = (all.iter().map(|(_, z)| z * z).sum::<f64>() / all.len() as f64).sqrt();
    assert!((0.45..1.6).contains(&rms), "RMS z {rms:.3} over {all:?}");
    let worst = all
        .iter()
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .expect("values");
    assert!(worst.1.abs() < 4.0, "{worst:?} (RMS z {rms:.3})");
}
