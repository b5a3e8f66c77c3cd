//! The cost of estimating the variance function: the Kackar–Harville term
//! (Kackar & Harville 1984, "Approximations for standard errors of
//! estimators of fixed and random effects in mixed linear models", JASA 79;
//! Kenward & Roger 1997, Biometrics 53, eq. 2-3) for the pedestal fit under
//! [`super::refit_under`]'s weights.
//!
//! **Model.** Per speed s the four real equation residuals e_s(θ) = A_s·θ − b_s
//! (linear in θ, [`ml::equation_residual`]) have the covariance
//! Σ_s(p) = Σ_c v_c(p)·G_s,c, one term per real number c of the
//! observation, v_c = max(Σ_j p_j·f_j,s, floor_c) (the variance function of
//! the module above, floored by the digits) and G_s,c the covariance a unit
//! variance of number c gives the equations ([`ml::equation_covariance`]).
//! The fit θ̂(p) minimises Σ_s e_sᵀΣ_s⁻¹e_s; its reported covariance is
//! Φ = (Σ_s A_sᵀΣ_s⁻¹A_s)⁻¹, right when p is known.
//!
//! **Term.** With p̂ estimated from the same residuals (pseudo-likelihood,
//! [`super::fit_variance_function`]), to first order in p̂ − p
//! θ̂(p̂) − θ̂(p) ≈ Σ_k (p̂_k − p_k)·∂θ̂/∂p_k, ∂θ̂/∂p_k = Φ·Σ_s A_sᵀΣ_s⁻¹V_k,sΣ_s⁻¹r_s
//! (V_k,s = ∂Σ_s/∂p_k = f_k,s·Σ_{c of k's channel, unfloored} G_s,c, r the
//! residual at θ̂(p)), so
//!
//! ```text
//! Var θ̂(p̂) ≈ Φ + Λ,  Λ = Φ·[Σ_kl W_kl (Q_kl − P_k·Φ·P_l)]·Φ,
//! P_k  = Σ_s A_sᵀΣ⁻¹V_kΣ⁻¹A_s,   Q_kl = Σ_s A_sᵀΣ⁻¹V_kΣ⁻¹V_lΣ⁻¹A_s,
//! W    = I⁻¹,  I_kl = ½Σ_s tr(Σ⁻¹V_kΣ⁻¹V_l)   (the information of p),
//! ```
//!
//! the −P·Φ·P part because r is a residual, not the noise. Assumptions:
//! Gaussian noise, p̂ and r independent to first order (Kackar–Harville),
//! the ML information of p (the loss of the θ̂'s few degrees of freedom
//! among 4n equations is neglected), components at their bound 0 or
//! floored out at every speed held known, Σ's dependence on θ
//! (the `ped` noise through H(θ)) held at θ̂. Λ is large only where the
//! weights the equations carrying a parameter's information depend on are
//! themselves poorly determined (W large where Q − PΦP is large); where p
//! is well determined W is small and Λ vanishes. Kenward–Roger's further
//! term, the bias of Φ(p̂) as an estimate of Φ(p), is another Λ for a
//! covariance linear in p (their R_ij = 0): [`super::refit`] adds 2Λ
//! (docs/estimation.md "Session 32").

use super::{magnitudes, variances, Family, COMPONENTS, PER_CHANNEL};
use crate::estimate::ml;
use crate::estimate::Observation;
use nalgebra::{DMatrix, Matrix4, SMatrix};
use plinth_shared::regression::{Parameter, PARAMETERS};

