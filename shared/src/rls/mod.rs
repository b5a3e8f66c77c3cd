//! Recursive least squares for one pedestal, in square-root information form.
//!
//! The normal equations are never formed. The estimator keeps the triangular
//! factor of the (exponentially weighted) regression matrix, A = Q·D^{1/2}·R̄,
//! with R̄ unit upper triangular and D diagonal, and folds in each new equation
//! with square-root-free Givens rotations (Gentleman 1973; Miller's AS 274).
//! That is the numerically safe "UD" form of RLS: it conditions like A, not
//! like AᵀA, the covariance P = R̄⁻¹·D⁻¹·R̄⁻ᵀ is symmetric positive definite by
//! construction whenever every d_i > 0, there is no square root or matrix
//! inverse per update, and without forgetting it reproduces the batch
//! least-squares solution exactly (no prior is needed).
//!
//! Forgetting is a separate step ([`Rls::forget`]) so that a caller decays
//! the information once per observation, however many equations it makes
//! (the pedestal estimator: once per speed, all four equations alike).
//!
//! An equation whose squares would overflow the working precision (a finite
//! but huge row: a tiny sensor sensitivity, a weight from a tiny noise) is
//! scaled down by a power of two before it is folded in, so that it cannot
//! turn the factor into infinities; that lowers its weight, so it is
//! counted ([`Rls::rescaled`]). An equation that is not finite is rejected
//! and counted ([`Rls::rejected`]).

mod pedestal;

pub use pedestal::{PedestalEstimate, PedestalRls};

use num_traits::Float;

/// Exponentially weighted least squares over `P` unknowns.
#[derive(Clone, Debug)]
pub struct Rls<T, const P: usize> {
    /// Diagonal of D: the information along each rotated direction.
    d: [T; P],
    /// Strict upper triangle of R̄ (the diagonal is one).
    r: [[T; P]; P],
    /// Transformed right-hand side: R̄·θ = z.
    z: [T; P],
    /// Weighted sum of squares of each column seen so far (rank test).
    column_ss: [T; P],
    /// Weighted residual sum of squares.
    rss: T,
    /// Effective number of equations, Σ λ^k.
    n_eff: T,
    /// Forgetting factor λ in (0, 1]; 1 = no forgetting.
    lambda: T,
    /// Equations scaled down to keep their squares finite.
    rescaled: u32,
    /// Equations refused as not finite.
    rejected: u32,
}

/// Why an estimate is not available.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RlsError {
    /// Parameter `index` is not determined by the data so far (too few or
    /// linearly dependent equations).
    Undetermined {
        /// Index of the first undetermined parameter.
        index: usize,
    },
    /// Fewer equations than unknowns plus one: no variance can be estimated.
    TooFewEquations,
}

impl<T: Float, const P: usize> Default for Rls<T, P> {
    fn default() -> Self {
        Self::new(T::one())
    }
}

impl<T: Float, const P: usize> Rls<T, P> {
    /// An empty estimator with forgetting factor `lambda` (1 = none). Values
    /// outside (0, 1] are clamped into it.
    pub fn new(lambda: T) -> Self {
        let lambda = if lambda > T::zero() && lambda <= T::one() {
            lambda
        } else {
            T::one()
        };
        Self {
            d: [T::zero(); P],
            r: [[T::zero(); P]; P],
            z: [T::zero(); P],
            column_ss: [T::zero(); P],
            rss: T::zero(),
            n_eff: T::zero(),
            lambda,
            rescaled: 0,
            rejected: 0,
        }
    }

    /// Forgets everything (keeps λ).
    pub fn reset(&mut self) {
        *self = Self::new(self.lambda);
    }

    /// Decays everything known by λ: once per observation, before its
    /// equations are folded in.
    pub fn forget(&mut self) {
        let lambda = self.lambda;
        if lambda < T::one() {
            for i in 0..P {
                self.d[i] = self.d[i] * lambda;
                self.column_ss[i] = self.column_ss[i] * lambda;
            }
            self.rss = self.rss * lambda;
            self.n_eff = self.n_eff * lambda;
        }
    }

    /// Folds in one equation `row·θ = rhs` with unit weight (see
    /// [`update_weighted`](Self::update_weighted)).
    pub fn update(&mut self, row: &[T; P], rhs: T) -> bool {
        self.update_weighted(row, rhs, T::one())
    }

