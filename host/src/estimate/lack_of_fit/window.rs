//! The windows of the structure test's scan ([`super::structure`]): runs
//! of consecutive speeds, each with an orthonormal basis of Legendre
//! polynomials in speed, and the sum of squares of the residuals that the
//! basis explains, scored so that windows of every size compare under
//! noise.

use super::structure::BLOCK;
use nalgebra::DMatrix;

/// Highest degree of the smooth residual basis (Legendre polynomials in
/// speed): enough for a resonance-shaped model error over a run-down.
pub const MAX_DEGREE: usize = 5;

/// Degree of the Legendre basis inside each local window of the scan: a
/// bump, a step or a sign change across a resonance.
pub const LOCAL_DEGREE: usize = 2;

/// Fewest speeds in a local window of the scan: three blocks of [`BLOCK`],
/// so that a shuffle can still break a trend inside it.
pub const MIN_WINDOW: usize = 3 * BLOCK;

/// Number of window widths of the scan besides the whole run: n/2, n/4, ...
/// n/2^[`SCALES`] speeds (none narrower than [`MIN_WINDOW`]).
pub const SCALES: usize = 5;

/// One window of the scan: consecutive speeds (in speed order) and an
/// orthonormal basis of Legendre polynomials over them.
pub(super) struct Window {
    /// The window's speeds: indices into the run in speed order.
    pub(super) range: std::ops::Range<usize>,
    /// Orthonormal columns: the Legendre polynomials over the window.
    pub(super) basis: DMatrix<f64>,
    /// The same basis row by row (speed by speed, `basis.ncols()` values
    /// each): what [`Window::explained_across`] reads once per shuffle.
    by_row: Vec<f64>,
    /// Highest degree of the basis.
    pub(super) degree: usize,
}

impl Window {
    pub(super) fn new(speeds_hz: &[f64], range: std::ops::Range<usize>, degree: usize) -> Self {
        let basis = legendre_basis(&speeds_hz[range.clone()], degree).qr().q();
        let by_row = basis.transpose().as_slice().to_vec();
        Self {
            range,
            basis,
            by_row,
            degree,
        }
    }

    /// Sum of squares of `w` (every speed, in speed order) that the basis
    /// explains, all four channels.
    pub(super) fn explained(&self, w: &[[f64; 4]]) -> f64 {
        let rows = &w[self.range.clone()];
        (0..self.basis.ncols())
            .map(|d| {
                let col = self.basis.column(d);
                let mut p = [0.0; 4];
                for (qd, r) in col.iter().zip(rows) {
                    for c in 0..4 {
                        p[c] += qd * r[c];
                    }
                }
                p.iter().map(|v| v * v).sum::<f64>()
            })
            .sum()
    }

    /// The part of [`Window::explained`] across blocks: the explained sum of
    /// squares less each block's own share (`ids`: the block of [`BLOCK`]
    /// speeds each speed came from). A block's own share moves with the
    /// block in a shuffle and is noise to the test (a block holding the peak
    /// of a model error scores alike wherever it lands); what a shuffle
    /// destroys, and a smooth curve has, is the agreement between
    /// neighbouring blocks. Zero on average for residuals without a trend.
    ///
    /// Every column of the basis in one pass over the rows (each column's
    /// sums in the same order as one column at a time: the same figures),
    /// so the rows and block ids are read once per window and shuffle.
    pub(super) fn explained_across(&self, w: &[[f64; 4]], ids: &[usize]) -> f64 {
        let rows = &w[self.range.clone()];
        let ids = &ids[self.range.clone()];
        // The number of columns as a constant: the sums stay in registers.
        // Windows are built with degree ≤ MAX_DEGREE (`windows`).
        match self.basis.ncols() {
            1 => across_here::<1>(&self.by_row, rows, ids),
            2 => across_here::<2>(&self.by_row, rows, ids),
            3 => across_here::<3>(&self.by_row, rows, ids),
            4 => across_here::<4>(&self.by_row, rows, ids),
            5 => across_here::<5>(&self.by_row, rows, ids),
            6 => across_here::<6>(&self.by_row, rows, ids),
            _ => f64::NAN,
        }
    }

    /// The sum across blocks `x` ([`Window::explained_across`]) in units of
    /// its spread for white residuals of mean square `level` (about
    /// level·√(2k) for k = 4·(degree + 1) explained components), so that
    /// windows of every size score alike under noise.
    pub(super) fn score_across(&self, x: f64, level: f64) -> f64 {
        let k = (4 * self.basis.ncols()) as f64;
        x / (level * (2.0 * k).sqrt())
    }

    /// The explained sum of squares `ss` in units of the mean square
    /// `level` as a normal score: Wilson–Hilferty's cube root of the χ²
    /// with 4·(degree + 1) degrees of freedom that white residuals of that
    /// level give, so that windows of every size score alike under noise.
    pub(super) fn score(&self, ss: f64, level: f64) -> f64 {
        let k = (4 * self.basis.ncols()) as f64;
        let v = 2.0 / (9.0 * k);
        ((ss / (level * k)).cbrt() - (1.0 - v)) / v.sqrt()
    }
}

