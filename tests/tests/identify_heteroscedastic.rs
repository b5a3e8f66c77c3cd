//! Issue 17: heteroscedastic noise without noise columns. A real probe's
//! noise is a fraction of the signal plus a floor; the scatter between
//! neighbouring speeds knows only one sd per channel or one fraction of the
//! magnitude, and under the fraction alone the readings of small amplitude
//! look nearly exact (docs/trust-noise-law.md, "Heteroscedastic noise without noise
//! columns"). The fit's residuals then reject the scatter's law and the
//! pedestal is refitted under the variance function they give
//! (host/src/estimate/noise/variance.rs).
//!
//! The exact responses are the simulator's (`plinth::sim`, the machine's
//! elements); the noise is drawn here, sd = 1 % of |phasor| + 0.1 % of the
//! channel's RMS (complex, split equally on the real and imaginary parts),
//! as scripts/ross_unseen.py's `unseen-overhung` machine does; the numbers
//! are written with 7 digits and read back.

use plinth::identify::Identification;
use plinth::rundir::RunDir;
use plinth::sim::{unbalance_response, EffectSet};
use plinth_tests::rundown::{identify, machine};
use plinth_tests::unseen::printed_ok;
use plinth_tests::write_run;
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};

/// The indices of each bearing's rows of `run`, bearings in name order.
fn bearing_rows(run: &RunDir) -> Vec<Vec<usize>> {
    let mut bearings: Vec<&String> = run.measurements.iter().map(|m| &m.bearing).collect();
    bearings.sort();
    bearings.dedup();
    bearings
        .into_iter()
        .map(|b| {
            (0..run.measurements.len())
                .filter(|&i| &run.measurements[i].bearing == b)
                .collect()
        })
        .collect()
}

/// The machine's exact run-down (5..=200 Hz in 2.5 Hz steps) with the
/// mixed noise of the module docs drawn with `seed` (`relative` fraction of
/// |phasor| plus `floor` of the channel's RMS), written with 7 digits and
/// read back.
fn mixed_noise_run(file: &str, relative: f64, floor: f64, seed: u64) -> RunDir {
    noise_run(file, &default_speeds(), relative, floor, 0.0, seed).0
}

/// The default run-down grid: 5..=200 Hz in 2.5 Hz steps.
fn default_speeds() -> Vec<f64> {
    (0..=78).map(|i| 5.0 + 2.5 * i as f64).collect()
}

/// [`mixed_noise_run`] at `speeds` [Hz] with a seismic pick-up's velocity
/// floor `velocity` [m/s] on the pedestal channels (complex sd velocity/Ω in
/// displacement, added to the sd), and the true complex sd [m] of every row
/// and channel.
fn noise_run(
    file: &str,
    speeds: &[f64],
    relative: f64,
    floor: f64,
    velocity: f64,
    seed: u64,
) -> (RunDir, Vec<[f64; 4]>) {
    let m = machine(file);
    let response = unbalance_response(&m, speeds, &EffectSet::none()).expect("simulation");
    let mut run = response.to_run_dir(None).expect("run directory");
    let mut sds = vec![[0.0; 4]; run.measurements.len()];
    let mut rng = StdRng::seed_from_u64(seed);
    for rows in bearing_rows(&run) {
        // `ch` names a channel (rel y/z, ped y/z) in the run and in `sds` alike.
        #[allow(clippy::needless_range_loop)]
        for ch in 0..4 {
            let value = |m: &plinth::rundir::Measurement| {
                if ch < 2 {
                    m.rel[ch]
                } else {
                    m.ped[ch - 2]
                }
            };
            let rms = (rows
                .iter()
                .map(|&i| value(&run.measurements[i]).norm_sqr())
                .sum::<f64>()
                / rows.len() as f64)
                .sqrt();
            for &i in &rows {
                let x = value(&run.measurements[i]);
                let omega = 2.0 * std::f64::consts::PI * run.measurements[i].speed_hz;
                let pick_up = if ch < 2 { 0.0 } else { velocity / omega };
                sds[i][ch] = relative * x.norm() + floor * rms + pick_up;
                let sd = sds[i][ch] / 2f64.sqrt();
                let re: f64 = StandardNormal.sample(&mut rng);
                let im: f64 = StandardNormal.sample(&mut rng);
                let noisy = x + num_complex::Complex::new(re * sd, im * sd);
                let m = &mut run.measurements[i];
                if ch < 2 {
                    m.rel[ch] = noisy;
                } else {
                    m.ped[ch - 2] = noisy;
                }
            }
        }
    }
    let dir = write_run(&run, Some(7));
    (RunDir::read(dir.path()).expect("read back"), sds)
}

