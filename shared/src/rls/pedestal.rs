//! The recursive estimator of one pedestal, weighted by the noise of its
//! phasors.
//!
//! # Weights
//!
//! Eq. 4's residual in direction d at one speed is e = Z_d·X_d − F_d with
//! Z_d = k_d − Ω²m + iΩc_d. Noise n_X on the pedestal phasor and n_rel on the
//! rotor-relative phasors (through F = (K_b + iΩC_b)·rel, cross terms
//! included: [`force_noise_variance`](crate::regression::force_noise_variance)) make it
//! e's noise Z_d·n_X − n_F, of variance |Z_d|²σ_X² + σ_F², half in each of
//! the real and imaginary equations (circular noise stays circular when
//! multiplied by a complex number, so the two are uncorrelated). Each
//! equation is folded in with the weight 1/variance: the recursive form of
//! weighted least squares.
//!
//! Z_d is taken at an estimate once 4·P equations are in (an estimate of
//! the parameters independent of this speed's own noise), and before that
//! from this speed's own data, |Z_d| = |F_d|/|X_d|. The estimate for the
//! weights is refreshed every [`WEIGHT_REFRESH`] speeds, not at every one:
//! a back-substitution per speed is a fifth of the update's cost, and
//! weights from an estimate a few speeds old are as good (a weight is
//! optimal to first order around the right value; once settled the
//! estimate moves by a fraction of its standard error per speed). What this
//! leaves out, and why it is good enough: the y and z equations share the
//! rel noise when the bearing is cross-coupled (their correlation is ignored:
//! the estimate stays unbiased, the weights slightly less than optimal), and
//! the errors-in-variables bias of least squares with noisy regressors (of
//! relative size σ_X²/|X|², 1e-4 for a phasor 1 % noisy: far below its
//! standard error; the host's maximum-likelihood fit removes it). Weights
//! fixed when an equation is folded in are not revised later (recursive).
//!
//! A standard deviation is never taken below 8 ε of the equation's own size
//! (ε of the working precision: what f32 phasors can carry), so noise-free
//! data cannot make infinite weights.
//!
//! # Forgetting
//!
//! λ decays the information once per speed: all four equations of one
//! phasor frame are forgotten alike.
//!
//! # Standard errors
//!
//! sqrt(φ·s²·diag((AᵀWA)⁻¹)) with s² = Σ(whitened residual)²/(n − P), the
//! reduced χ² (1 when the residuals are as large as the phasors' noise says;
//! reported, so that a wrong noise scale or a model error shows), and φ the
//! long-run factor of consecutive phasors sharing revolutions
//! ([`long_run_factor`](crate::extractor::long_run_factor): their errors
//! correlate, so the independent-equation formula is off by φ).

use super::{larger, libm_sqrt, magnitude, Rls, RlsError};
use crate::bearing::BearingCoefficients;
use crate::phasor::{Complex, Phasor2};
use crate::regression::{equations, force_noise_variance, ParameterScale, PARAMETERS};
use num_traits::Float;

/// The solver's column order: θ's indices (k_y, k_z, m, c_y, c_z) as
/// (k_y, c_y, k_z, c_z, m). The y equations then live on solver columns
/// 0, 1, 4 and the z equations on 2, 3, 4, and with the shared mass last
/// the factor never fills in between y and z: each equation rotates three
/// columns, not five.
const SOLVER_ORDER: [usize; PARAMETERS] = [0, 3, 1, 4, 2];

/// Solver columns of the y and of the z equations.
const Y_COLUMNS: [usize; 3] = [0, 1, 4];
const Z_COLUMNS: [usize; 3] = [2, 3, 4];

/// θ order from solver order.
fn from_solver<T: Copy>(v: &[T; PARAMETERS]) -> [T; PARAMETERS] {
    let mut out = *v;
    for (s, &p) in SOLVER_ORDER.iter().enumerate() {
        out[p] = v[s];
    }
    out
}

/// The solver's result in θ order (an undetermined solver column named by
/// its θ index).
fn solved<T: Copy>(r: Result<[T; PARAMETERS], RlsError>) -> Result<[T; PARAMETERS], RlsError> {
    match r {
        Ok(v) => Ok(from_solver(&v)),
        Err(RlsError::Undetermined { index }) => Err(RlsError::Undetermined {
            index: SOLVER_ORDER.get(index).copied().unwrap_or(index),
        }),
        Err(e) => Err(e),
    }
}

