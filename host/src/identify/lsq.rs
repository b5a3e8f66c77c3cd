//! Column-scaled linear least squares by singular value decomposition, with
//! the statistics an identification needs to say how far to trust itself.

use nalgebra::{DMatrix, DVector};

/// The solution of min ‖A·θ − b‖₂ and what the data say about it.
#[derive(Clone, Debug, PartialEq)]
pub struct LeastSquares {
    /// The estimate θ (minimum-norm in the scaled unknowns when rank deficient).
    pub theta: Vec<f64>,
    /// Standard errors sqrt(σ²·diag((AᵀA)⁻¹)) with σ² = RSS/(n − p);
    /// infinite when not estimable (rank deficient, or n ≤ p).
    pub std_err: Vec<f64>,
    /// Covariance σ²·(AᵀA)⁻¹ of θ (row-major, p×p); empty when not
    /// estimable (as `std_err` is infinite).
    pub covariance: Vec<f64>,
    /// Residual sum of squares ‖A·θ − b‖² [b unit²].
    pub rss: f64,
    /// Number of equations n.
    pub equations: usize,
    /// Condition number σ_max/σ_min of A with unit-norm columns; infinite
    /// when rank deficient.
    pub condition_number: f64,
    /// Numerical rank of the column-scaled A.
    pub rank: usize,
    /// The right singular vector of the smallest singular value, in the
    /// column-scaled unknowns and normalised: the direction in parameter space
    /// the data determine worst (which parameters are confounded).
    pub weakest_direction: Vec<f64>,
    /// Per unknown, the squared length of its share of the numerical null
    /// space (Σ over singular values counted as zero of V_ij², in [0, 1]):
    /// near 1 for an unknown the data say nothing about, 0 for a fully
    /// determined one. All zero when the rank is full.
    pub undetermined: Vec<f64>,
}

impl LeastSquares {
    /// The covariance over all five pedestal parameters when `columns` are
    /// the estimated ones, in θ order (zero for fixed parameters); `None`
    /// when not estimable or not finite.
    pub fn covariance_of(
        &self,
        columns: &[plinth_shared::regression::Parameter],
    ) -> Option<[[f64; 5]; 5]> {
        let p = columns.len();
        if self.covariance.len() != p * p || !self.covariance.iter().all(|c| c.is_finite()) {
            return None;
        }
        let mut out = [[0.0; 5]; 5];
        for (a, &ca) in columns.iter().enumerate() {
            for (b, &cb) in columns.iter().enumerate() {
                out[ca as usize][cb as usize] = self.covariance[a * p + b];
            }
        }
        Some(out)
    }

    /// Root-mean-square residual sqrt(RSS/n) [b unit].
    pub fn residual_rms(&self) -> f64 {
        if self.equations == 0 {
            f64::NAN
        } else {
            (self.rss / self.equations as f64).sqrt()
        }
    }
}

