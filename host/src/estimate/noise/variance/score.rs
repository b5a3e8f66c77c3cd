//! The score statistic of [`super::homoscedasticity_p`], prepared once per
//! fit so that it can be recomputed on many residual vectors, and the noise
//! columns' shape test built on it ([`columns_shape_p`]).
//!
//! **Statistic.** At the null Σ0,s = σ²·Σ_own,s (σ² profiled: its ML value
//! Σ eᵀΣ_own⁻¹e / 4n) the score of component k (channel ch, factor f_k,s)
//! is U_k = (1/σ²)·½Σ_s f_k,s (q_s,ch/σ² − t_s,ch) with q_s,ch = yᵀG_s,ch·y,
//! y = Σ_own,s⁻¹e_s and t_s,ch = tr(Σ_own,s⁻¹G_s,ch), and the information is
//! that at σ² = 1 over σ⁴: the statistic UᵀI⁻¹U (the efficient one, σ²
//! profiled out) depends on the residuals only through the sums
//! Σ_s f_k,s·q_s,ch and Σ_s yᵀe, and is unchanged when all residuals are
//! scaled together. [`Score::new`] keeps everything else.
//!
//! **The columns' test** ([`columns_shape_p`]). Two things make the χ²
//! null of that statistic wrong for noise columns (docs/estimation.md, Session 41 (lowsnr17)):
//! (1) the fraction's regressor |X_ch,s|² read from the speed's own phasor is,
//! where a channel reads near its noise, that speed's own noise, correlated
//! with its squared residual under the null (the columns of a stiff
//! pedestal read below its noise were rejected at p = 1e-67); (2) a few peak
//! speeds carry the fraction's direction, where the fit's leverage is, and
//! the statistic's law is then far from χ². The test reads the regressor
//! from the neighbouring speeds (|X| interpolated linearly in speed between
//! the nearest speed below and above, never the speed itself: independent
//! of its noise), and takes its p-value from a parametric bootstrap of the
//! statistic under the columns themselves: residuals drawn N(0, Σ_own,s)
//! at every speed, less their projection on the fit's parameters (the
//! linearised refit, A·δθ with δθ = F⁻¹ΣAᵀΣ⁻¹ε: the leverage), the
//! regressors held. Its null is then that of the columns whatever the
//! leverage and the signal-to-noise ratio. Draws stop early (Besag &
//! Clifford 1991, sequential Monte-Carlo p-values) once [`EXCEEDANCES`] of
//! them reach the observed statistic, so accepted columns cost a few tens
//! of draws and only rejected ones the [`BOOTSTRAP_DRAWS`].

use super::{
    eigen_pseudo_inverse, jacobi_scaling, speeds, Family, Speed, MAX_TEST_SPEEDS, PER_CHANNEL,
};
use crate::estimate::{ml, Observation};
use nalgebra::{DMatrix, DVector, Matrix4, SMatrix, SVector, Vector4};
use plinth_shared::regression::{Parameter, PARAMETERS};
use rand::{rngs::StdRng, Rng, SeedableRng};
use rand_distr::StandardNormal;

/// Most draws of the columns' bootstrap [-]: with none of them reaching
/// either observed statistic its p-value is 2/(this + 1) = 1e-3 (Bonferroni
/// over the two statistics), the least it can give and
/// [`super::super::columns::COLUMNS_P`].
pub const BOOTSTRAP_DRAWS: usize = 1999;

/// Draws reaching the observed statistic at which the bootstrap stops, once
/// both statistics have that many: its p-value is then twice this over the
/// draws made (Besag & Clifford; Bonferroni over the two) [-].
pub const EXCEEDANCES: usize = 10;

/// The score statistic of one fit's speeds, everything but the residuals
/// (module docs).
pub(super) struct Score {
    /// Σ_own,s⁻¹ [1/N²] per speed.
    inverses: Vec<Matrix4<f64>>,
    /// The free components ([`super::COMPONENTS`] order).
    free: Vec<usize>,
    /// Σ_s f_k,s·t_s,ch per free component, at σ² = 1 [-].
    traces: Vec<f64>,
    /// Jacobi scaling 1/√I_kk of the free components and (last) of σ².
    scaling: Vec<f64>,
    /// Scaled I_k,σ²/I_σ²σ² per free component: the σ² profiling.
    coupling: Vec<f64>,
    /// Pseudo-inverse of the scaled efficient information.
    inverse: DMatrix<f64>,
    /// Its rank: the statistic's χ² degrees of freedom [-].
    pub rank: usize,
}

