//! Monte-Carlo rates of `plinth diagnose` (issue 17), run by
//! `scripts/bench-diagnose.sh` (the ignored test `bench_rates`; `BENCH_RUNS`
//! seeds per case). Data made by the simulator's elements and effects
//! (`plinth::sim`), never by the model under test.
//!
//! - False-alarm rate per run on clean data: the skid machine on rigid
//!   ground (oil films, geometry given) and a three-bearing machine with
//!   tabulated cross-coupled bearings, each at 3 and at 12 digits, with
//!   0.5 % noise and its `*_sd` columns, and with heteroscedastic noise
//!   (1 % of each phasor's own magnitude, no noise columns). A run is a
//!   false alarm when anything is named or the verdict is untrusted. The
//!   rate is given with its 95 % Clopper–Pearson upper bound.
//! - Detection rate per effect and per combination (0.5 % noise with
//!   columns): "named right" (exactly the true effects, each at its
//!   bearing), "named wrong" (something named, not exactly that) and
//!   "missed" (nothing named).
//!
//! The small check [`rates_are_computed_right`] runs with the suite.

use plinth::diagnose::cli::oil_films;
use plinth::diagnose::machine::MachineCheck;
use plinth::diagnose::{diagnose, Options};
use plinth::effects::EffectKind;
use plinth::rundir::RunDir;
use plinth::sim::machine::BearingModel;
use plinth::sim::{unbalance_response, EffectSet, Machine};
use plinth_tests::simulated::{
    on_rigid_ground, right_pedestal_on_a_sub_base, simulated_run, speeds, Writing,
};
use plinth_tests::write_run;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

const SKID: &str = include_str!("../../examples/two-pedestals-on-skid.toml");
const THREE: &str = include_str!("../machines/three-bearing-tabulated.toml");

/// Noise fraction of each channel's RMS (with `*_sd` columns).
const NOISE: f64 = 0.005;

/// Heteroscedastic noise: sd of each phasor as a fraction of its magnitude.
const HETERO: f64 = 0.01;

fn skid() -> Machine {
    Machine::from_toml_str(SKID, "two-pedestals-on-skid.toml").expect("machine file")
}

fn three_bearing() -> Machine {
    Machine::from_toml_str(THREE, "three-bearing-tabulated.toml").expect("machine file")
}

/// The skid machine on rigid ground.
fn rigid() -> Machine {
    on_rigid_ground(&skid())
}

/// The rigid skid machine with the right pedestal alone on its own sub-base.
fn sub_base() -> Machine {
    right_pedestal_on_a_sub_base(&skid())
}

/// How a bench run's numbers are written.
#[derive(Clone, Copy, Debug)]
enum Noise {
    /// No noise; rounded to these significant digits.
    Digits(u32),
    /// [`NOISE`] of each channel's RMS with `*_sd` columns, full precision.
    Columns,
    /// [`HETERO`] of each phasor's magnitude, no columns, 12 digits.
    Hetero,
}

impl Noise {
    fn label(self) -> String {
        match self {
            Noise::Digits(d) => format!("{d} digits"),
            Noise::Columns => format!("{} % noise + sd columns", 100.0 * NOISE),
            Noise::Hetero => format!("hetero {} % of |phasor|", 100.0 * HETERO),
        }
    }
}

/// Simulates `machine` with `effects` at 5-120 Hz (2 Hz steps), written as
/// `noise` says, read back.
fn run_dir(machine: &Machine, effects: &EffectSet, noise: Noise, seed: u64) -> RunDir {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut normal = || -> f64 { StandardNormal.sample(&mut rng) };
    let grid = speeds(5.0, 120.0, 2.0);
    match noise {
        Noise::Digits(d) => {
            let w = Writing {
                digits: Some(d),
                noise: 0.0,
                rel_noise: None,
            };
            simulated_run(machine, &grid, effects, w, &mut normal)
        }
        Noise::Columns => {
            let w = Writing {
                digits: None,
                noise: NOISE,
                rel_noise: None,
            };
            simulated_run(machine, &grid, effects, w, &mut normal)
        }
        Noise::Hetero => {
            let response = unbalance_response(machine, &grid, effects).expect("simulation");
            let mut run = response.to_run_dir(None).expect("run dir");
            for m in &mut run.measurements {
                for ch in 0..4 {
                    let z = if ch < 2 {
                        &mut m.rel[ch]
                    } else {
                        &mut m.ped[ch - 2]
                    };
                    let s = HETERO * z.norm() / std::f64::consts::SQRT_2;
                    *z += num_complex::Complex::new(normal(), normal()) * s;
                }
            }
            let dir = write_run(&run, Some(12));
            RunDir::read(dir.path()).expect("read back")
        }
    }
}