/// Speeds between two refreshes of the estimate the weights use.
pub const WEIGHT_REFRESH: u16 = 8;

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
    /// Σ(whitened residual)²/(n − P): 1 when the residuals are as large as
    /// the phasors' noise says (dimensionless); with unit weights
    /// ([`PedestalRls::update`]) the residual variance [N²]. NaN while
    /// n ≤ P.
    pub reduced_chi_square: T,
    /// Equations scaled down because their squares would overflow.
    pub rescaled: u32,
    /// Equations rejected as not finite (or with no finite noise).
    pub rejected: u32,
}

/// The recursive estimator of one pedestal's (k_y, k_z, m, c_y, c_z) from
/// eq. 4, with parameter scaling so that f32 suffices.
#[derive(Clone, Debug)]
pub struct PedestalRls<T = f32> {
    rls: Rls<T, PARAMETERS>,
    scale: ParameterScale<T>,
    /// φ: parameter variances per independent-equation variance.
    long_run_factor: T,
    /// The estimate (physical units) the weights use, and the speeds
    /// folded in since it was taken.
    weight_theta: Option<[T; PARAMETERS]>,
    weight_age: u16,
}

impl<T: Float> Default for PedestalRls<T> {
    fn default() -> Self {
        Self::new(ParameterScale::default(), T::one())
    }
}

impl<T: Float> PedestalRls<T> {
    /// A new estimator with the given column scales and forgetting factor λ
    /// per speed.
    pub fn new(scale: ParameterScale<T>, lambda: T) -> Self {
        Self {
            rls: Rls::new(lambda),
            scale,
            long_run_factor: T::one(),
            weight_theta: None,
            weight_age: 0,
        }
    }

    /// Sets φ, the factor on the parameter variances for errors correlated
    /// between consecutive speeds (see the module documentation); a value
    /// that is not finite and positive leaves it at 1.
    pub fn with_long_run_factor(mut self, phi: T) -> Self {
        if phi.is_finite() && phi > T::zero() {
            self.long_run_factor = phi;
        }
        self
    }

    /// Forgets all data.
    pub fn reset(&mut self) {
        self.rls.reset();
        self.weight_theta = None;
        self.weight_age = 0;
    }

    /// Folds in one speed with unit weights (ordinary least squares):
    /// `omega` [rad/s], the absolute pedestal 1X displacement `ped` [m] and
    /// the bearing force on the pedestal `force` [N]. Returns how many of
    /// the four equations were accepted (finite).
    pub fn update(&mut self, omega: T, ped: &Phasor2<T>, force: &Phasor2<T>) -> usize {
        self.fold(omega, ped, force, [T::one(); 2])
    }

    /// Folds in one speed weighted by its noise: `omega` [rad/s], the
    /// absolute pedestal 1X displacement `ped` [m], the rotor-relative one
    /// `rel` [m] and the bearing's coefficients at this speed (the force on
    /// the pedestal is F = (K_b + iΩC_b)·rel), with the noise standard
    /// deviations sqrt(E|n|²) of the rel phasors `rel_sd` and of the ped
    /// phasors `ped_sd` [m], (y, z). Returns how many of the four equations
    /// were accepted.
    ///
    /// Eq. 4 is homogeneous in (ped, rel): all phasors and their noise are
    /// first divided by their largest magnitude, which changes nothing in
    /// the fit but keeps every square in range, so huge but valid phasors
    /// (a tiny sensitivity) are as good as any.
    pub fn update_weighted(
        &mut self,
        omega: T,
        ped: &Phasor2<T>,
        rel: &Phasor2<T>,
        bearing: &BearingCoefficients<T>,
        rel_sd: [T; 2],
        ped_sd: [T; 2],
    ) -> usize {
        let size = |c: &Complex<T>| larger(magnitude(c.re), magnitude(c.im));
        let largest = ped
            .iter()
            .chain(rel)
            .map(size)
            .chain(rel_sd)
            .chain(ped_sd)
            .fold(T::zero(), larger);
        if !(largest.is_finite() && largest > T::zero()) {
            return self.fold(omega, ped, &bearing.force(omega, rel), [T::nan(); 2]);
        }
        let k = T::one() / largest;
        let ped = ped.map(|p| p * k);
        let rel = rel.map(|r| r * k);
        let force = bearing.force(omega, &rel);
        let force_var = force_noise_variance(bearing, omega, &rel_sd.map(|s| s * k));
        let settled = T::from(4 * PARAMETERS).unwrap_or_else(T::one);
        if self.weight_theta.is_none() || self.weight_age >= WEIGHT_REFRESH {
            self.weight_theta = match solved(self.rls.estimate()) {
                Ok(t) if self.rls.equations() >= settled => Some(self.scale.unscale(&t)),
                _ => None,
            };
            self.weight_age = 0;
        }
        self.weight_age = self.weight_age.saturating_add(1);
        let theta = self.weight_theta;
        let floor = T::epsilon() * T::from(8.0).unwrap_or_else(T::one);
        let mut weight = [T::nan(); 2];
        for d in 0..2 {
            let x2 = ped[d].norm_sqr();
            let f2 = force[d].norm_sqr();
            let z2 = match theta {
                Some(t) => Complex::new(t[d] - omega * omega * t[2], omega * t[3 + d]).norm_sqr(),
                None => f2 / x2,
            };
            let s = ped_sd[d] * k;
            // Complex variance of the residual; half of it in each of the
            // real and imaginary equations.
            let var = larger(
                z2 * s * s + force_var[d],
                floor * floor * larger(f2, z2 * x2),
            );
            weight[d] = (T::one() + T::one()) / var;
        }
        self.fold(omega, &ped, &force, weight)
    }

