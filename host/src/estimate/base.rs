//! Pedestals on a shared base: the one physical model, and its
//! maximum-likelihood fits with the base measured or not.
//!
//! Per direction d (y or z, independent: the base translates, as in
//! `sim/base.rs`), pedestal i of a group standing on one base obeys
//!
//! ```text
//! −Ω²m_i·X_i + d_i·(X_i − X_B) = F_i,   d_i = k_i + iΩc_i,  F_i = K*_i·rel_i
//! ```
//!
//! and the base, on its springs and dampers to ground,
//!
//! ```text
//! S_g·X_B = Σ_i d_i·(X_i − X_B) = Σ_i (F_i + Ω²m_i·X_i) = T,   S_g = K_B + iΩC_B − Ω²M_B
//! ```
//!
//! (T is the total force the pedestals pass to the base). With the base
//! **measured** X_B is data and each pedestal's equation is linear in θ
//! ([`fit_on_measured_base`]). With the base **unmeasured**, X_B = G·T with
//! G = 1/S_g eliminates it: the residual of pedestal i,
//!
//! ```text
//! e_i = (d_i − Ω²m_i)·X_i − F_i − d_i·G·Σ_j (F_j + Ω²m_j·X_j),
//! ```
//!
//! couples every pedestal of the group through the speed-dependent,
//! complex, rank-one term d·dᵀ-like G (the noise of every pedestal's rel and
//! ped enters every pedestal's equation through T). The base is
//! parametrised by G = κ/(1 − Ω²μ + iΩγ) with κ = 1/K_B (the quasi-static
//! compliance), μ = M_B/K_B = 1/Ω_B², γ = C_B/K_B: rigid ground is κ = 0.
//!
//! Both fits are the errors-in-variables ML of [`super::gauss_helmert`]
//! (the full per-speed covariance of all residuals of the group, whitened).
//! The unmeasured fit starts from the rigid-base fits, profiles the base
//! frequency f_B (log-spaced from a third of the lowest speed to three times
//! the highest) and damping ratio ζ_B on a grid with the weights frozen, then
//! frees everything. What the data determine is decided per direction
//! ([`BaseIdentifiability`]) from the fitted f_B against the speed range,
//! the Fisher information and a likelihood ratio against rigid ground.

use super::gauss_helmert::{self as gh, Equations};
use super::Observation;
use nalgebra::{DMatrix, DVector};
use num_complex::Complex;
use serde::Serialize;
use std::f64::consts::TAU;

type C = Complex<f64>;

/// One group of pedestals standing on one unmeasured base (y and z
/// independent, translation only, as in `sim/base.rs`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BaseGroup {
    /// Indices into the observation slice given to the fits.
    pub bearings: Vec<usize>,
}

/// Per-direction (y, z) base parameters: dynamic stiffness to ground
/// S_g(Ω) = K_B + iΩC_B − Ω²M_B.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct BaseParams {
    /// Stiffness to ground K_B [N/m] (∞ for rigid ground).
    pub k: [f64; 2],
    /// Damping to ground C_B [N·s/m].
    pub c: [f64; 2],
    /// Mass M_B [kg].
    pub m: [f64; 2],
}

impl BaseParams {
    /// Rigid ground: no base motion.
    pub const RIGID: BaseParams = BaseParams {
        k: [f64::INFINITY; 2],
        c: [0.0; 2],
        m: [0.0; 2],
    };

    /// Base receptance G = 1/S_g [m/N] in direction `d` at Ω [rad/s]
    /// (0 for rigid ground).
    pub fn receptance(&self, d: usize, omega: f64) -> C {
        if !self.k[d].is_finite() {
            return C::new(0.0, 0.0);
        }
        C::new(1.0, 0.0) / C::new(self.k[d] - omega * omega * self.m[d], omega * self.c[d])
    }
}

