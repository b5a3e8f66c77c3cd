//! Noise correlated along the run: its measure, the long-run (HAC)
//! covariance of a series of scores, and the standard errors widened for it.
//!
//! **Why.** A fit weighs each speed's phasors by their own noise and takes
//! the noise of different speeds as independent ([`super::noise`]). A
//! tracking filter whose time constant is longer than the time between
//! stored vectors (a fine logging step on a fast run-down) makes the noise
//! of neighbouring speeds alike: along the run it is an AR(1) of lag-one
//! correlation ρ. A smooth parameter averages the noise over the run, and
//! the variance of a mean of an AR(1) is (1 + ρ)/(1 − ρ) times the white
//! one: at ρ = 0.8 the honest ± is three times the fit's own (measured on
//! ROSS unseen-eight `corr-noise`: RMS z 1.9-3.9, `ok` beyond 3 ± in 9 of
//! 23 runs, docs/unseen-eight.md finding 1).
//!
//! **Measure** ([`lag_one_correlation`]). The whitened residuals w_t (one
//! real 4-vector per speed, in speed order) are noise in units of its own
//! sd where the model fits. Each component is first cleared of a
//! Legendre polynomial of degree [`DETREND_DEGREE`] over the run (a broad
//! model error, smooth over the whole run, is not the noise's correlation),
//! then ρ̂ = Σ_t Σ_c w_{t,c}w_{t−1,c} / Σ_t Σ_c w_{t,c}² pooled over the four
//! components. It is taken as there when it exceeds the one-sided
//! [`SERIAL_P`] quantile of the same figure over white residuals of as
//! many speeds ([`white_quantile`]: simulated, a fixed seed, the
//! detrending included), so that a run of white noise keeps its ± exactly
//! in all but [`SERIAL_P`] of bearings. The detrending takes some of the
//! AR(1)'s low-frequency power with the trend, so ρ̂ is biased low (376
//! speeds at ρ = 0.80: 0.777 expected; 50 speeds: 0.59): the AR(1)'s ρ
//! the widening (and the delay's linearisation,
//! [`super::lack_of_fit::delay_unknown`]) use is the one whose expected ρ̂
//! is the measured one ([`ar1_rho`], the expectation in closed form to
//! second order, [`expected_lag_one`]); the lack-of-fit tests take ρ̂ as
//! it is (a local model error's residual is correlated too, and the
//! larger ρ would take it for noise).
//!
//! **Widening** ([`ar1_widening`]). With the noise an AR(1) of lag-one
//! correlation ρ along the run (the same for every whitened component, as
//! a filter common to the channels makes it), the fit's estimate has the
//! sandwich covariance H⁻¹MH⁻¹, H = Σ_t J_tᵀJ_t and M = Σ_t Σ_s ρ^|t−s|
//! J_tᵀJ_s (J_t speed t's whitened Jacobian): the long-run covariance of the
//! scores J_tᵀw_t under that AR(1), the parametric (prewhitened) form of
//! [`long_run_covariance`]. Each parameter's ± is widened by
//! √((H⁻¹MH⁻¹)_kk/(H⁻¹)_kk) ≥ 1. The form is chosen over the Bartlett
//! kernel of the scores themselves because it does not square residuals:
//! with 40-60 speeds (some machines) a kernel estimate of a long-run
//! variance is itself noisy, and the Bartlett kernel with Andrews'
//! bandwidth is biased low at ρ = 0.8 (docs/estimation-scatter.md, Session
//! 48).
//!
//! **The structure test** ([`prewhitened`]): the lack-of-fit scan's null
//! (blocks of speeds shuffled) keeps a correlation shorter than a block
//! only; a correlation of ρ = 0.8 lasts longer and the scan took it for a
//! smooth model error. Where ρ̂ is there, the scan is made on the residuals
//! prewhitened by it, (w_t − ρ̂w_{t−1})/√(1 − ρ̂²), white under the AR(1),
//! while a model error smooth in speed stays smooth (damped by the factor
//! √((1 − ρ̂)/(1 + ρ̂)) against the noise: what the correlation costs in
//! power).
//!
//! **diagnose** (`crate::diagnose::ml_final::serial`): the final fit's
//! equations (4 real rows per bearing and speed, a group of bearings at
//! once) are measured by the same rule ([`measured_equations`], ρ̂ pooled
//! over all of a speed's rows, its white limit and the bias removal for as
//! many components), its inference made on the equations prewhitened by the
//! AR(1)'s ρ ([`prewhitened_equations_of`]) with each parameter's ± scaled
//! from the generalised fit's to the sandwich of the white fit's values
//! ([`ar1_gls_widening`]): the values diagnose reports are the white fit's.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

