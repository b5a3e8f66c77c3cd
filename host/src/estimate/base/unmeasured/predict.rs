//! The group's model at given parameters: the pedestal motion the coupled
//! equations predict from the measured bearing forces, and the misfit χ²
//! of the measured motion.

use super::equations::{common_speeds, Unmeasured};
use crate::estimate::base::{spring, BaseFitError, BaseGroup, BaseParams, C};
use crate::estimate::gauss_helmert as gh;
use crate::estimate::Observation;
use nalgebra::{DMatrix, DVector};
use std::f64::consts::TAU;

/// The model's pedestal motion of a group at one speed ([`predict`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Prediction {
    /// Rotor speed [Hz].
    pub speed_hz: f64,
    /// Pedestal motion (y, z) [m] of each group member (group order).
    pub ped: Vec<[C; 2]>,
}

/// The model's prediction of every group member's pedestal motion at each
/// speed all members share (as in [`BaseFitResult::speeds_hz`]), given the
/// measured bearing forces (from each observation's rel), the pedestals
/// `theta` (group order) and `base`: the solution of the coupled equations
/// of the module docs. Compare with the measured `ped` for a gap.
pub fn predict(
    obs: &[Vec<Observation>],
    group: &BaseGroup,
    theta: &[[f64; 5]],
    base: &BaseParams,
) -> Result<Vec<Prediction>, BaseFitError> {
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
            for (xi, v) in x.iter_mut().zip(sol.iter()) {
                xi[d] = *v;
            }
        }
        out.push(Prediction {
            speed_hz: w / TAU,
            ped: x,
        });
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