/// What the data determine about the base in one direction.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum BaseIdentifiability {
    /// The base mode lies inside the speed range: M_B, K_B and C_B.
    Full,
    /// The mode lies above the range: only the quasi-static compliance
    /// 1/K_B [m/N] (± its standard error) is determined.
    QuasiStatic {
        /// 1/K_B [m/N].
        compliance_m_per_n: f64,
        /// Its standard error [m/N].
        std_err: f64,
    },
    /// The mode lies below the range: the base moves as a mass, M_B [kg].
    MassLine {
        /// M_B [kg].
        mass_kg: f64,
        /// Its standard error [kg].
        std_err: f64,
    },
    /// No base motion is detectable: the pedestals stand on rigid ground
    /// as far as these data tell.
    NotDetected,
}

impl BaseIdentifiability {
    /// `full`, `quasi_static`, `mass_line` or `not_detected`.
    pub fn name(&self) -> &'static str {
        match self {
            BaseIdentifiability::Full => "full",
            BaseIdentifiability::QuasiStatic { .. } => "quasi_static",
            BaseIdentifiability::MassLine { .. } => "mass_line",
            BaseIdentifiability::NotDetected => "not_detected",
        }
    }
}

/// The joint fit of a group of pedestals and their base.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BaseFitResult {
    /// θ = (k_y [N/m], k_z [N/m], m [kg], c_y, c_z [N·s/m]) per bearing of
    /// the group, in the group's order.
    pub pedestals: Vec<[f64; 5]>,
    /// Standard errors of `pedestals`, same units.
    pub pedestal_std_err: Vec<[f64; 5]>,
    /// The base (meaningful as far as `identifiability` says).
    pub base: BaseParams,
    /// Standard errors of `base`, same units (∞ when not determined).
    pub base_std_err: BaseParams,
    /// Base natural frequency sqrt(K_B/M_B)/2π (y, z) [Hz] (NaN when M_B ≤ 0).
    pub base_frequency_hz: [f64; 2],
    /// What the data determine in y and z.
    pub identifiability: [BaseIdentifiability; 2],
    /// J = Σ eᵀΣ⁻¹e at the estimate [-].
    pub chi2: f64,
    /// Degrees of freedom (real equations − parameters).
    pub dof: usize,
    /// J of the same pedestals on rigid ground (refitted) [-]: the
    /// likelihood ratio J_rigid − J tests for base motion.
    pub chi2_rigid: f64,
    /// RMS of each pedestal's unweighted equation residual e_i [N] (group order).
    pub pedestal_residual_rms: Vec<f64>,
    /// Condition number of the unit-diagonal Fisher information of the
    /// estimated parameters, square-rooted (as for the rigid fit) [-].
    pub condition_number: f64,
    /// True when the final iteration met its convergence test.
    pub converged: bool,
    /// Levenberg–Marquardt iterations of the final fit.
    pub iterations: usize,
    /// Speeds used (those every pedestal of the group has) [Hz].
    pub speeds_hz: Vec<f64>,
}

/// Why a base fit could not run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BaseFitError {
    /// A group member that is not in the observations.
    #[error("base group names observation {index}, but only {available} bearings were given")]
    NoSuchBearing {
        /// The index.
        index: usize,
        /// Bearings given.
        available: usize,
    },
    /// An empty group, or one naming a bearing twice.
    #[error("a base group needs distinct bearings (got {0:?})")]
    BadGroup(Vec<usize>),
    /// Too few common speeds for the parameters.
    #[error("{equations} equations at the speeds all pedestals of the group share, for {parameters} parameters")]
    TooFewEquations {
        /// Real equations.
        equations: usize,
        /// Parameters.
        parameters: usize,
    },
    /// The noise model gives no noise, or the data are not finite.
    #[error("the likelihood cannot be evaluated (no noise at some speed, or non-finite data)")]
    NotEvaluable,
}

/// One speed of a group: the observation of each group member.
struct Speed {
    omega: f64,
    obs: Vec<Observation>,
    /// Each member's bearing force F = K*·rel [N].
    force: Vec<[C; 2]>,
    var: Vec<f64>,
}

/// The unmeasured-base equations of a group (module docs); parameters
/// p = (θ of each member, then (κ, μ, γ) for y, then for z).
struct Unmeasured {
    speeds: Vec<Speed>,
}

/// Offset of the base parameters of direction `d` in p for `n` pedestals.
fn base_at(n: usize, d: usize) -> usize {
    5 * n + 3 * d
}