/// Λ [θ units², the covariance's] of the fit `theta` on `obs` (each with
/// the variances of the variance function `law`, [`COMPONENTS`], the
/// `family`'s components free), over the parameters `columns`, with
/// `covariance` (Φ over all five parameters) the fit's: the first-order
/// covariance the estimation of `law` adds (module docs). `None` when a
/// number is not finite or a Σ_s is singular; zero when no component is
/// free.
pub fn kackar_harville(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    covariance: &[[f64; PARAMETERS]; PARAMETERS],
    law: &[f64; COMPONENTS],
    family: Family,
    columns: &[Parameter],
) -> Option<[[f64; PARAMETERS]; PARAMETERS]> {
    let np = columns.len();
    let active: Vec<usize> = (0..COMPONENTS)
        .filter(|&k| family.free(k) && law[k] > 0.0)
        .collect();
    let m = active.len();
    let mut out = [[0.0; PARAMETERS]; PARAMETERS];
    if m == 0 || np == 0 {
        return Some(out);
    }
    let mut info = DMatrix::<f64>::zeros(m, m);
    let mut p_mat = vec![DMatrix::<f64>::zeros(np, np); m];
    let mut q_mat = vec![DMatrix::<f64>::zeros(np, np); m * m];
    for o in obs {
        let sigma = ml::equation_covariance(o, theta);
        let a = sigma.try_inverse()?;
        let jac = jacobian(o, theta, columns);
        let aj = a * &jac;
        // Which real numbers the law (not the digits) gives: only they move
        // with p.
        let law_var = variances(o, law, &[0.0; 8]);
        let g: [Matrix4<f64>; 4] = std::array::from_fn(|ch| {
            let mut unit = *o;
            unit.var = [0.0; 8];
            for c in [2 * ch, 2 * ch + 1] {
                if law_var[c] >= o.var[c] {
                    unit.var[c] = 1.0;
                }
            }
            ml::equation_covariance(&unit, theta)
        });
        let magnitude_sq = magnitudes(o).map(|x| x * x);
        let inv = super::inv_omega_sq(o);
        // B_k = Σ⁻¹V_k and R_k = Σ⁻¹V_kΣ⁻¹A.
        let b: Vec<Matrix4<f64>> = active
            .iter()
            .map(|&k| a * g[k / PER_CHANNEL] * super::factor(k, &magnitude_sq, inv))
            .collect();
        let r: Vec<_> = b.iter().map(|bk| bk * &aj).collect();
        for i in 0..m {
            p_mat[i] += jac.transpose() * &r[i];
            for j in i..m {
                info[(i, j)] += 0.5 * b[i].component_mul(&b[j].transpose()).sum();
                // Q_ij = AᵀΣ⁻¹V_i·R_j = (B_iᵀ·A)ᵀ·R_j.
                let left = b[i].transpose() * &jac;
                q_mat[i * m + j] += left.transpose() * &r[j];
            }
        }
    }
    for i in 0..m {
        for j in 0..i {
            info[(i, j)] = info[(j, i)];
            q_mat[i * m + j] = q_mat[j * m + i].transpose();
        }
    }
    let w = pseudo_inverse(&info)?;
    let phi = DMatrix::<f64>::from_fn(np, np, |r, c| {
        covariance[columns[r] as usize][columns[c] as usize]
    });
    let mut middle = DMatrix::<f64>::zeros(np, np);
    for i in 0..m {
        for j in 0..m {
            let wij = w[(i, j)];
            if wij != 0.0 {
                middle += (&q_mat[i * m + j] - &p_mat[i] * &phi * &p_mat[j]) * wij;
            }
        }
    }
    let lambda = &phi * middle * &phi;
    if !lambda.iter().all(|v| v.is_finite()) {
        return None;
    }
    for (r, &pr) in columns.iter().enumerate() {
        for (c, &pc) in columns.iter().enumerate() {
            out[pr as usize][pc as usize] = 0.5 * (lambda[(r, c)] + lambda[(c, r)]);
        }
    }
    Some(out)
}

/// ∂e/∂θ [N per θ unit] of one speed over `columns` (4 × columns): e is
/// linear in θ, so a difference of [`ml::equation_residual`] over a step of
/// the parameter's own size is exact to rounding.
fn jacobian(o: &Observation, theta: &[f64; PARAMETERS], columns: &[Parameter]) -> DMatrix<f64> {
    let e0 = ml::equation_residual(o, theta);
    let mut jac = DMatrix::<f64>::zeros(4, columns.len());
    for (c, &p) in columns.iter().enumerate() {
        let k = p as usize;
        let h = if theta[k] != 0.0 { theta[k].abs() } else { 1.0 };
        let mut t = *theta;
        t[k] += h;
        let col: SMatrix<f64, 4, 1> = (ml::equation_residual(o, &t) - e0) / h;
        jac.set_column(c, &col);
    }
    jac
}

/// The Moore–Penrose inverse of the symmetric positive semi-definite `info`
/// after Jacobi scaling (the components' units differ by many decades),
/// eigenvalues below 1e-10 of the largest dropped; `None` when not finite.
fn pseudo_inverse(info: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let n = info.nrows();
    let d: Vec<f64> = (0..n)
        .map(|k| {
            let x = info[(k, k)];
            if x > 0.0 {
                1.0 / x.sqrt()
            } else {
                0.0
            }
        })
        .collect();
    let scaled = DMatrix::<f64>::from_fn(n, n, |r, c| d[r] * info[(r, c)] * d[c]);
    let eig = scaled.symmetric_eigen();
    let top = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
    if !(top > 0.0 && top.is_finite()) {
        return None;
    }
    let mut inv = DMatrix::<f64>::zeros(n, n);
    for (i, &lambda) in eig.eigenvalues.iter().enumerate() {
        if lambda > 1e-10 * top {
            let v = eig.eigenvectors.column(i);
            inv += v * v.transpose() / lambda;
        }
    }
    Some(DMatrix::from_fn(n, n, |r, c| d[r] * inv[(r, c)] * d[c]))
}