/// bearings.csv rewritten for the machine's oil films at `factor` times
/// their clearance (the table is wrong, the machine is not).
fn table_for_clearance(machine: &Machine, run: &mut RunDir, factor: f64) {
    for row in &mut run.bearings {
        let b = machine
            .bearings
            .iter()
            .find(|b| b.name == row.bearing)
            .expect("bearing");
        let BearingModel::OilFilm(film) = &b.model else {
            panic!("not an oil film")
        };
        let mut written = *film;
        written.clearance *= factor;
        row.coefficients = written.coefficients(row.speed_hz).expect("film");
    }
}

/// A bench case: a machine, what is wrong with it (effects, a table for
/// another clearance) and what diagnose should name: (effect, bearing),
/// the bearing empty for the bases and for `bearing_coefficients` (named
/// at every bearing whose table is off).
struct Case {
    label: String,
    machine: Machine,
    effects: EffectSet,
    table: Option<f64>,
    noise: Noise,
    truth: Vec<(&'static str, &'static str)>,
}

/// What one run of a case gave.
#[derive(Clone, Debug)]
struct Outcome {
    named: Vec<(String, String)>,
    trusted: bool,
    reasons: Vec<String>,
    /// Trusted after the machine-level check with the right machine file
    /// (`--machine`, `MachineCheck`); `None`: not simulated.
    machine_trusted: Option<bool>,
    /// The same with a machine file whose first unbalance is turned by 90°
    /// (the machine-level rule's detection).
    wrong_file_trusted: Option<bool>,
    seconds: f64,
}

impl Outcome {
    /// The named set is exactly the truth (each effect at its bearing; an
    /// empty truth bearing matches any bearing).
    fn right(&self, truth: &[(&str, &str)]) -> bool {
        let covers = |(e, b): &(&str, &str)| {
            self.named
                .iter()
                .any(|(ne, nb)| ne == e && (b.is_empty() || nb == b))
        };
        let explained = |(ne, nb): &(String, String)| {
            truth
                .iter()
                .any(|(e, b)| ne == e && (b.is_empty() || nb == b))
        };
        truth.iter().all(covers) && self.named.iter().all(explained)
    }
}

fn run_case(case: &Case, seed: u64) -> Outcome {
    let mut run = run_dir(&case.machine, &case.effects, case.noise, seed);
    if let Some(f) = case.table {
        table_for_clearance(&case.machine, &mut run, f);
    }
    let options = Options {
        oil_films: oil_films(&case.machine),
        ..Options::default()
    };
    let started = std::time::Instant::now();
    let out = diagnose(&run, &options).expect("diagnose");
    let trusted_with = |machine: &Machine| {
        MachineCheck::of(machine, &out).ok().map(|c| {
            let mut d = out.diagnosis.clone();
            c.apply(&mut d);
            d.trusted
        })
    };
    let machine_trusted = trusted_with(&case.machine);
    let mut turned = case.machine.clone();
    turned.unbalances[0].angle_deg += 90.0;
    let wrong_file_trusted = trusted_with(&turned);
    let d = out.diagnosis;
    Outcome {
        named: d
            .steps
            .iter()
            .filter(|s| s.dropped.is_none())
            .map(|s| (s.effect.clone(), s.bearing.clone()))
            .collect(),
        trusted: d.trusted,
        reasons: d.trust_reasons.clone(),
        machine_trusted,
        wrong_file_trusted,
        seconds: started.elapsed().as_secs_f64(),
    }
}