/// Real 2×2 block of complex factor `a` into `b` at (row, col).
fn put(b: &mut DMatrix<f64>, row: usize, col: usize, a: C) {
    b[(row, col)] += a.re;
    b[(row, col + 1)] -= a.im;
    b[(row + 1, col)] += a.im;
    b[(row + 1, col + 1)] += a.re;
}

/// Pedestal spring-damper d = k + iΩc in direction `d` of θ [N/m].
fn spring(theta: &[f64], d: usize, omega: f64) -> C {
    C::new(theta[d], omega * theta[3 + d])
}

impl Equations for Unmeasured {
    fn speeds(&self) -> usize {
        self.speeds.len()
    }

    fn variance(&self, s: usize) -> &[f64] {
        &self.speeds[s].var
    }

    fn error(&self, s: usize, p: &[f64]) -> DVector<f64> {
        let sp = &self.speeds[s];
        let n = sp.obs.len();
        let w = sp.omega;
        let w2 = w * w;
        let mut e = DVector::zeros(4 * n);
        for d in 0..2 {
            let q = &p[base_at(n, d)..base_at(n, d) + 3];
            let g = C::new(q[0], 0.0) / C::new(1.0 - w2 * q[1], w * q[2]);
            let t: C = sp
                .obs
                .iter()
                .enumerate()
                .map(|(j, o)| sp.force[j][d] + w2 * p[5 * j + 2] * o.ped[d])
                .sum();
            for (i, o) in sp.obs.iter().enumerate() {
                let th = &p[5 * i..5 * i + 5];
                let di = spring(th, d, w);
                let r = (di - w2 * th[2]) * o.ped[d] - sp.force[i][d] - di * g * t;
                e[4 * i + 2 * d] = r.re;
                e[4 * i + 2 * d + 1] = r.im;
            }
        }
        e
    }

    fn residual(&self, s: usize, p: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
        let sp = &self.speeds[s];
        let n = sp.obs.len();
        let w = sp.omega;
        let w2 = w * w;
        let mut e = DVector::zeros(4 * n);
        let mut b = DMatrix::zeros(4 * n, 8 * n);
        for d in 0..2 {
            let q = &p[base_at(n, d)..base_at(n, d) + 3];
            let g = C::new(q[0], 0.0) / C::new(1.0 - w2 * q[1], w * q[2]);
            let t: C = sp
                .obs
                .iter()
                .enumerate()
                .map(|(j, o)| sp.force[j][d] + w2 * p[5 * j + 2] * o.ped[d])
                .sum();
            for (i, o) in sp.obs.iter().enumerate() {
                let th = &p[5 * i..5 * i + 5];
                let di = spring(th, d, w);
                let h = di - w2 * th[2];
                let r = h * o.ped[d] - sp.force[i][d] - di * g * t;
                e[4 * i + 2 * d] = r.re;
                e[4 * i + 2 * d + 1] = r.im;
                for (j, oj) in sp.obs.iter().enumerate() {
                    let coupling = -di * g;
                    // ∂e_i/∂X_j and ∂e_i/∂rel_j (through F_j = K*_j·rel_j).
                    let dx =
                        coupling * (w2 * p[5 * j + 2]) + if i == j { h } else { C::new(0.0, 0.0) };
                    put(&mut b, 4 * i + 2 * d, 8 * j + 4 + 2 * d, dx);
                    let df = coupling - if i == j { 1.0 } else { 0.0 };
                    for c in 0..2 {
                        put(&mut b, 4 * i + 2 * d, 8 * j + 2 * c, df * oj.kstar[d][c]);
                    }
                }
            }
        }
        (e, b)
    }
}

