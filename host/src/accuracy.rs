//! `plinth accuracy`: a Monte-Carlo of the identification on the simulator's
//! data against the Cramér–Rao bound.
//!
//! The machine's clean run-down is simulated once. Each draw perturbs it the
//! way measurements are perturbed and identifies it as a user would (noise
//! model estimated from the data):
//! - `--noise FRAC`: complex Gaussian noise of FRAC × each channel's RMS over
//!   speed on every channel, rel and ped ([`crate::sim::Noise`]);
//! - `--digits N`: every number rounded to N significant digits. Rounding is
//!   deterministic, so each draw first turns all phasors by a random common
//!   phase and scales them by a random factor in [1, 10) (the same machine
//!   with its unbalance turned and resized: the pedestal equations are
//!   linear), which changes every rounding error.
//!
//! The draws run in parallel (rayon) and are gathered in draw order: the
//! same seed gives the same numbers whatever the number of threads
//! (`RAYON_NUM_THREADS`). A progress line shows on a terminal.
//!
//! Per parameter it reports the RMS error of OLS and ML, the bound (from the
//! Fisher information at the truth with the true noise; for digits the mean
//! over draws of the bound with the rounding variance ulp²/12 of each
//! number), each estimator's bias in standard errors of the mean, and the
//! ratio of the standard error each reports (RMS over draws) to its observed
//! scatter.

use crate::estimate::ml;
use crate::estimate::noise::{ColumnDigits, Quantisation};
use crate::estimate::pedestal::number_variance;
use crate::estimate::{complex_stiffness, Observation};
use crate::identify::{fit_run, Identification, Options};
use crate::rundir::{round_to_digits, DigitsMode, Measurement, RunDir};
use crate::sim::{unbalance_response, EffectSet, Machine, Noise};
use anyhow::{anyhow, bail, Context, Result};
use plinth_shared::phasor::omega_from_hz;
use plinth_shared::regression::{Parameter, PARAMETERS};
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use serde::Serialize;
use std::path::PathBuf;

/// How each draw perturbs the clean run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Perturbation {
    /// Complex Gaussian noise, RMS relative to each channel's RMS [-].
    Noise(f64),
    /// Rounding to this many significant digits.
    Digits(u32),
}

/// One parameter of one pedestal over the draws.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParameterAccuracy {
    /// Bearing name.
    pub bearing: String,
    /// Parameter name (k_y, k_z, m, c_y, c_z).
    pub parameter: String,
    /// True value (θ units: N/m, kg, N·s/m).
    pub truth: f64,
    /// Cramér–Rao bound: the smallest sd an unbiased estimator can have.
    pub crb: f64,
    /// RMS error of the paper's OLS.
    pub ols_rms: f64,
    /// RMS error of ML.
    pub ml_rms: f64,
    /// OLS's mean error in standard errors of the mean [-].
    pub ols_bias_sem: f64,
    /// ML's mean error in standard errors of the mean [-].
    pub ml_bias_sem: f64,
    /// RMS of the standard error OLS reports / OLS's observed sd [-].
    pub ols_se_ratio: f64,
    /// RMS of the standard error ML reports / ML's observed sd [-].
    pub ml_se_ratio: f64,
}

/// The Monte-Carlo's result.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Accuracy {
    /// Machine name.
    pub machine: String,
    /// The perturbation of each draw.
    pub perturbation: Perturbation,
    /// Number of draws.
    pub draws: usize,
    /// Draws whose ML fit fell back to OLS or did not converge.
    pub ml_failures: usize,
    /// One row per pedestal and parameter.
    pub parameters: Vec<ParameterAccuracy>,
}

impl Accuracy {
    /// The row of `bearing`'s `parameter`.
    pub fn get(&self, bearing: &str, parameter: Parameter) -> Option<&ParameterAccuracy> {
        self.parameters
            .iter()
            .find(|p| p.bearing == bearing && p.parameter == parameter.name())
    }
}

/// Runs the Monte-Carlo on `machine` at `speeds_hz` [Hz], its draws in
/// parallel (rayon); the result depends on `seed` only, not on the number
/// of threads.
pub fn monte_carlo(
    machine: &Machine,
    speeds_hz: &[f64],
    perturbation: Perturbation,
    draws: usize,
    seed: u64,
) -> Result<Accuracy> {
    monte_carlo_with_progress(machine, speeds_hz, perturbation, draws, seed, false)
}

