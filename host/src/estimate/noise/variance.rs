//! The variance function of a bearing's noise, estimated from a converged
//! pedestal fit's own residuals (Carroll & Ruppert, "Transformation and
//! Weighting in Regression", ch. 3: pseudo-likelihood estimation of a
//! variance function).
//!
//! **Why.** The scatter between neighbouring speeds ([`super::Scatter`])
//! knows two laws per channel: one sd at every speed, or an sd proportional
//! to the phasor's magnitude. A real probe's noise is a mix of both (a
//! fraction of the signal plus a floor). Under the proportional law the
//! readings of small amplitude (far from a resonance, where a channel's
//! magnitude falls by 100–1000×) are given a noise far below their floor: the
//! fit treats them as nearly exact, and its ± are too small (issue 17,
//! docs/trust-noise-law.md "Heteroscedastic noise without noise columns").
//!
//! **Model.** Per complex channel ch (rel y, rel z, ped y, ped z) each real
//! part has the variance v = α_ch·|X_ch|² + β_ch [m²] (α [-], β [m²], both ≥ 0),
//! which contains both scatter laws; the [`Family::VelocityFloor`] adds
//! γ_ch/Ω² (γ [m²/s²], Ω [rad/s]): a velocity pick-up's floor integrated to
//! displacement, largest at low speed, which neither α nor β can take
//! (noise columns on trial, [`super::columns`]). At a converged fit θ̂ the residual e_s
//! of a speed's four real equations has the covariance
//! Σ_s = Σ_ch (α_ch·|X_ch,s|² + β_ch)·G_s,ch, where G_s,ch is the covariance
//! the unit variance of channel ch's two real numbers gives the equations
//! ([`ml::equation_covariance`]: the equations' sensitivities to that channel).
//! The residuals are, on clean data, samples of N(0, Σ_s).
//!
//! **When** ([`homoscedasticity_p`]): a score test of the fit's own noise
//! (its variances times one scale) against the eight-parameter family, on
//! the Gaussian likelihood of the residuals; the variance function is used
//! only when the score test rejects at [`HETEROSCEDASTIC_P`]. It runs on
//! every fit whose noise came from the scatter (either law) and the model
//! fits, so it is written for cost: the residuals the fit already has, one
//! product per channel per speed (the α and β of a channel share G_ch), and
//! at most [`MAX_TEST_SPEEDS`] evenly spaced speeds. The test is evidence
//! for the scatter's law only where that law was measured: where its
//! windows left out most speeds of a channel (resonances its local fits do
//! not follow, [`super::BearingNoise::scatter_mostly_carried`]) the law is
//! carried to the speeds the fit leans on, whose residuals show less than
//! their noise, and the variance function is used whatever the test says
//! ([`refit`]; unseen-six: the scatter's law kept gave RMS z 1.45-1.73,
//! docs/estimation-scatter.md, Session 47 (scatlaw17)).
//!
//! **Fit** ([`fit_variance_function`]): the restricted (REML) pseudo-likelihood
//! of the residuals maximised over (α, β) ≥ 0 by the multiplicative fixed
//! point of its score, p_k ← p_k·Σ_s uᵀM_s,k·u / Σ_s tr(P_s·M_s,k) with
//! u = Σ_s⁻¹e_s and P_s = Σ_s⁻¹ − Σ_s⁻¹·A_s·F⁻¹·A_sᵀ·Σ_s⁻¹ (A_s the speed's
//! regression rows, F = Σ_s A_sᵀ·Σ_s⁻¹·A_s over the fitted parameters).
//! The residuals are the fit's own: E[e_s·e_sᵀ] = Σ_s − A_s·F⁻¹·A_sᵀ, and a
//! speed the fit leans on (a resonance: most of k − Ω²m's information in
//! 1-3 speeds) shows far less than its noise. The plain pseudo-likelihood
//! (tr(Σ_s⁻¹M_s,k) in the denominator) read that shortfall as a small
//! fraction α, often 0, and weighted those speeds up to 3× above their
//! noise (unseen-six `clean-s1`: α = 0 on rel z or ped z in 15-16 of 68
//! B1 fits, 5 of 68 with the leverage allowed for; docs/estimation-scatter.md, Session 46 (noise17)).

