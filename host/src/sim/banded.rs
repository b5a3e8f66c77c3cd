//! Banded complex LU factorisation with partial pivoting (LAPACK `zgbtf2` /
//! `zgbtrs`), the solver behind the per-speed unbalance response.
//!
//! The machine's dynamic stiffness matrix is banded when the pedestal DOFs are
//! numbered next to their bearing node, so one factorisation costs
//! O(n·kl·(kl+ku)) instead of O(n³) for a dense LU.

use num_complex::Complex;

/// Complex f64.
pub type C64 = Complex<f64>;

/// Why a banded factorisation or solve failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BandError {
    /// A zero pivot: the matrix is singular (e.g. an unsupported rigid-body mode).
    #[error("singular matrix: zero pivot in column {column}")]
    Singular {
        /// Column (DOF index) of the zero pivot.
        column: usize,
    },
    /// A pivot beyond double precision's range: its squared magnitude
    /// (what partial pivoting compares) overflowed, i.e. a term of the
    /// matrix, or one made from it, is above about 1.3e154 (√f64::MAX).
    #[error("overflow: the pivot of column {column} is beyond double precision's range")]
    Overflow {
        /// Column (DOF index) of the pivot.
        column: usize,
    },
    /// A right-hand side of the wrong length.
    #[error("right-hand side has {got} rows, matrix has {expected}")]
    Dimension {
        /// Rows the matrix has.
        expected: usize,
        /// Rows the right-hand side has.
        got: usize,
    },
}

/// The storage layout of an n×n band matrix with `kl` sub- and `ku`
/// super-diagonals (LAPACK band storage with `kl` fill-in rows), without the
/// data: for arrays that share a [`BandMatrix`]'s layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BandShape {
    /// Order.
    pub n: usize,
    /// Sub-diagonals.
    pub kl: usize,
    /// Super-diagonals.
    pub ku: usize,
}

impl BandShape {
    /// Leading dimension of the storage (rows per column).
    pub fn ldab(&self) -> usize {
        2 * self.kl + self.ku + 1
    }

    /// Number of stored elements.
    pub fn len(&self) -> usize {
        self.ldab() * self.n
    }

    /// Whether the matrix is 0×0.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Storage index of element (r, c), or `None` outside the band.
    #[inline]
    pub fn index(&self, r: usize, c: usize) -> Option<usize> {
        if r >= self.n || c >= self.n || r > c + self.kl || c > r + self.ku {
            return None;
        }
        Some(c * self.ldab() + self.kl + self.ku + r - c)
    }
}

/// A square complex band matrix with `kl` sub- and `ku` super-diagonals, in
/// LAPACK band storage with `kl` extra rows for the fill-in of pivoting.
///
/// Element (r, c) lives at `data[c·ldab + kl + ku + r − c]`.
#[derive(Clone, Debug)]
pub struct BandMatrix {
    n: usize,
    kl: usize,
    ku: usize,
    ldab: usize,
    data: Vec<C64>,
    pivots: Vec<usize>,
    /// Per column of L: rows below the diagonal that hold multipliers.
    lower: Vec<u32>,
    /// Per column of U: its first nonzero row.
    upper_top: Vec<usize>,
    /// Reciprocals of U's diagonal (the pivots), so the back substitution
    /// multiplies instead of dividing.
    inv_pivot: Vec<C64>,
    factored: bool,
}

impl BandMatrix {
    /// A zero n×n band matrix with `kl` sub- and `ku` super-diagonals.
    pub fn zeros(n: usize, kl: usize, ku: usize) -> Self {
        let ldab = 2 * kl + ku + 1;
        Self {
            n,
            kl,
            ku,
            ldab,
            data: vec![C64::new(0.0, 0.0); ldab * n],
            pivots: vec![0; n],
            lower: Vec::new(),
            upper_top: Vec::new(),
            inv_pivot: Vec::new(),
            factored: false,
        }
    }

    /// Order of the matrix.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of sub-diagonals.
    pub fn kl(&self) -> usize {
        self.kl
    }

    /// Number of super-diagonals.
    pub fn ku(&self) -> usize {
        self.ku
    }

    /// Storage index of element (r, c), or `None` outside the band.
    #[inline]
    pub fn index(&self, r: usize, c: usize) -> Option<usize> {
        if r >= self.n || c >= self.n || r > c + self.kl || c > r + self.ku {
            return None;
        }
        Some(c * self.ldab + self.kl + self.ku + r - c)
    }

