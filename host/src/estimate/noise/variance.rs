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
//! docs/trust.md "Heteroscedastic noise without noise columns").
//!
//! **Model.** Per complex channel ch (rel y, rel z, ped y, ped z) each real
//! part has the variance v = α_ch·|X_ch|² + β_ch [m²] (α [-], β [m²], both ≥ 0),
//! which contains both scatter laws. At a converged fit θ̂ the residual e_s
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
//! at most [`MAX_TEST_SPEEDS`] evenly spaced speeds.
//!
//! **Fit** ([`fit_variance_function`]): the pseudo-likelihood of the residuals
//! maximised over (α, β) ≥ 0 by the multiplicative fixed point of its score,
//! p_k ← p_k·Σ_s uᵀM_s,k·u / Σ_s tr(Σ_s⁻¹M_s,k) with u = Σ_s⁻¹e_s.

use crate::estimate::ml::{self, MlFit};
use crate::estimate::Observation;
use nalgebra::{Matrix4, SMatrix, SVector, Vector4};
use plinth_shared::regression::{Parameter, PARAMETERS};

/// Parameters of the variance function: (α, β) of each of the four complex
/// channels, in the order α_rel_y, β_rel_y, α_rel_z, …
pub const COMPONENTS: usize = 8;

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
    /// Σ under the observation's own variances [N²].
    own: Matrix4<f64>,
}

impl Speed {
    /// Σ [N²] under the variance function `p` ([`COMPONENTS`]).
    fn sigma(&self, p: &[f64; COMPONENTS]) -> Matrix4<f64> {
        (0..4)
            .map(|ch| self.g[ch] * (p[2 * ch] * self.magnitude_sq[ch] + p[2 * ch + 1]))
            .sum()
    }

