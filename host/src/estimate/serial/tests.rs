//! Unit tests of [`super`].

use super::*;
use nalgebra::{DMatrix, DVector};
use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, StandardNormal};

fn speeds(n: usize) -> Vec<f64> {
    (0..n).map(|i| 100.0 + 0.4 * i as f64).collect()
}

/// Rows of unit noise along the run, an AR(1) of lag-one correlation `rho`.
fn ar1(n: usize, rho: f64, seed: u64) -> Vec<[f64; 4]> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut last = [0.0; 4];
    (0..n)
        .map(|t| {
            let z: [f64; 4] = std::array::from_fn(|_| StandardNormal.sample(&mut rng));
            last = if t == 0 {
                z
            } else {
                std::array::from_fn(|c| rho * last[c] + (1.0 - rho * rho).sqrt() * z[c])
            };
            last
        })
        .collect()
}

#[test]
fn white_residuals_are_rarely_called_correlated_and_an_ar1_is_measured() {
    // 300 white runs each of 50 and 376 speeds: about 1 % above the limit
    // (at most 3 % here); an AR(1) of ρ = 0.8 over 376 speeds found every
    // time and measured within 0.1 (the cubic detrending takes a little).
    for n in [50, 376] {
        let s = speeds(n);
        let found = (0..300)
            .filter(|&seed| measured(&s, &ar1(n, 0.0, seed)).is_some())
            .count();
        assert!(found <= 9, "{found} of 300 white runs of {n} speeds");
    }
    let s = speeds(376);
    for seed in 0..20 {
        let (_, rho, _) = measured(&s, &ar1(376, 0.8, 1000 + seed)).expect("correlated");
        assert!((rho - 0.8).abs() < 0.1, "seed {seed}: ρ̂ {rho}");
    }
    // A smooth trend over the run is not read as correlation.
    let mut w = ar1(376, 0.0, 7);
    for (t, r) in w.iter_mut().enumerate() {
        r[0] += 5.0 * (t as f64 / 376.0 * 2.0 - 1.0).powi(3);
    }
    assert!(measured(&s, &w).is_none());
}

#[test]
fn the_detrending_bias_is_removed() {
    // The expected ρ̂ in closed form against 400 simulated runs (32 and
    // 376 speeds, ρ 0, 0.5, 0.8): within 0.01 (the simulation's own sd
    // of a mean: 0.004 at 32 speeds), and ρ̂ well below ρ at 32 speeds.
    for n in [32, 376] {
        let s = speeds(n);
        for rho in [0.0, 0.5, 0.8] {
            let draws: Vec<f64> = (0..400)
                .map(|seed| lag_one_correlation(&s, &ar1(n, rho, 5000 + seed)).expect("ρ̂"))
                .collect();
            let mean = draws.iter().sum::<f64>() / draws.len() as f64;
            // ar1_rho inverts the closed form: the mean of many ρ̂ maps
            // back to ρ.
            let back = ar1_rho(&s, mean);
            assert!(
                (back - rho).abs() < if n == 32 { 0.04 } else { 0.01 },
                "{n} speeds, ρ {rho}: mean ρ̂ {mean}, back {back}"
            );
        }
    }
    let s = speeds(32);
    assert!(ar1_rho(&s, 0.45) > 0.75, "{}", ar1_rho(&s, 0.45));
    // 376 speeds at ρ̂ 0.777 (the ROSS runs' mean 0.77): ρ 0.80.
    let back = ar1_rho(&speeds(376), 0.777);
    assert!((back - 0.80).abs() < 0.005, "{back}");
    // Monotone, clamped.
    assert_eq!(ar1_rho(&speeds(376), 0.99), MAX_RHO);
    assert_eq!(ar1_rho(&speeds(376), -0.5), 0.0);
}

#[test]
fn prewhitened_equations_are_the_rows_prewhitened() {
    let w = ar1(20, 0.8, 11);
    let m = DMatrix::from_fn(80, 1, |r, _| w[r / 4][r % 4]);
    let p = prewhitened_equations(&m, 0.7);
    let rows = prewhitened(&w, 0.7);
    for r in 0..80 {
        assert!((p[(r, 0)] - rows[r / 4][r % 4]).abs() < 1e-12);
    }
}

#[test]
fn the_white_limit_is_at_serial_p() {
    // 2.326 sd above the mean at 1 %: the limit over 376 speeds is
    // about −4/376 + 2.326/√(4·376) (the pooled ρ̂'s sd for white noise).
    let limit = white_quantile(&speeds(376));
    let approx = -4.0 / 376.0 + 2.326 / (4.0f64 * 376.0).sqrt();
    assert!((limit - approx).abs() < 0.01, "{limit} against {approx}");
}

#[test]
fn the_widening_is_the_long_run_variance_of_a_mean() {
    // One parameter every speed carries alike (a mean): its variance
    // under an AR(1) is (1 + ρ)/(1 − ρ) times the white one for a long
    // run (less the ends' share: Σ_{t,s} ρ^|t−s| over n² pairs).
    let n = 400;
    let jac = DMatrix::from_element(4 * n, 1, 1.0);
    for rho in [0.0, 0.5, 0.8] {
        let f = ar1_widening(&jac, rho).expect("H regular")[0];
        let exact = ((1.0 + rho) / (1.0 - rho)
            - 2.0 * rho * (1.0 - rho.powi(n as i32)) / (n as f64 * (1.0 - rho).powi(2)))
        .sqrt();
        assert!((f - exact).abs() < 1e-9, "ρ {rho}: {f} against {exact}");
    }
    // A parameter one speed alone carries is not widened.
    let mut jac = DMatrix::zeros(4 * n, 1);
    jac[(4 * 200, 0)] = 1.0;
    assert!((ar1_widening(&jac, 0.8).expect("H regular")[0] - 1.0).abs() < 1e-12);
}

#[test]
fn prewhitened_ar1_residuals_are_white() {
    let s = speeds(376);
    let w = ar1(376, 0.8, 3);
    let (rho, _, _) = measured(&s, &w).expect("correlated");
    let white = prewhitened(&w, rho);
    assert!(lag_one_correlation(&s, &white).expect("measured").abs() < 0.1);
}

#[test]
fn the_long_run_covariance_of_white_scores_is_their_sum_of_squares() {
    // No correlation: the Bartlett bandwidth is small and the long-run
    // covariance near Σ g gᵀ.
    let mut rng = StdRng::seed_from_u64(9);
    let scores: Vec<DVector<f64>> = (0..500)
        .map(|_| DVector::from_fn(1, |_, _| StandardNormal.sample(&mut rng)))
        .collect();
    let (s, bandwidth) = long_run_covariance(&scores, 1);
    let plain: f64 = scores.iter().map(|g| g[0] * g[0]).sum();
    assert!(bandwidth < 5.0, "{bandwidth}");
    assert!(
        (s[(0, 0)] / plain - 1.0).abs() < 0.2,
        "{}",
        s[(0, 0)] / plain
    );
}