    /// Folds in one equation `row·θ = rhs` with weight `weight` (1/variance
    /// of its error). Non-finite input and a weight that is not finite and
    /// positive are rejected and reported as `false`, so one bad sample
    /// cannot poison the estimate; a finite equation whose weighted squares
    /// would overflow is scaled down by powers of two (see the module
    /// documentation).
    pub fn update_weighted(&mut self, row: &[T; P], rhs: T, weight: T) -> bool {
        self.update_weighted_on(core::array::from_fn::<usize, P, _>(|i| i), row, rhs, weight)
    }

    /// [`update_weighted`](Self::update_weighted) for a row that is zero
    /// outside the columns `support` (ascending, each < P), in a problem
    /// whose rows keep the factor's fill-in inside the supports: every
    /// row's support must contain, after its first column, every column
    /// that any earlier row shares a pivot with (for the pedestal: the y
    /// rows on (k_y, c_y, m), the z rows on (k_z, c_z, m), with m last).
    /// The rotations then touch only those columns: exact, and for three
    /// of five columns less than half the work.
    pub(crate) fn update_weighted_on<const S: usize>(
        &mut self,
        support: [usize; S],
        row: &[T; P],
        rhs: T,
        weight: T,
    ) -> bool {
        // The mean magnitude: NaN and infinity propagate into it (one test
        // for all), it cannot overflow, and the largest entry is at most
        // P + 1 times it.
        let entries = T::from(P + 1).unwrap_or_else(T::one);
        let inv = T::one() / entries;
        let mean = row
            .iter()
            .fold(magnitude(rhs) * inv, |t, x| t + magnitude(*x) * inv);
        if !(mean.is_finite() && weight.is_finite() && weight > T::zero()) {
            self.rejected = self.rejected.saturating_add(1);
            return false;
        }
        let mut x = *row;
        let mut y = rhs;
        // Weighted squares up to max/2³², so that 2³² of them stay finite.
        let two = T::one() + T::one();
        let sixteen = two * two * two * two;
        let limit = T::max_value()
            / (sixteen * sixteen * sixteen * sixteen * sixteen * sixteen * sixteen * sixteen)
            / (entries * entries);
        let fits = |s: T| {
            let m = mean * s;
            m * m * weight <= limit
        };
        if !fits(T::one()) {
            // Powers of two: exact, whatever the precision.
            let mut s = T::one() / sixteen;
            while !fits(s) {
                s = s / sixteen;
                if s == T::zero() {
                    self.rejected = self.rejected.saturating_add(1);
                    return false;
                }
            }
            for v in x.iter_mut() {
                *v = *v * s;
            }
            y = y * s;
            self.rescaled = self.rescaled.saturating_add(1);
        }
        self.n_eff = self.n_eff + T::one();
        let scaled = x;

        let mut w = weight;
        // Branch-free, so that the loops unroll into straight-line code with
        // fixed offsets: a zero entry, or a row already absorbed (w = 0),
        // makes the rotation the identity exactly (c̄ = d/d = 1, s̄ = 0), the
        // one case 0/0 is mapped to it.
        for (a, &i) in support.iter().enumerate() {
            let xi = x[i];
            self.column_ss[i] = self.column_ss[i] + weight * scaled[i] * scaled[i];
            let di = self.d[i];
            let dpi = di + w * xi * xi;
            let (cbar, sbar) = if dpi > T::zero() {
                (di / dpi, w * xi / dpi)
            } else {
                (T::one(), T::zero())
            };
            w = cbar * w;
            self.d[i] = dpi;
            for &k in &support[a + 1..] {
                let xk = x[k];
                x[k] = xk - xi * self.r[i][k];
                self.r[i][k] = cbar * self.r[i][k] + sbar * xk;
            }
            let yk = y;
            y = yk - xi * self.z[i];
            self.z[i] = cbar * self.z[i] + sbar * yk;
        }
        self.rss = self.rss + w * y * y;
        true
    }

    /// Relative tolerance below which a direction counts as undetermined:
    /// d_i / Σx_i² is 1 − R² of column i on the columns before it.
    fn tolerance() -> T {
        // About 100 ulps of the working precision.
        T::epsilon() * T::from(100.0).unwrap_or_else(T::one)
    }

    /// First parameter the data do not determine, if any.
    fn undetermined(&self) -> Option<usize> {
        (0..P).find(|&i| {
            !(self.column_ss[i] > T::zero() && self.d[i] > Self::tolerance() * self.column_ss[i])
        })
    }

    /// The least-squares estimate θ, or which parameter is not yet determined.
    pub fn estimate(&self) -> Result<[T; P], RlsError> {
        if let Some(index) = self.undetermined() {
            return Err(RlsError::Undetermined { index });
        }
        let mut theta = [T::zero(); P];
        for i in (0..P).rev() {
            let mut s = self.z[i];
            for k in (i + 1)..P {
                s = s - self.r[i][k] * theta[k];
            }
            theta[i] = s;
        }
        Ok(theta)
    }

