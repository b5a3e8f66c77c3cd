//! The noise of a phasor, from the scatter between the revolutions it is
//! made of.
//!
//! # Model
//!
//! Each revolution's constant-D phasor D̃_j (per channel, converted to
//! displacement) is the true phasor plus a noise n_j. Noise that is white
//! over the samples (sensor and ADC noise) makes the n_j of different
//! revolutions independent (disjoint integration windows) and circular
//! (E n² = 0), with a variance σ² = E|n|² [m²] that changes slowly with the
//! speed (samples per revolution, the ÷Ω of a seismic pick-up).
//!
//! # The scatter, without the trend
//!
//! During a run-down the true D̃_j changes from revolution to revolution, and
//! that change is not noise. The extractor models it as a cubic in the
//! revolution number (see [`mid_revolution`]); the fourth difference
//! Δ⁴_j = D̃_{j+1} − 4D̃_j + 6D̃_{j−1} − 4D̃_{j−2} + D̃_{j−3} removes any cubic
//! exactly, so E|Δ⁴|² = (1 + 16 + 36 + 16 + 1)·σ² = 70σ² and |Δ⁴|²/70 is an
//! unbiased estimate of σ², one per revolution (the quartic remainder of a
//! phasor changing 2.5 % per revolution through a resonance is below 1e-6 of
//! it). Over the R revolutions of one output the mean of these is unbiased
//! whatever the overlap of their differences: that is the small-sample
//! correction (the differences spend the degrees of freedom of the trend;
//! there is no further n − 1). Just after the keyphasor was acquired, fewer
//! revolutions are known; the extractor then uses the last full estimate of
//! the channel (the noise does not change with a keyphasor fault), and before
//! any, the highest difference there is (which then includes some trend:
//! an over-estimate, never an under-estimate).
//!
//! # Pooled over revolutions
//!
//! One output's own few revolutions are far too few to weigh it by: the
//! mean of R overlapping |Δ⁴|²/70 has about 2R real degrees of freedom
//! (fewer, since neighbouring differences share four of their five
//! revolutions), so 1/σ̂², the weight a fit gives the phasor, is biased high
//! by k/(k − 2) (infinitely for R = 1) and a χ² of the whitened residuals
//! comes out 1.5 to 4 instead of 1. The noise of a channel changes slowly
//! with the speed, so [`NoisePool`] pools the per-revolution estimates of
//! the last [`POOLED_REVOLUTIONS`] revolutions (a running mean, then an
//! exponential one). Each is first divided by the speed law of white
//! sample noise ([`white_noise_law`]: the one-revolution coefficient of
//! white noise has a variance ∝ 1/samples per revolution ∝ f, divided by
//! Ω² per integration of a seismic channel) and the pool is multiplied back
//! at the output's speed, so that a run-down's changing speed is not
//! averaged into the estimate. Its ~30 effective complex degrees of
//! freedom leave 1/σ̂² a few percent high at most. The pool survives
//! keyphasor faults (the noise does not change with a missed pulse).
//!
//! Through a sharp, lightly damped resonance the response is not a cubic
//! over five revolutions, and for a few revolutions |Δ⁴|² is the trend's
//! quartic remainder, hundreds of times the noise: taken at face value it
//! would hold the pool up for a hundred revolutions after (measured on a
//! simulated run-down at 1 Hz/s: the noise-free ped columns reported 240×
//! their real error right after a mode, decaying over 15 Hz). So once the
//! pool has [`FOOTING`] estimates, one above [`OUTLIER`] times its level
//! enters at that level (winsorised): for noise, |Δ⁴|²/70 is about
//! exponentially distributed and exceeds 8× its mean with probability
//! e⁻⁸ = 3e-4 (the bias is 3e-3 of the mean), while a real rise of the
//! noise still lifts the pool by up to 11 % per revolution.
//!
//! # From revolutions to the output
//!
//! An output is the mean over R revolutions of [`mid_revolution`], a
//! widely linear combination of the revolution and its neighbours (j−2 …
//! j+1). Its noise is y = Σ_m (a_m·n_m + b_m·n̄_m) over the R + 3 revolutions
//! it touches, so E|y|² = G·σ² with the gain G = Σ_m (|a_m|² + |b_m|²)
//! ([`average_noise_gain`], ≈ 1/R for large R; the run-down correction's
//! differences make it larger for small R). The extractor reports
//! sd = sqrt(G·σ̂²): formats.md's sqrt(E|n|²) of the output's noise.
//!
//! # Consecutive outputs share revolutions
//!
//! Output k and k + 1 both contain the revolutions at their common border,
//! so their noises correlate. Summed over a long run the corrections are
//! differences and telescope: Σ_j mid_j = Σ_j D̃_j + (ends), so the long-run
//! variance per output is σ²/R, not G·σ². A fit whose rows change slowly
//! from output to output (a run-down) therefore has parameter variances
//! φ = (σ²/R)/(G·σ²) = 1/(R·G) times those computed as if the outputs were
//! independent with variance G·σ² ([`long_run_factor`]); φ < 1 means the
//! correlation between neighbours is negative on balance (the
//! corrections' differences), φ > 1 that it is positive.