/// The speeds every member of `group` has, with their observations.
fn common_speeds(obs: &[Vec<Observation>], group: &BaseGroup) -> Result<Vec<Speed>, BaseFitError> {
    let mut seen = Vec::new();
    for &i in &group.bearings {
        if i >= obs.len() {
            return Err(BaseFitError::NoSuchBearing {
                index: i,
                available: obs.len(),
            });
        }
        if seen.contains(&i) {
            return Err(BaseFitError::BadGroup(group.bearings.clone()));
        }
        seen.push(i);
    }
    let Some(&first) = group.bearings.first() else {
        return Err(BaseFitError::BadGroup(Vec::new()));
    };
    let mut speeds: Vec<Speed> = Vec::new();
    for o in obs[first].iter().filter(|o| o.is_finite()) {
        let members: Option<Vec<Observation>> = group
            .bearings
            .iter()
            .map(|&i| {
                obs[i]
                    .iter()
                    .find(|x| x.speed_hz == o.speed_hz && x.is_finite())
                    .copied()
            })
            .collect();
        if let Some(members) = members {
            let var = members.iter().flat_map(|m| m.var).collect();
            speeds.push(Speed {
                omega: o.omega(),
                force: members.iter().map(Observation::force).collect(),
                obs: members,
                var,
            });
        }
    }
    speeds.sort_by(|a, b| a.omega.total_cmp(&b.omega));
    speeds.dedup_by(|a, b| a.omega == b.omega);
    Ok(speeds)
}

/// Most iterations of a profiling fit and of the final fit.
const GRID_ITERATIONS: usize = 20;
const FINAL_ITERATIONS: usize = 200;
/// Base frequencies of the profile grid, and the damping ratio each of its
/// fits starts from.
const GRID_FREQUENCIES: usize = 24;
const GRID_DAMPING: f64 = 0.05;
/// Likelihood-ratio threshold (J_rigid − J) for base motion in one
/// direction: the 1e-3 upper point of χ²(3) (three base parameters).
pub const DETECTION_THRESHOLD: f64 = 16.27;

