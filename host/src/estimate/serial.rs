//! Noise correlated along the run: its measure, the long-run (HAC)
//! covariance of a series of scores, and the standard errors widened for it.
//!
//! **Why.** A fit weighs each speed's phasors by their own noise and takes
//! the noise of different speeds as independent ([`super::noise`]). A
//! tracking filter whose time constant is longer than the time between
//! stored vectors (a fine logging step on a fast run-down) makes the noise
//! of neighbouring speeds alike: along the run it is an AR(1) of lag-one
//! correlation ρ. A smooth parameter averages the noise over the run, and
//! the variance of a mean of an AR(1) is (1 + ρ)/(1 − ρ) times the white
//! one: at ρ = 0.8 the honest ± is three times the fit's own (measured on
//! ROSS unseen-eight `corr-noise`: RMS z 1.9-3.9, `ok` beyond 3 ± in 9 of
//! 23 runs, docs/unseen-eight.md finding 1).
//!
//! **Measure** ([`lag_one_correlation`]). The whitened residuals w_t (one
//! real 4-vector per speed, in speed order) are noise in units of its own
//! sd where the model fits. Each component is first cleared of a
//! Legendre polynomial of degree [`DETREND_DEGREE`] over the run (a broad
//! model error, smooth over the whole run, is not the noise's correlation),
//! then ρ̂ = Σ_t Σ_c w_{t,c}w_{t−1,c} / Σ_t Σ_c w_{t,c}² pooled over the four
//! components. It is taken as there when it exceeds the one-sided
//! [`SERIAL_P`] quantile of the same figure over white residuals of as
//! many speeds ([`white_quantile`]: simulated, a fixed seed, the
//! detrending included), so that a run of white noise keeps its ± exactly
//! in all but [`SERIAL_P`] of bearings. The detrending takes some of the
//! AR(1)'s low-frequency power with the trend, so ρ̂ is biased low (376
//! speeds at ρ = 0.80: 0.777 expected; 50 speeds: 0.59): the AR(1)'s ρ
//! the widening (and the delay's linearisation,
//! [`super::lack_of_fit::delay_unknown`]) use is the one whose expected ρ̂
//! is the measured one ([`ar1_rho`], the expectation in closed form to
//! second order, [`expected_lag_one`]); the lack-of-fit tests take ρ̂ as
//! it is (a local model error's residual is correlated too, and the
//! larger ρ would take it for noise).
//!
//! **Widening** ([`ar1_widening`]). With the noise an AR(1) of lag-one
//! correlation ρ along the run (the same for every whitened component, as
//! a filter common to the channels makes it), the fit's estimate has the
//! sandwich covariance H⁻¹MH⁻¹, H = Σ_t J_tᵀJ_t and M = Σ_t Σ_s ρ^|t−s|
//! J_tᵀJ_s (J_t speed t's whitened Jacobian): the long-run covariance of the
//! scores J_tᵀw_t under that AR(1), the parametric (prewhitened) form of
//! [`long_run_covariance`]. Each parameter's ± is widened by
//! √((H⁻¹MH⁻¹)_kk/(H⁻¹)_kk) ≥ 1. The form is chosen over the Bartlett
//! kernel of the scores themselves because it does not square residuals:
//! with 40-60 speeds (some machines) a kernel estimate of a long-run
//! variance is itself noisy, and the Bartlett kernel with Andrews'
//! bandwidth is biased low at ρ = 0.8 (docs/estimation-scatter.md, Session
//! 48).
//!
//! **The structure test** ([`prewhitened`]): the lack-of-fit scan's null
//! (blocks of speeds shuffled) keeps a correlation shorter than a block
//! only; a correlation of ρ = 0.8 lasts longer and the scan took it for a
//! smooth model error. Where ρ̂ is there, the scan is made on the residuals
//! prewhitened by it, (w_t − ρ̂w_{t−1})/√(1 − ρ̂²), white under the AR(1),
//! while a model error smooth in speed stays smooth (damped by the factor
//! √((1 − ρ̂)/(1 + ρ̂)) against the noise: what the correlation costs in
//! power).

use nalgebra::{DMatrix, DVector};
use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use statrs::distribution::ContinuousCDF;

/// One-sided size of the test "the residuals are correlated along the run"
/// [-]: a white run's ± are widened in this share of bearings.
pub const SERIAL_P: f64 = 0.01;

