//! The normal equations of a tall least-squares problem, accumulated row
//! by row (dense, or over the columns an equation can have non-zero): the
//! cheap screen of many similar problems ([`super::solve`] stays the fit).

use nalgebra::DMatrix;

/// The normal equations AᵀA·θ = Aᵀb of a tall least-squares problem,
/// accumulated row by row without storing A: p² + p numbers however many
/// rows. Squaring A squares its condition number, so [`super::solve`] (an SVD of
/// A) stays the estimate a fit reports; this is the cheap screen of many
/// similar problems, solved only when the column-scaled A is well
/// conditioned ([`NormalEquations::solve`]).
#[derive(Clone, Debug, PartialEq)]
pub struct NormalEquations {
    p: usize,
    /// AᵀA, row-major p×p, its upper triangle (i ≤ j) only: the lower one
    /// would hold the same sums bit for bit (the same products in the same
    /// order), so [`NormalEquations::solve`] reads the upper one mirrored.
    ata: Vec<f64>,
    /// Aᵀb.
    atb: Vec<f64>,
    /// Rows added.
    rows: usize,
}

/// What [`NormalEquations::solve`] gives.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalSolution {
    /// The estimate θ.
    pub theta: Vec<f64>,
    /// (AᵀA)⁻¹, row-major p×p: σ² times it is θ's covariance.
    pub inverse: Vec<f64>,
    /// Condition number of A with unit-norm columns [-].
    pub condition_number: f64,
}

impl NormalEquations {
    /// Empty normal equations of `p` unknowns.
    pub fn new(p: usize) -> Self {
        Self {
            p,
            ata: vec![0.0; p * p],
            atb: vec![0.0; p],
            rows: 0,
        }
    }

    /// Adds one equation row·θ = rhs (`row` of length p).
    ///
    /// Every product is added, zeros included: a zero product leaves a sum
    /// as it is (the sums start at +0 and, in round-to-nearest, only
    /// −0 + −0 gives −0, so a sum is never −0), so the result is that of
    /// skipping a finite row's zero entries bit for bit, without a branch
    /// per entry. Only AᵀA's upper triangle is summed; five unknowns (eq.
    /// 4's) take a loop of fixed length.
    #[inline]
    pub fn add(&mut self, row: &[f64], rhs: f64) {
        if self.p == 5 {
            if let Some(row) = row.first_chunk::<5>() {
                if self.add_fixed(row, rhs) {
                    return;
                }
            }
        }
        let p = self.p;
        for (i, &ri) in row.iter().enumerate().take(p) {
            for (j, &rj) in row.iter().enumerate().take(p).skip(i) {
                self.ata[i * p + j] += ri * rj;
            }
            self.atb[i] += ri * rhs;
        }
        self.rows += 1;
    }

    /// [`NormalEquations::add`] of a row whose entries outside `nonzero`
    /// (positions, increasing) are +0 by construction (eq. 4's y and z
    /// equations: three of five): only the products that can be non-zero
    /// are added. Wherever AᵀA's diagonal stays finite (which
    /// [`NormalEquations::solve`] requires) every entry and product is
    /// finite, the skipped products are ±0, and the sums are those of
    /// [`NormalEquations::add`] bit for bit (a sum starts at +0 and is
    /// never −0: adding ±0 leaves it as it is).
    #[inline]
    pub fn add_sparse(&mut self, row: &[f64], nonzero: &[usize], rhs: f64) {
        let p = self.p;
        for (a, &i) in nonzero.iter().enumerate() {
            let ri = row[i];
            for &j in &nonzero[a..] {
                self.ata[i * p + j] += ri * row[j];
            }
            self.atb[i] += ri * rhs;
        }
        self.rows += 1;
    }

    /// [`NormalEquations::add_sparse`] of five unknowns with the `N`
    /// positions that can be non-zero known at compile time (eq. 4's y and
    /// z equations of the full model: the same products added to the same
    /// sums in the same order); false, adding nothing, when these equations
    /// do not have five unknowns.
    #[inline(always)]
    pub fn add_sparse_fixed<const N: usize>(
        &mut self,
        row: &[f64; 5],
        nonzero: [usize; N],
        rhs: f64,
    ) -> bool {
        if self.p != 5 {
            return false;
        }
        let (Some(ata), Some(atb)) = (
            self.ata.first_chunk_mut::<25>(),
            self.atb.first_chunk_mut::<5>(),
        ) else {
            return false;
        };
        for (a, &i) in nonzero.iter().enumerate() {
            let ri = row[i];
            for &j in &nonzero[a..] {
                ata[i * 5 + j] += ri * row[j];
            }
            atb[i] += ri * rhs;
        }
        self.rows += 1;
        true
    }