use crate::estimate::ml::{self, MlFit};
use crate::estimate::Observation;
use nalgebra::{DMatrix, Matrix4, SMatrix, Vector4};
use plinth_shared::regression::{Parameter, PARAMETERS};

/// Parameters of the variance function: (α, β, γ) of each of the four
/// complex channels, in the order α_rel_y, β_rel_y, γ_rel_y, α_rel_z, …
/// (a [`Family`] says which are free; the others stay 0).
pub const COMPONENTS: usize = 12;

/// Components per channel (α, β, γ) [-].
const PER_CHANNEL: usize = 3;

/// Which components of the variance function a test and a fit free.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// α|X|² + β per channel: a fraction of the amplitude plus a floor (the
    /// scatter's two laws and their mix).
    FractionFloor,
    /// α|X|² + β + γ/Ω² per channel: also a velocity pick-up's floor in
    /// displacement (1/Ω in sd).
    VelocityFloor,
    /// β + γ/Ω² per channel, no fraction: the floors alone, whose
    /// regressors no few peak speeds carry (the columns' test's second
    /// statistic, [`columns_shape_p`]).
    Floors,
}

impl Family {
    /// Whether component `k` ([`COMPONENTS`] order) is free.
    fn free(self, k: usize) -> bool {
        match self {
            Family::FractionFloor => k % PER_CHANNEL != 2,
            Family::VelocityFloor => true,
            Family::Floors => !k.is_multiple_of(PER_CHANNEL),
        }
    }

    /// The free components, in [`COMPONENTS`] order.
    fn components(self) -> Vec<usize> {
        (0..COMPONENTS).filter(|&k| self.free(k)).collect()
    }
}

/// p-value of the score test below which the fit's noise law is rejected
/// for the variance function [-].
pub const HETEROSCEDASTIC_P: f64 = 1e-3;

/// Rounds of (variance function from the residuals, refit under it) [-].
pub const ROUNDS: usize = 3;

/// Most speeds the score test ([`homoscedasticity_p`]) reads: above it, an
/// evenly spaced subset (every ⌈n/this⌉-th speed in the given order). The
/// test's size is that of any fixed subset (exact under the null); its power
/// grows with the speeds, and at this many it is far beyond what a mix of
/// 1 % of |X| plus a floor needs (runs of 100-200 speeds reject it). It keeps
/// the test's cost bounded on fine sweeps (20 001 speeds: identify's cost
/// target) [-].
pub const MAX_TEST_SPEEDS: usize = 2_000;

/// Most fixed-point iterations of [`fit_variance_function`].
const MAX_ITERATIONS: usize = 200;
/// Relative change of every component below which the fixed point stops [-].
const SETTLED: f64 = 1e-7;

/// A speed's residual and the covariance each channel adds per unit.
struct Speed {
    /// Equation residual e [N].
    e: Vector4<f64>,
    /// G_ch [N²/m²]: the covariance of e per unit variance of channel ch's
    /// two real numbers. Component α_ch adds |X_ch|²·G_ch, β_ch adds G_ch.
    g: [Matrix4<f64>; 4],
    /// |X_ch|² [m²] of the four channels.
    magnitude_sq: [f64; 4],
    /// 1/Ω² [s²] at the speed.
    inv_omega_sq: f64,
    /// Σ under the observation's own variances [N²].
    own: Matrix4<f64>,
    /// The regression rows A [N per θ unit] (eq. 4, all five parameters).
    a: SMatrix<f64, 4, PARAMETERS>,
}