/// Joint ML fit of all pedestals of `group` and its base (module docs).
/// `obs[b]` are bearing b's observations (with their noise variances, from
/// [`super::noise`]); `start[b]` its rigid-ground fit θ (both indexed like
/// `obs`; only the group's entries are read).
pub fn fit_on_unmeasured_base(
    obs: &[Vec<Observation>],
    group: &BaseGroup,
    start: &[[f64; 5]],
) -> Result<BaseFitResult, BaseFitError> {
    let speeds = common_speeds(obs, group)?;
    let n = group.bearings.len();
    let n_par = 5 * n + 6;
    let n_eq = 4 * n * speeds.len();
    if n_eq <= n_par || speeds.len() < 4 {
        return Err(BaseFitError::TooFewEquations {
            equations: n_eq,
            parameters: n_par,
        });
    }
    let (w_lo, w_hi) = (speeds[0].omega, speeds[speeds.len() - 1].omega);
    let w_mid = (w_lo * w_hi).sqrt();
    let eq = Unmeasured { speeds };
    let mut p0 = vec![0.0; n_par];
    let mut scale = vec![1.0; n_par];
    let mut k_sum = 0.0;
    for (i, &b) in group.bearings.iter().enumerate() {
        let th = start.get(b).copied().unwrap_or([0.0; 5]);
        p0[5 * i..5 * i + 5].copy_from_slice(&th);
        let k = th[0].abs().max(th[1].abs()).max(1.0);
        k_sum += k;
        scale[5 * i] = th[0].abs().max(1e-3 * k);
        scale[5 * i + 1] = th[1].abs().max(1e-3 * k);
        scale[5 * i + 2] = th[2].abs().max(1e-3 * k / (w_mid * w_mid));
        scale[5 * i + 3] = th[3].abs().max(1e-3 * k / w_mid);
        scale[5 * i + 4] = th[4].abs().max(1e-3 * k / w_mid);
    }
    for d in 0..2 {
        let o = base_at(n, d);
        scale[o] = 1.0 / k_sum;
        scale[o + 1] = 1.0 / (w_mid * w_mid);
        scale[o + 2] = 1.0 / w_mid;
    }
    let pedestal_free: Vec<bool> = (0..n_par).map(|k| k < 5 * n).collect();
    let frozen: Vec<DMatrix<f64>> = (0..eq.speeds())
        .map(|s| gh::whitening(&eq, s, &p0))
        .collect::<Option<_>>()
        .ok_or(BaseFitError::NotEvaluable)?;

    // Rigid ground, refitted under this model's weights (the null).
    let rigid = gh::fit(&eq, &p0, &scale, &pedestal_free, None, FINAL_ITERATIONS)
        .ok_or(BaseFitError::NotEvaluable)?;

    // Profile the base frequency with frozen weights: every fit of the grid
    // starts from the rigid pedestals with the base mode at f (both
    // directions, then each direction alone) and frees everything.
    let (f_lo, f_hi) = (w_lo / TAU, w_hi / TAU);
    let grid: Vec<f64> = (0..GRID_FREQUENCIES)
        .map(|j| {
            let (a, b) = ((f_lo / 3.0).ln(), (3.0 * f_hi).ln());
            (a + (b - a) * j as f64 / (GRID_FREQUENCIES - 1) as f64).exp()
        })
        .collect();
    let all = vec![true; n_par];
    let shaped = |from: &[f64], d: usize, f: f64, zeta: f64| -> Vec<f64> {
        let mut p = from.to_vec();
        let wb = TAU * f;
        let o = base_at(n, d);
        // A base as compliant as the pedestals together, mode at f.
        p[o] = scale[o];
        p[o + 1] = 1.0 / (wb * wb);
        p[o + 2] = 2.0 * zeta / wb;
        p
    };
    let mut best = rigid.p.clone();
    let mut best_cost =
        gh::whitened(&eq, &best, Some(&frozen)).map_or(f64::INFINITY, |w| w.norm_squared());
    let consider =
        |p: Vec<f64>, frozen: &[DMatrix<f64>], best: &mut Vec<f64>, best_cost: &mut f64| {
            if let Some(m) = gh::fit(&eq, &p, &scale, &all, Some(frozen), GRID_ITERATIONS) {
                if m.cost < *best_cost {
                    *best_cost = m.cost;
                    *best = m.p;
                }
            }
        };
    for &f in &grid {
        let p = shaped(&shaped(&rigid.p, 0, f, GRID_DAMPING), 1, f, GRID_DAMPING);
        consider(p, &frozen, &mut best, &mut best_cost);
    }
    // Weights at the best so far, then each direction's mode on its own.
    let refrozen: Vec<DMatrix<f64>> = (0..eq.speeds())
        .map(|s| gh::whitening(&eq, s, &best))
        .collect::<Option<_>>()
        .unwrap_or(frozen);
    best_cost =
        gh::whitened(&eq, &best, Some(&refrozen)).map_or(f64::INFINITY, |w| w.norm_squared());
    for d in 0..2 {
        let from = best.clone();
        for &f in &grid {
            consider(
                shaped(&from, d, f, GRID_DAMPING),
                &refrozen,
                &mut best,
                &mut best_cost,
            );
        }
    }

    // Everything free, with the likelihood's own weights.
    let full = gh::fit(&eq, &best, &scale, &all, None, FINAL_ITERATIONS)
        .ok_or(BaseFitError::NotEvaluable)?;
    let full = if full.cost <= rigid.cost {
        full
    } else {
        rigid.clone()
    };
    let mut p = full.p.clone();
    let mut free = all.clone();

    // What the data determine, per direction.
    let mut ident = [BaseIdentifiability::NotDetected; 2];
    for (d, slot) in ident.iter_mut().enumerate() {
        let o = base_at(n, d);
        let mut null = p.clone();
        null[o..o + 3].copy_from_slice(&[0.0; 3]);
        let mut free_null = all.clone();
        free_null[o..o + 3].copy_from_slice(&[false; 3]);
        let j_null = gh::fit(&eq, &null, &scale, &free_null, None, FINAL_ITERATIONS)
            .map_or(f64::INFINITY, |m| m.cost);
        if j_null - full.cost < DETECTION_THRESHOLD {
            p[o..o + 3].copy_from_slice(&[0.0; 3]);
            free[o..o + 3].copy_from_slice(&[false; 3]);
            continue;
        }
        let (kappa, mu) = (p[o], p[o + 1]);
        let w_b = if mu > 0.0 {
            mu.powf(-0.5)
        } else {
            f64::INFINITY
        };
        *slot = if w_b < w_lo {
            BaseIdentifiability::MassLine {
                mass_kg: mu / kappa,
                std_err: f64::NAN,
            }
        } else if w_b > w_hi {
            BaseIdentifiability::QuasiStatic {
                compliance_m_per_n: kappa,
                std_err: f64::NAN,
            }
        } else {
            BaseIdentifiability::Full
        };
    }
    // Refit with the undetected directions held rigid.
    let fin = if free != all {
        gh::fit(&eq, &p, &scale, &free, None, FINAL_ITERATIONS).ok_or(BaseFitError::NotEvaluable)?
    } else {
        full
    };
    let p = fin.p.clone();
    let idx: Vec<usize> = (0..n_par).filter(|&k| free[k]).collect();
    let f_all = gh::fisher(&eq, &p, &scale).ok_or(BaseFitError::NotEvaluable)?;
    let f = DMatrix::from_fn(idx.len(), idx.len(), |r, c| f_all[(idx[r], idx[c])]);
    let mut cov = DMatrix::from_element(n_par, n_par, 0.0);
    let inv = gh::inverse_psd(&f);
    for (r, &a) in idx.iter().enumerate() {
        for (c, &b) in idx.iter().enumerate() {
            cov[(a, b)] = inv[(r, c)];
        }
    }
    let se = |k: usize| cov[(k, k)].max(0.0).sqrt();
    // Delta method: variance of g(p) with gradient `grad` over indices `at`.
    let delta = |at: &[usize], grad: &[f64]| -> f64 {
        let mut v = 0.0;
        for (a, ga) in at.iter().zip(grad) {
            for (b, gb) in at.iter().zip(grad) {
                v += ga * gb * cov[(*a, *b)];
            }
        }
        v.max(0.0).sqrt()
    };
    let mut base = BaseParams::RIGID;
    let mut base_se = BaseParams {
        k: [f64::INFINITY; 2],
        c: [f64::INFINITY; 2],
        m: [f64::INFINITY; 2],
    };
    let mut base_frequency_hz = [f64::NAN; 2];
    for d in 0..2 {
        let o = base_at(n, d);
        let (kappa, mu, gamma) = (p[o], p[o + 1], p[o + 2]);
        if ident[d] == BaseIdentifiability::NotDetected {
            continue;
        }
        let at = [o, o + 1, o + 2];
        base.k[d] = 1.0 / kappa;
        base.m[d] = mu / kappa;
        base.c[d] = gamma / kappa;
        base_se.k[d] = delta(&at, &[-1.0 / (kappa * kappa), 0.0, 0.0]);
        base_se.m[d] = delta(&at, &[-mu / (kappa * kappa), 1.0 / kappa, 0.0]);
        base_se.c[d] = delta(&at, &[-gamma / (kappa * kappa), 0.0, 1.0 / kappa]);
        if mu > 0.0 {
            base_frequency_hz[d] = 1.0 / (TAU * mu.sqrt());
        }
        match &mut ident[d] {
            BaseIdentifiability::QuasiStatic {
                compliance_m_per_n,
                std_err,
            } => {
                *compliance_m_per_n = kappa;
                *std_err = se(o);
            }
            BaseIdentifiability::MassLine { mass_kg, std_err } => {
                *mass_kg = base.m[d];
                *std_err = base_se.m[d];
            }
            _ => {}
        }
    }
    Ok(BaseFitResult {
        pedestals: (0..n)
            .map(|i| std::array::from_fn(|k| p[5 * i + k]))
            .collect(),
        pedestal_std_err: (0..n)
            .map(|i| std::array::from_fn(|k| se(5 * i + k)))
            .collect(),
        base,
        base_std_err: base_se,
        base_frequency_hz,
        identifiability: ident,
        chi2: fin.cost,
        dof: n_eq - idx.len(),
        chi2_rigid: rigid.cost,
        pedestal_residual_rms: (0..n)
            .map(|i| {
                let ss: f64 = (0..eq.speeds())
                    .map(|s| eq.residual(s, &p).0.rows(4 * i, 4).norm_squared())
                    .sum();
                (ss / (4 * eq.speeds()) as f64).sqrt()
            })
            .collect(),
        condition_number: gh::condition_number(&f),
        converged: fin.converged,
        iterations: fin.iterations,
        speeds_hz: eq.speeds.iter().map(|s| s.omega / TAU).collect(),
    })
}