    /// [`NormalEquations::add`] with `P` unknowns known at compile time
    /// (the same products added to the same sums in the same order);
    /// false, adding nothing, when these equations do not have `P`.
    #[inline]
    fn add_fixed<const P: usize>(&mut self, row: &[f64; P], rhs: f64) -> bool {
        if self.p != P {
            return false;
        }
        let (Some(ata), Some(atb)) = (self.ata.get_mut(..P * P), self.atb.get_mut(..P)) else {
            return false;
        };
        for (i, (&ri, atb_i)) in row.iter().zip(atb).enumerate() {
            for (j, &rj) in row.iter().enumerate().skip(i) {
                ata[i * P + j] += ri * rj;
            }
            *atb_i += ri * rhs;
        }
        self.rows += 1;
        true
    }

    /// Entry (i, j) of AᵀA (from its upper triangle).
    fn ata(&self, i: usize, j: usize) -> f64 {
        self.ata[i.min(j) * self.p + i.max(j)]
    }

    /// Equations added.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// The least-squares solution when A has more rows than unknowns and
    /// its column-scaled condition number is at most `max_condition`
    /// (then θ carries about max_condition²·ε of relative error); `None`
    /// otherwise (rank deficient, ill conditioned or not finite: use
    /// [`super::solve`]).
    pub fn solve(&self, max_condition: f64) -> Option<NormalSolution> {
        let p = self.p;
        if p == 0 || self.rows <= p {
            return None;
        }
        let d: Vec<f64> = (0..p).map(|j| self.ata(j, j).sqrt()).collect();
        if !d.iter().all(|&x| x > 0.0 && x.is_finite()) {
            return None;
        }
        let m = DMatrix::from_fn(p, p, |i, j| self.ata(i, j) / (d[i] * d[j]));
        let eigen = m.clone().symmetric_eigenvalues();
        let lo = eigen.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = eigen.iter().copied().fold(0.0, f64::max);
        let condition_number = (hi / lo).sqrt();
        if !(lo > 0.0 && condition_number <= max_condition) {
            return None;
        }
        let inverse_scaled = m.cholesky()?.inverse();
        let inverse: Vec<f64> = (0..p * p)
            .map(|k| inverse_scaled[(k / p, k % p)] / (d[k / p] * d[k % p]))
            .collect();
        let theta: Vec<f64> = (0..p)
            .map(|i| (0..p).map(|j| inverse[i * p + j] * self.atb[j]).sum())
            .collect();
        theta
            .iter()
            .all(|t| t.is_finite())
            .then_some(NormalSolution {
                theta,
                inverse,
                condition_number,
            })
    }
}

#[cfg(test)]
mod tests {
    use super::super::solve;
    use super::*;
    use nalgebra::DVector;