/// (estimate − truth)/± of every parameter of every pedestal printed `ok`.
/// How many bearings of `id` were fitted under a variance function of their
/// residuals (the scatter's law or the columns' shape rejected).
fn variance_functions(id: &Identification) -> usize {
    id.noise
        .values()
        .filter(|n| n.variance_function.is_some())
        .count()
}

fn z_scores(run: &RunDir, id: &Identification) -> Vec<(String, f64)> {
    printed_ok(run, id, true)
        .into_iter()
        .map(|(name, got, se, want)| (name, (got - want) / se))
        .collect()
}

/// The z-scores of seed `seed`'s pedestals ([`z_scores`]), each checked
/// within 4 (no value beyond 4 of its ±).
fn checked_z_scores(run: &RunDir, id: &Identification, seed: u64) -> Vec<(String, f64)> {
    let z = z_scores(run, id);
    for (name, v) in &z {
        assert!(v.abs() < 4.0, "seed {seed}: {name} is {v:.2} of its ± off");
    }
    z
}

/// RMS of the z-scores `all`, checked below 1.5 (1 when calibrated).
fn assert_rms_calibrated(all: &[(String, f64)]) {
    let rms = (all.iter().map(|(_, v)| v * v).sum::<f64>() / all.len() as f64).sqrt();
    assert!(rms < 1.5, "RMS of (estimate − truth)/± = {rms:.2}");
}

/// Under a fraction of |phasor| plus a floor, without noise columns, the
/// fits take the variance function whichever law the scatter chose (one sd
/// per channel too: feng-hahn damped seed 1 printed k_y 6.6 ± off when only
/// the proportional law was tested), nothing is untrusted, and the printed ±
/// mean what they say: no value beyond 4 of its ±, RMS of
/// (estimate − truth)/± below 1.5 over 6 runs (1 when calibrated). Before
/// the variance function the ROSS machine gave an RMS of 14 on B1 c_y.
#[test]
fn a_fraction_plus_a_floor_without_columns_keeps_its_promise() {
    let mut all = Vec::new();
    let mut taken = 0;
    for seed in 1..=6 {
        let run = mixed_noise_run("examples/feng-hahn-1997-damped.toml", 0.01, 0.001, seed);
        let id = identify(&run);
        taken += variance_functions(&id);
        assert!(
            id.pedestals.iter().all(|p| p.trusted),
            "seed {seed}: untrusted {:?}",
            id.pedestals
                .iter()
                .filter(|p| !p.trusted)
                .map(|p| (&p.bearing, &p.warnings))
                .collect::<Vec<_>>()
        );
        all.extend(checked_z_scores(&run, &id, seed));
    }
    assert_rms_calibrated(&all);
    assert!(taken > 0, "the variance function was never taken");
}

/// Noise of one sd per channel (no fraction) is in the scatter's own law;
/// the score test may still reject its estimated channel ratios (measured in
/// docs/trust-noise-law.md), and either way the ± keep their promise.
#[test]
fn one_sd_per_channel_keeps_its_promise_with_or_without_the_variance_function() {
    let mut all = Vec::new();
    for seed in 1..=6 {
        let run = mixed_noise_run("examples/feng-hahn-1997-damped.toml", 0.0, 0.01, seed);
        let id = identify(&run);
        assert!(id.pedestals.iter().all(|p| p.trusted), "seed {seed}");
        all.extend(checked_z_scores(&run, &id, seed));
    }
    assert_rms_calibrated(&all);
}

/// ROSS unseen-overhung's stored clean run with true-law noise columns
/// (scripts/ross_unseen.py, seed 1 of `clean-h1c`: sd = 1 % of |phasor| +
/// 0.1 % of the channel's RMS, written as the `*_sd` columns).
fn ross_true_columns() -> RunDir {
    plinth_tests::unseen::stored(
        concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-2"),
        "clean-h1c",
    )
}