/// The model's prediction of every group member's pedestal motion (y, z)
/// [m] at each common speed, given the measured bearing forces (from each
/// observation's rel), the pedestals `theta` (group order) and `base`:
/// the solution of the coupled equations of the module docs. Outer index:
/// speed (as in [`BaseFitResult::speeds_hz`]), inner: group member.
pub fn predict(
    obs: &[Vec<Observation>],
    group: &BaseGroup,
    theta: &[[f64; 5]],
    base: &BaseParams,
) -> Result<Vec<(f64, Vec<[C; 2]>)>, BaseFitError> {
    let speeds = common_speeds(obs, group)?;
    let n = group.bearings.len();
    if theta.len() != n {
        return Err(BaseFitError::BadGroup(group.bearings.clone()));
    }
    let mut out = Vec::with_capacity(speeds.len());
    for sp in &speeds {
        let w = sp.omega;
        let w2 = w * w;
        let mut x = vec![[C::new(0.0, 0.0); 2]; n];
        for d in 0..2 {
            let g = base.receptance(d, w);
            // (d_i − Ω²m_i)·X_i − d_i·G·Σ_j Ω²m_j·X_j = F_i + d_i·G·Σ_j F_j
            let f_sum: C = sp.obs.iter().map(|o| o.force()[d]).sum();
            let a = DMatrix::from_fn(n, n, |i, j| {
                let di = spring(&theta[i], d, w);
                let diag = if i == j {
                    di - w2 * theta[i][2]
                } else {
                    C::new(0.0, 0.0)
                };
                diag - di * g * w2 * theta[j][2]
            });
            let rhs = DVector::from_fn(n, |i, _| {
                sp.obs[i].force()[d] + spring(&theta[i], d, w) * g * f_sum
            });
            let sol = a.lu().solve(&rhs).ok_or(BaseFitError::NotEvaluable)?;
            for i in 0..n {
                x[i][d] = sol[i];
            }
        }
        out.push((w / TAU, x));
    }
    Ok(out)
}