impl Speed {
    /// Σ [N²] under the variance function `p` ([`COMPONENTS`]).
    fn sigma(&self, p: &[f64; COMPONENTS]) -> Matrix4<f64> {
        (0..4)
            .map(|ch| {
                let v: f64 = (0..PER_CHANNEL)
                    .map(|j| p[PER_CHANNEL * ch + j] * self.factor(PER_CHANNEL * ch + j))
                    .sum();
                self.g[ch] * v
            })
            .sum()
    }

    /// Factor [m², 1 or s²] component k's covariance is of its channel's G.
    fn factor(&self, k: usize) -> f64 {
        factor(k, &self.magnitude_sq, self.inv_omega_sq)
    }
}

/// Factor of component `k` ([`COMPONENTS`] order) at a speed of squared
/// magnitudes `magnitude_sq` [m²] and 1/Ω² `inv_omega_sq` [s²]: |X_ch|² for
/// α, 1 for β, 1/Ω² for γ.
fn factor(k: usize, magnitude_sq: &[f64; 4], inv_omega_sq: f64) -> f64 {
    match k % PER_CHANNEL {
        0 => magnitude_sq[k / PER_CHANNEL],
        1 => 1.0,
        _ => inv_omega_sq,
    }
}

/// 1/Ω² [s²] of an observation (Ω = 2π·speed [rad/s]); 0 at no speed.
fn inv_omega_sq(o: &Observation) -> f64 {
    let omega = o.omega();
    if omega > 0.0 {
        1.0 / (omega * omega)
    } else {
        0.0
    }
}

fn speeds<'a>(
    obs: impl Iterator<Item = &'a Observation>,
    theta: &[f64; PARAMETERS],
) -> Option<Vec<Speed>> {
    let mut out = Vec::new();
    for o in obs {
        let magnitude = magnitudes(o);
        let g: [Matrix4<f64>; 4] = std::array::from_fn(|ch| {
            let mut unit = *o;
            unit.var = [0.0; 8];
            unit.var[2 * ch] = 1.0;
            unit.var[2 * ch + 1] = 1.0;
            ml::equation_covariance(&unit, theta)
        });
        // Σ is linear in the variances: with equal variances on each
        // channel's real and imaginary parts (the scatter's laws and the
        // variance function give them) it is Σ_ch v_ch·G_ch, no new product.
        let paired = (0..4).all(|ch| o.var[2 * ch] == o.var[2 * ch + 1]);
        let own = if paired {
            (0..4).map(|ch| g[ch] * o.var[2 * ch]).sum()
        } else {
            ml::equation_covariance(o, theta)
        };
        let speed = Speed {
            e: ml::equation_residual(o, theta),
            g,
            magnitude_sq: magnitude.map(|m| m * m),
            inv_omega_sq: inv_omega_sq(o),
            own,
            a: ml::rows(o).0,
        };
        let finite = speed.e.iter().all(|v| v.is_finite())
            && speed.own.iter().all(|v| v.is_finite())
            && speed.g.iter().all(|gc| gc.iter().all(|v| v.is_finite()));
        if !finite {
            return None;
        }
        out.push(speed);
    }
    Some(out)
}

/// |X| [m] of the four complex channels (rel y, rel z, ped y, ped z).
pub fn magnitudes(o: &Observation) -> [f64; 4] {
    [
        o.rel[0].norm(),
        o.rel[1].norm(),
        o.ped[0].norm(),
        o.ped[1].norm(),
    ]
}

/// The variance [m²] of each real number ([`super::REAL_CHANNELS`] order)
/// of an observation under the variance function `p` ([`COMPONENTS`]),
/// never below `floor` [m²] (the number's digits,
/// [`super::BearingNoise::digits_var`]): a number written with 12 digits
/// carries its rounding, ulp²/12 of its own ulp, which varies tenfold with
/// the mantissa at one |X|; the law's average fraction is up to 2.4× below
/// it in sd where the leading digits are small (docs/trust-noise-law.md "Session 27").
pub fn variances(o: &Observation, p: &[f64; COMPONENTS], floor: &[f64; 8]) -> [f64; 8] {
    let magnitude_sq = magnitudes(o).map(|m| m * m);
    let inv = inv_omega_sq(o);
    std::array::from_fn(|c| {
        let ch = c / 2;
        let v: f64 = (0..PER_CHANNEL)
            .map(|j| p[PER_CHANNEL * ch + j] * factor(PER_CHANNEL * ch + j, &magnitude_sq, inv))
            .sum();
        v.max(floor[c])
    })
}