/// The same run with each bearing-channel's column replaced by its RMS over
/// the speeds (what scripts/bench_hetero.py's `h1c-const` writes): one sd
/// per channel, as field instruments often write, while the noise grows
/// with the amplitude at the resonances.
fn constant_columns(mut run: RunDir) -> RunDir {
    for rows in bearing_rows(&run) {
        let rms: [f64; 4] = std::array::from_fn(|ch| {
            let sum: f64 = rows
                .iter()
                .map(|&i| run.measurements[i].noise_sd.expect("noise columns")[ch].powi(2))
                .sum();
            (sum / rows.len() as f64).sqrt()
        });
        for &i in &rows {
            run.measurements[i].noise_sd = Some(rms);
        }
    }
    run
}

/// Noise columns that misdescribe the noise (one sd per channel against a
/// fraction of |phasor| plus a floor, issue 17) are put on trial by the
/// fit's residuals (host/src/estimate/noise/columns.rs): their shape is
/// rejected at every bearing, the pedestal is refitted under the variance
/// function of its residuals with a warning saying so, and its ± are those
/// the true columns give (within 15 %; under the constant columns B1 c_z's
/// ± was 2.8× and k_z's 1.3× too wide, and over 30 seeds 4 runs printed an
/// `ok` k or m more than 3 ± off). The true columns are not rejected.
#[test]
fn noise_columns_with_the_wrong_shape_are_rejected_and_the_pm_stay_honest() {
    let truth_run = ross_true_columns();
    let truthful = identify(&truth_run);
    for (b, n) in &truthful.noise {
        assert!(
            n.variance_function.is_none(),
            "true columns rejected at {b}"
        );
    }
    let run = constant_columns(ross_true_columns());
    let id = identify(&run);
    for p in &id.pedestals {
        let n = &id.noise[&p.bearing];
        let law = n.variance_function.as_ref();
        assert!(
            law.is_some_and(|l| l.p_value <= 1e-3),
            "{}: constant columns not rejected",
            p.bearing
        );
        assert!(
            p.warnings
                .iter()
                .any(|w| w.message.contains("noise columns misdescribe")),
            "{}: no warning",
            p.bearing
        );
        let want = truthful
            .pedestals
            .iter()
            .find(|q| q.bearing == p.bearing)
            .expect("bearing");
        let (got, expected) = (p.std_err.theta(), want.std_err.theta());
        for (k, (g, e)) in got.iter().zip(expected).enumerate() {
            assert!(
                (g / e - 1.0).abs() < 0.15,
                "{} parameter {k}: ± {g:.4e} against {e:.4e} under the true columns",
                p.bearing
            );
        }
    }
    for (name, v, se, t) in printed_ok(&run, &id, false) {
        assert!(((v - t) / se).abs() < 3.0, "{name}: {v} ± {se}, truth {t}");
    }
}

/// A seismic pick-up's velocity floor (1 µm/s, scripts/ross_unseen.py's
/// unseen-flex pick-ups: sd 1 µm/s / Ω in displacement, largest at low
/// speed) on the pedestal channels of the simulator's feng-hahn damped
/// machine, on top of 1 % of |phasor| + 0.1 % of the channel's RMS, the
/// noise columns written flat (each bearing-channel's RMS of the true sd).
/// The columns' shape is rejected, the variance function the fit reports
/// has the pick-ups' floor (RMS over the two pedestal channels within a
/// factor 2 of 1 µm/s: the equation residuals tell the channels' shares
/// apart less well than their sum, one channel's share can fall to 0; a
/// fraction of |X| and a floor cannot take it; main reported no velocity
/// floor), and no value printed `ok` is beyond 4 of its ±. Power: the
/// columns' shape is rejected on at least five of the six fits (since
/// session 41 the test's p comes from a parametric bootstrap under the
/// columns, whose null no longer rejects true columns of a pedestal read
/// below its noise: seed 2's right bearing reaches p = 7e-3, above the
/// 1e-3 limit, and keeps the flat columns, its values within their ±;
/// docs/estimation.md "Session 41 (lowsnr17)").
#[test]
fn flat_columns_over_a_pick_ups_velocity_floor_give_that_floor() {
    const VELOCITY: f64 = 1e-6;
    let (mut fits, mut kept) = (0, Vec::new());
    for seed in 1..=3 {
        let (mut run, sds) = noise_run(
            "examples/feng-hahn-1997-damped.toml",
            &default_speeds(),
            0.01,
            0.001,
            VELOCITY,
            seed,
        );
        for rows in bearing_rows(&run) {
            let rms: [f64; 4] = std::array::from_fn(|ch| {
                let sum: f64 = rows.iter().map(|&i| sds[i][ch].powi(2)).sum();
                (sum / rows.len() as f64).sqrt()
            });
            for &i in &rows {
                run.measurements[i].noise_sd = Some(rms);
            }
        }
        let dir = write_run(&run, Some(7));
        let run = RunDir::read(dir.path()).expect("read back");
        let id = identify(&run);
        for (b, n) in &id.noise {
            let law = serde_json::to_value(&n.variance_function).expect("json");
            fits += 1;
            if law.is_null() {
                kept.push(format!("seed {seed} {b}"));
                continue;
            }
            let floor = |ch: &str| law["velocity_floor_sd"][ch].as_f64().unwrap_or(0.0);
            let (y, z) = (floor("ped_y"), floor("ped_z"));
            let v = ((y * y + z * z) / 2.0).sqrt();
            assert!(
                (0.5 * VELOCITY..2.0 * VELOCITY).contains(&v),
                "seed {seed} {b}: pick-ups' velocity floor {v:.3e} m/s (RMS of y {y:.3e}, z {z:.3e}), truth {VELOCITY:e}"
            );
        }
        checked_z_scores(&run, &id, seed);
    }
    assert!(
        fits == 6 && kept.len() <= 1,
        "flat columns kept on {kept:?} of {fits} fits"
    );
}