/// J = Σ eᵀΣ⁻¹e [-] of the group's equations (module docs) at given
/// pedestals (group order) and base, with the observations' noise: the
/// misfit a diagnosis compares with its degrees of freedom.
pub fn chi2(
    obs: &[Vec<Observation>],
    group: &BaseGroup,
    theta: &[[f64; 5]],
    base: &BaseParams,
) -> Result<f64, BaseFitError> {
    let speeds = common_speeds(obs, group)?;
    let n = group.bearings.len();
    if theta.len() != n {
        return Err(BaseFitError::BadGroup(group.bearings.clone()));
    }
    let mut p: Vec<f64> = theta.iter().flatten().copied().collect();
    for d in 0..2 {
        if base.k[d].is_finite() && base.k[d] != 0.0 {
            p.extend([
                1.0 / base.k[d],
                base.m[d] / base.k[d],
                base.c[d] / base.k[d],
            ]);
        } else {
            p.extend([0.0; 3]);
        }
    }
    gh::cost(&Unmeasured { speeds }, &p).ok_or(BaseFitError::NotEvaluable)
}

/// One speed of a measured base: its 1X motion and the noise of each real
/// number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BaseObservation {
    /// Rotor speed [Hz].
    pub speed_hz: f64,
    /// Absolute base displacement (y, z) [m].
    pub motion: [C; 2],
    /// Noise variance [m²] of (y re, y im, z re, z im).
    pub var: [f64; 4],
}

/// One pedestal on a measured base: per speed its observation and the
/// base's; p = θ.
struct Measured {
    speeds: Vec<(Observation, BaseObservation, Vec<f64>)>,
}

impl Equations for Measured {
    fn speeds(&self) -> usize {
        self.speeds.len()
    }

    fn variance(&self, s: usize) -> &[f64] {
        &self.speeds[s].2
    }

