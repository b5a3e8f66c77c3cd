//! The ± of a fit whose weights are a variance function estimated from the
//! same fit's residuals ([`super::refit_under`]).
//!
//! **Why.** The fit's own covariance F⁻¹ (F = Σ_s Aᵀ·Σ_s⁻¹·A) holds when
//! each speed's equation covariance Σ_s is the noise's. Under a variance
//! function fitted to the residuals (α, β per channel: eight numbers from
//! the 4n residuals of n speeds), Σ_s is itself an estimate, and its error
//! moves the estimate: on ROSS unseen-five (32 speeds, 3 % noise) the
//! fractions and floors it finds scatter by factors of 2-30 around the
//! truth, the estimate's scatter is 10-25 % above the ± and 3 % of clean
//! `ok` pedestals were more than 3 ± off (docs/estimation-scatter.md "Session 40 (scatterpm17)").
//!
//! **Model.** θ̂ solves Σ_s Aᵀ·W_s(p̂)·e_s = 0 with W_s = Σ_s(p)⁻¹ and p̂
//! the variance function. A small error δp moves it by
//! δθ = F⁻¹·Σ_s Aᵀ·(∂W_s/∂p_k)·e_s·δp_k with ∂W_s/∂p_k = −W_s·M_sk·W_s
//! (M_sk = f_k·G_s,ch the covariance component k adds, [`super::Speed`]).
//! With δp of covariance V_p (the inverse of the restricted
//! pseudo-likelihood's information, I_kl = ½·tr(P·M_k·P·M_l) with
//! P = W − W·A·F⁻¹·Aᵀ·W over all speeds: the residuals are the fit's own,
//! [`super::fit_variance_function`]; with B_s = W_s·A_s it is
//! ½·Σ_s tr(W_s·M_sk·W_s·M_sl) − ½·tr(F⁻¹·R_kl) − ½·tr(F⁻¹·R_lk) +
//! ½·tr(F⁻¹·Q_k·F⁻¹·Q_l), Q_k = Σ_s B_sᵀ·M_sk·B_s,
//! R_kl = Σ_s B_sᵀ·M_sl·W_s·M_sk·B_s) and e_s of covariance
//! Σ_s, the expected covariance this adds is F⁻¹·Δ·F⁻¹ with
//! Δ = Σ_kl V_p,kl·Σ_s Aᵀ·W_s·M_sk·W_s·M_sl·W_s·A. For one variance scale
//! (M = Σ, V = 2s²/(4n)) Δ = F·2/(4n): the Student-t factor ν/(ν − 2) to
//! first order; for a variance function it is that factor's
//! multi-parameter form, large where a speed's weight rests on a poorly
//! determined component (a floor the residuals hardly see).

use super::{eigen_pseudo_inverse, jacobi_scaling, speeds, COMPONENTS, PER_CHANNEL};
use crate::estimate::ml;
use crate::estimate::Observation;
use nalgebra::{DMatrix, Matrix4, SMatrix};
use plinth_shared::regression::{Parameter, PARAMETERS};