/// [`across`] with the processor's 256-bit vectors where it has them
/// (AVX, detected when run): each channel's products and sums are the
/// same IEEE operations, four lanes at a time instead of two (no fused
/// multiply-add: `fma` is not enabled), so the figures are the same bit for
/// bit. This is the inner loop of every shuffle of the structure test.
fn across_here<const C: usize>(by_row: &[f64], rows: &[[f64; 4]], ids: &[usize]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the processor has AVX (checked just above), the only
        // requirement of a `target_feature(enable = "avx")` function.
        return unsafe { across_avx::<C>(by_row, rows, ids) };
    }
    across::<C>(by_row, rows, ids)
}

/// [`across`] compiled for AVX ([`across_here`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn across_avx<const C: usize>(by_row: &[f64], rows: &[[f64; 4]], ids: &[usize]) -> f64 {
    across::<C>(by_row, rows, ids)
}

/// [`Window::explained_across`] of the window's `rows` and block `ids`
/// over its basis of `C` columns stored row by row (`by_row`).
///
/// Each row's projections go into its block's sums only; a block's sums
/// are added to the window's when the block ends (the window's sums are
/// the sums of its blocks' sums): one accumulation per row and column
/// instead of two, at a rounding of the order of 1e-16 of the sums.
///
/// Block by block: a run of rows with one id is summed into sums of its
/// own that start at zero (held in registers), then added to the
/// window's. The same sums in the same order as adding each row to
/// running block sums reset at every change of id (the window's sums are
/// never −0, so the zero that reset added before the first block changed
/// nothing).
#[inline(always)]
fn across<const C: usize>(by_row: &[f64], rows: &[[f64; 4]], ids: &[usize]) -> f64 {
    let square = |v: &[f64; 4]| v.iter().map(|x| x * x).sum::<f64>();
    let n = rows.len().min(ids.len()).min(by_row.len() / C);
    let mut p = [[0.0; 4]; C];
    let mut own = [0.0; C];
    let mut start = 0;
    while start < n {
        let id = ids[start];
        let end = ids[start..n]
            .iter()
            .position(|&k| k != id)
            .map_or(n, |len| start + len);
        let mut b = [[0.0; 4]; C];
        for (q, r) in by_row[start * C..end * C]
            .chunks_exact(C)
            .zip(&rows[start..end])
        {
            for d in 0..C {
                let qd = q[d];
                for c in 0..4 {
                    b[d][c] += qd * r[c];
                }
            }
        }
        for d in 0..C {
            own[d] += square(&b[d]);
            for c in 0..4 {
                p[d][c] += b[d][c];
            }
        }
        start = end;
    }
    (0..C).map(|d| square(&p[d]) - own[d]).sum()
}

/// The windows of the scan over `n` speeds `speeds_hz` (in speed order):
/// the whole run with Legendre polynomials of degree ≤ [`MAX_DEGREE`] (at
/// most n/(2·[`BLOCK`]) − 1), then windows of n/2, n/4, ... speeds
/// ([`SCALES`] widths, none under [`MIN_WINDOW`]) overlapping by about
/// half, from the first speed to the last, each with degree ≤
/// [`LOCAL_DEGREE`].
pub(super) fn windows(speeds_hz: &[f64], scales: usize) -> Vec<Window> {
    let n = speeds_hz.len();
    let mut out = vec![Window::new(
        speeds_hz,
        0..n,
        MAX_DEGREE.min(n / (2 * BLOCK) - 1),
    )];
    for k in 1..=scales {
        let width = n >> k;
        if width < MIN_WINDOW {
            break;
        }
        // Starts spread evenly from the first speed to n − width, about
        // half a width apart.
        let gaps = ((n - width) as f64 / (width / 2) as f64).round().max(1.0) as usize;
        for j in 0..=gaps {
            let start = (j * (n - width) + gaps / 2) / gaps;
            out.push(Window::new(speeds_hz, start..start + width, LOCAL_DEGREE));
        }
    }
    out
}

/// Legendre polynomials P_0..P_degree of the speeds mapped onto [−1, 1],
/// one column each.
fn legendre_basis(speeds_hz: &[f64], degree: usize) -> DMatrix<f64> {
    let lo = speeds_hz.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = speeds_hz.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let span = (hi - lo).max(f64::MIN_POSITIVE);
    DMatrix::from_fn(speeds_hz.len(), degree + 1, |i, d| {
        let x = 2.0 * (speeds_hz[i] - lo) / span - 1.0;
        legendre(d, x)
    })
}

