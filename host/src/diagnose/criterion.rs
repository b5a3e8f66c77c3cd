//! Model selection: is an augmented model's extra physics supported by the
//! data beyond what the measurement noise can explain?
//!
//! The equations are whitened by their propagated noise (`fit::Weights`), so
//! with a right model and right noise the residuals have unit variance. The
//! evidence for a candidate is the Wald statistic of the hypothesis "the extra
//! parameters are zero" (Cθ = 0, q constraints) in the augmented fit:
//!
//! ```text
//! W = (Cθ)ᵀ·(C·V·Cᵀ)⁻¹·(Cθ)
//! ```
//!
//! computed twice and the smaller kept:
//! - with V the covariance implied by the noise floor alone (unit-variance
//!   whitened residuals): for linear terms W then equals the drop in the
//!   weighted residual sum of squares, a χ² test relative to the floor;
//! - with V a heteroskedasticity- and autocorrelation-robust sandwich
//!   covariance (Newey–West, Bartlett kernel over speeds, Andrews' AR(1)
//!   plug-in bandwidth) built from the augmented fit's own residuals. This is
//!   what keeps rounded data honest: rounding errors at neighbouring speeds
//!   are alike (not white), and a smooth regressor projects them coherently;
//!   the robust covariance sees that correlation and any noise beyond the
//!   floor.
//!
//! **Profiled scalars** (a delay, a loss factor, a table's clearance or
//! stiffness ratio: the candidates that add one nonlinear scalar) are
//! tested by the likelihood ratio instead, the drop of the
//! errors-in-variables criterion the profile minimises from the scalar's
//! null to its estimate ([`Inference::evidence_profiled`]); the robust form
//! scales it by the floor-to-robust variance ratio. The Wald statistic is
//! the quadratic approximation of that drop at the estimate, and it is not
//! invariant to how the model is parametrised: where the scalar trades
//! against a linear term at its null and less so away from it, the curvature
//! at the estimate overstates the drop. A delay on a pedestal block 30-50
//! times stiffer than its bearing (unseen-flex's B1) is the case: at τ = 0
//! the delay's column iΩ·D·X is the damping's (iΩ·k·X) but for the small
//! Ω³τm part; at τ = 400 µs the fitted damping is −τ·k (−1.3e6 N·s/m) and
//! the column gains a −Ω²·c·X part no linear term takes. On a clean run
//! (seed 382) the criterion drops by 12.6 from τ = 0 to τ = 485 µs while
//! the Wald statistic at 485 ± 73 µs is 44 (docs/diagnose.md, "Session 36").
//!
//! Under the null, W is asymptotically χ²(q). The p-value of the best
//! candidate is Bonferroni-corrected for the number of candidates tried in the
//! step (every bearing, effect and variant counts). The candidates are ranked
//! by the Schwarz criterion ΔBIC = W − q·ln N (N real equations), which
//! charges each extra parameter; a winner must have ΔBIC > 0 and a corrected
//! p-value below the significance level.

use crate::estimate::pedestal::noise_level;
/// The one long-run (HAC) covariance ([`crate::estimate::serial`]), here
/// for its callers in diagnose.
pub use crate::estimate::serial::long_run_covariance;
use anyhow::{bail, Result};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Parameter covariance of a fit under the noise floor and robustly.
#[derive(Clone, Debug)]
pub struct Inference {
    /// Estimates (linear parameters, then nonlinear scalars), SI units.
    pub estimate: DVector<f64>,
    /// Column norms used to normalise the Jacobian (estimate·norm is O(1)).
    norms: Vec<f64>,
    /// Covariance of the normalised parameters under the noise floor.
    cov_floor: DMatrix<f64>,
    /// Robust (HAC sandwich) covariance of the normalised parameters.
    cov_robust: DMatrix<f64>,
    /// Number of real equations.
    pub rows: usize,
    /// Bartlett bandwidth used (speeds).
    pub bandwidth: f64,
    /// The factor [-] the floor covariance is multiplied by for the reported
    /// ± ([`Self::reported_std_err`]): the one rule
    /// [`crate::estimate::pedestal::NoiseLevel::reported_scale`] of the
    /// whitened residuals' χ² on rows − parameters degrees of freedom.
    reported_scale: f64,
}