/// A coarse run of few speeds, the noise law estimated from them: the
/// unseen-five machine (tests/data/ross-unseen-5/unseen-five.toml, its
/// exact responses `plinth::sim`'s) on its 32-speed run-down table (56.1
/// down to 9.6 Hz in 1.5 Hz steps) with its noise, 3 % of |phasor| plus
/// 0.3 % of the channel's RMS, no noise columns. The fit's residuals reject
/// the scatter's law and the pedestals are refitted under a variance
/// function of eight numbers estimated from 128 residuals; its error moves
/// the estimate, and the ± must carry it (estimate::noise::variance,
/// "uncertainty"). Over 60 seeds the RMS of (estimate − truth)/± of k_y,
/// k_z and m over both pedestals must lie in 0.92-1.08 (its sampling sd
/// about 0.04). Measured on these seeds: main's code (fd6fbae) 1.110 (the
/// variance function's error ignored); with its error carried 1.046
/// (docs/estimation-scatter.md "Session 40 (scatterpm17)").
#[test]
fn few_speeds_with_an_estimated_noise_law_keep_their_promise() {
    let speeds: Vec<f64> = (0..32).map(|i| 9.6 + 1.5 * i as f64).collect();
    let mut z2 = Vec::new();
    let mut taken = 0;
    for seed in 1..=60 {
        let run = noise_run(
            "tests/data/ross-unseen-5/unseen-five.toml",
            &speeds,
            0.03,
            0.003,
            0.0,
            seed,
        )
        .0;
        let id = identify(&run);
        taken += variance_functions(&id);
        for (_, got, se, want) in printed_ok(&run, &id, false) {
            z2.push(((got - want) / se).powi(2));
        }
    }
    let rms = (z2.iter().sum::<f64>() / z2.len() as f64).sqrt();
    eprintln!(
        "RMS z {rms:.3} over {} values, variance function taken {taken}/120",
        z2.len()
    );
    assert!(
        taken >= 60,
        "the variance function was taken {taken}/120 times"
    );
    assert!(z2.len() >= 300, "only {} values printed ok", z2.len());
    assert!(
        (0.92..=1.08).contains(&rms),
        "RMS of (estimate − truth)/± of k_y, k_z, m = {rms:.3} over {} values",
        z2.len()
    );
}

/// unseen-flex's sensor noise (scripts/ross_unseen_machines.py): proximity
/// probes 0.5 % of |phasor| + 0.05 µm, seismic pick-ups 1 % of |phasor| + a
/// velocity floor of 1 µm/s (complex sd [m]), at speed `speed_hz` [Hz].
fn flex_sd(channel: usize, x: num_complex::Complex<f64>, speed_hz: f64) -> f64 {
    if channel < 2 {
        0.005 * x.norm() + 5e-8
    } else {
        0.01 * x.norm() + 1e-6 / (2.0 * std::f64::consts::PI * speed_hz)
    }
}