/// Solves min ‖A·θ − b‖₂ for an n×p matrix A (n rows of p coefficients) in
/// f64. The columns are first scaled to unit Euclidean norm so that the
/// condition number and the rank test measure the data, not the units.
/// Singular values below max(n, p)·ε·σ_max count as zero.
pub fn solve(a: &DMatrix<f64>, b: &DVector<f64>) -> LeastSquares {
    let (n, p) = a.shape();
    let norms: Vec<f64> = (0..p).map(|j| a.column(j).norm()).collect();
    let mut scaled = a.clone();
    for (j, &s) in norms.iter().enumerate() {
        if s > 0.0 && s.is_finite() {
            scaled.column_mut(j).unscale_mut(s);
        }
    }
    let svd = scaled.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u.as_ref(), svd.v_t.as_ref()) else {
        // nalgebra always returns U and Vᵀ when asked; stay total anyway.
        return degenerate(n, p);
    };
    let sv = &svd.singular_values;
    let s_max = sv.iter().copied().fold(0.0, f64::max);
    let tol = (n.max(p) as f64) * f64::EPSILON * s_max;
    let rank = sv.iter().filter(|&&s| s > tol).count();

    // θ_scaled = Σ_j v_j (u_jᵀ b) / σ_j over the retained singular values.
    let mut theta_scaled = DVector::<f64>::zeros(p);
    for (j, &s) in sv.iter().enumerate() {
        if s > tol {
            let coef = u.column(j).dot(b) / s;
            theta_scaled += v_t.row(j).transpose() * coef;
        }
    }
    let theta: Vec<f64> = (0..p)
        .map(|i| {
            if norms[i] > 0.0 {
                theta_scaled[i] / norms[i]
            } else {
                0.0
            }
        })
        .collect();
    let theta_v = DVector::from_column_slice(&theta);
    let residual = a * &theta_v - b;
    let rss = residual.norm_squared();

    // The singular values come out of nalgebra unordered in general.
    let (j_min, s_min) = sv
        .iter()
        .copied()
        .enumerate()
        .fold(
            (0, f64::INFINITY),
            |acc, (j, s)| if s < acc.1 { (j, s) } else { acc },
        );
    let condition_number = if rank == p && p > 0 && n >= p {
        s_max / s_min
    } else {
        f64::INFINITY
    };
    // With fewer rows than columns the null space is not spanned by Vᵀ's rows
    // (nalgebra returns min(n, p) of them): then any column will do.
    let weakest_direction: Vec<f64> = if sv.len() == p {
        v_t.row(j_min).iter().copied().collect()
    } else {
        vec![1.0 / (p as f64).sqrt(); p]
    };

    // The null space: the rows of Vᵀ with zero singular values, plus (when
    // n < p) the directions nalgebra does not return, i.e. everything the
    // returned rows do not span.
    let undetermined: Vec<f64> = (0..p)
        .map(|i| {
            let determined: f64 = sv
                .iter()
                .enumerate()
                .filter(|(_, &s)| s > tol)
                .map(|(j, _)| v_t[(j, i)].powi(2))
                .sum();
            (1.0 - determined).clamp(0.0, 1.0)
        })
        .collect();

    let covariance = if rank == p && n > p {
        let sigma2 = rss / (n - p) as f64;
        let mut cov = vec![0.0; p * p];
        for i in 0..p {
            for k in 0..p {
                let c: f64 = sv
                    .iter()
                    .enumerate()
                    .map(|(j, &s)| v_t[(j, i)] * v_t[(j, k)] / (s * s))
                    .sum();
                cov[i * p + k] = sigma2 * c / (norms[i] * norms[k]);
            }
        }
        cov
    } else {
        Vec::new()
    };
    let std_err = if rank == p && n > p {
        let sigma2 = rss / (n - p) as f64;
        (0..p)
            .map(|i| {
                let var_scaled: f64 = sv
                    .iter()
                    .enumerate()
                    .map(|(j, &s)| (v_t[(j, i)] / s).powi(2))
                    .sum();
                (sigma2 * var_scaled).sqrt() / norms[i]
            })
            .collect()
    } else {
        vec![f64::INFINITY; p]
    };

    LeastSquares {
        theta,
        std_err,
        covariance,
        rss,
        equations: n,
        condition_number,
        rank,
        weakest_direction,
        undetermined,
    }
}

/// The normal equations AᵀA·θ = Aᵀb of a tall least-squares problem,
/// accumulated row by row without storing A: p² + p numbers however many
/// rows. Squaring A squares its condition number, so [`solve`] (an SVD of
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
    /// [`solve`]).
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