mod bias;
mod long_run;
mod measure;

pub use bias::{ar1_rho, ar1_rho_of};
pub use long_run::long_run_covariance;
pub use measure::{lag_one_correlation, lag_one_of, white_quantile, white_quantile_of};

/// One-sided size of the test "the residuals are correlated along the run"
/// [-]: a white run's ± are widened in this share of bearings.
pub const SERIAL_P: f64 = 0.01;

/// Degree of the Legendre polynomial over the run cleared from each
/// whitened component before its lag-one correlation is measured.
pub const DETREND_DEGREE: usize = 3;

/// White-noise draws that set [`white_quantile`].
pub const WHITE_DRAWS: usize = 400;

/// Fewest speeds on which a correlation is measured.
pub const MIN_SPEEDS: usize = 12;

/// Largest lag-one correlation used [-]: beyond it the residuals are a
/// trend, not noise, and (1 + ρ)/(1 − ρ) would be set by the trend.
pub const MAX_RHO: f64 = 0.95;

/// The residuals' correlation along the run as measured and used
/// (`identify --json`: `noise.<bearing>.serial_correlation`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SerialCorrelation {
    /// The lag-one correlation of the whitened residuals along the run
    /// (speed order, each component detrended) [-].
    pub lag_one: f64,
    /// Its one-sided [`SERIAL_P`] quantile for white residuals of as many
    /// speeds [-]: above it the correlation is taken as there.
    pub white_limit: f64,
    /// The AR(1)'s lag-one correlation that `lag_one` implies once the
    /// detrending's bias is removed ([`ar1_rho`]; at most [`MAX_RHO`]) [-]:
    /// what the widening and the lack-of-fit tests use.
    #[serde(default)]
    pub ar1_rho: f64,
    /// Speeds it was measured on.
    pub speeds: usize,
    /// Each parameter's ± widened by this factor (k_y, k_z, m, c_y, c_z; 1
    /// for a fixed one) [-]: √((1 + ρ)/(1 − ρ)) for a parameter the run
    /// averages, less for one a few speeds carry.
    pub widening: [f64; 5],
}

/// The correlation of `rows` at `speeds_hz` when it is there (ρ̂ above its
/// white limit), as (the AR(1)'s ρ that ρ̂ implies, [`ar1_rho`], at most
/// [`MAX_RHO`]; ρ̂; the limit); `None` when it is not or cannot be
/// measured.
pub fn measured(speeds_hz: &[f64], rows: &[[f64; 4]]) -> Option<(f64, f64, f64)> {
    measured_of(speeds_hz, rows.as_flattened(), 4)
}

/// [`measured`] of `rows` flat, `width` real components per speed: ρ̂
/// pooled over all of them, its white limit and the bias removal for as
/// many ([`lag_one_of`], [`white_quantile_of`], [`ar1_rho_of`]).
pub fn measured_of(speeds_hz: &[f64], rows: &[f64], width: usize) -> Option<(f64, f64, f64)> {
    let rho = lag_one_of(speeds_hz, rows, width)?;
    let limit = white_quantile_of(speeds_hz, width);
    (rho > limit).then(|| (ar1_rho_of(speeds_hz, rho, width), rho, limit))
}