/// p-value [-] of the score test that the residuals of the fit `theta` on
/// `obs` have the covariance of the observations' own variances times one
/// scale, against the variance function of the module docs (its `family`'s
/// components); `None` when a speed's numbers are not finite or its
/// covariance is singular.
pub fn homoscedasticity_p(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    family: Family,
) -> Option<f64> {
    let speeds = speeds(obs.iter().step_by(score::test_stride(obs.len())), theta)?;
    if speeds.is_empty() {
        return None;
    }
    let score = Score::new(&speeds, family)?;
    let residuals: Vec<Vector4<f64>> = speeds.iter().map(|s| s.e).collect();
    let statistic = score.statistic(&speeds, &residuals)?;
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    let chi = ChiSquared::new(score.rank as f64).ok()?;
    Some(chi.sf(statistic))
}

/// The variance function (α, β per channel, module docs) maximising the
/// Gaussian restricted pseudo-likelihood of the residuals of the fit `theta`
/// (parameters `columns`) on `obs` over the `family`'s components (the
/// others 0), started from the
/// observations' own noise; `None` when a speed's numbers are not finite or
/// the iteration leaves the finite numbers.
pub fn fit_variance_function(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    columns: &[Parameter],
    family: Family,
) -> Option<[f64; COMPONENTS]> {
    let speeds = speeds(obs.iter(), theta)?;
    if speeds.is_empty() {
        return None;
    }
    // Start: each channel's mean variance, an equal share from each free
    // term (the mean of its factor over the speeds given that share).
    let n = obs.len() as f64;
    let share = 1.0 / (0..PER_CHANNEL).filter(|&j| family.free(j)).count() as f64;
    let mut p = [0.0; COMPONENTS];
    for ch in 0..4 {
        let mean_var = obs
            .iter()
            .map(|o| 0.5 * (o.var[2 * ch] + o.var[2 * ch + 1]))
            .sum::<f64>()
            / n;
        for j in (0..PER_CHANNEL).filter(|&j| family.free(j)) {
            let k = PER_CHANNEL * ch + j;
            let mean_factor = speeds.iter().map(|s| s.factor(k)).sum::<f64>() / n;
            p[k] = if mean_factor > 0.0 {
                share * mean_var / mean_factor
            } else {
                0.0
            };
        }
    }
    for _ in 0..MAX_ITERATIONS {
        let mut num = [0.0; COMPONENTS];
        let mut den = [0.0; COMPONENTS];
        let inverses: Vec<Matrix4<f64>> = speeds
            .iter()
            .map(|s| s.sigma(&p).try_inverse())
            .collect::<Option<_>>()?;
        let leverage = leverage_parts(&speeds, &inverses, columns)?;
        for ((s, a), h) in speeds.iter().zip(&inverses).zip(&leverage) {
            let w = a * s.e;
            let projection = a - h;
            for ch in 0..4 {
                let quadratic = (w.transpose() * s.g[ch] * w)[0];
                let trace = (projection * s.g[ch]).trace();
                for k in PER_CHANNEL * ch..PER_CHANNEL * (ch + 1) {
                    num[k] += s.factor(k) * quadratic;
                    den[k] += s.factor(k) * trace;
                }
            }
        }
        let mut change: f64 = 0.0;
        for k in 0..COMPONENTS {
            if p[k] > 0.0 && den[k] > 0.0 {
                let next = p[k] * num[k] / den[k];
                change = change.max((next - p[k]).abs() / p[k]);
                p[k] = next;
            }
        }
        if !p.iter().all(|v| v.is_finite()) {
            return None;
        }
        if change < SETTLED {
            break;
        }
    }
    Some(p)
}