    /// Forgets once, then folds in the four equations of one speed, each
    /// with its direction's weight `weight` [1/N²] (NaN: rejected).
    fn fold(&mut self, omega: T, ped: &Phasor2<T>, force: &Phasor2<T>, weight: [T; 2]) -> usize {
        self.rls.forget();
        let mut accepted = 0;
        for (i, eq) in equations(omega, ped, force).iter().enumerate() {
            let scaled = self.scale.scale(eq);
            let row = SOLVER_ORDER.map(|p| scaled.row[p]);
            let folded = if i < 2 {
                self.rls
                    .update_weighted_on(Y_COLUMNS, &row, scaled.rhs, weight[0])
            } else {
                self.rls
                    .update_weighted_on(Z_COLUMNS, &row, scaled.rhs, weight[1])
            };
            if folded {
                accepted += 1;
            }
        }
        accepted
    }

    /// The current estimate in physical units.
    pub fn estimate(&self) -> Result<PedestalEstimate<T>, RlsError> {
        let scaled = solved(self.rls.estimate())?;
        let theta = self.scale.unscale(&scaled);
        let phi = libm_sqrt(self.long_run_factor);
        let std_err = match solved(self.rls.std_errors()) {
            Ok(se) => self.scale.unscale(&se.map(|s| s * phi)),
            Err(_) => [T::nan(); PARAMETERS],
        };
        Ok(PedestalEstimate {
            theta,
            std_err,
            equations: self.rls.equations(),
            reduced_chi_square: self.rls.residual_variance().unwrap_or_else(|_| T::nan()),
            rescaled: self.rls.rescaled(),
            rejected: self.rls.rejected(),
        })
    }