/// [`measured_of`] on whitened equations' residual `resid` (speed order,
/// the same number of real rows at each of `speeds_hz` [Hz], a group's
/// 4 rows per bearing): (ρ, ρ̂, the limit); `None` where the correlation is
/// not there, cannot be measured, or the rows do not divide into the
/// speeds.
pub fn measured_equations(speeds_hz: &[f64], resid: &DVector<f64>) -> Option<(f64, f64, f64)> {
    let n = speeds_hz.len();
    if n == 0 || !resid.len().is_multiple_of(n) {
        return None;
    }
    measured_of(speeds_hz, resid.as_slice(), resid.len() / n)
}

/// The largest factor by which an AR(1) noise of lag-one correlation
/// `rho` [-] along the run inflates the variance of a projection of the
/// residuals on a column smooth in speed, over the white noise's: its
/// spectrum at frequency zero, (1 + ρ)/(1 − ρ) [-].
pub fn long_run_factor(rho: f64) -> f64 {
    (1.0 + rho) / (1.0 - rho)
}

/// Upper-tail p-value of a fit's χ² = `chi2` on `dof` [-] when its
/// whitened residuals are an AR(1) of lag-one correlation `rho` along the
/// run [-]: the mean of χ² stays dof, its variance grows by
/// F = (1 + ρ²)/(1 − ρ²) (Σ_{t,s} ρ^{2|t−s|} per term), so χ²/F is taken
/// as χ²(dof/F) (Satterthwaite); `rho` 0 gives the plain χ²(dof) tail.
pub fn level_p(chi2: f64, dof: usize, rho: f64) -> f64 {
    let f = (1.0 + rho * rho) / (1.0 - rho * rho);
    statrs::distribution::ChiSquared::new(dof as f64 / f)
        .map(|d| 1.0 - statrs::distribution::ContinuousCDF::cdf(&d, chi2 / f))
        .unwrap_or(f64::NAN)
}

/// One whitened figure `x` of a speed prewhitened by the AR(1) of lag-one
/// correlation `rho` [-] given the same figure `previous` of the speed
/// before: (x − ρ·previous)/√(1 − ρ²).
fn prewhiten(x: f64, previous: f64, rho: f64) -> f64 {
    (x - rho * previous) / (1.0 - rho * rho).sqrt()
}

/// `rows` (speed order) prewhitened by the AR(1) of lag-one correlation
/// `rho` [-]: (w_t − ρw_{t−1})/√(1 − ρ²), the first row as it is.
pub fn prewhitened(rows: &[[f64; 4]], rho: f64) -> Vec<[f64; 4]> {
    rows.iter()
        .enumerate()
        .map(|(t, r)| {
            if t == 0 {
                *r
            } else {
                std::array::from_fn(|c| prewhiten(r[c], rows[t - 1][c], rho))
            }
        })
        .collect()
}

/// Whitened equations (4 rows per speed, speed order: a Jacobian or a
/// residual, any number of columns) prewhitened by the AR(1) of lag-one
/// correlation `rho` [-] as [`prewhitened`] does the residuals: each row
/// of speed t less ρ times the same row of speed t − 1, over √(1 − ρ²);
/// the first speed's rows as they are. A least-squares fit of the
/// prewhitened equations is the generalised one under the AR(1) (its ±
/// the AR(1)'s, its likelihood ratios the AR(1)'s).
pub fn prewhitened_equations(m: &DMatrix<f64>, rho: f64) -> DMatrix<f64> {
    prewhitened_equations_of(m, 4, rho)
}

/// [`prewhitened_equations`] with `rows_per_speed` real rows per speed (a
/// group's 4 per bearing).
pub fn prewhitened_equations_of(m: &DMatrix<f64>, rows_per_speed: usize, rho: f64) -> DMatrix<f64> {
    let mut out = m.clone();
    for r in rows_per_speed..m.nrows() {
        for c in 0..m.ncols() {
            out[(r, c)] = prewhiten(m[(r, c)], m[(r - rows_per_speed, c)], rho);
        }
    }
    out
}

