//! The whitening factor L of Σ = B·D·Bᵀ (Σ = L·Lᵀ) and the solve L⁻¹e,
//! made in buffers kept from one speed to the next instead of new matrices
//! per speed (the central-difference Jacobian of a base fit makes thousands
//! per iteration).
//!
//! The arithmetic is nalgebra's, operation for operation (its
//! `Matrix::cholesky` and `solve_lower_triangular`: the same products,
//! sums and divisions in the same order, no fused multiply-add), so every
//! number is the same to the last bit as with the matrices it replaces;
//! the unit tests check that bit for bit.

use nalgebra::{DMatrix, DVector};

/// Buffers of [`Workspace::factor`]: B·D, Bᵀ, Σ and its lower Cholesky
/// factor (column-major, upper triangle not read).
pub(super) struct Workspace {
    bd: DMatrix<f64>,
    bt: DMatrix<f64>,
    sigma: DMatrix<f64>,
    l: DMatrix<f64>,
}

impl Workspace {
    /// Empty buffers (sized on first use).
    pub(super) fn new() -> Self {
        Self {
            bd: DMatrix::zeros(0, 0),
            bt: DMatrix::zeros(0, 0),
            sigma: DMatrix::zeros(0, 0),
            l: DMatrix::zeros(0, 0),
        }
    }

    /// Factors Σ = B·D·Bᵀ for B = `b` and D = diag(`var`) (noise variance
    /// of each measured number, order of B's columns), regularised by 1e-12
    /// of its mean diagonal when singular, as `gauss_helmert::whitening`;
    /// false when Σ has no noise at all or cannot be factored.
    pub(super) fn factor(&mut self, b: &DMatrix<f64>, var: &[f64]) -> bool {
        let (r, c) = b.shape();
        if self.bd.shape() != (r, c) {
            self.bd = DMatrix::zeros(r, c);
            self.bt = DMatrix::zeros(c, r);
            self.sigma = DMatrix::zeros(r, r);
            self.l = DMatrix::zeros(r, r);
        }
        b.transpose_to(&mut self.bt);
        self.bd.copy_from(b);
        for (col, v) in var.iter().enumerate() {
            self.bd.column_mut(col).scale_mut(*v);
        }
        self.sigma.gemm(1.0, &self.bd, &self.bt, 0.0);
        let trace = self.sigma.trace();
        if !(trace > 0.0 && trace.is_finite()) {
            return false;
        }
        self.l.copy_from(&self.sigma);
        if cholesky_in_place(self.l.as_mut_slice(), r) {
            return true;
        }
        // Σ + 1e-12·(trace/n)·I, as nalgebra adds the identity scaled.
        let jitter = 1e-12 * trace / r as f64;
        for (k, (l, s)) in self.l.iter_mut().zip(self.sigma.iter()).enumerate() {
            *l = *s + if k % (r + 1) == 0 { jitter } else { 0.0 };
        }
        cholesky_in_place(self.l.as_mut_slice(), r)
    }

    /// e ← L⁻¹e with the factor of the last successful [`Workspace::factor`];
    /// false where L has a zero on its diagonal.
    pub(super) fn solve(&self, e: &mut DVector<f64>) -> bool {
        solve_lower_in_place(self.l.as_slice(), self.l.nrows(), e.as_mut_slice())
    }

    /// The last factor as a lower-triangular matrix (upper triangle zero).
    pub(super) fn lower(&self) -> DMatrix<f64> {
        let mut l = self.l.clone();
        l.fill_upper_triangle(0.0, 1);
        l
    }
}

/// In-place lower Cholesky factor of the n×n column-major `a`, nalgebra's
/// left-looking column algorithm (`Cholesky::new`); false where a pivot is
/// zero, negative or not a number.
fn cholesky_in_place(a: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        for k in 0..j {
            let factor = -a[k * n + j];
            let (left, right) = a.split_at_mut(j * n);
            let col_k = &left[k * n + j..k * n + n];
            for (y, x) in right[j..n].iter_mut().zip(col_k) {
                *y += factor * x;
            }
        }
        let diag = a[j * n + j];
        if diag.is_nan() || diag <= 0.0 {
            return false;
        }
        let denom = diag.sqrt();
        a[j * n + j] = denom;
        for y in &mut a[j * n + j + 1..j * n + n] {
            *y /= denom;
        }
    }
    true
}

/// b ← L⁻¹b for the n×n column-major lower-triangular `l`, nalgebra's
/// column-oriented forward substitution (`solve_lower_triangular_mut`);
/// false where a diagonal entry is zero.
fn solve_lower_in_place(l: &[f64], n: usize, b: &mut [f64]) -> bool {
    for i in 0..n {
        let diag = l[i * n + i];
        if diag == 0.0 {
            return false;
        }
        let coeff = b[i] / diag;
        b[i] = coeff;
        for (y, x) in b[i + 1..n].iter_mut().zip(&l[i * n + i + 1..i * n + n]) {
            *y += -coeff * x;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// nalgebra's own path (what `gauss_helmert::whitening` did before the
    /// workspace): B·D·Bᵀ, Cholesky, jitter when singular.
    fn reference(b: &DMatrix<f64>, var: &[f64]) -> Option<DMatrix<f64>> {
        let mut bd = b.clone();
        for (c, v) in var.iter().enumerate() {
            bd.column_mut(c).scale_mut(*v);
        }
        let sigma = bd * b.transpose();
        let n = sigma.nrows();
        let trace = sigma.trace();
        if !(trace > 0.0 && trace.is_finite()) {
            return None;
        }
        if let Some(c) = sigma.clone().cholesky() {
            return Some(c.l());
        }
        let jitter = DMatrix::identity(n, n) * (1e-12 * trace / n as f64);
        (sigma + jitter).cholesky().map(|c| c.l())
    }

    /// A reproducible pseudo-random number in [−1, 1).
    fn noise(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    fn bits(m: &[f64]) -> Vec<u64> {
        m.iter().map(|v| v.to_bits()).collect()
    }

    #[test]
    fn the_factor_and_the_solve_are_nalgebras_to_the_bit() {
        let mut state = 7;
        // Group sizes 1-4 (4n equations, 8n measured numbers), and a rank-
        // deficient B (its last rows a copy: the jitter path).
        for n in 1..=4 {
            for deficient in [false, true] {
                let (r, c) = (4 * n, 8 * n);
                let mut b = DMatrix::from_fn(r, c, |_, _| 1e6 * noise(&mut state));
                if deficient {
                    let first = b.row(0).into_owned();
                    b.set_row(r - 1, &first);
                }
                let var: Vec<f64> = (0..c).map(|_| 1e-20 * (1.5 + noise(&mut state))).collect();
                let want = reference(&b, &var).expect("reference factor");
                let mut ws = Workspace::new();
                assert!(ws.factor(&b, &var));
                assert_eq!(bits(ws.lower().as_slice()), bits(want.as_slice()), "n {n}");
                let e = DVector::from_fn(r, |_, _| 1e-3 * noise(&mut state));
                let want_w = want.solve_lower_triangular(&e).expect("reference solve");
                let mut w = e.clone();
                assert!(ws.solve(&mut w));
                assert_eq!(bits(w.as_slice()), bits(want_w.as_slice()), "n {n}");
            }
        }
    }

    #[test]
    fn no_noise_is_no_factor() {
        let b = DMatrix::from_element(4, 8, 1.0);
        assert!(!Workspace::new().factor(&b, &[0.0; 8]));
        assert!(reference(&b, &[0.0; 8]).is_none());
    }
}