    /// Diagonal of (AᵀA)⁻¹ (the unscaled covariance), from R̄⁻¹·D⁻¹·R̄⁻ᵀ.
    pub fn covariance_diagonal(&self) -> Result<[T; P], RlsError> {
        if let Some(index) = self.undetermined() {
            return Err(RlsError::Undetermined { index });
        }
        // U = R̄⁻¹, unit upper triangular, column by column.
        let mut u = [[T::zero(); P]; P];
        for j in 0..P {
            u[j][j] = T::one();
            for i in (0..j).rev() {
                let mut s = T::zero();
                for k in (i + 1)..=j {
                    s = s + self.r[i][k] * u[k][j];
                }
                u[i][j] = -s;
            }
        }
        let mut diag = [T::zero(); P];
        for (j, dj) in diag.iter_mut().enumerate() {
            let mut s = T::zero();
            for i in j..P {
                s = s + u[j][i] * u[j][i] / self.d[i];
            }
            *dj = s;
        }
        Ok(diag)
    }

    /// Residual variance σ² = RSS / (n − P) [rhs unit²].
    pub fn residual_variance(&self) -> Result<T, RlsError> {
        let dof = self.n_eff - T::from(P).unwrap_or_else(T::zero);
        if dof <= T::zero() || dof.is_nan() {
            return Err(RlsError::TooFewEquations);
        }
        Ok(self.rss / dof)
    }

    /// Standard errors of θ: sqrt(σ²·diag((AᵀA)⁻¹)).
    pub fn std_errors(&self) -> Result<[T; P], RlsError> {
        let sigma2 = self.residual_variance()?;
        let mut diag = self.covariance_diagonal()?;
        for v in diag.iter_mut() {
            *v = libm_sqrt(sigma2 * *v);
        }
        Ok(diag)
    }

    /// Weighted residual sum of squares [rhs unit²].
    pub fn residual_sum_of_squares(&self) -> T {
        self.rss
    }

    /// Effective number of equations folded in (each observation's decayed
    /// by λ per later observation).
    pub fn equations(&self) -> T {
        self.n_eff
    }

    /// Equations scaled down because their squares would overflow.
    pub fn rescaled(&self) -> u32 {
        self.rescaled
    }

    /// Equations rejected as not finite.
    pub fn rejected(&self) -> u32 {
        self.rejected
    }

    /// Smallest 1 − R² of a column on the columns before it, in [0, 1]: near
    /// zero means the parameters are nearly collinear (ill-conditioned fit).
    pub fn collinearity_margin(&self) -> T {
        let mut worst = T::one();
        for i in 0..P {
            if self.column_ss[i] > T::zero() {
                worst = worst.min(self.d[i] / self.column_ss[i]);
            } else {
                worst = T::zero();
            }
        }
        worst
    }
}

/// The larger of two numbers that are not NaN: a compare and a select (the
/// M4F has no float max instruction; `Float::max` is a library call with
/// NaN handling).
#[inline(always)]
pub(crate) fn larger<T: PartialOrd>(a: T, b: T) -> T {
    if b > a {
        b
    } else {
        a
    }
}

/// |x|, inline: a compare and a negation (`Float::abs` goes through libm,
/// which the M4F image builds for size and does not inline: a call per
/// entry on the update path). NaN stays NaN.
#[inline(always)]
pub(crate) fn magnitude<T: Float>(x: T) -> T {
    if x < T::zero() {
        -x
    } else {
        x
    }
}

