//! Runs made by the simulator (`plinth::sim`) for the diagnose tests: a
//! machine's unbalance response with injected effects, complex Gaussian
//! noise of a fraction of each channel's RMS written in the `*_sd` columns,
//! written with some digits and read back as `plinth` reads a run. The base
//! is never measured (no `base.csv`).

use plinth::diagnose::report::Pedestal;
use plinth::rundir::{DigitsMode, RunDir, WriteOptions};
use plinth::sim::{unbalance_response, EffectSet, Machine};

/// How a simulated run is written.
#[derive(Clone, Copy, Debug)]
pub struct Writing {
    /// Significant digits (rounded); `None` = full precision.
    pub digits: Option<u32>,
    /// Complex Gaussian noise: sd = this fraction of each channel's RMS over
    /// speed (rel, ped), written in the `*_sd` columns; 0 = none.
    pub noise: f64,
    /// Separate noise fraction of the rel probes when set (their absolute
    /// noise floor dominates with stiff rolling-element bearings).
    pub rel_noise: Option<f64>,
}

/// Speeds `lo`, `lo + step`, ..., `hi` [Hz].
pub fn speeds(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    let n = ((hi - lo) / step).round() as usize;
    (0..=n).map(|i| lo + step * i as f64).collect()
}

/// Simulates `machine` at `speeds` [Hz] with `effects`, adds the noise of
/// `w` (standard normal draws from `normal`, two per channel and
/// measurement: real then imaginary part) with its `*_sd` columns, writes
/// the run with the digits of `w` and reads it back.
pub fn simulated_run(
    machine: &Machine,
    speeds: &[f64],
    effects: &EffectSet,
    w: Writing,
    normal: &mut dyn FnMut() -> f64,
) -> RunDir {
    let response = unbalance_response(machine, speeds, effects).expect("simulation");
    let mut run = response.to_run_dir(None).expect("run dir");
    if w.noise > 0.0 {
        for name in machine.bearing_names() {
            let idx: Vec<usize> = (0..run.measurements.len())
                .filter(|&i| run.measurements[i].bearing == name)
                .collect();
            let mut sd = [0.0; 4];
            for (ch, s) in sd.iter_mut().enumerate() {
                let ms: f64 = idx
                    .iter()
                    .map(|&i| {
                        let m = &run.measurements[i];
                        if ch < 2 { m.rel[ch] } else { m.ped[ch - 2] }.norm_sqr()
                    })
                    .sum::<f64>()
                    / idx.len() as f64;
                let fraction = if ch < 2 {
                    w.rel_noise.unwrap_or(w.noise)
                } else {
                    w.noise
                };
                *s = fraction * ms.sqrt();
            }
            for &i in &idx {
                let m = &mut run.measurements[i];
                for (ch, s) in sd.iter().enumerate() {
                    let a = normal();
                    let b = normal();
                    let n = num_complex::Complex::new(a, b) * (s / std::f64::consts::SQRT_2);
                    if ch < 2 {
                        m.rel[ch] += n;
                    } else {
                        m.ped[ch - 2] += n;
                    }
                }
                m.noise_sd = Some(sd);
            }
        }
    }
    let dir = tempfile::tempdir().expect("tempdir");
    run.write_with(
        dir.path(),
        &WriteOptions {
            digits: w.digits,
            digits_mode: DigitsMode::Round,
        },
    )
    .expect("write");
    assert!(!dir.path().join("base.csv").exists());
    RunDir::read(dir.path()).expect("read back")
}

/// `machine` on rigid ground: every base removed, every bearing off it.
pub fn on_rigid_ground(machine: &Machine) -> Machine {
    let mut m = machine.clone();
    m.bases.clear();
    for b in &mut m.bearings {
        b.base = None;
    }
    m.validate().expect("valid machine");
    m
}

/// The skid example `skid` (tests: examples/two-pedestals-on-skid.toml)
/// with its left pedestal on rigid ground and its right pedestal alone on
/// the base, made a sub-base of 120 kg, 8.0 / 6.0 MN/m (y / z) and
/// 1.5 / 1.2 kN·s/m: `pedestal_sub_base` at bearing `right`.
pub fn right_pedestal_on_a_sub_base(skid: &Machine) -> Machine {
    let mut m = skid.clone();
    m.bases[0].name = "sub-base".into();
    m.bases[0].m = [120.0, 120.0];
    m.bases[0].k = [8.0e6, 6.0e6];
    m.bases[0].c = [1.5e3, 1.2e3];
    m.bearings[0].base = None;
    m.validate().expect("valid machine");
    m
}

/// Asserts that every pedestal of `run`'s truth has k_y, k_z and m in
/// `got` within the fraction `tolerance` of the truth (`label` in the
/// message).
pub fn assert_pedestals_near_truth(run: &RunDir, got: &[Pedestal], tolerance: f64, label: &str) {
    let truth = run.truth.as_ref().expect("truth");
    for p in &truth.pedestals {
        let got = got
            .iter()
            .find(|x| x.bearing == p.bearing)
            .expect("pedestal");
        for (key, want) in [
            ("k_y", p.pedestal.k_y),
            ("k_z", p.pedestal.k_z),
            ("m", p.pedestal.m),
        ] {
            let v = got.values[key];
            assert!(
                (v - want).abs() / want < tolerance,
                "{label} {} {key}: {v} vs {want}",
                p.bearing
            );
        }
    }
}
