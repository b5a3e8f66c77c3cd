//! The mean test of [`super`]: is a fit's whitened residual mean over the
//! run beyond noise? Judged by negating blocks of speeds at random.
//!
//! Under the model the fitted residuals are r = (I − H)e with e noise
//! symmetric about zero, so their mean has no sign to prefer; a broad,
//! one-signed model error gives them one. The block shuffles of the scan
//! ([`super::structure`]) cannot see it: a mean is the same in every order
//! of the blocks, so the scan removes it. Negating each block of
//! [`BLOCK`] consecutive speeds with probability 1/2 keeps the short-range
//! correlation of rounding errors inside a block and any pattern of noise
//! level (the residuals are locally standardised first), and gives the
//! mean its null: the test is self-normalised (the block sums set the
//! spread), so it needs no noise level, which a scatter estimate would
//! inflate by the very error it is testing and the model's own χ² would
//! absorb. Its null is wider than the exact one (σ²·1ᵀ(I − H)1/n² ≤
//! σ²/n, which a block's negation cannot reproduce): conservative, never
//! liberal. A mean made by a few blocks (a narrow resonance's residue) is
//! as large in many negations and is left to the scan.

use super::structure::BLOCK;
use rand::{rngs::StdRng, Rng, SeedableRng};

/// Random negations of the mean test (its p-value resolution is
/// 1/([`NEGATIONS`]+1)): more than the scan's [`super::PERMUTATIONS`]
/// shuffles, since each costs one pass over the block sums only and the
/// structure test's p-value is twice the smaller of the two
/// (`super::structure`); stopped like the scan after
/// [`super::STOP_AFTER_EXCEEDANCES`] exceedances.
pub const NEGATIONS: usize = 9999;

/// The mean test's figures ([`mean_test`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct MeanTest {
    /// The run's mean across blocks, |S|² − Σ_b |B_b|² (S the sum of each
    /// component over the run, B_b over block b), in units of its spread
    /// for white residuals (n·level·√8, level the mean square) [-].
    pub statistic: f64,
    /// The same statistic's median over the negations made [-].
    pub null_median: f64,
    /// Share of the residuals' sum of squares the mean explains, |S|²/n
    /// over Σ|w|² [-].
    pub explained: f64,
    /// Share of negations scoring at least as high (Besag & Clifford, as
    /// the scan: [`super::STOP_AFTER_EXCEEDANCES`] of at most
    /// [`NEGATIONS`]) [-].
    pub p_value: f64,
}

/// Squared norm of a 4-vector.
fn square(v: &[f64; 4]) -> f64 {
    v.iter().map(|x| x * x).sum()
}

/// The mean test on locally standardised whitened residuals `w` (one real
/// 4-vector per speed, in speed order); `None` without a finite non-zero
/// sum of squares.
pub(super) fn mean_test(w: &[[f64; 4]]) -> Option<MeanTest> {
    let n = w.len();
    let total: f64 = w.iter().map(square).sum();
    if n == 0 || !(total > 0.0 && total.is_finite()) {
        return None;
    }
    let sums: Vec<[f64; 4]> = w
        .chunks(BLOCK)
        .map(|b| std::array::from_fn(|c| b.iter().map(|r| r[c]).sum()))
        .collect();
    let own: f64 = sums.iter().map(square).sum();
    let level = total / (4 * n) as f64;
    let unit = n as f64 * level * 8f64.sqrt();
    // |Σ s_b B_b|² over signs s_b = ±1 (bit b of `bits`); Σ_b |B_b|² is the
    // same under every negation, so |S|² alone orders them.
    let signed = |bits: &[u64]| -> f64 {
        let mut s = [0.0; 4];
        for (b, v) in sums.iter().enumerate() {
            let k = if bits[b / 64] >> (b % 64) & 1 == 1 {
                -1.0
            } else {
                1.0
            };
            for c in 0..4 {
                s[c] += k * v[c];
            }
        }
        square(&s)
    };
    let mut bits = vec![0u64; sums.len().div_ceil(64)];
    let observed = signed(&bits);
    let mut rng = StdRng::seed_from_u64(0x3ea7_51a9);
    let mut null = Vec::with_capacity(NEGATIONS);
    let mut above = 0;
    for _ in 0..NEGATIONS {
        for x in &mut bits {
            *x = rng.random();
        }
        let v = signed(&bits);
        null.push(v);
        if v >= observed {
            above += 1;
            if above == super::STOP_AFTER_EXCEEDANCES {
                break;
            }
        }
    }
    let done = null.len();
    let p_value = crate::estimate::monte_carlo::sequential_p_value(
        above,
        done,
        super::STOP_AFTER_EXCEEDANCES,
    );
    null.sort_by(f64::total_cmp);
    Some(MeanTest {
        statistic: (observed - own) / unit,
        null_median: (null[done / 2] - own) / unit,
        explained: observed / n as f64 / total,
        p_value,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_distr::StandardNormal;

    fn white(n: usize, seed: u64, offset: [f64; 4]) -> Vec<[f64; 4]> {
        let mut rng = StdRng::seed_from_u64(seed);
        (0..n)
            .map(|_| std::array::from_fn(|c| offset[c] + rng.sample::<f64, _>(StandardNormal)))
            .collect()
    }

    #[test]
    fn a_mean_is_found_and_noise_passes_at_its_rate() {
        // 400 runs of 70 speeds of white residuals: p < 0.01 about 4 times
        // (at most 10 here, a binomial tail of 0.3 %). A mean of 0.5 noise sd
        // on one of the four components (z = 0.5·√70 = 4.2 against the
        // exact null): measured 286/400 (2026-11-28) against negations of
        // 14 blocks, whose sums carry the mean too (self-normalised).
        let (mut clean, mut found) = (0, 0);
        for seed in 0..400 {
            let t = mean_test(&white(70, seed, [0.0; 4])).expect("residuals");
            clean += (t.p_value < 0.01) as usize;
            let t = mean_test(&white(70, 1000 + seed, [0.5, 0.0, 0.0, 0.0])).expect("residuals");
            found += (t.p_value < 0.01) as usize;
        }
        eprintln!("white: {clean}/400 below p = 0.01; mean 0.5 sd: {found}/400");
        assert!(clean <= 10, "{clean}/400 clean runs below p = 0.01");
        assert!(found >= 240, "a mean of 0.5 sd found in {found}/400");
    }
}