/// Degree of the Legendre polynomial over the run cleared from each
/// whitened component before its lag-one correlation is measured.
pub const DETREND_DEGREE: usize = 3;

/// White-noise draws that set [`white_quantile`].
pub const WHITE_DRAWS: usize = 400;

/// Fewest speeds on which a correlation is measured.
pub const MIN_SPEEDS: usize = 12;

/// Largest lag-one correlation used [-]: beyond it the residuals are a
/// trend, not noise, and (1 + ρ)/(1 − ρ) would be set by the trend.
pub const MAX_RHO: f64 = 0.95;

/// The residuals' correlation along the run as measured and used
/// (`identify --json`: `noise.<bearing>.serial_correlation`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SerialCorrelation {
    /// The lag-one correlation of the whitened residuals along the run
    /// (speed order, each component detrended) [-].
    pub lag_one: f64,
    /// Its one-sided [`SERIAL_P`] quantile for white residuals of as many
    /// speeds [-]: above it the correlation is taken as there.
    pub white_limit: f64,
    /// The AR(1)'s lag-one correlation that `lag_one` implies once the
    /// detrending's bias is removed ([`ar1_rho`]; at most [`MAX_RHO`]) [-]:
    /// what the widening and the lack-of-fit tests use.
    #[serde(default)]
    pub ar1_rho: f64,
    /// Speeds it was measured on.
    pub speeds: usize,
    /// Each parameter's ± widened by this factor (k_y, k_z, m, c_y, c_z; 1
    /// for a fixed one) [-]: √((1 + ρ)/(1 − ρ)) for a parameter the run
    /// averages, less for one a few speeds carry.
    pub widening: [f64; 5],
}

/// An orthonormal basis (columns) of the Legendre polynomials of degree
/// ≤ [`DETREND_DEGREE`] over the run at `speeds_hz` [Hz]: what
/// [`detrended`] clears from each component (one QR per set of speeds).
fn detrend_basis(speeds_hz: &[f64]) -> DMatrix<f64> {
    let n = speeds_hz.len();
    let lo = speeds_hz.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = speeds_hz.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let span = (hi - lo).max(f64::MIN_POSITIVE);
    let basis = DMatrix::from_fn(n, DETREND_DEGREE + 1, |i, d| {
        let x = 2.0 * (speeds_hz[i] - lo) / span - 1.0;
        // Legendre P_d by its recurrence.
        let (mut p0, mut p1) = (1.0, x);
        match d {
            0 => 1.0,
            1 => x,
            _ => {
                for k in 1..d {
                    let k = k as f64;
                    let p2 = ((2.0 * k + 1.0) * x * p1 - k * p0) / (k + 1.0);
                    p0 = p1;
                    p1 = p2;
                }
                p1
            }
        }
    });
    basis.qr().q()
}

/// Each component of `rows` (speed order) cleared of its least-squares
/// fit on the orthonormal basis `q` ([`detrend_basis`] of the run's speeds).
fn detrended(q: &DMatrix<f64>, rows: &[[f64; 4]]) -> Vec<[f64; 4]> {
    let n = rows.len();
    let mut out = rows.to_vec();
    for c in 0..4 {
        let y = DVector::from_iterator(n, rows.iter().map(|r| r[c]));
        let fit = q * (q.tr_mul(&y));
        for (o, f) in out.iter_mut().zip(fit.iter()) {
            o[c] -= f;
        }
    }
    out
}

/// The pooled lag-one correlation of `rows` (in speed order) [-].
fn pooled_lag_one(rows: &[[f64; 4]]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (t, r) in rows.iter().enumerate() {
        for c in 0..4 {
            den += r[c] * r[c];
            if t > 0 {
                num += r[c] * rows[t - 1][c];
            }
        }
    }
    if den > 0.0 {
        num / den
    } else {
        0.0
    }
}

/// The lag-one correlation along the run of whitened residual `rows` at
/// `speeds_hz` [Hz] (same order, ascending; module docs) [-]; `None` with
/// fewer than [`MIN_SPEEDS`] speeds, speeds not ascending or figures not
/// finite.
pub fn lag_one_correlation(speeds_hz: &[f64], rows: &[[f64; 4]]) -> Option<f64> {
    let n = rows.len();
    if n < MIN_SPEEDS
        || speeds_hz.len() != n
        || speeds_hz.windows(2).any(|s| s[1] < s[0])
        || rows.iter().flatten().any(|v| !v.is_finite())
    {
        return None;
    }
    let r = pooled_lag_one(&detrended(&detrend_basis(speeds_hz), rows));
    r.is_finite().then_some(r)
}