/// Square root through libm, in the working precision, so the host computes
/// bit for bit what the MCU computes (IEEE sqrt is correctly rounded in both)
/// and the M4F never falls back to software double precision.
#[inline]
pub(crate) fn libm_sqrt<T: Float>(x: T) -> T {
    if core::mem::size_of::<T>() == core::mem::size_of::<f32>() {
        match x.to_f32() {
            Some(v) => T::from(libm::sqrtf(v)).unwrap_or_else(T::nan),
            None => T::nan(),
        }
    } else {
        match x.to_f64() {
            Some(v) => T::from(libm::sqrt(v)).unwrap_or_else(T::nan),
            None => T::nan(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_normal_equations_on_noisy_data() {
        // Independent check: solve AᵀA θ = Aᵀb directly in f64 (3 unknowns).
        let rows: [[f64; 3]; 6] = [
            [1.0, 2.0, 0.5],
            [0.3, -1.0, 2.0],
            [2.0, 0.1, -0.7],
            [-1.2, 0.8, 1.1],
            [0.5, 0.5, 0.5],
            [1.7, -0.3, 0.2],
        ];
        let b = [1.0, -0.5, 2.2, 0.4, 0.9, 1.3];
        let mut rls = Rls::<f64, 3>::default();
        for (r, y) in rows.iter().zip(b) {
            rls.update(r, y);
        }
        let mut ata = [[0.0; 3]; 3];
        let mut atb = [0.0; 3];
        for (r, y) in rows.iter().zip(b) {
            for i in 0..3 {
                atb[i] += r[i] * y;
                for j in 0..3 {
                    ata[i][j] += r[i] * r[j];
                }
            }
        }
        // Cramer's rule for the 3×3 system.
        let det = |m: &[[f64; 3]; 3]| {
            m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
        };
        let d = det(&ata);
        let theta = rls.estimate().unwrap();
        for k in 0..3 {
            let mut m = ata;
            for i in 0..3 {
                m[i][k] = atb[i];
            }
            assert!((theta[k] - det(&m) / d).abs() < 1e-12);
        }
        // Covariance diagonal against the cofactors of AᵀA.
        let cov = rls.covariance_diagonal().unwrap();
        let minor = |k: usize| {
            let idx: [usize; 2] = match k {
                0 => [1, 2],
                1 => [0, 2],
                _ => [0, 1],
            };
            ata[idx[0]][idx[0]] * ata[idx[1]][idx[1]] - ata[idx[0]][idx[1]] * ata[idx[1]][idx[0]]
        };
        for k in 0..3 {
            assert!((cov[k] - minor(k) / d).abs() < 1e-12);
        }
        // RSS equals the residual of the solution.
        let rss: f64 = rows
            .iter()
            .zip(b)
            .map(|(r, y)| (r.iter().zip(&theta).map(|(a, t)| a * t).sum::<f64>() - y).powi(2))
            .sum();
        assert!((rls.residual_sum_of_squares() - rss).abs() < 1e-12);
    }

    #[test]
    fn reports_undetermined_parameters() {
        let mut rls = Rls::<f64, 3>::default();
        assert_eq!(rls.estimate(), Err(RlsError::Undetermined { index: 0 }));
        rls.update(&[1.0, 1.0, 0.0], 1.0);
        rls.update(&[2.0, 2.0, 0.0], 2.0);
        rls.update(&[0.0, 0.0, 1.0], 2.0);
        // Columns 0 and 1 are identical: parameter 1 is not determined.
        assert_eq!(rls.estimate(), Err(RlsError::Undetermined { index: 1 }));
        assert!(rls.collinearity_margin() < 1e-12);
    }

    #[test]
    fn ignores_non_finite_equations() {
        let mut rls = Rls::<f32, 2>::default();
        assert!(!rls.update(&[f32::NAN, 1.0], 1.0));
        assert!(!rls.update(&[1.0, 1.0], f32::INFINITY));
        assert_eq!(rls.equations(), 0.0);
        assert_eq!(rls.rejected(), 2);
    }

    #[test]
    fn a_row_too_large_to_square_is_scaled_not_folded_as_infinity() {
        // y = 2x + 1 with one equation at x = 1e30 (its square overflows
        // f32): the estimate stays finite and exact, and the rescale counted.
        let mut rls = Rls::<f32, 2>::default();
        for x in [0.0f32, 1.0, 2.0, 3.0] {
            assert!(rls.update(&[x, 1.0], 2.0 * x + 1.0));
        }
        assert!(rls.update(&[1e30, 1.0], 2e30 + 1.0));
        assert_eq!(rls.rescaled(), 1);
        let theta = rls.estimate().unwrap();
        assert!(
            (theta[0] - 2.0).abs() < 1e-5 && (theta[1] - 1.0).abs() < 1e-3,
            "{theta:?}"
        );
        let se = rls.covariance_diagonal().unwrap();
        assert!(se.iter().all(|v| v.is_finite()), "{se:?}");
    }

    #[test]
    fn forgetting_tracks_a_change() {
        // θ switches from 1 to 3 halfway; λ = 0.8 follows, λ = 1 averages.
        let mut forgetful = Rls::<f64, 1>::new(0.8);
        let mut steady = Rls::<f64, 1>::default();
        for i in 0..200 {
            let y = if i < 100 { 1.0 } else { 3.0 };
            forgetful.forget();
            forgetful.update(&[1.0], y);
            steady.update(&[1.0], y);
        }
        assert!((forgetful.estimate().unwrap()[0] - 3.0).abs() < 1e-9);
        assert!((steady.estimate().unwrap()[0] - 2.0).abs() < 1e-12);
    }
}