    #[test]
    fn dense_sums_equal_the_sums_of_non_zero_products() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(17);
        for p in [3usize, 5] {
            let mut ne = NormalEquations::new(p);
            let (mut ata, mut atb) = (vec![0.0f64; p * p], vec![0.0f64; p]);
            for _ in 0..2000 {
                let row: Vec<f64> = (0..p)
                    .map(|_| match rng.random_range(0..4) {
                        0 => 0.0,
                        1 => -0.0,
                        2 => rng.random_range(-1e-300..1e-300),
                        _ => rng.random_range(-1e3..1e3),
                    })
                    .collect();
                let rhs =
                    rng.random_range(-1.0..1.0) * if rng.random_bool(0.2) { 0.0 } else { 1.0 };
                ne.add(&row, rhs);
                for i in (0..p).filter(|&i| row[i] != 0.0) {
                    for j in (i..p).filter(|&j| row[j] != 0.0) {
                        ata[i * p + j] += row[i] * row[j];
                    }
                    atb[i] += row[i] * rhs;
                }
            }
            for (a, b) in ne.ata.iter().zip(&ata).chain(ne.atb.iter().zip(&atb)) {
                assert_eq!(a.to_bits(), b.to_bits(), "p = {p}");
            }
        }
    }

    /// The sparse sums of eq. 4's rows (and, at five unknowns, those of the
    /// fixed positions) are the dense ones bit for bit: every
    /// equation mode, every subset of the five unknowns, ped phasors with
    /// +0, −0, tiny and ordinary parts.
    #[test]
    fn sparse_sums_of_eq4_rows_equal_the_dense_sums() {
        use plinth_shared::phasor::Complex;
        use plinth_shared::regression::{equations_for_mode, EquationMode};
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(29);
        let part = |rng: &mut rand::rngs::StdRng| match rng.random_range(0..5) {
            0 => 0.0,
            1 => -0.0,
            2 => rng.random_range(-1e-300..1e-300),
            _ => rng.random_range(-1e-6..1e-6),
        };
        for mode in [
            EquationMode::RealAndImag,
            EquationMode::RealPlusImag,
            EquationMode::Real,
            EquationMode::Imag,
        ] {
            for subset in 1u32..32 {
                let columns: Vec<usize> = (0..5).filter(|c| subset & (1 << c) != 0).collect();
                let p = columns.len();
                let positions = |params: [usize; 3]| -> Vec<usize> {
                    (0..p).filter(|&k| params.contains(&columns[k])).collect()
                };
                let (y, z) = (positions([0, 2, 3]), positions([1, 2, 4]));
                let (mut dense, mut sparse) = (NormalEquations::new(p), NormalEquations::new(p));
                let mut fixed = NormalEquations::new(p);
                for _ in 0..300 {
                    let mut c = || Complex::new(part(&mut rng), part(&mut rng));
                    let ped = [c(), c()];
                    let force = [c(), c()];
                    let omega = rng.random_range(1.0..2000.0);
                    let (eqs, n) = equations_for_mode(mode, omega, &ped, &force);
                    for (i, eq) in eqs[..n].iter().enumerate() {
                        let row: Vec<f64> = columns.iter().map(|&c| eq.row[c]).collect();
                        dense.add(&row, eq.rhs);
                        let nonzero = if i < n / 2 { &y } else { &z };
                        sparse.add_sparse(&row, nonzero, eq.rhs);
                        if let Ok(row) = <[f64; 5]>::try_from(row.as_slice()) {
                            let added = if i < n / 2 {
                                fixed.add_sparse_fixed(&row, [0, 2, 3], eq.rhs)
                            } else {
                                fixed.add_sparse_fixed(&row, [1, 2, 4], eq.rhs)
                            };
                            assert!(added);
                        }
                    }
                }
                let pairs = dense.ata.iter().zip(&sparse.ata);
                for (a, b) in pairs.chain(dense.atb.iter().zip(&sparse.atb)) {
                    assert_eq!(a.to_bits(), b.to_bits(), "{mode:?} {columns:?}");
                }
                assert_eq!(dense.rows(), sparse.rows());
                if p == 5 {
                    assert_eq!(y, [0, 2, 3]);
                    assert_eq!(z, [1, 2, 4]);
                    let pairs = dense.ata.iter().zip(&fixed.ata);
                    for (a, b) in pairs.chain(dense.atb.iter().zip(&fixed.atb)) {
                        assert_eq!(a.to_bits(), b.to_bits(), "{mode:?} fixed");
                    }
                    assert_eq!(dense.rows(), fixed.rows());
                }
            }
        }
    }

    #[test]
    fn normal_equations_agree_with_the_svd() {
        let n = 200;
        let rows: Vec<[f64; 3]> = (0..n)
            .map(|i| {
                let x = i as f64 / n as f64;
                [1.0, 1e6 * x, 1e-3 * (7.0 * x).sin()]
            })
            .collect();
        let b: Vec<f64> = (0..n)
            .map(|i| {
                2.0 - 3e-6 * rows[i][1] + 5e3 * rows[i][2] + 1e-3 * ((i * 37 % 11) as f64 - 5.0)
            })
            .collect();
        let a = DMatrix::from_fn(n, 3, |i, j| rows[i][j]);
        let svd = solve(&a, &DVector::from_vec(b.clone()));
        let mut ne = NormalEquations::new(3);
        for (r, &y) in rows.iter().zip(&b) {
            ne.add(r, y);
        }
        let s = ne.solve(1e4).unwrap();
        let sigma2 = svd.rss / (n - 3) as f64;
        for (j, (&t, &t_svd)) in s.theta.iter().zip(&svd.theta).enumerate() {
            assert!((t - t_svd).abs() <= 1e-10 * t_svd.abs(), "{j}");
            let se = (sigma2 * s.inverse[j * 3 + j]).sqrt();
            assert!((se - svd.std_err[j]).abs() <= 1e-9 * svd.std_err[j], "{j}");
        }
        assert!((s.condition_number - svd.condition_number).abs() < 1e-9 * svd.condition_number);
        let mut collinear = NormalEquations::new(2);
        for i in 0..10 {
            collinear.add(&[i as f64, 2.0 * i as f64], 1.0);
        }
        assert_eq!(collinear.solve(1e4), None);
    }
}