    /// The raw band storage (for assembling many matrices with one pattern).
    pub fn data_mut(&mut self) -> &mut [C64] {
        self.factored = false;
        &mut self.data
    }

    /// Element (r, c) (zero outside the band). Meaningless after `factor`.
    pub fn get(&self, r: usize, c: usize) -> C64 {
        self.index(r, c)
            .map_or(C64::new(0.0, 0.0), |i| self.data[i])
    }

    /// Adds `v` to element (r, c); returns false (and changes nothing) when
    /// (r, c) lies outside the band.
    #[inline]
    pub fn add(&mut self, r: usize, c: usize, v: C64) -> bool {
        match self.index(r, c) {
            Some(i) => {
                self.data[i] += v;
                self.factored = false;
                true
            }
            None => false,
        }
    }

    /// Sets every stored element, fill-in rows included, to zero.
    pub fn clear(&mut self) {
        self.data.fill(C64::new(0.0, 0.0));
        self.factored = false;
    }

    /// LU factorisation in place with partial pivoting (row interchanges),
    /// unblocked LAPACK `zgbtf2`. Only the structural nonzeros are worked
    /// on: each column's multipliers stop at its last nonzero row and each
    /// U column's back substitution starts at its first nonzero row (a
    /// shaft's Timoshenko band is 7 wide; only the pedestal nodes reach
    /// `kl`, `ku`), so the cost follows the actual profile, not the widest.
    pub fn factor(&mut self) -> Result<(), BandError> {
        let kl = self.kl;
        self.factor_with(|_, column| column[..kl].fill(C64::new(0.0, 0.0)))
    }

    /// [`BandMatrix::factor`] of a matrix whose columns are written by
    /// `column(c, storage)` just before the elimination first reaches
    /// column c (storage: the column's `ldab` stored elements, fill-in rows
    /// first, which `column` must set to zero). Writing each column while it
    /// is about to be used saves a pass over the whole band per solve.
    pub fn factor_with(
        &mut self,
        mut column: impl FnMut(usize, &mut [C64]),
    ) -> Result<(), BandError> {
        let (n, kl, ku, ldab) = (self.n, self.kl, self.ku, self.ldab);
        let kv = kl + ku;
        self.factored = false;
        let a = &mut self.data;
        // Columns are written (fill-in rows zero) as the elimination is
        // about to reach them: the first kv now, column j + kv at step j
        // (the fill-in of step j reaches column j + kv at most).
        let mut write = |a: &mut [C64], c: usize| {
            if c < n {
                column(c, &mut a[c * ldab..(c + 1) * ldab]);
            }
        };
        for c in 0..kv {
            write(a, c);
        }
        self.lower.clear();
        self.lower.resize(n, 0);
        self.upper_top.clear();
        self.upper_top.extend(0..n);
        self.inv_pivot.clear();
        self.inv_pivot.resize(n, C64::new(0.0, 0.0));
        let mut ju = 0usize;
        for j in 0..n {
            write(a, j + kv);
            let col = j * ldab;
            // The last nonzero below the diagonal (fill from earlier columns
            // included: column j is fully updated by now).
            let mut km = kl.min(n - 1 - j);
            while km > 0 && {
                let v = a[col + kv + km];
                v.re == 0.0 && v.im == 0.0
            } {
                km -= 1;
            }
            let mut jp = 0usize;
            let mut best = a[col + kv].norm_sqr();
            for i in 1..=km {
                let v = a[col + kv + i].norm_sqr();
                if v > best {
                    best = v;
                    jp = i;
                }
            }
            self.pivots[j] = j + jp;
            self.lower[j] = km as u32;
            if best == 0.0 {
                return Err(BandError::Singular { column: j });
            }
            if !best.is_finite() {
                return Err(BandError::Overflow { column: j });
            }
            ju = ju.max((j + ku + jp).min(n - 1));
            if jp != 0 {
                for c in j..=ju {
                    let base = c * ldab + kv;
                    a.swap(base + j - c, base + j + jp - c);
                }
            }
            let inv = C64::new(1.0, 0.0) / a[col + kv];
            self.inv_pivot[j] = inv;
            for i in 1..=km {
                a[col + kv + i] *= inv;
            }
            // Column j's multipliers and each later column as slices
            // (no index checks in the inner loop).
            let (left, right) = a.split_at_mut((j + 1) * ldab);
            let l = &left[col + kv + 1..=col + kv + km];
            for c in j + 1..=ju {
                let base = (c - j - 1) * ldab + kv + j - c;
                let t = right[base];
                if t.re == 0.0 && t.im == 0.0 {
                    continue;
                }
                if self.upper_top[c] == c {
                    self.upper_top[c] = j;
                }
                let target = &mut right[base + 1..=base + km];
                for (x, &li) in target.iter_mut().zip(l) {
                    *x -= li * t;
                }
            }
        }
        self.factored = true;
        Ok(())
    }