use super::variation::mid_revolution;
use super::SensorKind;
use crate::phasor::Phasor;

const ZERO: Phasor = Phasor::new(0.0, 0.0);

/// Σc² of the k-th difference's binomial coefficients, k = 1 … 4.
const DIFFERENCE_SQUARES: [f32; 4] = [2.0, 6.0, 20.0, 70.0];

/// An estimate of one revolution's noise variance σ² [m²] from the
/// revolution (`this`), its successor (`next`) and up to three predecessors
/// (`earlier` = [j−3, j−2, j−1], each `None` unless contiguous with the
/// ones after it), and the order of the difference used (4 when all are
/// known: unbiased for a cubic trend).
pub fn revolution_variance(
    earlier: [Option<Phasor>; 3],
    this: Phasor,
    next: Phasor,
) -> (f32, usize) {
    // The contiguous run ending at `next`, oldest first.
    let mut run = [ZERO; 5];
    let mut len = 0;
    for e in earlier.iter().rev() {
        match e {
            Some(p) => {
                len += 1;
                run[3 - len] = *p;
            }
            None => break,
        }
    }
    run[3] = this;
    run[4] = next;
    let start = 3 - len;
    let order = len + 1;
    // The order-th difference of run[start..5] by repeated differencing.
    let mut d = run;
    for k in 0..order {
        for i in start..(4 - k) {
            d[i] = d[i + 1] - d[i];
        }
    }
    (d[start].norm_sqr() / DIFFERENCE_SQUARES[order - 1], order)
}

/// Revolutions over which [`NoisePool`] pools a channel's noise variance.
pub const POOLED_REVOLUTIONS: u16 = 64;

/// A per-revolution estimate above this many times the pooled level enters
/// the pool at this many times it (see the module documentation).
pub const OUTLIER: f32 = 8.0;

/// Estimates in the pool before it clips outliers.
const FOOTING: u16 = 8;

/// How the variance of one revolution's displacement phasor from white
/// sample noise scales with the speed `speed_hz` [Hz] for a `kind` channel,
/// up to a constant: f (the coefficient of N = f_s/f samples has variance
/// ∝ 1/N), divided by Ω² for a velocity and Ω⁴ for an acceleration
/// pick-up (converted to displacement). Positive for a positive speed.
pub fn white_noise_law(kind: SensorKind, speed_hz: f32) -> f32 {
    match kind {
        SensorKind::Displacement => speed_hz,
        SensorKind::Velocity => 1.0 / speed_hz,
        SensorKind::Acceleration => 1.0 / (speed_hz * speed_hz * speed_hz),
    }
}

/// Each channel's per-revolution noise variance, pooled over the last
/// [`POOLED_REVOLUTIONS`] revolutions in units of [`white_noise_law`] (see
/// the module documentation). Fixed size, allocation-free.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoisePool<const N: usize> {
    kinds: [SensorKind; N],
    /// Pooled σ²/law from fourth differences (unbiased for a cubic trend).
    level: [f32; N],
    /// How many went in, up to [`POOLED_REVOLUTIONS`].
    count: u16,
    /// The same from lower differences, used only while `count` is 0 (they
    /// include some trend: an over-estimate, never an under-estimate).
    rough: [f32; N],
    rough_count: u16,
}

impl<const N: usize> NoisePool<N> {
    /// An empty pool for channels of these kinds.
    pub fn new(kinds: [SensorKind; N]) -> Self {
        Self {
            kinds,
            level: [0.0; N],
            count: 0,
            rough: [0.0; N],
            rough_count: 0,
        }
    }