impl Score {
    /// The statistic's fixed part on `speeds` for the `family`'s components;
    /// `None` when a speed's covariance is singular or the information is
    /// not positive.
    pub(super) fn new(speeds: &[Speed], family: Family) -> Option<Self> {
        let free = family.components();
        let m = free.len();
        let n = speeds.len();
        let mut info = DMatrix::<f64>::zeros(m + 1, m + 1);
        let mut traces = vec![0.0; m];
        let mut inverses = Vec::with_capacity(n);
        for s in speeds {
            let a = s.own.try_inverse()?;
            let b: [Matrix4<f64>; 4] = std::array::from_fn(|ch| a * s.g[ch]);
            let trace: [f64; 4] = std::array::from_fn(|ch| b[ch].trace());
            // tr(B·B') = Σ B ∘ B'ᵀ.
            let mut pair = [[0.0; 4]; 4];
            for ch in 0..4 {
                for other in ch..4 {
                    pair[ch][other] = b[ch].component_mul(&b[other].transpose()).sum();
                    pair[other][ch] = pair[ch][other];
                }
            }
            for (i, &k) in free.iter().enumerate() {
                let (ch, fk) = (k / PER_CHANNEL, s.factor(k));
                traces[i] += fk * trace[ch];
                for (j, &l) in free.iter().enumerate().skip(i) {
                    info[(i, j)] += 0.5 * fk * s.factor(l) * pair[ch][l / PER_CHANNEL];
                }
                info[(i, m)] += 0.5 * fk * trace[ch];
            }
            info[(m, m)] += 2.0;
            inverses.push(a);
        }
        for k in 0..=m {
            for l in 0..k {
                info[(k, l)] = info[(l, k)];
            }
        }
        let scaling = jacobi_scaling(&info);
        let info =
            DMatrix::<f64>::from_fn(m + 1, m + 1, |k, l| scaling[k] * info[(k, l)] * scaling[l]);
        let phi = info[(m, m)];
        if phi.is_nan() || phi <= 0.0 {
            return None;
        }
        let coupling: Vec<f64> = (0..m).map(|k| info[(k, m)] / phi).collect();
        let eff = DMatrix::<f64>::from_fn(m, m, |k, l| info[(k, l)] - coupling[k] * info[(m, l)]);
        let (inverse, rank) = eigen_pseudo_inverse(&eff)?;
        (rank > 0).then_some(Self {
            inverses,
            free,
            traces,
            scaling,
            coupling,
            inverse,
            rank,
        })
    }

    /// The statistic [-] of the residuals `e` [N] (one per speed, in the
    /// order of [`Score::new`]'s speeds; `speeds` those speeds); `None` when
    /// it is not finite or the residuals are all zero.
    pub(super) fn statistic(&self, speeds: &[Speed], e: &[Vector4<f64>]) -> Option<f64> {
        let m = self.free.len();
        let mut weighted = vec![0.0; m];
        let mut own = 0.0;
        for ((s, a), e) in speeds.iter().zip(&self.inverses).zip(e) {
            let y = a * e;
            own += e.dot(&y);
            let q: [f64; 4] = std::array::from_fn(|ch| y.dot(&(s.g[ch] * y)));
            for (i, &k) in self.free.iter().enumerate() {
                weighted[i] += s.factor(k) * q[k / PER_CHANNEL];
            }
        }
        let n = speeds.len() as f64;
        let scale = own / (4.0 * n);
        if !(scale > 0.0 && scale.is_finite()) {
            return None;
        }
        let v_scale = 0.5 * (own / scale - 4.0 * n) * self.scaling[m];
        let ue = DVector::<f64>::from_fn(m, |i, _| {
            0.5 * (weighted[i] / scale - self.traces[i]) * self.scaling[i]
                - self.coupling[i] * v_scale
        });
        let statistic = (ue.transpose() * &self.inverse * &ue)[0];
        statistic.is_finite().then_some(statistic)
    }
}

/// The speeds the score test reads (every ⌈n/[`MAX_TEST_SPEEDS`]⌉-th).
pub(super) fn test_stride(n: usize) -> usize {
    n.div_ceil(MAX_TEST_SPEEDS).max(1)
}