    /// Solves A·x = b in place after `factor` (LAPACK `zgbtrs`, no transpose).
    pub fn solve_in_place(&self, b: &mut [C64]) -> Result<(), BandError> {
        if b.len() != self.n {
            return Err(BandError::Dimension {
                expected: self.n,
                got: b.len(),
            });
        }
        debug_assert!(self.factored, "solve before factor");
        let (n, ldab) = (self.n, self.ldab);
        let kv = self.kl + self.ku;
        let a = &self.data;
        // L: forward elimination with the row interchanges.
        for j in 0..n.saturating_sub(1) {
            let lm = self.lower[j] as usize;
            let p = self.pivots[j];
            if p != j {
                b.swap(p, j);
            }
            let bj = b[j];
            if bj.re == 0.0 && bj.im == 0.0 {
                continue;
            }
            let col = j * ldab + kv;
            for (bi, &l) in b[j + 1..=j + lm].iter_mut().zip(&a[col + 1..=col + lm]) {
                *bi -= l * bj;
            }
        }
        // U: back substitution, from each column's first nonzero row.
        for j in (0..n).rev() {
            let col = j * ldab + kv;
            b[j] *= self.inv_pivot[j];
            let bj = b[j];
            if bj.re == 0.0 && bj.im == 0.0 {
                continue;
            }
            let top = self.upper_top[j];
            let (head, _) = b.split_at_mut(j);
            for (bi, &u) in head[top..].iter_mut().zip(&a[col + top - j..col]) {
                *bi -= u * bj;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    }

    #[test]
    fn matches_dense_solve_with_pivoting() {
        let mut s = 7u64;
        for &(n, kl, ku) in &[(1, 0, 0), (5, 1, 2), (30, 4, 3), (40, 9, 9), (12, 0, 5)] {
            let mut band = BandMatrix::zeros(n, kl, ku);
            let mut dense = DMatrix::<C64>::zeros(n, n);
            for r in 0..n {
                for c in 0..n {
                    if r <= c + kl && c <= r + ku {
                        // Small diagonal forces row interchanges.
                        let v =
                            C64::new(lcg(&mut s), lcg(&mut s)) * if r == c { 0.01 } else { 1.0 };
                        assert!(band.add(r, c, v));
                        dense[(r, c)] = v;
                    }
                }
            }
            let b: Vec<C64> = (0..n).map(|_| C64::new(lcg(&mut s), lcg(&mut s))).collect();
            let expected = dense
                .clone()
                .lu()
                .solve(&DVector::from_vec(b.clone()))
                .unwrap();
            band.factor().unwrap();
            let mut x = b.clone();
            band.solve_in_place(&mut x).unwrap();
            for i in 0..n {
                assert!(
                    (x[i] - expected[i]).norm() <= 1e-9 * (1.0 + expected[i].norm()),
                    "n={n} i={i}"
                );
            }
        }
    }

    #[test]
    fn singular_matrix_is_reported() {
        let mut band = BandMatrix::zeros(3, 1, 1);
        band.add(0, 0, C64::new(1.0, 0.0));
        band.add(2, 2, C64::new(1.0, 0.0));
        assert_eq!(band.factor(), Err(BandError::Singular { column: 1 }));
        // A term whose square overflows is named as such, not as a zero.
        let mut band = BandMatrix::zeros(2, 1, 1);
        band.add(0, 0, C64::new(1.0, 0.0));
        band.add(1, 1, C64::new(1e300, 0.0));
        assert_eq!(band.factor(), Err(BandError::Overflow { column: 1 }));
        let mut band = BandMatrix::zeros(2, 1, 1);
        band.add(0, 0, C64::new(1.0, 0.0));
        band.add(1, 1, C64::new(1e150, 0.0));
        assert!(band.factor().is_ok(), "below √f64::MAX it is solved");
    }

    #[test]
    fn out_of_band_add_is_refused() {
        let mut band = BandMatrix::zeros(4, 1, 1);
        assert!(!band.add(0, 3, C64::new(1.0, 0.0)));
        assert!(band.add(1, 0, C64::new(1.0, 0.0)));
    }
}