/// Legendre polynomial P_d(x) by the three-term recurrence.
fn legendre(d: usize, x: f64) -> f64 {
    let (mut p0, mut p1) = (1.0, x);
    if d == 0 {
        return p0;
    }
    for k in 1..d {
        let kf = k as f64;
        let p2 = ((2.0 * kf + 1.0) * x * p1 - kf * p0) / (kf + 1.0);
        p0 = p1;
        p1 = p2;
    }
    p1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legendre_recurrence_matches_closed_forms() {
        for x in [-1.0, -0.3, 0.0, 0.7, 1.0] {
            assert!((legendre(2, x) - 0.5 * (3.0 * x * x - 1.0)).abs() < 1e-12);
            assert!((legendre(3, x) - 0.5 * (5.0 * x * x * x - 3.0 * x)).abs() < 1e-12);
        }
    }

    /// [`across`] as it was first written: every row added to running
    /// block sums that are folded into the window's and reset at each
    /// change of id (the reference for the block-by-block loop).
    fn across_by_row<const C: usize>(by_row: &[f64], rows: &[[f64; 4]], ids: &[usize]) -> f64 {
        let square = |v: &[f64; 4]| v.iter().map(|x| x * x).sum::<f64>();
        let mut p = [[0.0; 4]; C];
        let mut b = [[0.0; 4]; C];
        let mut own = [0.0; C];
        let mut id = usize::MAX;
        for ((q, r), &k) in by_row.chunks_exact(C).zip(rows).zip(ids) {
            if k != id {
                for d in 0..C {
                    own[d] += square(&b[d]);
                    for c in 0..4 {
                        p[d][c] += b[d][c];
                    }
                    b[d] = [0.0; 4];
                }
                id = k;
            }
            for d in 0..C {
                for c in 0..4 {
                    b[d][c] += q[d] * r[c];
                }
            }
        }
        (0..C)
            .map(|d| {
                let own = own[d] + square(&b[d]);
                let total: [f64; 4] = std::array::from_fn(|c| p[d][c] + b[d][c]);
                square(&total) - own
            })
            .sum()
    }

    #[test]
    fn the_vector_loop_gives_the_same_sums_bit_for_bit() {
        // Pseudo-random rows and a window's basis; blocks of BLOCK speeds
        // in a shuffled order (and a last block cut short): `across_here`
        // (block by block, AVX where the processor has it) equals the
        // portable loop and the row-by-row reference exactly.
        let s: Vec<f64> = (0..203).map(|i| 5.0 + 0.37 * i as f64).collect();
        let mut x = 0.271_828_f64;
        let mut next = || {
            x = (x * 9_301.0 + 0.497_3) % 1.0;
            x - 0.5
        };
        let rows: Vec<[f64; 4]> = (0..203).map(|_| std::array::from_fn(|_| next())).collect();
        let ids: Vec<usize> = (0..203).map(|i| (i / BLOCK * 7) % 41).collect();
        for degree in 0..=MAX_DEGREE {
            let w = Window::new(&s, 10..188, degree);
            let (r, i) = (&rows[10..188], &ids[10..188]);
            let fast = match degree + 1 {
                1 => across_here::<1>(&w.by_row, r, i),
                2 => across_here::<2>(&w.by_row, r, i),
                3 => across_here::<3>(&w.by_row, r, i),
                4 => across_here::<4>(&w.by_row, r, i),
                5 => across_here::<5>(&w.by_row, r, i),
                _ => across_here::<6>(&w.by_row, r, i),
            };
            let portable = match degree + 1 {
                1 => across::<1>(&w.by_row, r, i),
                2 => across::<2>(&w.by_row, r, i),
                3 => across::<3>(&w.by_row, r, i),
                4 => across::<4>(&w.by_row, r, i),
                5 => across::<5>(&w.by_row, r, i),
                _ => across::<6>(&w.by_row, r, i),
            };
            let reference = match degree + 1 {
                1 => across_by_row::<1>(&w.by_row, r, i),
                2 => across_by_row::<2>(&w.by_row, r, i),
                3 => across_by_row::<3>(&w.by_row, r, i),
                4 => across_by_row::<4>(&w.by_row, r, i),
                5 => across_by_row::<5>(&w.by_row, r, i),
                _ => across_by_row::<6>(&w.by_row, r, i),
            };
            assert_eq!(fast.to_bits(), portable.to_bits(), "degree {degree}");
            assert_eq!(fast.to_bits(), reference.to_bits(), "degree {degree}");
            assert!(fast.is_finite());
        }
    }

    #[test]
    fn windows_cover_the_run_at_every_width() {
        let s: Vec<f64> = (0..70).map(|i| 5.0 + 2.5 * i as f64).collect();
        let w = windows(&s, SCALES);
        // The whole run (degree 5), 3 windows of 35 speeds, 8 of 17.
        assert_eq!(w[0].range, 0..70);
        assert_eq!(w[0].degree, MAX_DEGREE);
        let of = |len: usize| w.iter().filter(|x| x.range.len() == len).count();
        assert_eq!((of(35), of(17), w.len()), (3, 8, 12));
        for x in &w[1..] {
            assert_eq!(x.degree, LOCAL_DEGREE);
            assert!(x.range.end <= 70);
            // Orthonormal columns.
            let g = x.basis.tr_mul(&x.basis);
            assert!((g - DMatrix::identity(3, 3)).abs().max() < 1e-9);
        }
        // A width under MIN_WINDOW is not scanned; without scales only the
        // whole run.
        assert_eq!(windows(&s[..40], SCALES).len(), 1 + 3);
        assert_eq!(windows(&s, 0).len(), 1);
    }
}