/// Per speed, the part W_s·A_s·F⁻¹·A_sᵀ·W_s [1/N²] of the weights the fit
/// of the parameters `columns` takes up (F = Σ_s A_sᵀ·W_s·A_s over those
/// columns, W_s = `inverses`): the expected e_s·e_sᵀ of a fitted residual
/// is Σ_s − A_s·F⁻¹·A_sᵀ, so a speed of high leverage (a resonance the
/// fit follows) shows less than its noise. `None` when F is singular.
fn leverage_parts(
    speeds: &[Speed],
    inverses: &[Matrix4<f64>],
    columns: &[Parameter],
) -> Option<Vec<Matrix4<f64>>> {
    // Fixed-size throughout (a fine sweep has 20 001 speeds): A's columns of
    // the parameters not fitted are zero, and F's rows and columns of them
    // (zero) get a unit diagonal, which leaves the fitted block's inverse
    // as it is and meets only A's zero columns.
    let fitted: [bool; PARAMETERS] =
        std::array::from_fn(|k| columns.iter().any(|c| *c as usize == k));
    let rows: Vec<SMatrix<f64, 4, PARAMETERS>> = speeds
        .iter()
        .map(|s| SMatrix::from_fn(|r, c| if fitted[c] { s.a[(r, c)] } else { 0.0 }))
        .collect();
    let mut f = SMatrix::<f64, PARAMETERS, PARAMETERS>::zeros();
    let mut wa = Vec::with_capacity(speeds.len());
    for (a, w) in rows.iter().zip(inverses) {
        let x = w * a;
        f += a.transpose() * x;
        wa.push(x);
    }
    let d: [f64; PARAMETERS] = std::array::from_fn(|k| {
        let x = f[(k, k)];
        if fitted[k] && x > 0.0 && x.is_finite() {
            1.0 / x.sqrt()
        } else {
            1.0
        }
    });
    let scaled = SMatrix::<f64, PARAMETERS, PARAMETERS>::from_fn(|r, c| {
        if !fitted[r] || !fitted[c] {
            if r == c {
                1.0
            } else {
                0.0
            }
        } else {
            d[r] * f[(r, c)] * d[c]
        }
    });
    let inv = scaled.try_inverse()?;
    let f_inv = SMatrix::<f64, PARAMETERS, PARAMETERS>::from_fn(|r, c| d[r] * inv[(r, c)] * d[c]);
    let out: Vec<Matrix4<f64>> = wa.iter().map(|x| x * f_inv * x.transpose()).collect();
    out.iter()
        .all(|h| h.iter().all(|v| v.is_finite()))
        .then_some(out)
}

/// The fit `fit` of `obs` (parameters `columns`) redone under the variance
/// function ([`Family::FractionFloor`]) of its residuals when the score test
/// ([`homoscedasticity_p`]) rejects the observations' own noise law at
/// [`HETEROSCEDASTIC_P`], or whatever its p when that law was not
/// `law_measured` on most speeds (module docs) ([`refit_under`]); `None`
/// when the law is kept or a step fails.
pub fn refit(
    obs: &[Observation],
    floor: impl Fn(&Observation) -> [f64; 8],
    columns: &[Parameter],
    fit: &MlFit,
    law_measured: bool,
) -> Option<Refit> {
    let p_value = homoscedasticity_p(obs, &fit.theta, Family::FractionFloor)?;
    if law_measured && p_value >= HETEROSCEDASTIC_P {
        return None;
    }
    refit_under(obs, floor, columns, fit, Family::FractionFloor, p_value)
}