/// ROSS's noise-free unseen-flex run (tests/data/ross-unseen-4/clean-exact,
/// `scripts/ross_unseen_exact.py unseen-flex clean-n1 DIR`: the grid of
/// `clean-n1`, 15 digits) with [`flex_sd`]'s noise drawn with `seed`,
/// without noise columns, written with 7 digits and read back: what
/// `ross_unseen.py --machine unseen-flex DIR clean-n1 SEED` writes, its
/// noise drawn here.
fn flex_noise_run(exact: &RunDir, seed: u64) -> RunDir {
    let mut run = exact.clone();
    let mut rng = StdRng::seed_from_u64(seed);
    for m in &mut run.measurements {
        let speed = m.speed_hz;
        for ch in 0..4 {
            let x = if ch < 2 { m.rel[ch] } else { m.ped[ch - 2] };
            let sd = flex_sd(ch, x, speed) / 2f64.sqrt();
            let re: f64 = StandardNormal.sample(&mut rng);
            let im: f64 = StandardNormal.sample(&mut rng);
            let noisy = x + num_complex::Complex::new(re * sd, im * sd);
            if ch < 2 {
                m.rel[ch] = noisy;
            } else {
                m.ped[ch - 2] = noisy;
            }
        }
    }
    let dir = write_run(&run, Some(7));
    RunDir::read(dir.path()).expect("read back")
}

/// A fit under the scatter's own pattern (one sd per channel, its residuals
/// not rejecting it at the score test's limit) while the noise grows with
/// the amplitude: ROSS's flexible roll, B2 (a soft bracket with its
/// resonances at 46 and 80 Hz in the run), 1 % noise without columns, keeps
/// the scatter's flat pattern in about a third of the runs, and its ± are
/// those of the wrong weights alone. Here: 500 draws of ROSS's exact
/// phasors; the RMS z of k_y, k_z, m, c_y, c_z over every pedestal printed
/// ok and fitted under the kept flat pattern should lie within 0.90-1.06
/// (sampling sd about 0.03). Measured: 1.116 over 152 fits on main's code
/// (4e8447f), 1.007 with the ± floored by the residuals' HC2 sandwich; that
/// floor was not kept (it widens right-pattern fits by 5-10 %:
/// estimation_accuracy's three-bearing-tabulated drive k_z ± / scatter
/// 1.17 → 1.29 against its limit 1.2), so this is an open reproducer
/// (docs/unseen.md "Session 41 (flexz17)").
#[test]
#[ignore = "open: a kept flat scatter pattern's ± are 12 % short (docs/unseen.md, Session 41 (flexz17))"]
fn a_kept_scatter_pattern_under_amplitude_noise_keeps_its_promise() {
    let exact = plinth_tests::unseen::stored(
        concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-4"),
        "clean-exact",
    );
    let (mut z2, mut fits) = (Vec::new(), 0);
    for seed in 1..=500 {
        let run = flex_noise_run(&exact, seed);
        let id = identify(&run);
        for p in id.pedestals.iter().filter(|p| p.trusted) {
            let kept = id.noise.get(&p.bearing).is_some_and(|n| {
                n.source == plinth::estimate::noise::NoiseSource::Scatter
                    && n.variance_function.is_none()
            });
            if !kept {
                continue;
            }
            fits += 1;
            let t = plinth_tests::unseen::truth_of(&run, &p.bearing);
            let (f, e) = (&p.pedestal, &p.std_err);
            for (got, se, want) in [
                (f.k_y, e.k_y, t.k_y),
                (f.k_z, e.k_z, t.k_z),
                (f.m, e.m, t.m),
                (f.c_y, e.c_y, t.c_y),
                (f.c_z, e.c_z, t.c_z),
            ] {
                z2.push(((got - want) / se).powi(2));
            }
        }
    }
    let rms = (z2.iter().sum::<f64>() / z2.len() as f64).sqrt();
    eprintln!("RMS z {rms:.3} over {fits} fits under the scatter's kept pattern");
    assert!(fits >= 100, "only {fits} fits kept the scatter's pattern");
    assert!(
        (0.90..=1.06).contains(&rms),
        "RMS of (estimate − truth)/± over {fits} fits under the scatter's kept pattern = {rms:.3}"
    );
}