/// The evidence for one set of constraints.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Evidence {
    /// Wald statistic relative to the noise floor (χ²).
    pub wald_floor: f64,
    /// Wald statistic with the autocorrelation-robust covariance.
    pub wald_robust: f64,
    /// The statistic used: the smaller of the two.
    pub wald: f64,
    /// Number of constraints (extra parameters) q.
    pub extra_parameters: usize,
    /// ΔBIC = W − q·ln N (positive favours the augmented model).
    pub delta_bic: f64,
    /// χ²(q) upper-tail probability of W.
    pub p_value: f64,
    /// p-value times the number of candidates tried, capped at 1.
    pub p_adjusted: f64,
}

impl Inference {
    /// Builds the covariances from the whitened Jacobian `jac` (rows = real
    /// equations, grouped by speed as given by `row_speed`), the whitened
    /// residual and the estimates.
    pub fn new(
        jac: &DMatrix<f64>,
        residual: &DVector<f64>,
        row_speed: &[usize],
        estimate: DVector<f64>,
    ) -> Result<Self> {
        let (n, p) = jac.shape();
        if n <= p {
            bail!("{n} equations cannot test {p} parameters");
        }
        let norms: Vec<f64> = (0..p)
            .map(|c| jac.column(c).norm().max(f64::MIN_POSITIVE))
            .collect();
        let mut jn = jac.clone();
        for (c, s) in norms.iter().enumerate() {
            jn.column_mut(c).scale_mut(1.0 / s);
        }
        let svd = jn.clone().svd(false, true);
        let vt = svd
            .v_t
            .as_ref()
            .ok_or_else(|| anyhow::anyhow!("SVD failed"))?;
        let smax = svd.singular_values.max();
        let mut inv_s2 = DVector::zeros(p);
        for i in 0..p {
            let s = svd.singular_values[i];
            if s <= 1e-13 * smax {
                bail!("the augmented model's parameters are not separately identifiable (singular Jacobian)");
            }
            inv_s2[i] = 1.0 / (s * s);
        }
        let a_inv = vt.transpose() * DMatrix::from_diagonal(&inv_s2) * vt;
        // Scores per speed, in speed order.
        let mut scores: Vec<DVector<f64>> = Vec::new();
        let mut last = usize::MAX;
        for (i, &j) in row_speed.iter().enumerate() {
            if j != last {
                scores.push(DVector::zeros(p));
                last = j;
            }
            if let Some(g) = scores.last_mut() {
                *g += jn.row(i).transpose() * residual[i];
            }
        }
        let (mut s, bandwidth) = long_run_covariance(&scores, p);
        s *= n as f64 / (n - p) as f64;
        let cov_robust = &a_inv * s * &a_inv;
        let reported_scale = noise_level(residual.norm_squared(), n - p, false).reported_scale();
        Ok(Self {
            estimate,
            norms,
            cov_floor: a_inv,
            cov_robust,
            rows: n,
            bandwidth,
            reported_scale,
        })
    }

    /// Standard error of parameter `i` [its SI unit]: the larger of the
    /// floor and robust values.
    pub fn std_err(&self, i: usize) -> f64 {
        self.cov_floor[(i, i)].max(self.cov_robust[(i, i)]).sqrt() / self.norms[i]
    }

    /// Standard error of parameter `i` as reported [its SI unit]: the
    /// larger of the floor value at the level the residuals show where they
    /// scatter significantly less than the noise floor says (the floor
    /// variance times `reported_scale`) and the robust value. The tests
    /// ([`Self::evidence`], the held-damping rule) keep [`Self::std_err`].
    ///
    /// Why: the floor is an upper bound by design (digits taken as
    /// truncated); on rigid ground at 3 digits it left every reported ±
    /// about 2 times too wide (RMS z 0.2-0.5, docs/diagnose-accuracy.md ("Session 39")).
    pub fn reported_std_err(&self, i: usize) -> f64 {
        (self.reported_scale * self.cov_floor[(i, i)])
            .max(self.cov_robust[(i, i)])
            .sqrt()
            / self.norms[i]
    }