/// Per column of the whitened Jacobian `jac` (4 rows per speed, speed
/// order), the factor √((H⁻¹MH⁻¹)_kk/(H⁻¹)_kk) ≥ 1 by which its standard
/// error grows when the noise is an AR(1) of lag-one correlation `rho`
/// along the run (module docs) [-]; `None` when H is singular.
pub fn ar1_widening(jac: &DMatrix<f64>, rho: f64) -> Option<Vec<f64>> {
    ar1_widening_of(jac, 4, rho)
}

/// The sandwich covariance H⁻¹MH⁻¹ of the white fit whose whitened
/// Jacobian is `jac` (`rows_per_speed` real rows per speed, speed order)
/// under an AR(1) of lag-one correlation `rho` [-] along the run (module
/// docs), and H⁻¹; `None` when H is singular or `jac`'s rows do not divide
/// into speeds. In the parameters' units squared.
fn ar1_sandwich(
    jac: &DMatrix<f64>,
    rows_per_speed: usize,
    rho: f64,
) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
    let p = jac.ncols();
    let r = rows_per_speed;
    if r == 0 || !jac.nrows().is_multiple_of(r) {
        return None;
    }
    let n = jac.nrows() / r;
    let h = jac.tr_mul(jac);
    let inv = h.try_inverse()?;
    // F_t = J_t + ρF_{t−1}: Σ_{s ≤ t} ρ^{t−s}J_s; M = Σ_t (J_tᵀF_t + F_tᵀJ_t − J_tᵀJ_t).
    let mut f = DMatrix::<f64>::zeros(r, p);
    let mut m = DMatrix::<f64>::zeros(p, p);
    for t in 0..n {
        let jt = jac.rows(r * t, r);
        f = jt + f * rho;
        let cross = jt.tr_mul(&f);
        m += &cross + cross.transpose() - jt.tr_mul(&jt);
    }
    Some((&inv * m * &inv, inv))
}

/// [`ar1_widening`] with `rows_per_speed` real rows per speed (a group's 4
/// per bearing).
pub fn ar1_widening_of(jac: &DMatrix<f64>, rows_per_speed: usize, rho: f64) -> Option<Vec<f64>> {
    let (v, inv) = ar1_sandwich(jac, rows_per_speed, rho)?;
    (0..jac.ncols())
        .map(|k| {
            let r = v[(k, k)] / inv[(k, k)];
            r.is_finite().then(|| r.max(1.0).sqrt())
        })
        .collect()
}

/// Per column of the whitened Jacobian `jac` (`rows_per_speed` real rows
/// per speed, speed order), the factor √((H⁻¹MH⁻¹)_kk/(J̃ᵀJ̃)⁻¹_kk) ≥ 1 [-]
/// from the ± of the generalised fit under an AR(1) of lag-one correlation
/// `rho` (J̃ the equations prewhitened by it, [`prewhitened_equations_of`])
/// to the sandwich ± of the white fit's values under the same AR(1)
/// ([`ar1_widening_of`]'s numerator): an inference made on the prewhitened
/// equations whose values are the white fit's is scaled by it. The
/// generalised fit is the efficient one, so the factor is at least 1; for
/// parameters smooth over a long run it is close to 1 (the white fit of a
/// smooth regression is nearly efficient under a stationary noise). `None`
/// where a matrix is singular.
pub fn ar1_gls_widening(jac: &DMatrix<f64>, rows_per_speed: usize, rho: f64) -> Option<Vec<f64>> {
    let (v, _) = ar1_sandwich(jac, rows_per_speed, rho)?;
    let jt = prewhitened_equations_of(jac, rows_per_speed, rho);
    let gls = jt.tr_mul(&jt).try_inverse()?;
    (0..jac.ncols())
        .map(|k| {
            let r = v[(k, k)] / gls[(k, k)];
            r.is_finite().then(|| r.max(1.0).sqrt())
        })
        .collect()
}