/// |X_ch|² [m²] of the four channels of each observation read from its
/// neighbours in speed, never from itself: |X| interpolated linearly in
/// speed between the nearest speed below and the nearest above (the
/// neighbours in speed order; at the ends the one neighbour), squared. The
/// fraction's regressor free of the speed's own noise (module docs).
pub fn neighbour_magnitudes_sq(obs: &[Observation]) -> Vec<[f64; 4]> {
    let mut order: Vec<usize> = (0..obs.len()).collect();
    order.sort_by(|&a, &b| obs[a].speed_hz.total_cmp(&obs[b].speed_hz));
    let mut out = vec![[0.0; 4]; obs.len()];
    for (rank, &i) in order.iter().enumerate() {
        let below = rank.checked_sub(1).map(|r| order[r]);
        let above = order.get(rank + 1).copied();
        let mag = |j: usize| super::magnitudes(&obs[j]);
        let x = match (below, above) {
            (Some(lo), Some(hi)) => {
                let (f_lo, f_hi) = (obs[lo].speed_hz, obs[hi].speed_hz);
                let t = if f_hi > f_lo {
                    ((obs[i].speed_hz - f_lo) / (f_hi - f_lo)).clamp(0.0, 1.0)
                } else {
                    0.5
                };
                let (m_lo, m_hi) = (mag(lo), mag(hi));
                std::array::from_fn(|ch| m_lo[ch] + t * (m_hi[ch] - m_lo[ch]))
            }
            (Some(j), None) | (None, Some(j)) => mag(j),
            (None, None) => super::magnitudes(&obs[i]),
        };
        out[i] = x.map(|v| v * v);
    }
    out
}

/// p-value [-] of the score test that the residuals of the fit `theta`
/// (free parameters `columns`) on `obs` have the covariance of the
/// observations' own variances (noise columns) times one scale, against a
/// fraction of |X|, a floor and a velocity pick-up's floor per channel
/// ([`Family::VelocityFloor`]) and against the two floors alone
/// ([`Family::Floors`]: no few peak speeds carry them), with the fraction's
/// regressor read from the neighbouring speeds ([`neighbour_magnitudes_sq`])
/// and each statistic's p-value from one parametric bootstrap under the
/// columns (module docs), the smaller doubled (Bonferroni): 2·(1 + fewest
/// draws reaching their observed statistic)/(1 + draws), or
/// 2·[`EXCEEDANCES`]/draws when it stops early; at least
/// 2/([`BOOTSTRAP_DRAWS`] + 1) = 1e-3. `None` when a speed's numbers are not
/// finite or its covariance singular.
pub fn columns_shape_p(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    columns: &[Parameter],
) -> Option<f64> {
    let stride = test_stride(obs.len());
    let regressor = neighbour_magnitudes_sq(obs);
    let mut speeds = speeds(obs.iter().step_by(stride), theta)?;
    for (s, r) in speeds.iter_mut().zip(regressor.iter().step_by(stride)) {
        s.magnitude_sq = *r;
    }
    if speeds.is_empty() {
        return None;
    }
    let scores = [
        Score::new(&speeds, Family::VelocityFloor)?,
        Score::new(&speeds, Family::Floors)?,
    ];
    let residuals: Vec<Vector4<f64>> = speeds.iter().map(|s| s.e).collect();
    let observed = [
        scores[0].statistic(&speeds, &residuals)?,
        scores[1].statistic(&speeds, &residuals)?,
    ];
    let rows: Vec<Rows> = obs
        .iter()
        .step_by(stride)
        .map(|o| {
            let a = ml::rows(o).0;
            Rows::from_fn(|r, c| {
                if columns.iter().any(|&p| p as usize == c) {
                    a[(r, c)]
                } else {
                    0.0
                }
            })
        })
        .collect();
    let draws = Draws::new(&speeds, &scores[0], rows)?;
    // Noise correlated along the run (an AR(1) of ρ between neighbouring
    // speeds, [`crate::estimate::serial`]): the draws carry it, ρ^stride
    // between the speeds tested. A white bootstrap takes the correlated
    // noise's clustered squares for a pattern of level the columns miss
    // (ROSS unseen-eight `corr-noise`: every bearing's columns rejected,
    // docs/estimation-scatter.md, Session 49 (corr17b)).
    let phi = crate::estimate::serial::measured_fit(
        obs,
        theta,
        columns,
        &crate::estimate::ml::Weighting::default(),
    )
    .map_or(0.0, |(rho, ..)| rho.powi(stride as i32));
    // A fixed seed: the same data give the same verdict.
    let mut rng = StdRng::seed_from_u64(0x05EE_DC01_u64 ^ speeds.len() as u64);
    let mut buffer = vec![Vector4::zeros(); speeds.len()];
    let mut reached = [0usize; 2];
    let mut made = 0;
    while made < BOOTSTRAP_DRAWS && reached.iter().any(|&r| r < EXCEEDANCES) {
        draws.draw(&mut rng, &mut buffer, phi);
        made += 1;
        for (i, score) in scores.iter().enumerate() {
            if score.statistic(&speeds, &buffer)? >= observed[i] {
                reached[i] += 1;
            }
        }
    }
    // Bonferroni over the two statistics.
    let fewest = reached[0].min(reached[1]);
    let p = 2.0 * crate::estimate::monte_carlo::sequential_p_value(fewest, made, EXCEEDANCES);
    Some(p.min(1.0))
}