fn degenerate(n: usize, p: usize) -> LeastSquares {
    LeastSquares {
        theta: vec![f64::NAN; p],
        std_err: vec![f64::INFINITY; p],
        covariance: Vec::new(),
        rss: f64::NAN,
        equations: n,
        condition_number: f64::INFINITY,
        rank: 0,
        weakest_direction: vec![f64::NAN; p],
        undetermined: vec![1.0; p],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn straight_line_fit_matches_closed_form() {
        // y = a + b·x: closed-form OLS and its standard errors.
        let x = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
        let y = [1.1, 2.9, 5.2, 7.1, 8.8, 11.2];
        let n = x.len() as f64;
        let a = DMatrix::from_fn(6, 2, |i, j| if j == 0 { 1.0 } else { x[i] * 1e6 });
        let b = DVector::from_column_slice(&y);
        let fit = solve(&a, &b);
        let mx = x.iter().sum::<f64>() / n;
        let my = y.iter().sum::<f64>() / n;
        let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
        let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
        let slope = sxy / sxx;
        let icpt = my - slope * mx;
        assert!((fit.theta[0] - icpt).abs() < 1e-12);
        assert!((fit.theta[1] * 1e6 - slope).abs() < 1e-12);
        let rss: f64 = x
            .iter()
            .zip(&y)
            .map(|(a, b)| (b - icpt - slope * a).powi(2))
            .sum();
        assert!((fit.rss - rss).abs() < 1e-12);
        let s2 = rss / (n - 2.0);
        let se_slope = (s2 / sxx).sqrt();
        let se_icpt = (s2 * (1.0 / n + mx * mx / sxx)).sqrt();
        assert!((fit.std_err[1] * 1e6 - se_slope).abs() < 1e-12);
        assert!((fit.std_err[0] - se_icpt).abs() < 1e-12);
        assert_eq!(fit.rank, 2);
        assert!(fit.condition_number > 1.0 && fit.condition_number < 10.0);
    }

    /// The normal equations give the SVD's estimate and standard errors
    /// on a well-conditioned problem, and refuse a rank-deficient one.
    /// Adding every product, zeros included, gives the sums of adding the
    /// non-zero ones only, bit for bit (the rule `add` relies on): rows of
    /// eq. 4's shape with +0, −0 and tiny entries, at five unknowns (the
    /// fixed-length loop) and at three (the general one).
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

    #[test]
    fn collinear_columns_are_rank_deficient() {
        let a = DMatrix::from_row_slice(4, 2, &[1.0, 2.0, 2.0, 4.0, 3.0, 6.0, 4.0, 8.0]);
        let b = DVector::from_column_slice(&[1.0, 2.0, 3.0, 4.0]);
        let fit = solve(&a, &b);
        assert_eq!(fit.rank, 1);
        assert!(fit.condition_number.is_infinite());
        assert!(fit.std_err.iter().all(|s| s.is_infinite()));
        // Both columns share the weak direction.
        assert!(fit.weakest_direction.iter().all(|v| v.abs() > 0.5));
        assert!(fit.undetermined.iter().all(|&u| (u - 0.5).abs() < 1e-12));
        assert!(fit.rss < 1e-20);
    }

    #[test]
    fn zero_columns_are_the_null_space() {
        let a = DMatrix::from_row_slice(3, 3, &[1.0, 0.0, 2.0, 2.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
        let b = DVector::from_column_slice(&[1.0, 2.0, 3.0]);
        let fit = solve(&a, &b);
        assert_eq!(fit.rank, 2);
        assert!(fit.undetermined[0] < 1e-12 && fit.undetermined[2] < 1e-12);
        assert!((fit.undetermined[1] - 1.0).abs() < 1e-12);
        assert_eq!(fit.theta[1], 0.0);
    }

    #[test]
    fn fewer_equations_than_unknowns() {
        let a = DMatrix::from_row_slice(1, 2, &[1.0, 1.0]);
        let b = DVector::from_column_slice(&[2.0]);
        let fit = solve(&a, &b);
        assert_eq!(fit.rank, 1);
        assert!(fit.condition_number.is_infinite());
        assert!(fit.std_err[0].is_infinite());
    }
}