/// The one-sided 1 − [`SERIAL_P`] quantile of [`lag_one_correlation`] over
/// white unit residuals at `speeds_hz` [Hz] [-]: the mean plus z sd over
/// [`WHITE_DRAWS`] simulated runs, z the standard normal's 1 − [`SERIAL_P`]
/// quantile (2.326 at 1 %; a fixed seed; the pooled correlation of 4n
/// numbers is close to normal).
pub fn white_quantile(speeds_hz: &[f64]) -> f64 {
    let n = speeds_hz.len();
    let mut rng = StdRng::seed_from_u64(0x5e71_a1c0 ^ n as u64);
    let q = detrend_basis(speeds_hz);
    let draws: Vec<f64> = (0..WHITE_DRAWS)
        .map(|_| {
            let rows: Vec<[f64; 4]> = (0..n)
                .map(|_| std::array::from_fn(|_| StandardNormal.sample(&mut rng)))
                .collect();
            pooled_lag_one(&detrended(&q, &rows))
        })
        .collect();
    let mean = draws.iter().sum::<f64>() / draws.len() as f64;
    let var = draws.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (draws.len() - 1) as f64;
    let z = statrs::distribution::Normal::standard().inverse_cdf(1.0 - SERIAL_P);
    mean + z * var.sqrt()
}

/// The correlation of `rows` at `speeds_hz` when it is there (ρ̂ above its
/// white limit), as (the AR(1)'s ρ that ρ̂ implies, [`ar1_rho`], at most
/// [`MAX_RHO`]; ρ̂; the limit); `None` when it is not or cannot be
/// measured.
pub fn measured(speeds_hz: &[f64], rows: &[[f64; 4]]) -> Option<(f64, f64, f64)> {
    let rho = lag_one_correlation(speeds_hz, rows)?;
    let limit = white_quantile(speeds_hz);
    (rho > limit).then(|| (ar1_rho(speeds_hz, rho), rho, limit))
}

/// The expected [`lag_one_correlation`] [-] of an AR(1) noise of lag-one
/// correlation `rho` [-] (stationary, unit variance, the same in each of
/// the four components) at the speeds whose detrending basis is `q`
/// ([`detrend_basis`]): with e = Mw (M = I − QQᵀ, what the detrending
/// leaves), ρ̂ = a/b, a = Σ_c e_cᵀAe_c (A the lag-one pairs, ½ either side
/// of the diagonal) and b = Σ_c e_cᵀe_c; to second order (the delta method
/// of a ratio over the four independent components)
/// E[ρ̂] ≈ E a/E b − cov(a, b)/(E b)² + E a·var(b)/(E b)³, with
/// E a = 4 tr(MAMΣ), E b = 4 tr(MΣ), cov(a, b) = 8 tr(MAMΣMΣ),
/// var(b) = 8 tr((MΣ)²), Σ_ts = ρ^|t−s|. The detrending takes some of the
/// AR(1)'s low-frequency power with the trend, so E[ρ̂] < ρ (376 speeds:
/// 0.777 at ρ = 0.80; 50 speeds: 0.59; white: −4/n, the basis's share).
/// Σ is applied by its recursions (Σx = f + g − x, f_t = x_t + ρf_{t−1},
/// g_t = x_t + ρg_{t+1}): O(n²) per call; [`ar1_rho`] inverts it by regula
/// falsi in a handful of calls.
fn expected_lag_one(q: &DMatrix<f64>, mam: &DMatrix<f64>, rho: f64) -> f64 {
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
    let k = 4.0;
    e_a / e_b - cov_ab / (k * e_b * e_b) + e_a * var_b / (k * e_b.powi(3))
}

