//! Maximum-likelihood fit of one pedestal on rigid ground together with a
//! constant probe runout r = (r_y, r_z) [m] on its `rel` probes.
//!
//! Per speed the residual of the pedestal equation with the runout taken
//! off the probes is
//!
//! ```text
//! e = H(θ)·X_ped − K*·(rel − r)
//! ```
//!
//! (the rigid model of [`super`] with rel − r for rel). r is a parameter,
//! not a measured number, so the noise covariance Σ(θ) of e is the rigid
//! model's; J(θ, r) = Σ eᵀΣ(θ)⁻¹e is minimised over all nine numbers at
//! once by the one Levenberg–Marquardt loop of
//! [`crate::estimate::gauss_helmert`]. Unlike a weighted least-squares fit
//! with the weights held at a reference θ, the likelihood counts that Σ
//! grows with |H(θ)| (the pick-up noise enters e through H(θ)·X_ped): where
//! the pedestal's motion is near its pick-ups' noise, the held-weights fit
//! pulls k and m toward zero (the regression-dilution bias of a noisy
//! regressor) and this fit does not. The covariance is the inverse of the
//! joint Fisher information over (θ, r): the ± of θ count the runout's
//! own uncertainty.

use crate::estimate::base::{put, spring};
use crate::estimate::gauss_helmert::{self as gh, Equations};
use crate::estimate::Observation;
use nalgebra::{DMatrix, DVector};
use num_complex::Complex;
use plinth_shared::regression::PARAMETERS;

/// The number of runout parameters: (r_y re, r_y im, r_z re, r_z im) [m].
pub const RUNOUT_PARAMETERS: usize = 4;

/// Most Levenberg–Marquardt iterations.
const ITERATIONS: usize = 200;

/// The ML fit of a pedestal with a probe runout.
#[derive(Clone, Debug)]
pub struct RunoutFit {
    /// θ = (k_y [N/m], k_z [N/m], m [kg], c_y [N·s/m], c_z [N·s/m]).
    pub theta: [f64; PARAMETERS],
    /// r = (r_y re, r_y im, r_z re, r_z im) [m].
    pub runout: [f64; RUNOUT_PARAMETERS],
    /// Inverse joint Fisher information over (θ, r) (θ's units, then m).
    pub covariance: DMatrix<f64>,
    /// J at the estimate [-].
    pub chi2: f64,
    /// Degrees of freedom 4n − 9.
    pub dof: usize,
}

impl RunoutFit {
    /// Standard error of parameter `i` of (θ, r) (θ's units, then m).
    pub fn std_err(&self, i: usize) -> f64 {
        self.covariance[(i, i)].max(0.0).sqrt()
    }
}

/// One pedestal's observations, p = (θ, r).
struct WithRunout<'a> {
    obs: &'a [Observation],
}

impl Equations for WithRunout<'_> {
    fn speeds(&self) -> usize {
        self.obs.len()
    }

    fn variance(&self, s: usize) -> &[f64] {
        &self.obs[s].var
    }

    fn residual(&self, s: usize, p: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
        let o = &self.obs[s];
        let w = o.omega();
        let r = [
            Complex::new(p[PARAMETERS], p[PARAMETERS + 1]),
            Complex::new(p[PARAMETERS + 2], p[PARAMETERS + 3]),
        ];
        let mut e = DVector::zeros(4);
        let mut b = DMatrix::zeros(4, 8);
        for d in 0..2 {
            let h = spring(p, d, w) - w * w * p[2];
            let mut v = h * o.ped[d];
            for (c, (k, (rel, r))) in o.kstar[d].iter().zip(o.rel.iter().zip(r)).enumerate() {
                v -= k * (rel - r);
                put(&mut b, 2 * d, 2 * c, -k);
            }
            put(&mut b, 2 * d, 4 + 2 * d, h);
            e[2 * d] = v.re;
            e[2 * d + 1] = v.im;
        }
        (e, b)
    }
}

/// The ML fit (module docs) of the pedestal of `obs` with a runout, from
/// `theta` and `runout` (the least-squares estimates). `None` when J cannot
/// be evaluated, the data have no more equations than parameters, or a
/// number is not finite.
pub fn fit_with_runout(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    runout: &[f64; RUNOUT_PARAMETERS],
) -> Option<RunoutFit> {
    let n = PARAMETERS + RUNOUT_PARAMETERS;
    let dof = (4 * obs.len()).checked_sub(n).filter(|d| *d > 0)?;
    if !obs.iter().all(Observation::is_finite) {
        return None;
    }
    let start: Vec<f64> = theta.iter().chain(runout).copied().collect();
    if !start.iter().all(|v| v.is_finite()) {
        return None;
    }
    // Units: each parameter's scale is its start's size, or (a zero start)
    // the size that moves the equations as much as the others do.
    let w_lo = obs
        .iter()
        .map(Observation::omega)
        .fold(f64::INFINITY, f64::min);
    let w_hi = obs.iter().map(Observation::omega).fold(0.0, f64::max);
    let w_mid = (w_lo * w_hi).sqrt().max(f64::MIN_POSITIVE);
    let k = theta[0].abs().max(theta[1].abs()).max(1.0);
    let rel_rms = (obs
        .iter()
        .map(|o| o.rel.iter().map(|v| v.norm_sqr()).sum::<f64>())
        .sum::<f64>()
        / (2 * obs.len()) as f64)
        .sqrt()
        .max(f64::MIN_POSITIVE);
    let mut scale = vec![
        theta[0].abs().max(1e-3 * k),
        theta[1].abs().max(1e-3 * k),
        theta[2].abs().max(1e-3 * k / (w_mid * w_mid)),
        theta[3].abs().max(1e-3 * k / w_mid),
        theta[4].abs().max(1e-3 * k / w_mid),
    ];
    scale.extend(runout.iter().map(|r| r.abs().max(1e-3 * rel_rms)));
    let eq = WithRunout { obs };
    let m = gh::fit(&eq, &start, &scale, &vec![true; n], None, ITERATIONS)?;
    if !m.p.iter().all(|v| v.is_finite()) {
        return None;
    }
    let f = gh::fisher(&eq, &m.p, &scale)?;
    Some(RunoutFit {
        theta: std::array::from_fn(|i| m.p[i]),
        runout: std::array::from_fn(|i| m.p[PARAMETERS + i]),
        covariance: gh::inverse_psd(&f),
        chi2: m.cost,
        dof,
    })
}