    /// Standard error of a linear combination cᵀθ [SI].
    pub fn std_err_of(&self, c: &[f64]) -> f64 {
        let (f, r) = self.variances_of(c);
        f.max(r).sqrt()
    }

    /// Standard error of a linear combination cᵀθ as reported [SI]: the
    /// rule of [`Self::reported_std_err`] (the floor at the residuals'
    /// level, or the robust value, the larger), so a value derived from
    /// reported parameters (a pedestal's f_n, ζ) has the ± they have.
    pub fn reported_std_err_of(&self, c: &[f64]) -> f64 {
        let (f, r) = self.variances_of(c);
        (self.reported_scale * f).max(r).sqrt()
    }

    /// cᵀθ's variance [SI²] under the noise floor and robustly.
    fn variances_of(&self, c: &[f64]) -> (f64, f64) {
        let cn = DVector::from_iterator(c.len(), c.iter().zip(&self.norms).map(|(a, s)| a / s));
        let f = (cn.transpose() * &self.cov_floor * &cn)[(0, 0)];
        let r = (cn.transpose() * &self.cov_robust * &cn)[(0, 0)];
        (f, r)
    }

    /// Variance [SI²] of the change g(θ̂_a) − g(θ̂_b) of a function g
    /// between two models that are both this fit's model (θ) with some
    /// parameters held at zero, fitted to the same data with the same
    /// weights, under the noise floor, to first order at both ends: model
    /// a lacks θ's parameters `absent_a`, model b lacks `absent_b`
    /// (indices into θ), `c_a` is ∇g at θ̂_a and `c_b` ∇g at θ̂_b (θ's
    /// indexing; their absent entries ignored). In a weighted linear fit a
    /// model without the parameters R has the estimate θ̂ moved along its
    /// regression on θ̂_R to θ_R = 0, θ̂ − C_{·R}·C_RR⁻¹·θ̂_R, so the change
    /// is uᵀθ̂ with u = c_a − c_b − E_aᵀC_aa⁻¹(C·c_a)_a + E_bᵀC_bb⁻¹(C·c_b)_b
    /// (E_x the rows of `absent_x`), and its variance is uᵀ·C·u (C the
    /// floor covariance). A step that adds γ to model b is a = θ, b = θ
    /// without γ: with c_b = c_a = c this is wᵀC_γγ⁻¹w, w = Cov(γ̂, cᵀθ̂)
    /// (the difference of the two fits' variances of cᵀθ̂, Hausman's
    /// identity); where g bends between the two estimates (c_b ≠ c_a) the
    /// shared parameters' own noise enters through c_a − c_b; with both
    /// absent sets empty (a group both models fit alike) that is all of it,
    /// uᵀCu with u = c_a − c_b. `None` when an index is out of range or a
    /// block is singular.
    pub fn floor_change_variance(
        &self,
        c_a: &[f64],
        c_b: &[f64],
        absent_a: &[usize],
        absent_b: &[usize],
    ) -> Option<f64> {
        let p = self.norms.len();
        if c_a.len() != p || c_b.len() != p || absent_a.iter().chain(absent_b).any(|&i| i >= p) {
            return None;
        }
        // Normalised gradient, zero on the model's absent parameters.
        let scaled = |v: &[f64], absent: &[usize]| {
            let mut out = DVector::from_iterator(p, v.iter().zip(&self.norms).map(|(a, s)| a / s));
            for &i in absent {
                out[i] = 0.0;
            }
            out
        };
        // E_Rᵀ·C_RR⁻¹·(C·c)_R: the gradient's part carried by the held
        // parameters' regression.
        let carried = |c: &DVector<f64>, absent: &[usize]| -> Option<DVector<f64>> {
            let mut out = DVector::zeros(p);
            if absent.is_empty() {
                return Some(out);
            }
            let block = DMatrix::from_fn(absent.len(), absent.len(), |r, k| {
                self.cov_floor[(absent[r], absent[k])]
            });
            let w_all = &self.cov_floor * c;
            let w = DVector::from_iterator(absent.len(), absent.iter().map(|&i| w_all[i]));
            let shift = block.try_inverse()? * w;
            for (k, &i) in absent.iter().enumerate() {
                out[i] = shift[k];
            }
            Some(out)
        };
        let (ca, cb) = (scaled(c_a, absent_a), scaled(c_b, absent_b));
        let u = &ca - &cb - carried(&ca, absent_a)? + carried(&cb, absent_b)?;
        let v = (u.transpose() * &self.cov_floor * &u)[(0, 0)];
        v.is_finite().then_some(v.max(0.0))
    }

