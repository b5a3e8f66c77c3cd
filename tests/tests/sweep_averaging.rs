//! A phasor averaged over more speed than a resonance is wide
//! (host/src/estimate/sweep.rs, docs/trust-sweep.md, Session 50 (sweep50)).
//!
//! 1. The bundled demo's short run-down (150 → 20 Hz at 20 Hz/s, 4
//!    revolutions a phasor: 1.4-3 Hz of speed per phasor through resonances
//!    0.1-0.2 Hz wide): main untrusted a pedestal of it for lack of fit, a
//!    sensor-gain ratio or a noise-scale mismatch in 15 of 20 runs (seeds
//!    9400-9419); with the box's `averaging.toml` the averaging's error is
//!    counted in each phasor's noise and the run is judged clean, its values
//!    within 3 of their ±.
//! 2. The model of the averaging (d = ½σ²P'', σ² = span²/12) against an
//!    independent path: ROSS's noise-free phasors of unseen-seven's `sweep`
//!    case (a tracking filter's mean over 32 revolutions of a 0.5 Hz/s
//!    coast-down, scripts/ross_unseen.py `swept`) next to its pointwise
//!    ones, made by
//!    `python3 scripts/ross_sweep_pointwise.py tests/data/sweep-averaging/unseen-seven-sweep.csv`.

use plinth::demo::{demo, DemoOptions};
use plinth::estimate::sweep::{self, Averaging};
use plinth::identify::cli::{identify_args, Args, Equations};
use plinth::sim::signals::RunDown;
use plinth_shared::phasor::Complex;
use std::collections::BTreeMap;
use std::path::Path;

/// `plinth identify DIR` as the CLI computes it.
fn identify(dir: &Path) -> plinth::identify::Identification {
    let args = Args {
        dir: dir.to_path_buf(),
        json: true,
        equations: Equations::RAndI,
        model: None,
        max_condition: plinth::identify::DEFAULT_MAX_CONDITION_NUMBER,
        estimator: plinth::identify::Estimator::Ml,
        compare_ols: false,
        truncated: false,
        slow_roll: None,
        unmeasured_base: None,
        plots: None,
        figure_style: plinth::plots::StyleArgs::default(),
        speeds: None,
        table_uncertainty: None,
        speed_uncertainty: None,
        sensor_uncertainty: None,
    };
    identify_args(&args).expect("identify").1
}

/// The demo test's short run-down at `seed`, run into `out`.
fn short_demo(out: &Path, seed: u64) -> DemoOptions {
    let mut opts = DemoOptions::bundled(out).expect("bundled machine");
    opts.rundown = RunDown {
        start_hz: 150.0,
        end_hz: 20.0,
        rate_hz_per_s: 20.0,
    };
    opts.seed = seed;
    opts
}

#[test]
fn a_demo_run_averaged_through_its_resonances_is_judged_clean() {
    // Seed 9406: main untrusted both pedestals (lack of fit: a sensor delay
    // of a few µs, and a noise scale mismatch at `left`).
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let o = demo(&short_demo(&out, 9406)).expect("the demo runs");
    // The box's run directory says how its phasors were averaged.
    let a = sweep::read(&o.run_dir)
        .expect("averaging.toml")
        .expect("written");
    assert_eq!(
        a,
        Averaging {
            revolutions: 4,
            rate_hz_per_s: None
        }
    );
    let id = identify(&o.run_dir);
    let truth = o.report.table.clone();
    for p in &id.pedestals {
        let kinds: Vec<_> = p.warnings.iter().map(|w| format!("{:?}", w.kind)).collect();
        assert!(p.trusted, "{} untrusted: {kinds:?}", p.bearing);
        for row in truth.iter().filter(|r| r.bearing == p.bearing) {
            let Some(t) = row.truth else { continue };
            let i = match row.parameter.as_str() {
                "k_y" => 0,
                "k_z" => 1,
                "m" => 2,
                "c_y" => 3,
                "c_z" => 4,
                _ => continue,
            };
            let (v, se) = (p.pedestal.theta()[i], p.std_err.theta()[i]);
            assert!(
                (v - t).abs() <= 3.0 * se,
                "{} {}: {v} ± {se} vs truth {t}",
                p.bearing,
                row.parameter
            );
        }
    }
}

