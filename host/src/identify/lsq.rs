//! Column-scaled linear least squares by singular value decomposition, with
//! the statistics an identification needs to say how far to trust itself.

use nalgebra::{DMatrix, DVector};

mod normal;
pub use normal::{NormalEquations, NormalSolution};

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