/// The lag-one correlation [-] of the AR(1) whose detrended residuals at
/// `speeds_hz` [Hz] are expected to show `observed` [-]
/// ([`lag_one_correlation`]): the root in [0, [`MAX_RHO`]] of
/// E[ρ̂](ρ) = `observed` ([`expected_lag_one`], increasing in ρ), by
/// regula falsi; 0 below E[ρ̂](0), [`MAX_RHO`] above E[ρ̂]([`MAX_RHO`]). The
/// measured ρ̂ is biased low by the detrending (ROSS unseen-eight
/// `corr-noise`, ρ = 0.80: ρ̂ 0.77 on average, the ± 5-8 % short,
/// docs/estimation-scatter.md, Session 49 (corr17b)); this removes it.
pub fn ar1_rho(speeds_hz: &[f64], observed: f64) -> f64 {
    let n = speeds_hz.len();
    if n < MIN_SPEEDS || !observed.is_finite() {
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
    let e = |rho: f64| expected_lag_one(&q, &mam, rho);
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

/// The largest factor by which an AR(1) noise of lag-one correlation
/// `rho` [-] along the run inflates the variance of a projection of the
/// residuals on a column smooth in speed, over the white noise's: its
/// spectrum at frequency zero, (1 + ρ)/(1 − ρ) [-].
pub fn long_run_factor(rho: f64) -> f64 {
    (1.0 + rho) / (1.0 - rho)
}

/// Upper-tail p-value of a fit's χ² = `chi2` on `dof` [-] when its
/// whitened residuals are an AR(1) of lag-one correlation `rho` along the
/// run [-]: the mean of χ² stays dof, its variance grows by
/// F = (1 + ρ²)/(1 − ρ²) (Σ_{t,s} ρ^{2|t−s|} per term), so χ²/F is taken
/// as χ²(dof/F) (Satterthwaite); `rho` 0 gives the plain χ²(dof) tail.
pub fn level_p(chi2: f64, dof: usize, rho: f64) -> f64 {
    let f = (1.0 + rho * rho) / (1.0 - rho * rho);
    statrs::distribution::ChiSquared::new(dof as f64 / f)
        .map(|d| 1.0 - statrs::distribution::ContinuousCDF::cdf(&d, chi2 / f))
        .unwrap_or(f64::NAN)
}

/// One whitened figure `x` of a speed prewhitened by the AR(1) of lag-one
/// correlation `rho` [-] given the same figure `previous` of the speed
/// before: (x − ρ·previous)/√(1 − ρ²).
fn prewhiten(x: f64, previous: f64, rho: f64) -> f64 {
    (x - rho * previous) / (1.0 - rho * rho).sqrt()
}

/// `rows` (speed order) prewhitened by the AR(1) of lag-one correlation
/// `rho` [-]: (w_t − ρw_{t−1})/√(1 − ρ²), the first row as it is.
pub fn prewhitened(rows: &[[f64; 4]], rho: f64) -> Vec<[f64; 4]> {
    rows.iter()
        .enumerate()
        .map(|(t, r)| {
            if t == 0 {
                *r
            } else {
                std::array::from_fn(|c| prewhiten(r[c], rows[t - 1][c], rho))
            }
        })
        .collect()
}

/// Whitened equations (4 rows per speed, speed order: a Jacobian or a
/// residual, any number of columns) prewhitened by the AR(1) of lag-one
/// correlation `rho` [-] as [`prewhitened`] does the residuals: each row
/// of speed t less ρ times the same row of speed t − 1, over √(1 − ρ²);
/// the first speed's rows as they are. A least-squares fit of the
/// prewhitened equations is the generalised one under the AR(1) (its ±
/// the AR(1)'s, its likelihood ratios the AR(1)'s).
pub fn prewhitened_equations(m: &DMatrix<f64>, rho: f64) -> DMatrix<f64> {
    let mut out = m.clone();
    for r in 4..m.nrows() {
        for c in 0..m.ncols() {
            out[(r, c)] = prewhiten(m[(r, c)], m[(r - 4, c)], rho);
        }
    }
    out
}

/// Per column of the whitened Jacobian `jac` (4 rows per speed, speed
/// order), the factor √((H⁻¹MH⁻¹)_kk/(H⁻¹)_kk) ≥ 1 by which its standard
/// error grows when the noise is an AR(1) of lag-one correlation `rho`
/// along the run (module docs) [-]; `None` when H is singular.
pub fn ar1_widening(jac: &DMatrix<f64>, rho: f64) -> Option<Vec<f64>> {
    let p = jac.ncols();
    let n = jac.nrows() / 4;
    let h = jac.tr_mul(jac);
    let inv = h.try_inverse()?;
    // F_t = J_t + ρF_{t−1}: Σ_{s ≤ t} ρ^{t−s}J_s; M = Σ_t (J_tᵀF_t + F_tᵀJ_t − J_tᵀJ_t).
    let mut f = DMatrix::<f64>::zeros(4, p);
    let mut m = DMatrix::<f64>::zeros(p, p);
    for t in 0..n {
        let jt = jac.rows(4 * t, 4);
        f = jt + f * rho;
        let cross = jt.tr_mul(&f);
        m += &cross + cross.transpose() - jt.tr_mul(&jt);
    }
    let v = &inv * m * &inv;
    (0..p)
        .map(|k| {
            let r = v[(k, k)] / inv[(k, k)];
            r.is_finite().then(|| r.max(1.0).sqrt())
        })
        .collect()
}

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

/// [`measured`] on the whitened residuals of the fit at `theta` (θ units)
/// to `obs` (speed order) over the estimated `columns` under `weighting`,
/// with the fit's whitened Jacobian: (ρ, ρ̂, its white limit, J); `None`
/// where the correlation is not there or cannot be measured.
pub fn measured_fit(
    obs: &[super::Observation],
    theta: &[f64; plinth_shared::regression::PARAMETERS],
    columns: &[plinth_shared::regression::Parameter],
    weighting: &super::ml::Weighting,
) -> Option<(f64, f64, f64, DMatrix<f64>)> {
    let (w, jac) = super::robust::whitened_jacobian(obs, theta, columns, weighting)?;
    let speeds: Vec<f64> = obs.iter().map(|o| o.speed_hz).collect();
    let rows: Vec<[f64; 4]> = (0..obs.len())
        .map(|t| std::array::from_fn(|c| w[4 * t + c]))
        .collect();
    let (rho, lag_one, white_limit) = measured(&speeds, &rows)?;
    Some((rho, lag_one, white_limit, jac))
}

/// The correlation along the run of the residuals of the fit at `theta`
/// (θ units) to `obs` (speed order) over the estimated `columns`, with an
/// equation error of variance `equation_var` [N²] (module docs): `None` when
/// it is not there (within its white limit), cannot be measured, or the
/// Jacobian fails; else its figures and the widening of each parameter's ±.
pub fn assess(
    obs: &[super::Observation],
    theta: &[f64; plinth_shared::regression::PARAMETERS],
    columns: &[plinth_shared::regression::Parameter],
    equation_var: f64,
) -> Option<SerialCorrelation> {
    let weighting = super::ml::Weighting::equation_error(equation_var);
    let (rho, lag_one, white_limit, jac) = measured_fit(obs, theta, columns, &weighting)?;
    let factors = ar1_widening(&jac, rho)?;
    let mut widening = [1.0; 5];
    for (&c, f) in columns.iter().zip(&factors) {
        widening[c as usize] = *f;
    }
    Some(SerialCorrelation {
        lag_one,
        white_limit,
        ar1_rho: rho,
        speeds: obs.len(),
        widening,
    })
}

impl SerialCorrelation {
    /// `covariance` (θ units squared) with each parameter's row and column
    /// scaled by its widening: the correlations kept.
    pub fn widen(&self, covariance: &mut [[f64; 5]; 5]) {
        for (i, row) in covariance.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v *= self.widening[i] * self.widening[j];
            }
        }
    }

    /// The largest widening over the parameters [-].
    pub fn largest_widening(&self) -> f64 {
        self.widening.iter().copied().fold(1.0, f64::max)
    }

    /// What identify says of it.
    pub fn message(&self) -> String {
        format!(
            "the noise is correlated along the run (lag-one ρ̂ = {:.2} of the whitened residuals over {} speeds, above {:.2}, its {} % limit for white noise; an AR(1) of ρ = {:.2} once the detrending's bias is removed): neighbouring speeds do not average out as independent ones, and the ± are widened ×{:.2} at most for it (the long-run covariance of an AR(1) noise along the run); the lack-of-fit tests allow for it (χ² on the degrees of freedom it leaves, the scan on the residuals prewhitened by it, the support-mode and sensor-delay scores deflated by (1 + ρ)/(1 − ρ))",
            self.lag_one,
            self.speeds,
            self.white_limit,
            100.0 * SERIAL_P,
            self.ar1_rho,
            self.largest_widening()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