    fn residual(&self, s: usize, p: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
        let (o, base, _) = &self.speeds[s];
        let w = o.omega();
        let mut e = DVector::zeros(4);
        let mut b = DMatrix::zeros(4, 12);
        for d in 0..2 {
            let dd = spring(p, d, w);
            let h = dd - w * w * p[2];
            let r = h * o.ped[d] - dd * base.motion[d] - o.force()[d];
            e[2 * d] = r.re;
            e[2 * d + 1] = r.im;
            put(&mut b, 2 * d, 4 + 2 * d, h);
            put(&mut b, 2 * d, 8 + 2 * d, -dd);
            for c in 0..2 {
                put(&mut b, 2 * d, 2 * c, -o.kstar[d][c]);
            }
        }
        (e, b)
    }
}

/// ML fit of one pedestal on a measured base (module docs): its
/// observations `obs`, the base motion `base` at the same speeds (matched
/// exactly; a speed without base motion is an error), from `start`
/// (e.g. the least-squares fit). Noise in rel, ped and the base motion all
/// weigh in. The result's covariance is over all five parameters.
pub fn fit_on_measured_base(
    obs: &[Observation],
    base: &[BaseObservation],
    start: &[f64; 5],
) -> Result<super::ml::MlFit, MeasuredBaseError> {
    let mut speeds = Vec::new();
    for o in obs.iter().filter(|o| o.is_finite()) {
        let b = base.iter().find(|b| b.speed_hz == o.speed_hz).ok_or(
            MeasuredBaseError::NoBaseMotion {
                speed_hz: o.speed_hz,
            },
        )?;
        let mut var = o.var.to_vec();
        var.extend(b.var);
        speeds.push((*o, *b, var));
    }
    let n_eq = 4 * speeds.len();
    if n_eq <= 5 {
        return Err(MeasuredBaseError::TooFewEquations { equations: n_eq });
    }
    let w_mid = {
        let lo = speeds
            .iter()
            .map(|s| s.0.omega())
            .fold(f64::INFINITY, f64::min);
        let hi = speeds.iter().map(|s| s.0.omega()).fold(0.0, f64::max);
        (lo * hi).sqrt().max(f64::MIN_POSITIVE)
    };
    let k = start[0].abs().max(start[1].abs()).max(1.0);
    let scale = [
        start[0].abs().max(1e-3 * k),
        start[1].abs().max(1e-3 * k),
        start[2].abs().max(1e-3 * k / (w_mid * w_mid)),
        start[3].abs().max(1e-3 * k / w_mid),
        start[4].abs().max(1e-3 * k / w_mid),
    ];
    let eq = Measured { speeds };
    let m = gh::fit(&eq, start, &scale, &[true; 5], None, FINAL_ITERATIONS)
        .ok_or(MeasuredBaseError::NotEvaluable)?;
    let f = gh::fisher(&eq, &m.p, &scale).ok_or(MeasuredBaseError::NotEvaluable)?;
    let inv = gh::inverse_psd(&f);
    let condition_number = gh::condition_number(&f);
    let residual_rms = ((0..eq.speeds())
        .map(|s| eq.residual(s, &m.p).0.norm_squared())
        .sum::<f64>()
        / n_eq as f64)
        .sqrt();
    Ok(super::ml::MlFit {
        theta: std::array::from_fn(|i| m.p[i]),
        covariance: std::array::from_fn(|r| std::array::from_fn(|c| inv[(r, c)])),
        chi2: m.cost,
        dof: n_eq - 5,
        iterations: m.iterations,
        converged: m.converged,
        condition_number,
        residual_rms,
    })
}

/// Why a measured-base fit could not run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeasuredBaseError {
    /// A pedestal speed without base motion at exactly that speed.
    #[error("no base motion at {speed_hz} Hz")]
    NoBaseMotion {
        /// The speed [Hz].
        speed_hz: f64,
    },
    /// No more equations than parameters.
    #[error("{equations} equations for 5 parameters")]
    TooFewEquations {
        /// Real equations.
        equations: usize,
    },
    /// The noise model gives no noise, or the data are not finite.
    #[error("the likelihood cannot be evaluated (no noise at some speed, or non-finite data)")]
    NotEvaluable,
}