/// [`measured`] on the whitened residuals of the fit at `theta` (θ units)
/// to `obs` (speed order) over the estimated `columns` under `weighting`,
/// with the fit's whitened Jacobian: (ρ, ρ̂, its white limit, J); `None`
/// where the correlation is not there or cannot be measured.
pub fn measured_fit(
    obs: &[super::Observation],
    theta: &[f64; plinth_shared::regression::PARAMETERS],
    columns: &[plinth_shared::regression::Parameter],
    weighting: &super::ml::Weighting,
) -> Option<(f64, f64, f64, DMatrix<f64>)> {
    let (w, jac) = super::robust::whitened_jacobian(obs, theta, columns, weighting)?;
    let speeds: Vec<f64> = obs.iter().map(|o| o.speed_hz).collect();
    let rows: Vec<[f64; 4]> = (0..obs.len())
        .map(|t| std::array::from_fn(|c| w[4 * t + c]))
        .collect();
    let (rho, lag_one, white_limit) = measured(&speeds, &rows)?;
    Some((rho, lag_one, white_limit, jac))
}

/// The correlation along the run of the residuals of the fit at `theta`
/// (θ units) to `obs` (speed order) over the estimated `columns`, with an
/// equation error of variance `equation_var` [N²] (module docs): `None` when
/// it is not there (within its white limit), cannot be measured, or the
/// Jacobian fails; else its figures and the widening of each parameter's ±.
pub fn assess(
    obs: &[super::Observation],
    theta: &[f64; plinth_shared::regression::PARAMETERS],
    columns: &[plinth_shared::regression::Parameter],
    equation_var: f64,
) -> Option<SerialCorrelation> {
    let weighting = super::ml::Weighting::equation_error(equation_var);
    let (rho, lag_one, white_limit, jac) = measured_fit(obs, theta, columns, &weighting)?;
    let factors = ar1_widening(&jac, rho)?;
    let mut widening = [1.0; 5];
    for (&c, f) in columns.iter().zip(&factors) {
        widening[c as usize] = *f;
    }
    Some(SerialCorrelation {
        lag_one,
        white_limit,
        ar1_rho: rho,
        speeds: obs.len(),
        widening,
    })
}

impl SerialCorrelation {
    /// `covariance` (θ units squared) with each parameter's row and column
    /// scaled by its widening: the correlations kept.
    pub fn widen(&self, covariance: &mut [[f64; 5]; 5]) {
        for (i, row) in covariance.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v *= self.widening[i] * self.widening[j];
            }
        }
    }

    /// The largest widening over the parameters [-].
    pub fn largest_widening(&self) -> f64 {
        self.widening.iter().copied().fold(1.0, f64::max)
    }

    /// What identify says of it.
    pub fn message(&self) -> String {
        let (measured, rho) = (self.lag_one, self.ar1_rho);
        format!(
            "the noise is correlated along the run: lag-one ρ̂ = {measured:.2} measured on the whitened residuals over {} speeds (above {:.2}, its {} % limit for white noise), an AR(1) of ρ = {rho:.2} once the detrending's bias is removed from it. Neighbouring speeds do not average out as independent ones: the ± are widened ×{:.2} at most (the long-run covariance of the AR(1) of ρ = {rho:.2} along the run) and the sensor-delay nuisance is fitted on the equations prewhitened by ρ = {rho:.2}; the lack-of-fit tests allow for the measured ρ̂ = {measured:.2} (χ² on the degrees of freedom it leaves, the scan on the residuals prewhitened by ρ̂, the support-mode and sensor-delay scores deflated by (1 + ρ̂)/(1 − ρ̂))",
            self.speeds,
            self.white_limit,
            100.0 * SERIAL_P,
            self.largest_widening(),
        )
    }
}

#[cfg(test)]
mod tests;