    /// Evidence against the constraints C·θ = 0 (rows of `c`, one per
    /// constraint, over the parameter vector), with `candidates` tried in the
    /// step and `n_total` real equations for the BIC penalty.
    pub fn evidence(
        &self,
        c: &DMatrix<f64>,
        candidates: usize,
        n_total: usize,
    ) -> Result<Evidence> {
        let q = c.nrows();
        let mut cn = c.clone();
        for (j, s) in self.norms.iter().enumerate() {
            cn.column_mut(j).scale_mut(1.0 / s);
        }
        let theta_n = DVector::from_iterator(
            self.norms.len(),
            self.estimate.iter().zip(&self.norms).map(|(t, s)| t * s),
        );
        let ct = &cn * theta_n;
        let wald = |cov: &DMatrix<f64>| -> Result<f64> {
            let m = &cn * cov * cn.transpose();
            let inv = m
                .clone()
                .try_inverse()
                .ok_or_else(|| anyhow::anyhow!("singular covariance of the extra parameters"))?;
            Ok((ct.transpose() * inv * &ct)[(0, 0)])
        };
        let wald_floor = wald(&self.cov_floor)?;
        let wald_robust = wald(&self.cov_robust)?;
        Ok(Evidence::of(
            wald_floor,
            wald_robust,
            q,
            candidates,
            n_total,
        ))
    }

    /// Evidence against the constraints `c` ([`Self::evidence`]'s
    /// arguments) by the likelihood ratio `lr`: the drop of the
    /// errors-in-variables criterion (`super::fit::gauss_helmert_rss`) from
    /// the fit under the constraints to this one [χ²]. Used where the
    /// group holds a profiled scalar: its own null
    /// (`super::fit::scalar_drop`: from the scalar's null to its estimate,
    /// the linear parameters refitted at both) or held dampings freed
    /// beside it (`super::forward::freed_held`). The floor statistic is
    /// `lr`; the robust one is `lr` times the floor-to-robust ratio of the
    /// two Wald forms, so autocorrelated or excess noise discounts it as it
    /// does the Wald statistic (module docs, "Profiled scalars").
    pub fn evidence_profiled(
        &self,
        c: &DMatrix<f64>,
        lr: f64,
        candidates: usize,
        n_total: usize,
    ) -> Result<Evidence> {
        let quadratic = self.evidence(c, candidates, n_total)?;
        let lr = lr.max(0.0);
        let ratio = if quadratic.wald_floor > 0.0 {
            quadratic.wald_robust / quadratic.wald_floor
        } else {
            1.0
        };
        Ok(Evidence::of(
            lr,
            lr * ratio,
            quadratic.extra_parameters,
            candidates,
            n_total,
        ))
    }
}

impl Evidence {
    /// The evidence of a floor and a robust statistic (χ²(`q`)), the smaller
    /// used, Bonferroni over `candidates`, the Schwarz penalty q·ln N with
    /// `n_total` real equations.
    fn of(floor: f64, robust: f64, q: usize, candidates: usize, n_total: usize) -> Self {
        let w = floor.min(robust);
        let p_value = chi2_sf(w, q);
        Self {
            wald_floor: floor,
            wald_robust: robust,
            wald: w,
            extra_parameters: q,
            delta_bic: w - q as f64 * (n_total as f64).ln(),
            p_value,
            p_adjusted: (p_value * candidates.max(1) as f64).min(1.0),
        }
    }
}