/// [`monte_carlo`] with a progress line on a terminal when `show_progress`.
pub fn monte_carlo_with_progress(
    machine: &Machine,
    speeds_hz: &[f64],
    perturbation: Perturbation,
    draws: usize,
    seed: u64,
    show_progress: bool,
) -> Result<Accuracy> {
    if draws < 2 {
        bail!("--draws {draws}: at least 2 draws are needed for a scatter");
    }
    if speeds_hz.len() < crate::identify::MIN_SPEEDS {
        bail!(
            "--speeds: {} speed(s); a pedestal is identified from at least {} (the Cramér–Rao bound of fewer is infinite)",
            speeds_hz.len(),
            crate::identify::MIN_SPEEDS
        );
    }
    match perturbation {
        Perturbation::Noise(f) if !(f.is_finite() && f > 0.0) => {
            bail!("--noise {f}: the noise fraction must be finite and > 0")
        }
        // Below a double's rounding the noise is no noise: its variance
        // underflows to 0 and the ML weights are undefined.
        Perturbation::Noise(f) if f < f64::EPSILON => {
            bail!(
                "--noise {f:e}: a noise fraction below {:e} (a double's rounding) is below the numbers' own rounding (a tiny one underflows to a variance of 0): use at least that",
                f64::EPSILON
            )
        }
        Perturbation::Digits(d) if !(1..=17).contains(&d) => {
            bail!("--digits {d}: between 1 and 17")
        }
        _ => {}
    }
    let response = unbalance_response(machine, speeds_hz, &EffectSet::none())
        .map_err(|e| anyhow!("simulating {}: {e}", machine.name))?;
    let clean = response
        .to_run_dir(None)
        .map_err(|e| anyhow!("simulating {}: {e}", machine.name))?;
    let truth = clean
        .truth
        .clone()
        .ok_or_else(|| anyhow!("the simulator gave no truth"))?;
    let bearings: Vec<String> = truth.pedestals.iter().map(|p| p.bearing.clone()).collect();
    if bearings.is_empty() {
        bail!(
            "machine {} has no pedestal to identify (no `pedestal` on any bearing)",
            machine.name
        );
    }
    let theta_true: Vec<[f64; PARAMETERS]> =
        truth.pedestals.iter().map(|p| p.pedestal.theta()).collect();
    let nb = bearings.len();
    let needed =
        crate::sim::budget::accuracy_bytes(nb as u64, speeds_hz.len() as u64, draws as u64);
    crate::sim::budget::check_count(
        "--draws",
        draws as u64,
        needed,
        crate::sim::budget::available_bytes(),
    )
    .map_err(|e| anyhow!(e))?;
    let mut crb_var = vec![[0.0; PARAMETERS]; nb];
    if let Perturbation::Noise(fraction) = perturbation {
        for (b, name) in bearings.iter().enumerate() {
            let rms: [f64; 4] = std::array::from_fn(|ch| channel_rms(&clean, name, ch));
            crb_var[b] = bound_with(&clean, name, &theta_true[b], &|_, c| {
                number_variance(Quantisation::Rounding, 0.0, Some(fraction * rms[c / 2]))
            })?;
        }
    }
    // The digits' random turns, drawn in order from the seed before the
    // draws run in parallel; the noise of draw k is seeded by (seed, k).
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let turns: Vec<num_complex::Complex<f64>> = match perturbation {
        Perturbation::Digits(_) => (0..draws)
            .map(|_| {
                num_complex::Complex::from_polar(
                    10f64.powf(rng.random::<f64>()),
                    std::f64::consts::TAU * rng.random::<f64>(),
                )
            })
            .collect(),
        Perturbation::Noise(_) => Vec::new(),
    };
    let done = std::sync::atomic::AtomicUsize::new(0);
    let ticker = std::sync::Mutex::new(crate::progress::Ticker::new(
        "accuracy: draws",
        draws,
        show_progress,
    ));
    let one_draw = |draw: usize| -> Result<Draw> {
        let mut bound_var = vec![[0.0; PARAMETERS]; nb];
        let run = match perturbation {
            Perturbation::Noise(fraction) => response
                .to_run_dir(Some(Noise {
                    fraction,
                    seed: seed.wrapping_mul(1_000_003).wrapping_add(draw as u64),
                }))
                .map_err(|e| anyhow!("{e}"))?,
            Perturbation::Digits(digits) => {
                let turned = turn_run(&clean, turns[draw]);
                let quantum = ColumnDigits {
                    digits,
                    lowest_digit_exponent: -400,
                };
                for (b, name) in bearings.iter().enumerate() {
                    bound_var[b] =
                        bound_with(&turned, name, &theta_true[b], &|m: &Measurement, c| {
                            let ulp = quantum.ulp(crate::estimate::noise::real_value(m, c));
                            number_variance(Quantisation::Rounding, ulp, None)
                        })?;
                }
                rounded(&turned, digits)
            }
        };
        // The estimates alone: the convention check `identify` adds
        // (refits of the run with mistakes undone) changes none of them.
        let ml_id = fit_run(&run, &Options::default())
            .with_context(|| format!("draw {draw}: ML identification"))?;
        let ols_id = fit_run(&run, &Options::default().ols())
            .with_context(|| format!("draw {draw}: OLS identification"))?;
        let mut out = Draw {
            ml: Vec::with_capacity(nb),
            ols: Vec::with_capacity(nb),
            ml_failures: 0,
            bound_var,
        };
        for name in &bearings {
            let ml_fit = pick(&ml_id, name)?;
            if ml_fit.has_warning(crate::identify::WarningKind::MlFailed) {
                out.ml_failures += 1;
            }
            out.ml
                .push((ml_fit.pedestal.theta(), ml_fit.std_err.theta()));
            let o = pick(&ols_id, name)?;
            out.ols.push((o.pedestal.theta(), o.std_err.theta()));
        }
        let finished = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        if let Ok(mut t) = ticker.lock() {
            t.tick(finished);
        }
        Ok(out)
    };
    // Parallel over draws; collected in draw order, so that every sum below
    // runs in the same order whatever the number of threads.
    let results: Vec<Draw> = (0..draws)
        .into_par_iter()
        .map(one_draw)
        .collect::<Result<Vec<Draw>>>()?;
    if let Ok(mut t) = ticker.lock() {
        t.finish();
    }
    // [bearing][draw] estimates and reported standard errors.
    let mut ml_est = vec![Vec::with_capacity(draws); nb];
    let mut ols_est = vec![Vec::with_capacity(draws); nb];
    let mut ml_failures = 0;
    for d in &results {
        ml_failures += d.ml_failures;
        for b in 0..nb {
            ml_est[b].push(d.ml[b]);
            ols_est[b].push(d.ols[b]);
            if let Perturbation::Digits(_) = perturbation {
                for (acc, x) in crb_var[b].iter_mut().zip(d.bound_var[b]) {
                    *acc += x / draws as f64;
                }
            }
        }
    }
    let mut parameters = Vec::new();
    for (b, name) in bearings.iter().enumerate() {
        for p in Parameter::ALL {
            let i = p as usize;
            let t = theta_true[b][i];
            let ml = stats(&ml_est[b], i, t);
            let ols = stats(&ols_est[b], i, t);
            parameters.push(ParameterAccuracy {
                bearing: name.clone(),
                parameter: p.name().to_string(),
                truth: t,
                crb: crb_var[b][i].sqrt(),
                ols_rms: ols.rms,
                ml_rms: ml.rms,
                ols_bias_sem: ols.bias_sem,
                ml_bias_sem: ml.bias_sem,
                ols_se_ratio: ols.se_ratio,
                ml_se_ratio: ml.se_ratio,
            });
        }
    }
    Ok(Accuracy {
        machine: machine.name.clone(),
        perturbation,
        draws,
        ml_failures,
        parameters,
    })
}

