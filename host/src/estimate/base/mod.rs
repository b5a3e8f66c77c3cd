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

mod measured;
mod unmeasured;

pub use measured::{fit_on_measured_base, BaseObservation, MeasuredBaseError};
pub use unmeasured::{
    chi2, fit_on_unmeasured_base, predict, widen_by_profile, Misfit, Prediction,
    DETECTION_THRESHOLD,
};

use nalgebra::DMatrix;
use num_complex::Complex;
use serde::Serialize;

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
    /// Standard errors of `pedestals`, same units: the Fisher ones, widened
    /// to the spread along the pedestal's mass split where that is larger
    /// once [`widen_by_profile`] has run on the fit (the profile
    /// likelihood, `unmeasured/profile.rs`; the reported fit only: it costs
    /// seconds).
    pub pedestal_std_err: Vec<[f64; 5]>,
    /// Per pedestal (group order) and parameter (k_y, k_z, m): true when
    /// the profile of J along it did not rise by 1 within 16 Fisher
    /// standard errors on a side (or reached zero): the data do not bound
    /// it there (its split with the base is not resolved) and its ± is a
    /// lower bound. False until [`widen_by_profile`] has run.
    pub split_unresolved: Vec<[bool; 3]>,
    /// Per direction (y, z) and base parameter (K_B, M_B, C_B): true when
    /// the profile of J along the base's own parameter (κ = 1/K_B,
    /// μ = M_B/K_B, γ = C_B/K_B) did not rise by 1 within 16 Fisher
    /// standard errors on a side (or reached zero): the data do not bound
    /// it there, and its ± is a lower bound. False until
    /// [`widen_by_profile`] has run.
    pub base_unresolved: [[bool; 3]; 2],
    /// Covariance of each pedestal's θ (group order; θ's units, zero rows
    /// and columns for fixed parameters), from the Fisher information at
    /// the estimate, each row and column scaled like its ± by
    /// [`widen_by_profile`]: f_n and ζ get their ± from it (`present::modal`).
    pub pedestal_covariance: Vec<[[f64; 5]; 5]>,
    /// The base (meaningful as far as `identifiability` says).
    pub base: BaseParams,
    /// Standard errors of `base`, same units (∞ when not determined): the
    /// Fisher ones by the delta method, widened to the profile
    /// likelihood's once [`widen_by_profile`] has run on the fit.
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

/// Real 2×2 block of complex factor `a` into `b` at (row, col).
pub(crate) fn put(b: &mut DMatrix<f64>, row: usize, col: usize, a: C) {
    b[(row, col)] += a.re;
    b[(row, col + 1)] -= a.im;
    b[(row + 1, col)] += a.im;
    b[(row + 1, col + 1)] += a.re;
}

/// Pedestal spring-damper d = k + iΩc in direction `d` of θ [N/m].
pub(crate) fn spring(theta: &[f64], d: usize, omega: f64) -> C {
    C::new(theta[d], omega * theta[3 + d])
}