    /// Adds one revolution's variance estimates [m²] per channel
    /// ([`revolution_variance`], of difference order `order`) at the
    /// revolution's speed `speed_hz` [Hz]. Non-finite estimates (a
    /// non-finite speed or phasor) are ignored.
    pub fn add(&mut self, variance: &[f32; N], order: usize, speed_hz: f32) {
        let ok = variance.iter().all(|v| v.is_finite()) && speed_hz.is_finite() && speed_hz > 0.0;
        if !ok {
            return;
        }
        let (level, count) = if order >= 4 {
            (&mut self.level, &mut self.count)
        } else {
            (&mut self.rough, &mut self.rough_count)
        };
        // Winsorised once the pool has its footing: an estimate above
        // OUTLIER × the pool counts as OUTLIER × the pool.
        let clip = *count >= FOOTING;
        *count = (*count + 1).min(POOLED_REVOLUTIONS);
        let weight = 1.0 / f32::from(*count);
        for ((l, v), kind) in level.iter_mut().zip(variance).zip(&self.kinds) {
            let mut x = v / white_noise_law(*kind, speed_hz);
            if clip && x > OUTLIER * *l {
                x = OUTLIER * *l;
            }
            *l += (x - *l) * weight;
        }
    }

    /// One revolution's noise variance σ² [m²] of channel `channel` at
    /// `speed_hz` [Hz]; NaN before any estimate (or out of range).
    pub fn variance(&self, channel: usize, speed_hz: f32) -> f32 {
        let level = if self.count > 0 {
            self.level.get(channel)
        } else if self.rough_count > 0 {
            self.rough.get(channel)
        } else {
            None
        };
        match (level, self.kinds.get(channel)) {
            (Some(l), Some(kind)) => l * white_noise_law(*kind, speed_hz),
            _ => f32::NAN,
        }
    }
}

/// The noise gain G of an output averaging `revolutions` (R ≥ 1)
/// run-down-corrected revolutions of a `kind` channel: E|y|² = G·σ² for
/// independent circular per-revolution noise of variance σ² (see the module
/// documentation). Exact for the steady state (three revolutions of history),
/// O(1) work for any R.
#[inline(never)]
pub fn average_noise_gain(kind: SensorKind, revolutions: u16) -> f32 {
    let r = i32::from(revolutions.max(1));
    let inv = 1.0 / r as f32;
    // Revolutions m = −2 … R touch mids j ∈ [m − 1, m + 2] ∩ [0, R). An
    // inner m touches all four, whose weights on it add up to one (a
    // constant phasor is left alone): it adds (1/R)².
    let inner = (r - 3).max(0);
    let mut gain = inner as f32 * inv * inv;
    let units = [Phasor::new(1.0, 0.0), Phasor::new(0.0, 1.0)];
    for m in -2..=r {
        let (lo, hi) = ((m - 1).max(0), (m + 2).min(r - 1));
        if m > 0 && m + 2 < r {
            continue;
        }
        let mut y = [ZERO; 2];
        for (u, unit) in units.iter().enumerate() {
            let at = |n: i32| if n == m { *unit } else { ZERO };
            for j in lo..=hi {
                y[u] += mid_revolution(kind, [Some(at(j - 2)), Some(at(j - 1))], at(j), at(j + 1));
            }
            y[u] *= inv;
        }
        // y = a·n + b·n̄ at n = 1 and n = i: a = (y₁ − i·yᵢ)/2, b = (y₁ + i·yᵢ)/2.
        let iy = Phasor::new(-y[1].im, y[1].re);
        let a = (y[0] - iy) * 0.5;
        let b = (y[0] + iy) * 0.5;
        gain += a.norm_sqr() + b.norm_sqr();
    }
    gain
}