/// What one draw gives: per bearing the ML and OLS estimates with their
/// standard errors, and (digits) the bound's variances at that draw.
struct Draw {
    ml: Vec<Estimate>,
    ols: Vec<Estimate>,
    ml_failures: usize,
    bound_var: Vec<[f64; PARAMETERS]>,
}

/// An estimate θ and the standard errors reported with it.
type Estimate = ([f64; PARAMETERS], [f64; PARAMETERS]);

struct Stats {
    rms: f64,
    bias_sem: f64,
    se_ratio: f64,
}

fn stats(est: &[([f64; PARAMETERS], [f64; PARAMETERS])], i: usize, truth: f64) -> Stats {
    let n = est.len() as f64;
    let mean = est.iter().map(|e| e.0[i]).sum::<f64>() / n;
    let sd = (est.iter().map(|e| (e.0[i] - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let rms = (est.iter().map(|e| (e.0[i] - truth).powi(2)).sum::<f64>() / n).sqrt();
    let se_rms = (est.iter().map(|e| e.1[i].powi(2)).sum::<f64>() / n).sqrt();
    Stats {
        rms,
        bias_sem: (mean - truth) / (sd / n.sqrt()),
        se_ratio: se_rms / sd,
    }
}

fn pick<'a>(id: &'a Identification, name: &str) -> Result<&'a crate::identify::PedestalFit> {
    id.pedestal(name)
        .ok_or_else(|| anyhow!("pedestal {name} was not identified"))
}

/// RMS over speeds of |phasor| of complex channel `ch` of a bearing [m].
fn channel_rms(run: &RunDir, bearing: &str, ch: usize) -> f64 {
    let v: Vec<f64> = run
        .measurements
        .iter()
        .filter(|m| m.bearing == bearing)
        .map(|m| crate::estimate::noise::complex_value(m, ch).norm_sqr())
        .collect();
    (v.iter().sum::<f64>() / v.len().max(1) as f64).sqrt()
}

/// The bound sd² per parameter from the clean run's observations with the
/// noise variance `var(measurement, real channel)` [m²].
fn bound_with(
    run: &RunDir,
    bearing: &str,
    theta: &[f64; PARAMETERS],
    var: &dyn Fn(&Measurement, usize) -> f64,
) -> Result<[f64; PARAMETERS]> {
    let schedules = run.bearing_schedules();
    let schedule = schedules
        .get(bearing)
        .ok_or_else(|| anyhow!("bearing {bearing} has no coefficients"))?;
    let mut obs = Vec::new();
    for m in run.measurements.iter().filter(|m| m.bearing == bearing) {
        let c = schedule
            .at(m.speed_hz)
            .map_err(|e| anyhow!("bearing {bearing}: {e}"))?;
        obs.push(Observation {
            speed_hz: m.speed_hz,
            rel: m.rel,
            ped: m.ped,
            kstar: complex_stiffness(&c, omega_from_hz(m.speed_hz)),
            var: std::array::from_fn(|k| var(m, k)),
        });
    }
    let (cov, _) = ml::bound(&obs, &Parameter::ALL, theta).map_err(|e| anyhow!("{e}"))?;
    Ok(std::array::from_fn(|i| cov[i][i]))
}

/// Every phasor of a run multiplied by `turn` (bearings and truth unchanged).
fn turn_run(run: &RunDir, turn: num_complex::Complex<f64>) -> RunDir {
    let mut out = run.clone();
    for m in &mut out.measurements {
        for z in m.rel.iter_mut().chain(m.ped.iter_mut()) {
            *z *= turn;
        }
    }
    out
}

/// Every number of a run's phasors rounded to `digits` significant digits.
fn rounded(run: &RunDir, digits: u32) -> RunDir {
    let mut out = run.clone();
    for m in &mut out.measurements {
        for z in m.rel.iter_mut().chain(m.ped.iter_mut()) {
            z.re = round_to_digits(z.re, digits, DigitsMode::Round);
            z.im = round_to_digits(z.im, digits, DigitsMode::Round);
        }
    }
    out
}

/// Command-line arguments of `plinth accuracy`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Simulates MACHINE.toml's clean run-down once, then per draw adds complex Gaussian noise \
(--noise FRAC: FRAC × each channel's RMS over speed, on rel and ped) or rounds to N \
significant digits (--digits N, after turning the phasors by a random common phase and \
scale), identifies the run with the paper's OLS and with ML (noise model estimated from the \
data), and prints per parameter: the Cramér–Rao bound (CRB), the RMS error of OLS and ML and \
their ratios to the bound, each estimator's mean error in standard errors of the mean, and \
the ratio of the standard error it reports to its observed scatter.")]
pub struct Args {
    /// Machine file (TOML, SI units).
    pub machine: PathBuf,
    /// Noise RMS relative to each channel's RMS [-] (default 0.01).
    #[arg(long, conflicts_with = "digits")]
    pub noise: Option<f64>,
    /// Round every number to this many significant digits instead of noise.
    #[arg(long)]
    pub digits: Option<u32>,
    /// Number of draws.
    #[arg(long, allow_negative_numbers = true, default_value_t = 200)]
    pub draws: usize,
    /// Seed of the draws.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1)]
    pub seed: u64,
    /// Speeds [Hz] as START:STOP:STEP (inclusive), or a comma-separated list.
    #[arg(long, default_value = "5:200:1")]
    pub speeds: String,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `plinth accuracy`.
pub fn run(args: &Args) -> Result<()> {
    let machine = Machine::from_toml_path(&args.machine)?;
    let speeds = crate::sim::cli::parse_speeds(&args.speeds)?;
    crate::sim::budget::check_solves(&format!("--speeds {}", args.speeds), &machine, speeds.len())
        .map_err(anyhow::Error::msg)?;
    let perturbation = match (args.noise, args.digits) {
        (_, Some(d)) => Perturbation::Digits(d),
        (Some(f), None) => Perturbation::Noise(f),
        (None, None) => Perturbation::Noise(0.01),
    };
    let acc =
        monte_carlo_with_progress(&machine, &speeds, perturbation, args.draws, args.seed, true)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&acc)?);
    } else {
        print!("{}", table(&acc));
    }
    Ok(())
}