/// The fit `fit` of `obs` (parameters `columns`) redone under the variance
/// function (`family`) of its residuals, after a score test rejected the
/// observations' own law at `p_value` [-]: [`ROUNDS`] rounds of
/// ([`fit_variance_function`], ML refit from the last estimate). Returns the
/// last refit, its variance function, `p_value` and the observations with
/// its variances (each never below `floor` of the observation: its digits'
/// variances [m²], [`variances`]); `None` when a step fails.
pub fn refit_under(
    obs: &[Observation],
    floor: impl Fn(&Observation) -> [f64; 8],
    columns: &[Parameter],
    fit: &MlFit,
    family: Family,
    p_value: f64,
) -> Option<Refit> {
    let mut obs = obs.to_vec();
    let mut current: Option<(MlFit, [f64; COMPONENTS])> = None;
    for _ in 0..ROUNDS {
        let theta = current.as_ref().map_or(fit.theta, |c| c.0.theta);
        let p = fit_variance_function(&obs, &theta, columns, family)?;
        for o in obs.iter_mut() {
            o.var = variances(o, &p, &floor(o));
        }
        if !obs
            .iter()
            .all(|o| o.var.iter().all(|v| *v > 0.0 && v.is_finite()))
        {
            return None;
        }
        let f = ml::fit(&obs, columns, &theta).ok()?;
        if !f.theta.iter().all(|v| v.is_finite()) {
            return None;
        }
        current = Some((f, p));
    }
    let (mut fit, law) = current?;
    // The law is an estimate from these residuals: its error is in the ±.
    if let Some(c) = with_law_uncertainty(&obs, &fit.theta, &law, columns, &fit.covariance) {
        fit.covariance = c;
    }
    Some(Refit {
        fit,
        law,
        p_value,
        obs,
    })
}

/// What [`refit`] gives.
#[derive(Clone, Debug)]
pub struct Refit {
    /// The ML fit under the variance function.
    pub fit: MlFit,
    /// The variance function (α [-], β [m²], γ [m²/s²] per channel, module
    /// docs).
    pub law: [f64; COMPONENTS],
    /// p-value of the score test that rejected the observations' own law [-].
    pub p_value: f64,
    /// The observations with the variance function's variances.
    pub obs: Vec<Observation>,
}

/// Relative eigenvalue below which a direction of a Jacobi-scaled
/// information is taken as not estimated [-] ([`eigen_pseudo_inverse`]).
const RANK_TOLERANCE: f64 = 1e-10;

/// Jacobi scaling 1/√I_kk of a symmetric information `info` (0 where the
/// diagonal is not positive and finite): the components' units differ by
/// many decades.
fn jacobi_scaling(info: &DMatrix<f64>) -> Vec<f64> {
    (0..info.nrows())
        .map(|k| {
            let x = info[(k, k)];
            if x > 0.0 && x.is_finite() {
                1.0 / x.sqrt()
            } else {
                0.0
            }
        })
        .collect()
}

/// The pseudo-inverse of the symmetric positive semi-definite (already
/// scaled) `m` and its rank: its directions below [`RANK_TOLERANCE`] of the
/// largest eigenvalue left out; `None` when it has no positive direction.
fn eigen_pseudo_inverse(m: &DMatrix<f64>) -> Option<(DMatrix<f64>, usize)> {
    let eig = m.clone().symmetric_eigen();
    let top = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
    if !(top > 0.0 && top.is_finite()) {
        return None;
    }
    let n = m.nrows();
    let mut inverse = DMatrix::<f64>::zeros(n, n);
    let mut rank = 0;
    for (i, &lambda) in eig.eigenvalues.iter().enumerate() {
        if lambda > RANK_TOLERANCE * top {
            let v = eig.eigenvectors.column(i);
            inverse += v * v.transpose() / lambda;
            rank += 1;
        }
    }
    Some((inverse, rank))
}

mod score;
mod uncertainty;
use score::Score;
pub use score::{columns_shape_p, neighbour_magnitudes_sq, BOOTSTRAP_DRAWS, EXCEEDANCES};
pub use uncertainty::with_law_uncertainty;

#[cfg(test)]
mod tests;
