//! Issue 17: the ± of a fit whose noise law is estimated from its own
//! residuals (no noise columns), on a machine of 58 speeds whose sensors'
//! noise grows with the signal and with speed (docs/unseen-six.md
//! "2. Clean runs without noise columns"; host/src/estimate/noise/variance.rs).
//!
//! The true phasors are ROSS's (tests/data/ross-unseen-6/clean-exact, made
//! by `python3 scripts/ross_unseen_exact.py unseen-six clean-s1
//! tests/data/ross-unseen-6/clean-exact`, python3 being the ROSS 2.3.0
//! venv's: the grid of `clean-s1`, 15 digits, no noise); the noise is
//! unseen-six's sensor law (scripts/ross_unseen_machines.py), drawn here:
//! complex sd = 0.5 % of |phasor| + a floor (0.3 %, 1 %, 0.5 %, 2 % of the
//! channel's RMS on rel y, rel z, ped y, ped z) + a tracking filter's
//! broadband term growing as √speed (5e-10 m/√Hz on the probes, 1e-8 on the
//! pick-ups), written with 7 digits and read back: what
//! `ross_unseen.py --machine unseen-six DIR clean-s1 SEED` writes.

use plinth::rundir::RunDir;
use plinth_tests::rundown::identify;
use plinth_tests::unseen::printed_ok;
use plinth_tests::write_run;
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};

/// unseen-six's sensor law per channel (rel y, rel z, ped y, ped z):
/// (fraction of |phasor| [-], floor as a fraction of the channel's RMS [-],
/// growth [m/√Hz]).
const LAW: [(f64, f64, f64); 4] = [
    (0.005, 0.003, 5e-10),
    (0.005, 0.01, 5e-10),
    (0.005, 0.005, 1e-8),
    (0.005, 0.02, 1e-8),
];

/// `exact` with [`LAW`]'s noise drawn with `seed`, written with 7 digits
/// and read back.
fn noisy(exact: &RunDir, seed: u64) -> RunDir {
    let mut run = exact.clone();
    let mut rng = StdRng::seed_from_u64(seed);
    let value = |m: &plinth::rundir::Measurement, ch: usize| {
        if ch < 2 {
            m.rel[ch]
        } else {
            m.ped[ch - 2]
        }
    };
    let mut bearings: Vec<String> = run.measurements.iter().map(|m| m.bearing.clone()).collect();
    bearings.sort();
    bearings.dedup();
    for b in &bearings {
        let rows: Vec<usize> = (0..run.measurements.len())
            .filter(|&i| &run.measurements[i].bearing == b)
            .collect();
        for (ch, &(fraction, floor, grow)) in LAW.iter().enumerate() {
            let rms = (rows
                .iter()
                .map(|&i| value(&run.measurements[i], ch).norm_sqr())
                .sum::<f64>()
                / rows.len() as f64)
                .sqrt();
            for &i in &rows {
                let m = &mut run.measurements[i];
                let x = value(m, ch);
                let sd =
                    (fraction * x.norm() + floor * rms + grow * m.speed_hz.sqrt()) / 2f64.sqrt();
                let re: f64 = StandardNormal.sample(&mut rng);
                let im: f64 = StandardNormal.sample(&mut rng);
                let n = x + num_complex::Complex::new(re * sd, im * sd);
                if ch < 2 {
                    m.rel[ch] = n;
                } else {
                    m.ped[ch - 2] = n;
                }
            }
        }
    }
    let dir = write_run(&run, Some(7));
    RunDir::read(dir.path()).expect("read back")
}

/// Over 150 draws of unseen-six's noise on ROSS's true phasors (58 speeds,
/// three pedestals, no noise columns: every bearing's noise law is the
/// variance function of its residuals), the pedestals printed `ok` must
/// mean their ±: the RMS of (estimate − truth)/± of k_y, k_z, m, c_y, c_z
/// over them within 0.92-1.08 (its sampling sd about 0.015) and at most
/// 1 % of the values beyond 3 of their ± (0.27 % for a normal z). Measured
/// (docs/estimation-scatter.md, Session 46 (noise17)): main's code (840c9e1) FAILS; this
/// branch's passes.
#[test]
fn an_estimated_noise_law_on_58_speeds_keeps_its_promise() {
    let exact = plinth_tests::unseen::stored(
        concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-6"),
        "clean-exact",
    );
    let (mut z2, mut beyond) = (Vec::new(), 0);
    for seed in 1..=150 {
        let run = noisy(&exact, seed);
        let id = identify(&run);
        for (_, got, se, want) in printed_ok(&run, &id, true) {
            let z = (got - want) / se;
            beyond += usize::from(z.abs() > 3.0);
            z2.push(z * z);
        }
    }
    let n = z2.len();
    let rms = (z2.iter().sum::<f64>() / n as f64).sqrt();
    eprintln!("RMS z {rms:.3} over {n} values, {beyond} beyond 3 ±");
    assert!(n >= 2000, "only {n} values printed ok");
    assert!(
        (0.92..=1.08).contains(&rms),
        "RMS of (estimate − truth)/± over {n} values = {rms:.3}"
    );
    assert!(
        beyond * 100 <= n,
        "{beyond} of {n} values beyond 3 of their ±"
    );
}

/// The same machine and noise as above on other draws (seeds 151-240): no
/// pedestal parameter's ± may be short. On unseen-six's 58 speeds the
/// scatter's windows leave out most speeds of every channel (the local
/// quartics cannot follow its four resonances at 1 Hz steps): its law is
/// carried there from the rest, and where the score test did not reject
/// it, main's identify took it as known. Those fits' ± were 0.5-0.65 of the
/// true law's on c_y (unseen-six B2, B3; docs/estimation-scatter.md,
/// Session 47 (scatlaw17)). Each (bearing, parameter)'s RMS of
/// (estimate − truth)/± over the draws must stay below 1.25 (its sampling
/// sd over 90 values is about 0.075) and at most 1 % of all values beyond
/// 3 of their ±.
#[test]
fn no_parameter_is_short_where_the_scatter_law_is_carried() {
    let exact = plinth_tests::unseen::stored(
        concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-6"),
        "clean-exact",
    );
    let mut z2: std::collections::BTreeMap<String, Vec<f64>> = Default::default();
    let mut beyond = 0;
    for seed in 151..=240 {
        let run = noisy(&exact, seed);
        let id = identify(&run);
        for (name, got, se, want) in printed_ok(&run, &id, true) {
            let z = (got - want) / se;
            beyond += usize::from(z.abs() > 3.0);
            z2.entry(name).or_default().push(z * z);
        }
    }
    let n: usize = z2.values().map(Vec::len).sum();
    let rms: Vec<(String, f64)> = z2
        .iter()
        .map(|(k, v)| (k.clone(), (v.iter().sum::<f64>() / v.len() as f64).sqrt()))
        .collect();
    eprintln!("{n} values, {beyond} beyond 3 ±; RMS z {rms:.2?}");
    assert!(n >= 1200, "only {n} values printed ok");
    for (name, r) in &rms {
        assert!(*r <= 1.25, "{name}: RMS of (estimate − truth)/± = {r:.3}");
    }
    assert!(
        beyond * 100 <= n,
        "{beyond} of {n} values beyond 3 of their ±"
    );
}