/// The result as an aligned text table.
pub fn table(acc: &Accuracy) -> String {
    let what = match acc.perturbation {
        Perturbation::Noise(f) => format!("complex Gaussian noise {f} × channel RMS"),
        Perturbation::Digits(d) => format!("rounded to {d} significant digits"),
    };
    let mut out = format!(
        "machine {}, {what}, {} draws ({} ML fits fell back or did not converge)\n\n",
        acc.machine, acc.draws, acc.ml_failures
    );
    let mut rows = vec![[
        "bearing",
        "param",
        "truth",
        "CRB",
        "OLS rms",
        "ML rms",
        "OLS/CRB",
        "ML/CRB",
        "OLS bias [sem]",
        "ML bias [sem]",
        "OLS se/sd",
        "ML se/sd",
    ]
    .map(String::from)
    .to_vec()];
    for p in &acc.parameters {
        rows.push(vec![
            p.bearing.clone(),
            p.parameter.clone(),
            format!("{:.4e}", p.truth),
            format!("{:.3e}", p.crb),
            format!("{:.3e}", p.ols_rms),
            format!("{:.3e}", p.ml_rms),
            format!("{:.2}", p.ols_rms / p.crb),
            format!("{:.2}", p.ml_rms / p.crb),
            format!("{:+.1}", p.ols_bias_sem),
            format!("{:+.1}", p.ml_bias_sem),
            format!("{:.2}", p.ols_se_ratio),
            format!("{:.2}", p.ml_se_ratio),
        ]);
    }
    let widths: Vec<usize> = (0..rows[0].len())
        .map(|c| rows.iter().map(|r| r[c].chars().count()).max().unwrap_or(0))
        .collect();
    for r in &rows {
        let line: Vec<String> = r
            .iter()
            .zip(&widths)
            .map(|(cell, w)| format!("{cell:<w$}"))
            .collect();
        out.push_str(line.join("  ").trim_end());
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn machine() -> Machine {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../examples/feng-hahn-1997-damped.toml");
        Machine::from_toml_path(path).expect("machine file")
    }

    /// The same seed gives the same numbers on one thread and on two (the
    /// draws run in parallel and are gathered in draw order), for noise and
    /// for digits; another seed gives other numbers.
    #[test]
    fn same_numbers_on_one_and_two_threads() {
        let machine = machine();
        let speeds: Vec<f64> = (5..=120).map(f64::from).collect();
        let on = |threads: usize, perturbation: Perturbation, seed: u64| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("thread pool")
                .install(|| monte_carlo(&machine, &speeds, perturbation, 6, seed))
                .expect("monte carlo")
        };
        for perturbation in [Perturbation::Noise(0.01), Perturbation::Digits(3)] {
            let one = on(1, perturbation, 7);
            let two = on(2, perturbation, 7);
            assert_eq!(one, two, "{perturbation:?}");
            assert_ne!(one, on(2, perturbation, 8), "{perturbation:?}");
        }
    }
}
