//! Readings against the quadratic through their neighbouring speeds: the
//! jumps that confirm an outlier speed ([`jump_speeds`]), and the channel
//! weights of the flip tests ([`super::flips`]). A model-free check on the
//! phasors themselves: the response is smooth in speed, a bad reading jumps.

use super::flips::{chi2_8, readings, Reading, FLIP_WINDOW};
use super::{local_scales, Observation, OUTLIER_FAMILY_RATE};
use nalgebra::DMatrix;
use num_complex::Complex;
use statrs::distribution::ContinuousCDF;

/// Speeds on each side a flip test predicts from.
pub const FLIP_NEIGHBOURS: usize = 3;

/// Speeds [Hz] at which a bearing's readings `obs` (any order) jump away
/// from the quadratic through their neighbouring speeds by more than the
/// noise allows: a(i) ([`super::keyphasor_flips`]) beyond the χ²(8) quantile at
/// [`OUTLIER_FAMILY_RATE`]/n. A model-free check on the phasors themselves:
/// a bad reading jumps, while a noise level the noise model's pattern misses
/// or a model error (both smooth in speed) does not.
pub fn jump_speeds(obs: &[Observation]) -> Vec<f64> {
    let s = readings(obs);
    let n = s.len();
    if n < FLIP_NEIGHBOURS + 1 {
        return Vec::new();
    }
    let limit = chi2_8().inverse_cdf(1.0 - OUTLIER_FAMILY_RATE / n as f64);
    let near: Vec<Vec<usize>> = (0..n).map(|i| neighbours(n, i)).collect();
    let negated = vec![false; n];
    let scale = channel_scales(&s, &near, &negated);
    (0..n)
        .filter(|&j| smoothness(&s, &near, &negated, &scale, j).is_some_and(|a| a > limit))
        .map(|j| s[j].speed_hz)
        .collect()
}

/// Per speed and channel, the local scale of |q−p|² [m²] (noise and
/// interpolation error, [`local_scales`] over [`FLIP_WINDOW`]) with the
/// speeds in `negated` negated.
fn channel_scales(s: &[Reading], near: &[Vec<usize>], negated: &[bool]) -> Vec<[f64; 4]> {
    let n = s.len();
    let errors: Vec<Option<[f64; 4]>> = (0..n)
        .map(|i| prediction_errors(s, &near[i], negated, i))
        .collect();
    let per_channel: [Vec<f64>; 4] = std::array::from_fn(|c| {
        let e: Vec<f64> = errors
            .iter()
            .map(|e| e.map_or(f64::NAN, |e| e[c]))
            .collect();
        local_scales(&e, std::f64::consts::LN_2, FLIP_WINDOW)
    });
    (0..n)
        .map(|i| std::array::from_fn(|c| per_channel[c][i].max(f64::MIN_POSITIVE)))
        .collect()
}

/// a(j) = Σ_c 2|q−p|²/scale_c of speed `j` against its neighbours `near[j]`
/// (about χ²(8) for a good reading) [-], the speeds in `negated` negated.
fn smoothness(
    s: &[Reading],
    near: &[Vec<usize>],
    negated: &[bool],
    scale: &[[f64; 4]],
    j: usize,
) -> Option<f64> {
    let e = prediction_errors(s, &near[j], negated, j)?;
    let a: f64 = (0..4).map(|c| 2.0 * e[c] / scale[j][c]).sum();
    a.is_finite().then_some(a)
}

/// The [`FLIP_NEIGHBOURS`]·2 speeds nearest to speed `i` of `n` by index
/// (both sides where there are), ascending distance.
pub(super) fn neighbours(n: usize, i: usize) -> Vec<usize> {
    // Outward from i, the lower index first at each distance: the order of
    // a sort by (distance, index), in O(FLIP_NEIGHBOURS) instead of O(n log n).
    let mut near = Vec::with_capacity(2 * FLIP_NEIGHBOURS);
    let mut d = 1;
    while near.len() < 2 * FLIP_NEIGHBOURS && (d <= i || i + d < n) {
        if d <= i {
            near.push(i - d);
        }
        if i + d < n && near.len() < 2 * FLIP_NEIGHBOURS {
            near.push(i + d);
        }
        d += 1;
    }
    near
}

/// |q−p|² per channel [m²] of speed `i` against the quadratic (prediction
/// p) through the speeds `near` ([`neighbours`]), with the speeds in
/// `negated` negated; `None` when it cannot be formed.
pub(super) fn prediction_errors(
    s: &[Reading],
    near: &[usize],
    negated: &[bool],
    i: usize,
) -> Option<[f64; 4]> {
    if near.len() < 4 {
        return None;
    }
    let sign = |j: usize| if negated[j] { -1.0 } else { 1.0 };
    let x0 = s[i].speed_hz;
    let span = near
        .iter()
        .map(|&j| (s[j].speed_hz - x0).abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let a = DMatrix::from_fn(near.len(), 3, |r, c| {
        ((s[near[r]].speed_hz - x0) / span).powi(c as i32)
    });
    // The prediction at x0 is gᵀy with g the first row of (AᵀA)⁻¹Aᵀ.
    let ata = (a.transpose() * &a).try_inverse()?;
    let g = (ata.row(0) * a.transpose()).transpose();
    Some(std::array::from_fn(|ch| {
        let p: Complex<f64> = near
            .iter()
            .zip(g.iter())
            .map(|(&j, &gj)| s[j].q[ch] * (gj * sign(j)))
            .sum();
        (s[i].q[ch] * sign(i) - p).norm_sqr()
    }))
}
