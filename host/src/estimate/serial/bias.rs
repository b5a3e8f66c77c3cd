//! The AR(1)'s ρ whose detrended residuals show the measured ρ̂: the
//! detrending's bias removed ([`super`] module docs, "Measure").

use super::measure::detrend_basis;
use super::{MAX_RHO, MIN_SPEEDS};
use nalgebra::DMatrix;

/// The expected [`super::lag_one_correlation`] [-] of an AR(1) noise of lag-one
/// correlation `rho` [-] (stationary, unit variance, the same in each of
/// the `k` = `width` components, 4 for one bearing) at the speeds whose detrending basis is `q`
/// ([`detrend_basis`]): with e = Mw (M = I − QQᵀ, what the detrending
/// leaves), ρ̂ = a/b, a = Σ_c e_cᵀAe_c (A the lag-one pairs, ½ either side
/// of the diagonal) and b = Σ_c e_cᵀe_c; to second order (the delta method
/// of a ratio over the k independent components)
/// E[ρ̂] ≈ E a/E b − cov(a, b)/(E b)² + E a·var(b)/(E b)³, with
/// E a = k tr(MAMΣ), E b = k tr(MΣ), cov(a, b) = 2k tr(MAMΣMΣ),
/// var(b) = 2k tr((MΣ)²), Σ_ts = ρ^|t−s|. The detrending takes some of the
/// AR(1)'s low-frequency power with the trend, so E[ρ̂] < ρ (376 speeds:
/// 0.777 at ρ = 0.80; 50 speeds: 0.59; white: −4/n, the basis's share).
/// Σ is applied by its recursions (Σx = f + g − x, f_t = x_t + ρf_{t−1},
/// g_t = x_t + ρg_{t+1}): O(n²) per call; [`ar1_rho`] inverts it by regula
/// falsi in a handful of calls.
fn expected_lag_one(q: &DMatrix<f64>, mam: &DMatrix<f64>, rho: f64, width: usize) -> f64 {
    let n = q.nrows();
    // Σ applied to each column of x (n × k).
    let sigma = |x: &DMatrix<f64>| {
        let mut out = x.clone();
        for mut col in out.column_iter_mut() {
            let x: Vec<f64> = col.iter().copied().collect();
            let mut f = vec![0.0; n];
            let mut g = vec![0.0; n];
            for t in 0..n {
                f[t] = x[t] + if t > 0 { rho * f[t - 1] } else { 0.0 };
            }
            for t in (0..n).rev() {
                g[t] = x[t] + if t + 1 < n { rho * g[t + 1] } else { 0.0 };
            }
            for t in 0..n {
                col[t] = f[t] + g[t] - x[t];
            }
        }
        out
    };
    // MΣ = Σ − Q(ΣQ)ᵀ (Σ symmetric); (MAM)Σ = (Σ(MAM))ᵀ (both symmetric).
    let powers: Vec<f64> = (0..n).map(|d| rho.powi(d as i32)).collect();
    let s = DMatrix::from_fn(n, n, |i, j| powers[i.abs_diff(j)]);
    let sq = sigma(q);
    let ms = &s - q * sq.transpose();
    let p = sigma(mam).transpose();
    let e_a = p.trace();
    let e_b = ms.trace();
    let cov_ab = 2.0 * p.component_mul(&ms.transpose()).sum();
    let var_b = 2.0 * ms.component_mul(&ms.transpose()).sum();
    let k = width as f64;
    e_a / e_b - cov_ab / (k * e_b * e_b) + e_a * var_b / (k * e_b.powi(3))
}

/// The lag-one correlation [-] of the AR(1) whose detrended residuals at
/// `speeds_hz` [Hz] are expected to show `observed` [-]
/// ([`super::lag_one_correlation`]): the root in [0, [`MAX_RHO`]] of
/// E[ρ̂](ρ) = `observed` ([`expected_lag_one`], increasing in ρ), by
/// regula falsi; 0 below E[ρ̂](0), [`MAX_RHO`] above E[ρ̂]([`MAX_RHO`]). The
/// measured ρ̂ is biased low by the detrending (ROSS unseen-eight
/// `corr-noise`, ρ = 0.80: ρ̂ 0.77 on average, the ± 5-8 % short,
/// docs/estimation-scatter.md, Session 49 (corr17b)); this removes it.
pub fn ar1_rho(speeds_hz: &[f64], observed: f64) -> f64 {
    ar1_rho_of(speeds_hz, observed, 4)
}

/// [`ar1_rho`] of a ρ̂ pooled over `width` real components per speed
/// ([`super::lag_one_of`]) [-].
pub fn ar1_rho_of(speeds_hz: &[f64], observed: f64, width: usize) -> f64 {
    let n = speeds_hz.len();
    if n < MIN_SPEEDS || width == 0 || !observed.is_finite() {
        return observed.clamp(0.0, MAX_RHO);
    }
    let q = detrend_basis(speeds_hz);
    // MAM, with A the lag-one pairs (½ either side of the diagonal).
    let mut am = DMatrix::<f64>::zeros(n, n);
    for t in 0..n {
        if t > 0 {
            am[(t, t - 1)] = 0.5;
        }
        if t + 1 < n {
            am[(t, t + 1)] = 0.5;
        }
    }
    let am = &am - (&am * &q) * q.transpose();
    let mam = &am - &q * (q.tr_mul(&am));
    let e = |rho: f64| expected_lag_one(&q, &mam, rho, width);
    if observed <= e(0.0) {
        return 0.0;
    }
    if observed >= e(MAX_RHO) {
        return MAX_RHO;
    }
    // Regula falsi (Illinois) on the bracket [0, MAX_RHO]: E is smooth
    // and increasing, a handful of evaluations reach 1e-9.
    let (mut lo, mut hi) = (0.0, MAX_RHO);
    let (mut f_lo, mut f_hi) = (e(lo) - observed, e(hi) - observed);
    let mut side = 0;
    for _ in 0..40 {
        let mid = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        let f_mid = e(mid) - observed;
        if f_mid.abs() < 1e-9 || hi - lo < 1e-9 {
            return mid;
        }
        if f_mid < 0.0 {
            (lo, f_lo) = (mid, f_mid);
            if side == -1 {
                f_hi *= 0.5;
            }
            side = -1;
        } else {
            (hi, f_hi) = (mid, f_mid);
            if side == 1 {
                f_lo *= 0.5;
            }
            side = 1;
        }
    }
    0.5 * (lo + hi)
}
