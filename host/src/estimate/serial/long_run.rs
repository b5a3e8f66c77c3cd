//! The long-run (HAC) covariance of a series of scores: Bartlett weights,
//! Andrews' AR(1) plug-in bandwidth (diagnose's Wald tests,
//! [`crate::diagnose::criterion`]).

use nalgebra::{DMatrix, DVector};

/// The long-run (heteroskedasticity- and autocorrelation-robust) covariance
/// Σ_t g_t g_tᵀ + Σ_l w_l (Γ_l + Γ_lᵀ) of a series of `p`-vector scores
/// `scores` in speed order (zero mean at an estimate), Bartlett weights
/// w_l = 1 − l/(S + 1) with Andrews' AR(1) plug-in bandwidth S (speeds),
/// returned with S. In the scores' units squared.
pub fn long_run_covariance(scores: &[DVector<f64>], p: usize) -> (DMatrix<f64>, f64) {
    let bandwidth = andrews_bandwidth(scores);
    let mut s = DMatrix::zeros(p, p);
    for g in scores {
        s += g * g.transpose();
    }
    let lags = bandwidth.floor() as usize;
    for l in 1..=lags.min(scores.len().saturating_sub(1)) {
        let w = 1.0 - l as f64 / (bandwidth + 1.0);
        let mut gamma = DMatrix::zeros(p, p);
        for t in l..scores.len() {
            gamma += &scores[t] * scores[t - l].transpose();
        }
        s += (&gamma + gamma.transpose()) * w;
    }
    (s, bandwidth)
}

/// Andrews (1991) AR(1) plug-in bandwidth of the Bartlett kernel for a
/// vector score series: S = 1.1447·(α·T)^{1/3}, at most T − 1.
fn andrews_bandwidth(scores: &[DVector<f64>]) -> f64 {
    let t = scores.len();
    if t < 3 {
        return 0.0;
    }
    let p = scores[0].len();
    let (mut num, mut den) = (0.0, 0.0);
    for a in 0..p {
        let series: Vec<f64> = scores.iter().map(|g| g[a]).collect();
        let (mut s01, mut s00) = (0.0, 0.0);
        for w in series.windows(2) {
            s01 += w[1] * w[0];
            s00 += w[0] * w[0];
        }
        if s00 <= 0.0 {
            continue;
        }
        // Guard the AR(1) coefficient away from ±1 (the plug-in formula
        // divides by 1 − ρ); the bandwidth is capped at T − 1 anyway.
        let rho = (s01 / s00).clamp(-0.999, 0.999);
        let mut innov = 0.0;
        for w in series.windows(2) {
            let e = w[1] - rho * w[0];
            innov += e * e;
        }
        let sigma2 = innov / (t - 1) as f64;
        let s4 = sigma2 * sigma2;
        num += 4.0 * rho * rho * s4 / ((1.0 - rho).powi(6) * (1.0 + rho).powi(2));
        den += s4 / (1.0 - rho).powi(4);
    }
    if den <= 0.0 {
        return 0.0;
    }
    let alpha = num / den;
    (1.1447 * (alpha * t as f64).cbrt()).min((t - 1) as f64)
}