/// A speed's regression rows A (4 equations × θ), zero in the columns of
/// the parameters held.
type Rows = SMatrix<f64, 4, PARAMETERS>;

/// What a bootstrap draw needs beyond the [`Score`]: each speed's Cholesky
/// factor of Σ_own, its regression rows A over the free parameters and
/// Σ_own⁻¹A, and the Jacobi-scaled inverse of the information ΣAᵀΣ⁻¹A.
struct Draws {
    factors: Vec<Matrix4<f64>>,
    rows: Vec<Rows>,
    weighted_rows: Vec<Rows>,
    /// Jacobi scaling of the parameters (0 for those held).
    scaling: SVector<f64, PARAMETERS>,
    /// Inverse of the scaled information (1 on the diagonal of those held).
    inverse: SMatrix<f64, PARAMETERS, PARAMETERS>,
}

impl Draws {
    fn new(speeds: &[Speed], score: &Score, rows: Vec<Rows>) -> Option<Self> {
        let mut info = SMatrix::<f64, PARAMETERS, PARAMETERS>::zeros();
        let mut factors = Vec::with_capacity(speeds.len());
        let mut weighted_rows = Vec::with_capacity(speeds.len());
        for ((s, a), r) in speeds.iter().zip(&score.inverses).zip(&rows) {
            factors.push(s.own.cholesky()?.l());
            let ar = a * r;
            info += r.transpose() * ar;
            weighted_rows.push(ar);
        }
        let scaling = SVector::<f64, PARAMETERS>::from_fn(|k, _| {
            let x = info[(k, k)];
            if x > 0.0 {
                1.0 / x.sqrt()
            } else {
                0.0
            }
        });
        let scaled = SMatrix::<f64, PARAMETERS, PARAMETERS>::from_fn(|k, l| {
            if scaling[k] == 0.0 || scaling[l] == 0.0 {
                if k == l {
                    1.0
                } else {
                    0.0
                }
            } else {
                scaling[k] * info[(k, l)] * scaling[l]
            }
        });
        let inverse = scaled.cholesky()?.inverse();
        Some(Self {
            factors,
            rows,
            weighted_rows,
            scaling,
            inverse,
        })
    }

    /// One draw of the statistic under the columns: residuals N(0, Σ_own)
    /// less their linearised refit; `buffer` holds them (one per speed).
    /// Their whitened parts are an AR(1) of lag-one correlation `phi` [-]
    /// along the speeds (0: independent).
    fn draw(&self, rng: &mut StdRng, buffer: &mut [Vector4<f64>], phi: f64) {
        let mut gradient = SVector::<f64, PARAMETERS>::zeros();
        let innovation = (1.0 - phi * phi).sqrt();
        let mut z = Vector4::<f64>::zeros();
        for (t, ((e, l), ar)) in buffer
            .iter_mut()
            .zip(&self.factors)
            .zip(&self.weighted_rows)
            .enumerate()
        {
            let fresh = Vector4::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal));
            z = if t == 0 {
                fresh
            } else {
                z * phi + fresh * innovation
            };
            *e = l * z;
            gradient += ar.tr_mul(e);
        }
        let step = self
            .scaling
            .component_mul(&(self.inverse * gradient.component_mul(&self.scaling)));
        for (e, r) in buffer.iter_mut().zip(&self.rows) {
            *e -= r * step;
        }
    }
}
