//! Δ̂'s share of θ̂'s own error: the speed column's regression column is
//! a generated regressor.
//!
//! The Δ step ([`super::linearise`]) is taken at the fitted θ̂: the column
//! ∂e/∂f (through the pedestal's Ω²m and iΩc and the weights, which move
//! with θ in the Gauss–Helmert fit) and the whitening are θ̂'s, not the
//! machine's. θ̂ is off by its noise, the same at every speed, and that
//! error changes the column everywhere at once: Δ̂ moves by ∇_θΔ̂·(θ̂ − θ)
//! , a term smooth in speed that the per-speed scatter
//! ([`super::spread::scatter_std`]) does not see and the information of Δ
//! (θ held at θ̂ in the column) does not count. Its mean over the noise is
//! zero to first order (the efficient score is orthogonal to θ), but its
//! size in one run is not: ∇_θΔ̂ at the data is made of the noise itself
//! (the column's change with θ against the residual), so Δ̂/σ_Δ had heavy
//! tails on clean ROSS runs (docs/trust-speed.md, Session 50 (speed50)).
//!
//! **Its variance** ([`theta_variance`], the delta method): Var(Δ̂) gains
//! ∇_θΔ̂ᵀ·Cov(θ̂)·∇_θΔ̂ per bearing (the bearings' θ̂ are independent: their
//! data are), with ∇_θΔ̂ at the data by central differences of the joint
//! step along the square-root directions of Cov(θ̂) (the information's,
//! times the bearing's excess, as Δ's own ±): Σ_k ((Δ̂(θ̂ + u_k) −
//! Δ̂(θ̂ − u_k))/2)², u_k the k-th principal direction scaled to its ±.

use super::linearise::{joint, terms, Terms};
use crate::estimate::lack_of_fit::delay_unknown::scaled_svd;
use crate::estimate::Observation;
use crate::rundir::BearingSchedule;
use nalgebra::DMatrix;
use plinth_shared::regression::{Parameter, PARAMETERS};

/// One bearing's fit as the Δ step takes it.
pub struct Fitted<'a> {
    /// Its observations as the step takes them (the fit's outliers out).
    pub obs: &'a [Observation],
    /// Its bearing table.
    pub schedule: &'a BearingSchedule,
    /// θ̂ (SI).
    pub theta: [f64; PARAMETERS],
    /// The estimated parameters, the columns of `terms.jac` in order.
    pub columns: &'a [Parameter],
    /// The step's terms at θ̂.
    pub terms: &'a Terms,
}

/// The square-root directions of Cov(θ̂) from the whitened Jacobian `jac`
/// (one per column, in θ units over the columns: Cov = Σ_k u_k·u_kᵀ),
/// `scale` times; `None` where the columns are degenerate ([`scaled_svd`]).
fn directions(jac: &DMatrix<f64>, scale: f64) -> Option<Vec<Vec<f64>>> {
    let (norms, singular_values, v_t) = scaled_svd(jac)?;
    let p = norms.len();
    Some(
        (0..p)
            .map(|k| {
                (0..p)
                    .map(|i| scale * v_t[(k, i)] / singular_values[k] / norms[i])
                    .collect()
            })
            .collect(),
    )
}

/// Var(Δ̂) from the bearings' θ̂ errors [Hz²] (module docs): `bearings`
/// the ones Δ is estimated from, in the order the joint step takes them.
/// `None` where a step cannot be formed.
pub fn theta_variance(bearings: &[Fitted<'_>]) -> Option<f64> {
    let base: Vec<Terms> = bearings.iter().map(|b| b.terms.clone()).collect();
    let mut var = 0.0;
    for (i, b) in bearings.iter().enumerate() {
        let (rows, p) = b.terms.jac.shape();
        let dof = rows.checked_sub(p + 1).filter(|&d| d > 0)? as f64;
        let excess = (b.terms.resid.norm_squared() / dof).max(1.0).sqrt();
        for u in directions(&b.terms.jac, excess)? {
            let at = |sign: f64| {
                let mut theta = b.theta;
                for (k, &c) in b.columns.iter().enumerate() {
                    theta[c as usize] += sign * u[k];
                }
                let mut moved = base.clone();
                moved[i] = terms(b.obs, b.schedule, &theta, b.columns)?;
                joint(&moved).map(|j| j.offset_hz)
            };
            let d = 0.5 * (at(1.0)? - at(-1.0)?);
            var += d * d;
        }
    }
    var.is_finite().then_some(var)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The square-root directions rebuild the information's covariance
    /// (XᵀX)⁻¹ times the scale², columns of very different units alike.
    #[test]
    fn the_directions_rebuild_the_covariance() {
        let x = DMatrix::from_row_slice(
            5,
            2,
            &[1.0, 2.0e6, 0.5, -1.0e6, 2.0, 3.0e6, -1.0, 0.5e6, 0.3, 1.0e6],
        );
        let u = directions(&x, 2.0).expect("directions");
        let cov = (x.transpose() * &x).try_inverse().expect("inverse") * 4.0;
        for i in 0..2 {
            for j in 0..2 {
                let sum: f64 = u.iter().map(|d| d[i] * d[j]).sum();
                assert!(
                    (sum - cov[(i, j)]).abs() <= 1e-9 * cov[(i, i)].sqrt() * cov[(j, j)].sqrt(),
                    "{i}{j}: {sum} against {}",
                    cov[(i, j)]
                );
            }
        }
    }
}