/// Upper tail P(χ²(q) > w).
pub fn chi2_sf(w: f64, q: usize) -> f64 {
    if w.is_nan() || w <= 0.0 {
        return 1.0;
    }
    match ChiSquared::new(q.max(1) as f64) {
        Ok(d) => d.sf(w),
        Err(_) => f64::NAN,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Under the null (white unit noise, extra regressor with no effect) the
    /// Wald statistic is χ²(1): its rejection rate at 5 % is near 5 %.
    #[test]
    fn wald_has_the_right_size_under_white_noise() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let (n, trials) = (200, 400);
        let mut rejections = 0;
        for _ in 0..trials {
            let mut j = DMatrix::zeros(n, 2);
            let mut y = DVector::zeros(n);
            for i in 0..n {
                let s = i as f64 / n as f64;
                j[(i, 0)] = 1.0;
                j[(i, 1)] = (6.0 * s).sin();
                y[i] = 2.0 + rng.sample::<f64, _>(rand_distr::StandardNormal);
            }
            let (beta, r, _) = crate::diagnose::fit::solve_normalised(&j, &y).unwrap();
            let rows: Vec<usize> = (0..n).collect();
            let inf = Inference::new(&j, &r, &rows, beta).unwrap();
            let c = DMatrix::from_row_slice(1, 2, &[0.0, 1.0]);
            let ev = inf.evidence(&c, 1, n).unwrap();
            if ev.p_value < 0.05 {
                rejections += 1;
            }
        }
        let rate = rejections as f64 / trials as f64;
        assert!(rate < 0.09, "false rejection rate {rate}");
    }

    /// Strongly autocorrelated noise fools the floor test but not the robust one.
    #[test]
    fn robust_wald_discounts_correlated_noise() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let n = 400;
        let mut e = 0.0;
        let mut j = DMatrix::zeros(n, 2);
        let mut y = DVector::zeros(n);
        for i in 0..n {
            e = 0.95 * e + 0.3 * rng.sample::<f64, _>(rand_distr::StandardNormal);
            j[(i, 0)] = 1.0;
            j[(i, 1)] = (i as f64 / 60.0).sin();
            y[i] = e;
        }
        let (beta, r, _) = crate::diagnose::fit::solve_normalised(&j, &y).unwrap();
        let rows: Vec<usize> = (0..n).collect();
        let inf = Inference::new(&j, &r, &rows, beta).unwrap();
        let ev = inf
            .evidence(&DMatrix::from_row_slice(1, 2, &[0.0, 1.0]), 1, n)
            .unwrap();
        assert!(ev.wald_robust < ev.wald_floor, "{ev:?}");
        assert!(ev.wald <= ev.wald_robust);
    }

    #[test]
    fn chi2_tail_values() {
        assert!((chi2_sf(3.841_458_820_694_124, 1) - 0.05).abs() < 1e-9);
        assert!((chi2_sf(5.991_464_547_107_979, 2) - 0.05).abs() < 1e-9);
        assert_eq!(chi2_sf(0.0, 1), 1.0);
    }

    /// The change variance of nested linear fits is the difference of
    /// their floor variances (Hausman's identity): a 4-parameter fit
    /// against its first 2 parameters, with no residual (so the robust
    /// covariance is zero and `std_err_of` is the floor's).
    #[test]
    fn the_change_variance_of_nested_fits_is_the_difference_of_their_variances() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let n = 60;
        let big = DMatrix::from_fn(n, 4, |_, _| rng.random_range(-1.0..1.0));
        let small = big.columns(0, 2).into_owned();
        let speeds: Vec<usize> = (0..n).collect();
        let zero = DVector::zeros(n);
        let a = Inference::new(&big, &zero, &speeds, DVector::zeros(4)).expect("big");
        let b = Inference::new(&small, &zero, &speeds, DVector::zeros(2)).expect("small");
        let c = [0.7, -1.3, 2.0, 0.4];
        let want = a.std_err_of(&c).powi(2) - b.std_err_of(&c[..2]).powi(2);
        let got = a
            .floor_change_variance(&c, &c, &[], &[2, 3])
            .expect("variance");
        assert!(want > 0.0);
        assert!((got - want).abs() < 1e-9 * want, "{got} vs {want}");
        // Only the added parameters' direction counts: with one of them
        // called shared the answer differs.
        let other = a
            .floor_change_variance(&c, &c, &[], &[3])
            .expect("variance");
        assert!((other - want).abs() > 1e-3 * want);
    }

    /// Where the function bends between the two estimates (its gradient
    /// `c0` at the smaller model's differs from `c` at the larger one's),
    /// the change cᵀθ̂ − c0ᵀθ̂₀ of two nested linear fits to the same unit
    /// white noise has the variance ‖A_aᵀc − A_bᵀc0‖² (A = (JᵀJ)⁻¹Jᵀ of
    /// each fit), which the same-gradient formula misses.
    #[test]
    fn the_change_variance_counts_the_gradient_at_both_ends() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let n = 60;
        let big = DMatrix::from_fn(n, 4, |_, _| rng.random_range(-1.0..1.0));
        let small = big.columns(0, 2).into_owned();
        let speeds: Vec<usize> = (0..n).collect();
        let a = Inference::new(&big, &DVector::zeros(n), &speeds, DVector::zeros(4)).expect("a");
        let pinv =
            |j: &DMatrix<f64>| (j.transpose() * j).try_inverse().expect("inverse") * j.transpose();
        let c = DVector::from_vec(vec![0.7, -1.3, 2.0, 0.4]);
        let c0 = DVector::from_vec(vec![1.5, 0.2]);
        let u = pinv(&big).transpose() * &c - pinv(&small).transpose() * &c0;
        let want = u.norm_squared();
        let c0_full = [c0[0], c0[1], 0.0, 0.0];
        let got = a
            .floor_change_variance(c.as_slice(), &c0_full, &[], &[2, 3])
            .expect("variance");
        assert!((got - want).abs() < 1e-9 * want, "{got} vs {want}");
        let same = a
            .floor_change_variance(c.as_slice(), c.as_slice(), &[], &[2, 3])
            .expect("variance");
        // The gradient at one end only misses the shared parameters' noise.
        assert!((same - want).abs() > 0.1 * want, "{same} vs {want}");
    }

    /// Two models that are neither nested (each lacks a parameter of the
    /// other, as a delay named with a damping held at zero against the
    /// model with the damping free): the change cᵀθ̂_a − c0ᵀθ̂_b of their
    /// linear fits to the same unit white noise has the variance
    /// ‖A_aᵀc − A_bᵀc0‖², from the union model's covariance.
    #[test]
    fn the_change_variance_of_two_restrictions_of_one_fit_is_exact() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let n = 50;
        let union = DMatrix::from_fn(n, 4, |_, _| rng.random_range(-1.0..1.0));
        let pick = |cols: [usize; 3]| DMatrix::from_fn(n, 3, |r, k| union[(r, cols[k])]);
        let (ja, jb) = (pick([0, 1, 2]), pick([0, 1, 3]));
        let pinv =
            |j: &DMatrix<f64>| (j.transpose() * j).try_inverse().expect("inverse") * j.transpose();
        let (ca, cb) = ([0.4, -0.9, 1.7], [1.1, -0.5, 0.8]);
        let u = pinv(&ja).transpose() * DVector::from_row_slice(&ca)
            - pinv(&jb).transpose() * DVector::from_row_slice(&cb);
        let want = u.norm_squared();
        let inf = Inference::new(
            &union,
            &DVector::zeros(n),
            &(0..n).collect::<Vec<_>>(),
            DVector::zeros(4),
        )
        .expect("union");
        let got = inf
            .floor_change_variance(
                &[ca[0], ca[1], ca[2], 0.0],
                &[cb[0], cb[1], 0.0, cb[2]],
                &[3],
                &[2],
            )
            .expect("variance");
        assert!((got - want).abs() < 1e-9 * want, "{got} vs {want}");
    }
}
