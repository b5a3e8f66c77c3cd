//! The lag-one correlation of whitened residuals along the run and its
//! limit for white noise ([`super`] module docs, "Measure").
//!
//! The residuals come as rows, one per speed in speed order, of `width`
//! real components each (4 for one bearing: y and z, real and imaginary;
//! 4 per bearing for a group of several), stored flat, row after row.

use super::{DETREND_DEGREE, MIN_SPEEDS, SERIAL_P, WHITE_DRAWS};
use nalgebra::{DMatrix, DVector};
use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use statrs::distribution::ContinuousCDF;

/// An orthonormal basis (columns) of the Legendre polynomials of degree
/// ≤ [`DETREND_DEGREE`] over the run at `speeds_hz` [Hz]: what
/// [`detrended`] clears from each component (one QR per set of speeds).
pub(super) fn detrend_basis(speeds_hz: &[f64]) -> DMatrix<f64> {
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

/// Each component of `rows` (flat, `width` per speed, speed order) cleared
/// of its least-squares fit on the orthonormal basis `q` ([`detrend_basis`]
/// of the run's speeds).
fn detrended(q: &DMatrix<f64>, rows: &[f64], width: usize) -> Vec<f64> {
    let n = rows.len() / width;
    let mut out = rows.to_vec();
    for c in 0..width {
        let y = DVector::from_iterator(n, (0..n).map(|t| rows[width * t + c]));
        let fit = q * (q.tr_mul(&y));
        for (t, f) in fit.iter().enumerate() {
            out[width * t + c] -= f;
        }
    }
    out
}

/// The pooled lag-one correlation of `rows` (flat, `width` per speed,
/// speed order) [-].
fn pooled_lag_one(rows: &[f64], width: usize) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for t in 0..rows.len() / width {
        for c in 0..width {
            let v = rows[width * t + c];
            den += v * v;
            if t > 0 {
                num += v * rows[width * (t - 1) + c];
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
    lag_one_of(speeds_hz, rows.as_flattened(), 4)
}

/// [`lag_one_correlation`] of `rows` flat, `width` real components per
/// speed [-].
pub fn lag_one_of(speeds_hz: &[f64], rows: &[f64], width: usize) -> Option<f64> {
    let n = speeds_hz.len();
    if n < MIN_SPEEDS
        || width == 0
        || rows.len() != width * n
        || speeds_hz.windows(2).any(|s| s[1] < s[0])
        || rows.iter().any(|v| !v.is_finite())
    {
        return None;
    }
    let r = pooled_lag_one(&detrended(&detrend_basis(speeds_hz), rows, width), width);
    r.is_finite().then_some(r)
}

/// The one-sided 1 − [`SERIAL_P`] quantile of [`lag_one_correlation`] over
/// white unit residuals at `speeds_hz` [Hz] [-]: the mean plus z sd over
/// [`WHITE_DRAWS`] simulated runs, z the standard normal's 1 − [`SERIAL_P`]
/// quantile (2.326 at 1 %; a fixed seed; the pooled correlation of 4n
/// numbers is close to normal).
pub fn white_quantile(speeds_hz: &[f64]) -> f64 {
    white_quantile_of(speeds_hz, 4)
}

/// [`white_quantile`] for `width` real components per speed [-].
pub fn white_quantile_of(speeds_hz: &[f64], width: usize) -> f64 {
    let n = speeds_hz.len();
    let mut rng = StdRng::seed_from_u64(0x5e71_a1c0 ^ n as u64);
    let q = detrend_basis(speeds_hz);
    let draws: Vec<f64> = (0..WHITE_DRAWS)
        .map(|_| {
            let rows: Vec<f64> = (0..n * width)
                .map(|_| StandardNormal.sample(&mut rng))
                .collect();
            pooled_lag_one(&detrended(&q, &rows, width), width)
        })
        .collect();
    let mean = draws.iter().sum::<f64>() / draws.len() as f64;
    let var = draws.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (draws.len() - 1) as f64;
    let z = statrs::distribution::Normal::standard().inverse_cdf(1.0 - SERIAL_P);
    mean + z * var.sqrt()
}