/// φ = 1/(R·G) for outputs of `revolutions` (R) revolutions with noise gain
/// `gain` (G, [`average_noise_gain`]): the long-run variance of consecutive
/// outputs per output, over the variance of one (see the module
/// documentation). Multiply the parameter variances of a fit that takes the
/// outputs as independent by φ.
pub fn long_run_factor(revolutions: u16, gain: f32) -> f32 {
    1.0 / (f32::from(revolutions.max(1)) * gain)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    const KINDS: [SensorKind; 3] = [
        SensorKind::Displacement,
        SensorKind::Velocity,
        SensorKind::Acceleration,
    ];

    #[test]
    fn a_cubic_trend_is_not_noise() {
        let cubic =
            |j: f32| Phasor::new(1.0 + 0.02 * j - 0.003 * j * j, -0.5 + 0.001 * j * j * j) * 1e-5;
        let (v, order) = revolution_variance(
            [Some(cubic(-3.0)), Some(cubic(-2.0)), Some(cubic(-1.0))],
            cubic(0.0),
            cubic(1.0),
        );
        assert_eq!(order, 4);
        assert!(v < 1e-22, "{v}");
        // Fewer revolutions: lower orders, counted from the newest.
        assert_eq!(
            revolution_variance([None, None, None], cubic(0.0), cubic(1.0)).1,
            1
        );
        assert_eq!(
            revolution_variance(
                [None, Some(cubic(-2.0)), Some(cubic(-1.0))],
                cubic(0.0),
                cubic(1.0)
            )
            .1,
            3
        );
        let line = |j: f32| Phasor::new(2.0 + j, 1.0 - 0.5 * j);
        let (v3, o3) = revolution_variance(
            [None, Some(line(-2.0)), Some(line(-1.0))],
            line(0.0),
            line(1.0),
        );
        assert_eq!(o3, 3);
        assert!(v3 < 1e-10);
    }

    #[test]
    fn differences_of_independent_noise_estimate_its_variance() {
        // Two alternating signs: Δ⁴ of (+1, −1, +1, −1, +1) is 16, |16|²/70.
        let s = |j: i32| Phasor::new(if j % 2 == 0 { 1.0 } else { -1.0 }, 0.0);
        let (v, _) = revolution_variance([Some(s(0)), Some(s(1)), Some(s(2))], s(3), s(4));
        assert!((v - 256.0 / 70.0).abs() < 1e-5, "{v}");
    }

    #[test]
    fn the_gain_falls_as_one_over_r_and_is_above_one_for_one_revolution() {
        for kind in KINDS {
            let g1 = average_noise_gain(kind, 1);
            // One revolution: the identity plus the correction's differences.
            assert!(g1 > 1.0 && g1 < 2.5, "{kind:?}: {g1}");
            for r in [4u16, 16, 256, 4096] {
                let g = average_noise_gain(kind, r);
                let rg = f32::from(r) * g;
                assert!(
                    rg > 0.9 && rg < 1.0 + 3.0 / f32::from(r),
                    "{kind:?} R={r}: R·G = {rg}"
                );
            }
            std::println!(
                "{kind:?}: G(1) = {g1:.3}, φ(1) = {:.3}, G(4) = {:.4}, φ(4) = {:.3}",
                long_run_factor(1, g1),
                average_noise_gain(kind, 4),
                long_run_factor(4, average_noise_gain(kind, 4))
            );
            let phi = long_run_factor(1, g1);
            assert!((phi * g1 - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn the_gain_is_the_variance_of_averaged_corrected_noise() {
        // Independent check: push many draws of unit circular noise through
        // the same mean of mid-revolution corrections and measure E|y|².
        let mut noise = crate::testing::Gauss(0x9e37_79b9_7f4a_7c15);
        let mut gauss = move || {
            let n = noise.complex(1.0);
            Phasor::new(n.re as f32, n.im as f32)
        };
        for kind in KINDS {
            for r in [1u16, 2, 4] {
                let draws = 20_000;
                let mut sum = 0.0f64;
                for _ in 0..draws {
                    let n: std::vec::Vec<Phasor> = (0..(r as usize + 3)).map(|_| gauss()).collect();
                    let mut y = ZERO;
                    for j in 0..r as usize {
                        y += mid_revolution(kind, [Some(n[j]), Some(n[j + 1])], n[j + 2], n[j + 3]);
                    }
                    y *= 1.0 / f32::from(r);
                    sum += f64::from(y.norm_sqr());
                }
                let measured = sum / draws as f64;
                let g = f64::from(average_noise_gain(kind, r));
                assert!(
                    (measured / g - 1.0).abs() < 0.04,
                    "{kind:?} R={r}: {measured} vs {g}"
                );
            }
        }
    }
}