    /// Factor [m² or 1] component k's covariance is of its channel's G.
    fn factor(&self, k: usize) -> f64 {
        if k.is_multiple_of(2) {
            self.magnitude_sq[k / 2]
        } else {
            1.0
        }
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
            own,
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
/// it in sd where the leading digits are small (docs/trust.md "Session 27").
pub fn variances(o: &Observation, p: &[f64; COMPONENTS], floor: &[f64; 8]) -> [f64; 8] {
    let magnitude = magnitudes(o);
    std::array::from_fn(|c| {
        let ch = c / 2;
        (p[2 * ch] * magnitude[ch].powi(2) + p[2 * ch + 1]).max(floor[c])
    })
}

/// p-value [-] of the score test that the residuals of the fit `theta` on
/// `obs` have the covariance of the observations' own variances times one
/// scale, against the variance function of the module docs; `None` when a
/// speed's numbers are not finite or its covariance is singular.
pub fn homoscedasticity_p(obs: &[Observation], theta: &[f64; PARAMETERS]) -> Option<f64> {
    let stride = obs.len().div_ceil(MAX_TEST_SPEEDS).max(1);
    let speeds = speeds(obs.iter().step_by(stride), theta)?;
    if speeds.is_empty() {
        return None;
    }
    // The null's scale: its maximum-likelihood value χ²/(4n).
    let mut chi2 = 0.0;
    let mut inverses = Vec::with_capacity(speeds.len());
    for s in &speeds {
        let a = s.own.try_inverse()?;
        chi2 += (s.e.transpose() * a * s.e)[0];
        inverses.push(a);
    }
    let scale = chi2 / (4 * speeds.len()) as f64;
    if !(scale > 0.0 && scale.is_finite()) {
        return None;
    }
    // Score U and information I of the components and of the null's scale
    // (index COMPONENTS, direction Σ_own), at Σ0 = scale·Σ_own. Component k
    // adds f_k·G_ch (f_k = |X_ch|² for α, 1 for β): with B_ch = Σ0⁻¹G_ch,
    // U_k = ½f_k(wᵀG_ch·w − tr B_ch), I_kl = ½f_k·f_l·tr(B_ch·B_ch'), and
    // the scale's direction gives Σ0⁻¹Σ_own = I/scale: one product per
    // channel and ten channel pairs per speed.
    const N: usize = COMPONENTS + 1;
    let mut u = SVector::<f64, N>::zeros();
    let mut info = SMatrix::<f64, N, N>::zeros();
    for (s, a) in speeds.iter().zip(&inverses) {
        let a0 = a / scale;
        let w = a0 * s.e;
        let b: [Matrix4<f64>; 4] = std::array::from_fn(|ch| a0 * s.g[ch]);
        let bt: [Matrix4<f64>; 4] = std::array::from_fn(|ch| b[ch].transpose());
        let trace: [f64; 4] = std::array::from_fn(|ch| b[ch].trace());
        let excess: [f64; 4] =
            std::array::from_fn(|ch| (w.transpose() * s.g[ch] * w)[0] - trace[ch]);
        // tr(B·B') = Σ B ∘ B'ᵀ.
        let mut pair = [[0.0; 4]; 4];
        for ch in 0..4 {
            for other in ch..4 {
                pair[ch][other] = b[ch].component_mul(&bt[other]).sum();
                pair[other][ch] = pair[ch][other];
            }
        }
        for k in 0..COMPONENTS {
            let (ch, fk) = (k / 2, s.factor(k));
            u[k] += 0.5 * fk * excess[ch];
            for l in k..COMPONENTS {
                info[(k, l)] += 0.5 * fk * s.factor(l) * pair[ch][l / 2];
            }
            info[(k, COMPONENTS)] += 0.5 * fk * trace[ch] / scale;
        }
        u[COMPONENTS] += 0.5 * ((w.transpose() * s.own * w)[0] - 4.0 / scale);
        info[(COMPONENTS, COMPONENTS)] += 2.0 / (scale * scale);
    }
    for k in 0..N {
        for l in 0..k {
            info[(k, l)] = info[(l, k)];
        }
    }
    // Jacobi scaling: the components' units differ by many decades.
    let d = SVector::<f64, N>::from_fn(|k, _| {
        let x = info[(k, k)];
        if x > 0.0 {
            1.0 / x.sqrt()
        } else {
            0.0
        }
    });
    let info = SMatrix::<f64, N, N>::from_fn(|k, l| d[k] * info[(k, l)] * d[l]);
    let u = u.component_mul(&d);
    // The efficient information of the components, the scale profiled out.
    let phi = info[(COMPONENTS, COMPONENTS)];
    if phi.is_nan() || phi <= 0.0 {
        return None;
    }
    let eff = SMatrix::<f64, COMPONENTS, COMPONENTS>::from_fn(|k, l| {
        info[(k, l)] - info[(k, COMPONENTS)] * info[(COMPONENTS, l)] / phi
    });
    let ue = SVector::<f64, COMPONENTS>::from_fn(|k, _| {
        u[k] - info[(k, COMPONENTS)] * u[COMPONENTS] / phi
    });
    let eig = eff.symmetric_eigen();
    let top = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
    if !(top > 0.0 && top.is_finite()) {
        return None;
    }
    let (mut statistic, mut rank) = (0.0, 0usize);
    for (i, &lambda) in eig.eigenvalues.iter().enumerate() {
        if lambda > 1e-10 * top {
            let proj = eig.eigenvectors.column(i).dot(&ue);
            statistic += proj * proj / lambda;
            rank += 1;
        }
    }
    if rank == 0 || !statistic.is_finite() {
        return None;
    }
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    let chi = ChiSquared::new(rank as f64).ok()?;
    Some(chi.sf(statistic))
}

/// The variance function (α, β per channel, module docs) maximising the
/// Gaussian pseudo-likelihood of the residuals of the fit `theta` on `obs`,
/// started from the observations' own noise; `None` when a speed's numbers
/// are not finite or the iteration leaves the finite numbers.
pub fn fit_variance_function(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
) -> Option<[f64; COMPONENTS]> {
    let speeds = speeds(obs.iter(), theta)?;
    if speeds.is_empty() {
        return None;
    }
    // Start: each channel's mean variance, half from each term.
    let n = obs.len() as f64;
    let mut p = [0.0; COMPONENTS];
    for ch in 0..4 {
        let mean_var = obs
            .iter()
            .map(|o| 0.5 * (o.var[2 * ch] + o.var[2 * ch + 1]))
            .sum::<f64>()
            / n;
        let mean_sq = obs.iter().map(|o| magnitudes(o)[ch].powi(2)).sum::<f64>() / n;
        p[2 * ch] = if mean_sq > 0.0 {
            0.5 * mean_var / mean_sq
        } else {
            0.0
        };
        p[2 * ch + 1] = 0.5 * mean_var;
    }
    for _ in 0..MAX_ITERATIONS {
        let mut num = [0.0; COMPONENTS];
        let mut den = [0.0; COMPONENTS];
        for s in &speeds {
            let a = s.sigma(&p).try_inverse()?;
            let w = a * s.e;
            for ch in 0..4 {
                let quadratic = (w.transpose() * s.g[ch] * w)[0];
                let trace = (a * s.g[ch]).trace();
                for k in [2 * ch, 2 * ch + 1] {
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

/// The fit `fit` of `obs` (parameters `columns`) redone under the variance
/// function of its residuals when the score test ([`homoscedasticity_p`])
/// rejects the observations' own noise law: [`ROUNDS`] rounds of
/// ([`fit_variance_function`], ML refit from the last estimate). Returns the
/// last refit, its variance function, the score test's p-value [-] and the
/// observations with its variances (each never below `floor` of the
/// observation: its digits' variances [m²], [`variances`]); `None` when the
/// test does not reject or a step fails.
pub fn refit(
    obs: &[Observation],
    floor: impl Fn(&Observation) -> [f64; 8],
    columns: &[Parameter],
    fit: &MlFit,
) -> Option<Refit> {
    let p_value = homoscedasticity_p(obs, &fit.theta)?;
    if p_value >= HETEROSCEDASTIC_P {
        return None;
    }
    let mut obs = obs.to_vec();
    let mut current: Option<(MlFit, [f64; COMPONENTS])> = None;
    for _ in 0..ROUNDS {
        let theta = current.as_ref().map_or(fit.theta, |c| c.0.theta);
        let p = fit_variance_function(&obs, &theta)?;
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
    let (fit, law) = current?;
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
    /// The variance function (α [-], β [m²] per channel, module docs).
    pub law: [f64; COMPONENTS],
    /// p-value of the score test that rejected the observations' own law [-].
    pub p_value: f64,
    /// The observations with the variance function's variances.
    pub obs: Vec<Observation>,
}