/// ln C(n, k).
fn ln_choose(n: u64, k: u64) -> f64 {
    (1..=k).map(|i| ((n - k + i) as f64 / i as f64).ln()).sum()
}

/// P(X ≤ x) for X ~ Binomial(n, p).
fn binomial_cdf(x: u64, n: u64, p: f64) -> f64 {
    if p <= 0.0 {
        return 1.0;
    }
    if p >= 1.0 {
        return if x >= n { 1.0 } else { 0.0 };
    }
    (0..=x.min(n))
        .map(|k| (ln_choose(n, k) + k as f64 * p.ln() + (n - k) as f64 * (-p).ln_1p()).exp())
        .sum::<f64>()
        .min(1.0)
}

/// The 95 % (two-sided) Clopper–Pearson upper bound of a rate after `x`
/// events in `n` trials: the p with P(X ≤ x | n, p) = 0.025 (1 when x = n).
fn clopper_pearson_upper(x: u64, n: u64) -> f64 {
    if x >= n {
        return 1.0;
    }
    let (mut lo, mut hi) = (x as f64 / n as f64, 1.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if binomial_cdf(x, n, mid) > 0.025 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

#[test]
fn rates_are_computed_right() {
    // Closed forms: 0 of n: (1 − p)^n = 0.025, p = 1 − 0.025^(1/n);
    // n − 1 of n: 1 − p^n = 0.025, p = 0.975^(1/n).
    for n in [10u64, 20, 100, 300] {
        let want = 1.0 - 0.025f64.powf(1.0 / n as f64);
        assert!((clopper_pearson_upper(0, n) - want).abs() < 1e-9, "{n}");
        let want = 0.975f64.powf(1.0 / n as f64);
        assert!((clopper_pearson_upper(n - 1, n) - want).abs() < 1e-9, "{n}");
    }
    // Tabulated: 2 of 50 → 0.1371 (Clopper–Pearson, 95 %).
    assert!((clopper_pearson_upper(2, 50) - 0.1371).abs() < 5e-4);
    assert!((binomial_cdf(3, 10, 0.5) - 176.0 / 1024.0).abs() < 1e-12);
    let o = Outcome {
        named: vec![
            ("foundation_coupling".into(), "left".into()),
            ("probe_runout".into(), "right".into()),
        ],
        trusted: true,
        reasons: vec![],
        machine_trusted: None,
        wrong_file_trusted: None,
        seconds: 0.0,
    };
    assert!(o.right(&[("foundation_coupling", ""), ("probe_runout", "right")]));
    assert!(!o.right(&[("foundation_coupling", ""), ("probe_runout", "left")]));
    assert!(!o.right(&[("probe_runout", "right")]));
    assert!(!o.right(&[
        ("foundation_coupling", ""),
        ("probe_runout", "right"),
        ("sensor_delay", "")
    ]));
}

fn clean_cases() -> Vec<Case> {
    let mut out = Vec::new();
    for (name, machine) in [("rigid skid", rigid()), ("three-bearing", three_bearing())] {
        for noise in [
            Noise::Digits(3),
            Noise::Digits(12),
            Noise::Columns,
            Noise::Hetero,
        ] {
            out.push(Case {
                label: format!("{name}, {}", noise.label()),
                machine: machine.clone(),
                effects: EffectSet::none(),
                table: None,
                noise,
                truth: vec![],
            });
        }
    }
    out
}

fn detection_cases() -> Vec<Case> {
    let one =
        |kind: EffectKind, bearing: &'static str| EffectSet::none().with(kind, Some(bearing), None);
    let case = |label: &str,
                machine: Machine,
                effects: EffectSet,
                table: Option<f64>,
                truth: Vec<(&'static str, &'static str)>| Case {
        label: label.to_string(),
        machine,
        effects,
        table,
        noise: Noise::Columns,
        truth,
    };
    vec![
        case(
            "probe_runout (left)",
            rigid(),
            one(EffectKind::ProbeRunout, "left"),
            None,
            vec![("probe_runout", "left")],
        ),
        case(
            "sensor_delay (right)",
            rigid(),
            one(EffectKind::SensorDelay, "right"),
            None,
            vec![("sensor_delay", "right")],
        ),
        case(
            "pedestal_cross_coupling (right)",
            rigid(),
            one(EffectKind::PedestalCrossCoupling, "right"),
            None,
            vec![("pedestal_cross_coupling", "right")],
        ),
        case(
            "foundation_coupling (shared skid)",
            skid(),
            EffectSet::none(),
            None,
            vec![("foundation_coupling", "")],
        ),
        case(
            "pedestal_sub_base (right)",
            sub_base(),
            EffectSet::none(),
            None,
            vec![("pedestal_sub_base", "right")],
        ),
        case(
            "bearing_coefficients (clearance -15 %)",
            rigid(),
            EffectSet::none(),
            Some(0.85),
            vec![("bearing_coefficients", "")],
        ),
        case(
            "skid + probe_runout (right)",
            skid(),
            one(EffectKind::ProbeRunout, "right"),
            None,
            vec![("foundation_coupling", ""), ("probe_runout", "right")],
        ),
        case(
            "skid + sensor_delay (left)",
            skid(),
            one(EffectKind::SensorDelay, "left"),
            None,
            vec![("foundation_coupling", ""), ("sensor_delay", "left")],
        ),
        case(
            "skid + pedestal_cross_coupling (left)",
            skid(),
            one(EffectKind::PedestalCrossCoupling, "left"),
            None,
            vec![
                ("foundation_coupling", ""),
                ("pedestal_cross_coupling", "left"),
            ],
        ),
        case(
            "cross_coupling (left) + sensor_delay (right)",
            rigid(),
            EffectSet::none()
                .with(EffectKind::PedestalCrossCoupling, Some("left"), None)
                .with(EffectKind::SensorDelay, Some("right"), None),
            None,
            vec![
                ("pedestal_cross_coupling", "left"),
                ("sensor_delay", "right"),
            ],
        ),
    ]
}

/// Runs every (case, seed) in parallel (rayon), the results per case.
fn run_all(cases: &[Case], runs: u64, seed0: u64) -> Vec<Vec<Outcome>> {
    let jobs: Vec<(usize, u64)> = (0..cases.len())
        .flat_map(|c| (0..runs).map(move |s| (c, s)))
        .collect();
    let done: Vec<(usize, Outcome)> = jobs
        .par_iter()
        .map(|&(c, s)| (c, run_case(&cases[c], seed0 + 1000 * c as u64 + s)))
        .collect();
    let mut out = vec![Vec::new(); cases.len()];
    for (c, o) in done {
        out[c].push(o);
    }
    out
}

fn percent(x: usize, n: usize) -> f64 {
    100.0 * x as f64 / n.max(1) as f64
}

/// Monte-Carlo rates (module docs). `BENCH_RUNS` seeds per clean case
/// (default 25), `BENCH_DETECT_RUNS` per detection case (default 3: a run
/// that chooses a base costs minutes under load); `BENCH_PART` = `clean`,
/// `detect` or both (default).
#[test]
#[ignore = "Monte-Carlo bench: scripts/bench-diagnose.sh"]
fn bench_rates() {
    let env = |name: &str, default: u64| -> u64 {
        std::env::var(name)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(default)
    };
    let runs = env("BENCH_RUNS", 25);
    let detect_runs = env("BENCH_DETECT_RUNS", 3);
    let part = std::env::var("BENCH_PART").unwrap_or_default();
    let started = std::time::Instant::now();
    if part.is_empty() || part == "clean" {
        let cases = clean_cases();
        let results = run_all(&cases, runs, 10_000);
        let (mut alarms, mut total, mut machine_alarms) = (0usize, 0usize, 0usize);
        let (mut wrong_flagged, mut wrong_total) = (0usize, 0usize);
        for (case, outs) in cases.iter().zip(&results) {
            let named = outs.iter().filter(|o| !o.named.is_empty()).count();
            let untrusted = outs
                .iter()
                .filter(|o| o.named.is_empty() && !o.trusted)
                .count();
            let secs: f64 = outs.iter().map(|o| o.seconds).sum::<f64>() / outs.len() as f64;
            println!(
                "BENCH clean {:<45} runs {:>3}  named {:>3}  untrusted-only {:>3}  ({secs:.1} s/run)",
                case.label,
                outs.len(),
                named,
                untrusted
            );
            for o in outs.iter().filter(|o| !o.named.is_empty() || !o.trusted) {
                println!(
                    "  false alarm: named {:?}, trusted {}, reasons {:?}",
                    o.named, o.trusted, o.reasons
                );
            }
            let machine = outs
                .iter()
                .filter(|o| o.trusted && o.machine_trusted != Some(true))
                .count();
            if machine > 0 {
                println!("  machine-level check untrusted (or not simulated) on {machine} runs");
            }
            machine_alarms += machine;
            for o in outs.iter().filter(|o| o.trusted) {
                wrong_total += 1;
                wrong_flagged += usize::from(o.wrong_file_trusted == Some(false));
            }
            alarms += named + untrusted;
            total += outs.len();
        }
        println!(
            "BENCH diagnose false-alarm rate: {alarms}/{total} clean runs = {:.1} % per run (95 % Clopper–Pearson upper bound {:.1} %)",
            percent(alarms, total),
            100.0 * clopper_pearson_upper(alarms as u64, total as u64)
        );
        println!(
            "BENCH diagnose --machine (right file) false-alarm rate: {machine_alarms}/{total} runs trusted at the pedestal level made untrusted = {:.1} % (95 % upper bound {:.1} %)",
            percent(machine_alarms, total),
            100.0 * clopper_pearson_upper(machine_alarms as u64, total as u64)
        );
        println!(
            "BENCH diagnose --machine detection (a file with the first unbalance turned by 90°): untrusted in {wrong_flagged}/{wrong_total} runs = {:.1} %",
            percent(wrong_flagged, wrong_total)
        );
    }
    if part.is_empty() || part == "detect" {
        // `BENCH_CASES`: only the cases whose label holds this text.
        let only = std::env::var("BENCH_CASES").unwrap_or_default();
        let cases: Vec<Case> = detection_cases()
            .into_iter()
            .filter(|c| c.label.contains(&only))
            .collect();
        // Case by case (the seeds of each in parallel), printed as each ends.
        for (c, case) in cases.iter().enumerate() {
            let results = run_all(
                std::slice::from_ref(case),
                detect_runs,
                20_000 + 1000 * c as u64,
            );
            let outs = &results[0];
            let right = outs.iter().filter(|o| o.right(&case.truth)).count();
            let missed = outs.iter().filter(|o| o.named.is_empty()).count();
            let wrong = outs.len() - right - missed;
            let secs: f64 = outs.iter().map(|o| o.seconds).sum::<f64>() / outs.len() as f64;
            println!(
                "BENCH detect {:<45} runs {:>3}  named right {:>3} ({:.0} %)  named wrong {:>3}  missed {:>3}  ({secs:.1} s/run)",
                case.label,
                outs.len(),
                right,
                percent(right, outs.len()),
                wrong,
                missed
            );
            for o in outs.iter().filter(|o| !o.right(&case.truth)) {
                println!("  not right: named {:?}", o.named);
            }
            // The machine-level check with the right file on the runs named
            // right (a false alarm of `--machine` after the effect, a base's
            // own uncertainty in its floor).
            let named_right: Vec<&Outcome> = outs.iter().filter(|o| o.right(&case.truth)).collect();
            let machine_untrusted = named_right
                .iter()
                .filter(|o| o.machine_trusted != Some(true))
                .count();
            println!(
                "  --machine (right file) untrusted on {machine_untrusted}/{} runs named right",
                named_right.len()
            );
        }
    }
    println!(
        "BENCH diagnose wall time {:.1} s",
        started.elapsed().as_secs_f64()
    );
}