    /// See [`Rls::collinearity_margin`].
    pub fn collinearity_margin(&self) -> T {
        self.rls.collinearity_margin()
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

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
        assert!(e.reduced_chi_square < 1e-18);
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

    /// A machine-like pedestal with a cross-coupled bearing: θ, the bearing,
    /// and per speed Ω [rad/s], rel [m] and the exact ped [m] (eq. 3).
    fn bench_case(speeds: usize) -> Case {
        bench_case_with(speeds, response)
    }

    /// θ, the bearing, and per speed (Ω [rad/s], rel [m], ped [m]).
    type Case = (
        [f64; 5],
        BearingCoefficients<f64>,
        Vec<(f64, Phasor2<f64>, Phasor2<f64>)>,
    );

    /// [`bench_case`] with rel phasors from `rel_at(speed index)`.
    fn bench_case_with(speeds: usize, rel_at: impl Fn(usize) -> Phasor2<f64>) -> Case {
        let theta = [8.0e6, 6.0e6, 150.0, 2000.0, 1500.0];
        let bearing = BearingCoefficients {
            k: [[2.0e8, 3.0e7], [-2.0e7, 1.5e8]],
            c: [[3.0e4, 0.0], [0.0, 2.5e4]],
        };
        let points = (0..speeds)
            .map(|i| {
                let omega = 2.0 * core::f64::consts::PI * (10.0 + 50.0 * i as f64 / speeds as f64);
                let rel = rel_at(i);
                let f = bearing.force(omega, &rel);
                let z = |k: f64, c: f64| Complex::new(k - omega * omega * theta[2], omega * c);
                let ped = [f[0] / z(theta[0], theta[3]), f[1] / z(theta[1], theta[4])];
                (omega, rel, ped)
            })
            .collect();
        (theta, bearing, points)
    }

    #[test]
    fn weighting_by_phasor_noise_gives_smaller_and_honest_errors() {
        // Every other speed is ten times noisier (a noisy band): the weighted
        // fit must beat ordinary least squares, and its reported standard
        // errors must match the scatter over noise draws.
        let (theta, bearing, points) = bench_case(60);
        let mut gauss = crate::testing::Gauss(11);
        let draws = 300;
        let (mut weighted_ss, mut plain_ss, mut reported) = ([0.0f64; 5], [0.0f64; 5], [0.0f64; 5]);
        let mut chi2 = 0.0;
        for _ in 0..draws {
            let mut weighted = PedestalRls::<f64>::default();
            let mut plain = PedestalRls::<f64>::default();
            for (i, (omega, rel, ped)) in points.iter().enumerate() {
                let level = if i % 2 == 0 { 0.002 } else { 0.02 };
                let rel_sd = rel.map(|r| level * r.norm());
                let ped_sd = ped.map(|p| level * p.norm());
                let rel_n: Phasor2<f64> =
                    core::array::from_fn(|d| rel[d] + gauss.complex(rel_sd[d]));
                let ped_n: Phasor2<f64> =
                    core::array::from_fn(|d| ped[d] + gauss.complex(ped_sd[d]));
                let force = bearing.force(*omega, &rel_n);
                assert_eq!(
                    weighted.update_weighted(*omega, &ped_n, &rel_n, &bearing, rel_sd, ped_sd),
                    4
                );
                plain.update(*omega, &ped_n, &force);
            }
            let (w, p) = (weighted.estimate().unwrap(), plain.estimate().unwrap());
            for k in 0..5 {
                weighted_ss[k] += (w.theta[k] - theta[k]).powi(2);
                plain_ss[k] += (p.theta[k] - theta[k]).powi(2);
                reported[k] += w.std_err[k].powi(2);
            }
            chi2 += w.reduced_chi_square;
        }
        let chi2 = chi2 / draws as f64;
        assert!((chi2 - 1.0).abs() < 0.1, "mean reduced χ² {chi2}");
        for k in 0..5 {
            let rms_w = (weighted_ss[k] / draws as f64).sqrt();
            let rms_p = (plain_ss[k] / draws as f64).sqrt();
            let se = (reported[k] / draws as f64).sqrt();
            std::println!(
                "θ{k}: weighted RMS error {rms_w:.3e}, OLS {rms_p:.3e}, reported/observed {:.3}",
                se / rms_w
            );
            assert!(
                rms_w < 0.8 * rms_p,
                "{k}: weighted {rms_w:.3e} vs plain {rms_p:.3e}"
            );
            assert!(
                (se / rms_w - 1.0).abs() < 0.2,
                "{k}: reported {se:.3e} vs scatter {rms_w:.3e}"
            );
        }
    }

    #[test]
    fn forgetting_is_once_per_speed() {
        let (_, bearing, points) = bench_case(10);
        let lambda = 0.9;
        let mut est = PedestalRls::<f64>::new(ParameterScale::default(), lambda);
        for (omega, rel, ped) in &points {
            est.update(*omega, ped, &bearing.force(*omega, rel));
        }
        let want = 4.0 * (1.0 - lambda.powi(10)) / (1.0 - lambda);
        assert!((est.estimate().unwrap().equations - want).abs() < 1e-9);
    }

    #[test]
    fn huge_but_valid_phasors_do_not_poison_the_estimate() {
        // A sensitivity 1e-25 of the real one: every phasor 1e25 times too
        // large, the regression's squares far beyond f32. Weighted, the
        // whitening removes the scale; unweighted, the rows are rescaled and
        // counted; both give the pedestal (the data are consistent).
        let (theta, bearing, points) = bench_case(40);
        let big = 1e25;
        let c32 = |c: Complex<f64>| Complex::new((c.re * big) as f32, (c.im * big) as f32);
        let mut weighted = PedestalRls::<f32>::default();
        let mut plain = PedestalRls::<f32>::default();
        for (omega, rel, ped) in &points {
            let (rel, ped) = (rel.map(c32), ped.map(c32));
            let (b, w) = (bearing.cast::<f32>(), *omega as f32);
            let force = b.force(w, &rel);
            let rel_sd = rel.map(|r| 1e-3 * r.norm());
            let ped_sd = ped.map(|p| 1e-3 * p.norm());
            assert_eq!(
                weighted.update_weighted(w, &ped, &rel, &b, rel_sd, ped_sd),
                4
            );
            assert_eq!(plain.update(w, &ped, &force), 4);
        }
        let (w, p) = (weighted.estimate().unwrap(), plain.estimate().unwrap());
        assert_eq!((w.rescaled, w.rejected), (0, 0));
        assert_eq!((p.rescaled, p.rejected), (160, 0));
        for k in 0..5 {
            for (name, e) in [("weighted", &w), ("plain", &p)] {
                let rel = (f64::from(e.theta[k]) - theta[k]).abs() / theta[k];
                assert!(rel < 1e-3, "{name} {k}: {} vs {}", e.theta[k], theta[k]);
                assert!(e.std_err[k].is_finite(), "{name} {k}");
            }
        }
        // A phasor with no usable noise (zero force and pedestal, zero sd) is
        // rejected, not folded in as an empty equation.
        let zero = [Complex::new(0.0f32, 0.0); 2];
        let b = bearing.cast::<f32>();
        assert_eq!(
            weighted.update_weighted(100.0, &zero, &zero, &b, [0.0; 2], [0.0; 2]),
            0
        );
        assert_eq!(weighted.estimate().unwrap().rejected, 4);
    }

    #[test]
    fn standard_errors_allow_for_phasors_sharing_revolutions() {
        // Pedestal-phasor noise as the extractor makes it with one revolution
        // per phasor: white per-revolution noise through the run-down
        // correction (each phasor shares revolutions with its neighbours), of
        // sd sqrt(G)·σ per phasor as the box reports. With φ the reported
        // standard errors match the scatter; the independent-phasor formula
        // would be off by 1/sqrt(φ).
        use crate::extractor::{average_noise_gain, long_run_factor, mid_revolution, SensorKind};
        let kind = SensorKind::Acceleration;
        let gain = average_noise_gain(kind, 1);
        let phi = f64::from(long_run_factor(1, gain));
        let gain = f64::from(gain);
        // A run-down: consecutive phasors at nearby speeds, rows changing
        // slowly (the condition under which φ holds).
        let slow = |i: usize| {
            let a = i as f64;
            [
                Complex::from_polar(1e-6 * (1.0 + 0.5 * (0.02 * a).sin()), 0.01 * a),
                Complex::from_polar(2e-6 * (1.0 + 0.4 * (0.015 * a).cos()), 1.0 - 0.012 * a),
            ]
        };
        let (theta, bearing, points) = bench_case_with(300, slow);
        let mut gauss = crate::testing::Gauss(23);
        let draws = 300;
        let (mut scatter, mut reported) = ([0.0f64; 5], [0.0f64; 5]);
        for _ in 0..draws {
            let mut est = PedestalRls::<f64>::default().with_long_run_factor(phi);
            // Per direction, the revolutions' noise (unit sd), one ahead.
            let unit = |g: &mut crate::testing::Gauss| {
                let n = g.complex(1.0);
                Complex::new(n.re as f32, n.im as f32)
            };
            let mut revs: Vec<[Complex<f32>; 2]> = (0..points.len() + 3)
                .map(|_| [unit(&mut gauss), unit(&mut gauss)])
                .collect();
            revs.truncate(points.len() + 3);
            for (i, (omega, rel, ped)) in points.iter().enumerate() {
                let sigma = ped.map(|p| 0.005 * p.norm());
                let noisy: Phasor2<f64> = core::array::from_fn(|d| {
                    let n = mid_revolution(
                        kind,
                        [Some(revs[i][d]), Some(revs[i + 1][d])],
                        revs[i + 2][d],
                        revs[i + 3][d],
                    );
                    ped[d] + Complex::new(f64::from(n.re), f64::from(n.im)) * sigma[d]
                });
                let ped_sd = sigma.map(|s| s * gain.sqrt());
                est.update_weighted(*omega, &noisy, rel, &bearing, [0.0; 2], ped_sd);
            }
            let e = est.estimate().unwrap();
            for k in 0..5 {
                scatter[k] += (e.theta[k] - theta[k]).powi(2);
                reported[k] += e.std_err[k].powi(2);
            }
        }
        for k in 0..5 {
            let ratio = (reported[k] / scatter[k]).sqrt();
            std::println!(
                "θ{k}: reported/observed {ratio:.3} with φ = {phi:.3}, {:.3} without",
                ratio / phi.sqrt()
            );
            assert!((ratio - 1.0).abs() < 0.15, "{k}: {ratio}");
        }
    }
}