/// The covariance [θ units] of the fit `covariance` (its F⁻¹ over all five
/// parameters, module docs) of `obs` (their variances the variance function
/// `law`'s, [`COMPONENTS`]) at `theta` (parameters `columns`), with the
/// variance function's own estimation error added (module docs): F⁻¹ +
/// F⁻¹·Δ·F⁻¹. Only the components of `law` that are positive count as
/// estimated. `None` when a speed's numbers are not finite, a covariance is
/// singular or the result is not finite.
pub fn with_law_uncertainty(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    law: &[f64; COMPONENTS],
    columns: &[Parameter],
    covariance: &[[f64; PARAMETERS]; PARAMETERS],
) -> Option<[[f64; PARAMETERS]; PARAMETERS]> {
    let speeds = speeds(obs.iter(), theta)?;
    let free: Vec<usize> = (0..COMPONENTS).filter(|&k| law[k] > 0.0).collect();
    let (m, p) = (free.len(), columns.len());
    if m == 0 || p == 0 || speeds.is_empty() {
        return Some(*covariance);
    }
    // Per speed: W·M_k (each free component) and W·A (the free columns).
    let mut wm: Vec<Vec<Matrix4<f64>>> = Vec::with_capacity(speeds.len());
    let mut wa: Vec<DMatrix<f64>> = Vec::with_capacity(speeds.len());
    let mut a_rows: Vec<DMatrix<f64>> = Vec::with_capacity(speeds.len());
    let mut info = DMatrix::<f64>::zeros(m, m);
    let c = DMatrix::<f64>::from_fn(p, p, |r, k| {
        covariance[columns[r] as usize][columns[k] as usize]
    });
    let mut q = vec![DMatrix::<f64>::zeros(p, p); m];
    let mut r_kl = vec![DMatrix::<f64>::zeros(p, p); m * m];
    for (s, o) in speeds.iter().zip(obs) {
        let w = s.own.try_inverse()?;
        // M_k (each free component) and W·M_k.
        let raw: Vec<Matrix4<f64>> = free
            .iter()
            .map(|&k| s.g[k / PER_CHANNEL] * s.factor(k))
            .collect();
        let mk: Vec<Matrix4<f64>> = raw.iter().map(|x| w * x).collect();
        for i in 0..m {
            for j in i..m {
                let v = 0.5 * mk[i].component_mul(&mk[j].transpose()).sum();
                info[(i, j)] += v;
                info[(j, i)] = info[(i, j)];
            }
        }
        let (a, _) = ml::rows(o);
        let a: SMatrix<f64, 4, PARAMETERS> = a;
        let a = DMatrix::<f64>::from_fn(4, p, |r, c| a[(r, columns[c] as usize)]);
        let w = DMatrix::<f64>::from_fn(4, 4, |r, c| w[(r, c)]);
        let wa_s = &w * &a;
        // M_k·W·A and W·M_k·W·A: the parts of the REML information.
        let x: Vec<DMatrix<f64>> = raw.iter().map(|r| dense(r) * &wa_s).collect();
        let y: Vec<DMatrix<f64>> = mk.iter().map(|r| dense(r) * &wa_s).collect();
        for i in 0..m {
            q[i] += wa_s.transpose() * &x[i];
            for j in 0..m {
                r_kl[i * m + j] += x[j].transpose() * &y[i];
            }
        }
        wa.push(wa_s);
        a_rows.push(a);
        wm.push(mk);
    }
    // The residuals are the fit's own: their covariance is P = W − W·A·F⁻¹·Aᵀ·W
    // in the weights, and the information ½·tr(P·M_k·P·M_l) is the ML one
    // less the cross terms ½·tr(F⁻¹·R_kl) + ½·tr(F⁻¹·R_lk) plus
    // ½·tr(F⁻¹·Q_k·F⁻¹·Q_l) (module docs).
    let cq: Vec<DMatrix<f64>> = q.iter().map(|x| &c * x).collect();
    for i in 0..m {
        for j in 0..m {
            let cross = (&c * &r_kl[i * m + j]).trace() + (&c * &r_kl[j * m + i]).trace();
            info[(i, j)] += 0.5 * ((&cq[i] * &cq[j]).trace() - cross);
        }
    }
    let v = pseudo_inverse(&info)?;
    let mut delta = DMatrix::<f64>::zeros(p, p);
    for ((mk, wa), a) in wm.iter().zip(&wa).zip(&a_rows) {
        // Σ_kl V_kl·W·M_k·W·M_l = Σ_k (W·M_k)·Σ_l V_kl·(W·M_l).
        let mut sum = Matrix4::<f64>::zeros();
        for (i, mi) in mk.iter().enumerate() {
            let mut inner = Matrix4::<f64>::zeros();
            for (j, mj) in mk.iter().enumerate() {
                inner += mj * v[(i, j)];
            }
            sum += mi * inner;
        }
        let sum = DMatrix::<f64>::from_fn(4, 4, |r, c| sum[(r, c)]);
        delta += a.transpose() * sum * wa;
    }
    let added = &c * (0.5 * (&delta + delta.transpose())) * &c;
    let mut out = *covariance;
    for (r, &pr) in columns.iter().enumerate() {
        for (k, &pk) in columns.iter().enumerate() {
            out[pr as usize][pk as usize] += added[(r, k)];
        }
    }
    out.iter().flatten().all(|x| x.is_finite()).then_some(out)
}

/// The pseudo-inverse of the symmetric positive semi-definite `info`, its
/// directions below [`super::RANK_TOLERANCE`] of the largest eigenvalue
/// (after Jacobi scaling) left out (the variance function's directions not
/// estimated, left out of V_p); `None` when it has no positive direction.
fn pseudo_inverse(info: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let n = info.nrows();
    let d = jacobi_scaling(info);
    let scaled = DMatrix::<f64>::from_fn(n, n, |r, c| d[r] * info[(r, c)] * d[c]);
    let (inv, _) = eigen_pseudo_inverse(&scaled)?;
    Some(DMatrix::<f64>::from_fn(n, n, |r, c| {
        d[r] * inv[(r, c)] * d[c]
    }))
}

/// A 4×4 matrix as a dynamic one.
fn dense(m: &Matrix4<f64>) -> DMatrix<f64> {
    DMatrix::<f64>::from_fn(4, 4, |r, c| m[(r, c)])
}