/// One channel's rows of the stored ROSS table: (speed [Hz], span [Hz],
/// pointwise, averaged).
type Series = Vec<(f64, f64, Complex<f64>, Complex<f64>)>;

fn ross_series() -> BTreeMap<(String, String), Series> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/sweep-averaging/unseen-seven-sweep.csv"
    );
    let text = std::fs::read_to_string(path).expect("stored ROSS table");
    let mut out: BTreeMap<(String, String), Series> = BTreeMap::new();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let n = |i: usize| f[i].parse::<f64>().expect("number");
        out.entry((f[1].to_string(), f[2].to_string()))
            .or_default()
            .push((
                n(0),
                n(3),
                Complex::new(n(4), n(5)),
                Complex::new(n(6), n(7)),
            ));
    }
    for s in out.values_mut() {
        s.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    out
}

#[test]
fn the_averaging_model_against_a_ross_tracking_filter() {
    let series = ross_series();
    assert_eq!(series.len(), 12, "3 bearings × 4 channels");
    // Over every interior speed of every channel: the true averaging error
    // (ROSS's averaged phasor less its pointwise one) against the model's
    // d = ½σ²P'' from the averaged phasors alone (the span a·N/f of the
    // file, as `rate_hz_per_s` gives it).
    let a = Averaging {
        revolutions: 32,
        rate_hz_per_s: Some(0.5),
    };
    let (mut true_ss, mut left_ss, mut large, mut covered) = (0.0, 0.0, 0, 0);
    for ((bearing, channel), s) in &series {
        let speeds: Vec<f64> = s.iter().map(|r| r.0).collect();
        let spans = sweep::spans_hz(&speeds, &a);
        let peak = s.iter().map(|r| r.2.norm()).fold(0.0, f64::max);
        for j in 1..s.len() - 1 {
            assert!((spans[j] - s[j].1).abs() < 1e-4 * s[j].1, "span");
            let d = sweep::averaging_error(
                [s[j - 1].0, s[j].0, s[j + 1].0],
                [s[j - 1].3, s[j].3, s[j + 1].3],
                spans[j],
            );
            let truth = s[j].3 - s[j].2;
            true_ss += truth.norm_sqr();
            left_ss += (truth - d).norm_sqr();
            // Where the averaging moves a phasor by more than 0.2 % of its
            // channel's peak, the model's size is the error's within a
            // factor of 2.5 (it is counted as a noise: its size is what
            // matters).
            if truth.norm() > 2e-3 * peak {
                large += 1;
                let r = d.norm() / truth.norm();
                if (0.4..2.5).contains(&r) {
                    covered += 1;
                } else {
                    eprintln!(
                        "{bearing} {channel} {:.2} Hz: |d| {:.3e} vs |error| {:.3e}",
                        s[j].0,
                        d.norm(),
                        truth.norm()
                    );
                }
            }
        }
    }
    eprintln!("left {:.3} of the averaging error's sum of squares; {covered} of {large} large errors sized within 2.5×", left_ss / true_ss);
    // 164 rows move by more than 0.2 % of their channel's peak; the model
    // sizes 152 of them within 2.5× (0.55-1.45×). The 12 it does not are
    // the first critical's peak at 17.0 Hz on every channel (0.29×: a
    // resonance 0.33 Hz wide between rows 0.75 Hz apart, whose curvature
    // three neighbouring means do not resolve); there the count is short
    // (docs/trust-sweep.md, "What is left"). As a correction d would leave
    // half the error's sum of squares: it is counted, not corrected.
    assert!(large >= 100, "{large}");
    assert!(covered * 10 >= large * 9, "{covered} of {large}");
}
