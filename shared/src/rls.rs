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

use crate::phasor::Phasor2;
use crate::regression::{equations, ParameterScale, PARAMETERS};
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
        }
    }

    /// Forgets everything (keeps λ).
    pub fn reset(&mut self) {
        *self = Self::new(self.lambda);
    }

    /// Folds in one equation `row·θ = rhs`. Non-finite input is ignored and
    /// reported as `false`, so one bad sample cannot poison the estimate.
    pub fn update(&mut self, row: &[T; P], rhs: T) -> bool {
        if !rhs.is_finite() || row.iter().any(|x| !x.is_finite()) {
            return false;
        }
        let lambda = self.lambda;
        if lambda < T::one() {
            for i in 0..P {
                self.d[i] = self.d[i] * lambda;
                self.column_ss[i] = self.column_ss[i] * lambda;
            }
            self.rss = self.rss * lambda;
        }
        self.n_eff = self.n_eff * lambda + T::one();
        for (ss, x) in self.column_ss.iter_mut().zip(row) {
            *ss = *ss + *x * *x;
        }

        let mut x = *row;
        let mut y = rhs;
        let mut w = T::one();
        for i in 0..P {
            if w == T::zero() {
                break;
            }
            let xi = x[i];
            if xi == T::zero() {
                continue;
            }
            let di = self.d[i];
            let dpi = di + w * xi * xi;
            let cbar = di / dpi;
            let sbar = w * xi / dpi;
            w = cbar * w;
            self.d[i] = dpi;
            for k in (i + 1)..P {
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

    /// Effective number of equations folded in, Σ λ^k.
    pub fn equations(&self) -> T {
        self.n_eff
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

/// Square root through libm, in the working precision, so the host computes
/// bit for bit what the MCU computes (IEEE sqrt is correctly rounded in both)
/// and the M4F never falls back to software double precision.
#[inline]
fn libm_sqrt<T: Float>(x: T) -> T {
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

/// A pedestal's identified parameters with their standard errors, in physical
/// units: θ = (k_y [N/m], k_z [N/m], m [kg], c_y [N·s/m], c_z [N·s/m]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PedestalEstimate<T = f32> {
    /// Parameter values (k_y, k_z, m, c_y, c_z).
    pub theta: [T; PARAMETERS],
    /// Standard errors in the same units; NaN when not yet estimable.
    pub std_err: [T; PARAMETERS],
    /// Number of equations folded in (effective, with forgetting).
    pub equations: T,
    /// RMS of the equation residuals [N].
    pub residual_rms: T,
}

/// The recursive estimator of one pedestal's (k_y, k_z, m, c_y, c_z) from
/// eq. 4, with parameter scaling so that f32 suffices.
#[derive(Clone, Debug)]
pub struct PedestalRls<T = f32> {
    rls: Rls<T, PARAMETERS>,
    scale: ParameterScale<T>,
}

impl<T: Float> Default for PedestalRls<T> {
    fn default() -> Self {
        Self::new(ParameterScale::default(), T::one())
    }
}

impl<T: Float> PedestalRls<T> {
    /// A new estimator with the given column scales and forgetting factor λ.
    pub fn new(scale: ParameterScale<T>, lambda: T) -> Self {
        Self {
            rls: Rls::new(lambda),
            scale,
        }
    }

    /// Forgets all data.
    pub fn reset(&mut self) {
        self.rls.reset();
    }

    /// Folds in one speed: `omega` [rad/s], the absolute pedestal 1X
    /// displacement `ped` [m] and the bearing force on the pedestal `force`
    /// [N]. Returns how many of the four equations were accepted (finite).
    pub fn update(&mut self, omega: T, ped: &Phasor2<T>, force: &Phasor2<T>) -> usize {
        let mut accepted = 0;
        for eq in equations(omega, ped, force) {
            let scaled = self.scale.scale(&eq);
            if self.rls.update(&scaled.row, scaled.rhs) {
                accepted += 1;
            }
        }
        accepted
    }

    /// The current estimate in physical units.
    pub fn estimate(&self) -> Result<PedestalEstimate<T>, RlsError> {
        let scaled = self.rls.estimate()?;
        let theta = self.scale.unscale(&scaled);
        let std_err = match self.rls.std_errors() {
            Ok(se) => self.scale.unscale(&se),
            Err(_) => [T::nan(); PARAMETERS],
        };
        let n = self.rls.equations();
        let residual_rms = if n > T::zero() {
            libm_sqrt(self.rls.residual_sum_of_squares() / n)
        } else {
            T::nan()
        };
        Ok(PedestalEstimate {
            theta,
            std_err,
            equations: n,
            residual_rms,
        })
    }

    /// See [`Rls::collinearity_margin`].
    pub fn collinearity_margin(&self) -> T {
        self.rls.collinearity_margin()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phasor::Complex;

    /// Forces of an exact pedestal (eq. 3) for a given pedestal response.
    fn pedestal_forces(theta: &[f64; 5], omega: f64, ped: &Phasor2<f64>) -> Phasor2<f64> {
        let dyn_stiffness = |k: f64, c: f64| Complex::new(k - omega * omega * theta[2], omega * c);
        [
            dyn_stiffness(theta[0], theta[3]) * ped[0],
            dyn_stiffness(theta[1], theta[4]) * ped[1],
        ]
    }

    fn response(i: usize) -> Phasor2<f64> {
        // Deterministic, varied phasors of micrometre size.
        let a = i as f64;
        [
            Complex::from_polar(1e-6 * (1.0 + 0.5 * (0.3 * a).sin()), 0.7 * a),
            Complex::from_polar(2e-6 * (1.0 + 0.4 * (0.2 * a).cos()), -0.4 * a + 1.0),
        ]
    }

    #[test]
    fn recovers_exact_pedestal_in_f64() {
        let theta = [8.0e6, 6.0e6, 150.0, 100.0, 70.0];
        let mut est = PedestalRls::<f64>::default();
        for i in 0..60 {
            let omega = 2.0 * core::f64::consts::PI * (5.0 + 3.0 * i as f64);
            let ped = response(i);
            assert_eq!(
                est.update(omega, &ped, &pedestal_forces(&theta, omega, &ped)),
                4
            );
        }
        let e = est.estimate().unwrap();
        for i in 0..5 {
            assert!(
                (e.theta[i] - theta[i]).abs() <= 1e-8 * theta[i],
                "{i}: {}",
                e.theta[i]
            );
        }
        assert!(e.residual_rms < 1e-9);
    }

    #[test]
    fn recovers_exact_pedestal_in_f32() {
        let theta = [8.0e6, 6.0e6, 150.0, 100.0, 70.0];
        let mut est = PedestalRls::<f32>::default();
        for i in 0..100 {
            let omega = 2.0 * core::f64::consts::PI * (2.0 + 2.0 * i as f64);
            let ped = response(i);
            let f = pedestal_forces(&theta, omega, &ped);
            let c32 = |c: Complex<f64>| Complex::new(c.re as f32, c.im as f32);
            est.update(
                omega as f32,
                &[c32(ped[0]), c32(ped[1])],
                &[c32(f[0]), c32(f[1])],
            );
        }
        let e = est.estimate().unwrap();
        for i in 0..5 {
            let rel = ((e.theta[i] as f64) - theta[i]).abs() / theta[i];
            assert!(rel < 1e-3, "param {i}: {} vs {}", e.theta[i], theta[i]);
        }
    }

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
    }

    #[test]
    fn forgetting_tracks_a_change() {
        // θ switches from 1 to 3 halfway; λ = 0.8 follows, λ = 1 averages.
        let mut forgetful = Rls::<f64, 1>::new(0.8);
        let mut steady = Rls::<f64, 1>::default();
        for i in 0..200 {
            let y = if i < 100 { 1.0 } else { 3.0 };
            forgetful.update(&[1.0], y);
            steady.update(&[1.0], y);
        }
        assert!((forgetful.estimate().unwrap()[0] - 3.0).abs() < 1e-9);
        assert!((steady.estimate().unwrap()[0] - 2.0).abs() < 1e-12);
    }
}
