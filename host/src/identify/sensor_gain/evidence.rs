//! The sensitivity ratios' evidence from one bearing's fit ([`super`]'s
//! module docs): the whitened equations extended by one column per
//! channel, and one Newton step of the fit's cost in the two y/z ratios
//! with θ profiled out.

use super::{chi2_upper, significant, GainEvidence, FAVOURED_LEVEL, MAX_RATIO_STD_ERR, RATIOS};
use crate::estimate::gauss_helmert::{self as gh, Equations};
use crate::estimate::lack_of_fit::delay_unknown::{information_std_errs, ratio};
use crate::estimate::ml::{Rigid, Weighting};
use crate::estimate::Observation;
use crate::identify::PedestalFit;
use nalgebra::{DMatrix, DVector};
use num_complex::Complex;
use plinth_shared::regression::{Parameter, PARAMETERS};

/// The observations of `fit` as the fit weighed them: sorted by speed, the
/// outlier speeds left out, the variances times the fit's
/// `variance_scale`.
pub(crate) fn as_fitted(
    obs: &[Observation],
    outliers: &[f64],
    variance_scale: f64,
) -> Vec<Observation> {
    let scale = if variance_scale.is_finite() && variance_scale > 0.0 {
        variance_scale
    } else {
        1.0
    };
    let mut out: Vec<Observation> = obs
        .iter()
        .filter(|o| o.is_finite() && !outliers.contains(&o.speed_hz))
        .map(|o| Observation {
            var: o.var.map(|v| v * scale),
            ..*o
        })
        .collect();
    out.sort_by(|a, b| a.speed_hz.total_cmp(&b.speed_hz));
    out
}

/// `o` with only channel `c` ([`super::CHANNELS`]) kept, the others zero.
fn only(o: &Observation, c: usize) -> Observation {
    let zero = Complex::new(0.0, 0.0);
    let mut k = Observation {
        rel: [zero; 2],
        ped: [zero; 2],
        ..*o
    };
    match c {
        0 | 1 => k.rel[c] = o.rel[c],
        _ => k.ped[c - 2] = o.ped[c - 2],
    }
    k
}

/// The whitened system at `theta`: residual r, θ's columns X (over
/// `columns`) and the four channels' columns T (module docs); `None` where
/// a covariance cannot be factored or a number is not finite.
fn linearise(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    columns: &[Parameter],
    weighting: &Weighting<'_>,
) -> Option<(DVector<f64>, DMatrix<f64>, DMatrix<f64>)> {
    let eq = Rigid::new(obs, weighting);
    let n = eq.speeds();
    let p = columns.len();
    let mut r = DVector::zeros(4 * n);
    let mut x = DMatrix::zeros(4 * n, p);
    let mut t = DMatrix::zeros(4 * n, 4);
    for (s, o) in obs.iter().enumerate() {
        let l = gh::whitening(&eq, s, theta)?;
        let e0 = eq.error(s, theta);
        r.rows_mut(4 * s, 4)
            .copy_from(&l.solve_lower_triangular(&e0)?);
        for (k, &c) in columns.iter().enumerate() {
            let mut at = *theta;
            at[c as usize] += 1.0;
            let col = l.solve_lower_triangular(&(eq.error(s, &at) - &e0))?;
            x.view_mut((4 * s, k), (4, 1)).copy_from(&col);
        }
        for c in 0..4 {
            let one = Rigid::new(&[only(o, c)], weighting);
            let col = l.solve_lower_triangular(&(-one.error(0, theta)))?;
            t.view_mut((4 * s, c), (4, 1)).copy_from(&col);
        }
    }
    let finite = r
        .iter()
        .chain(x.iter())
        .chain(t.iter())
        .all(|v| v.is_finite());
    finite.then_some((r, x, t))
}

/// Least-squares solution of X·b = y with X's columns scaled to unit norm
/// first (their units differ by many orders); `None` where it fails.
fn solve(x: &DMatrix<f64>, y: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let norms: Vec<f64> = x.column_iter().map(|c| c.norm()).collect();
    if !norms.iter().all(|v| v.is_finite() && *v > 0.0) {
        return None;
    }
    let mut scaled = x.clone();
    for (mut c, s) in scaled.column_iter_mut().zip(&norms) {
        c /= *s;
    }
    let mut b = scaled.svd(true, true).solve(y, 1e-13).ok()?;
    for (mut row, s) in b.row_iter_mut().zip(&norms) {
        row /= *s;
    }
    Some(b)
}

/// J(θ) = Σ eᵀΣ⁻¹e of `obs` under `weighting` with each channel's
/// sensitivity error `eps` [-] undone ([`super::CHANNELS`]): the phasors divided
/// by 1 + ε and their noise variances by (1 + ε)², the one definition of
/// the equations ([`Rigid`]) on what the channels would have read.
fn objective(
    obs: &[Observation],
    weighting: &Weighting<'_>,
    theta: &[f64; PARAMETERS],
    eps: [f64; 4],
) -> Option<f64> {
    let undone: Vec<Observation> = obs
        .iter()
        .map(|o| {
            let mut u = *o;
            for (c, e) in eps.iter().enumerate() {
                let g = 1.0 + e;
                match c {
                    0 | 1 => u.rel[c] /= g,
                    _ => u.ped[c - 2] /= g,
                }
                u.var[2 * c] /= g * g;
                u.var[2 * c + 1] /= g * g;
            }
            u
        })
        .collect();
    Rigid::new(&undone, weighting).objective(theta)
}

/// What the data of `obs` (one bearing, as observed) say of its channel
/// gains at the fit `fit` (module docs); `outliers` the speeds the fit left
/// out [Hz], `variance_scale` and `equation_error_sd` [N] the fit's noise
/// level and equation error, `inflation` the long-run factor of a serial
/// correlation of its residuals (1 without), `bearings` the number of
/// bearings of the run tested. `None` where a figure cannot be formed or
/// no direction of the ratios is estimable.
#[allow(clippy::too_many_arguments)]
pub fn evidence(
    fit: &PedestalFit,
    obs: &[Observation],
    outliers: &[f64],
    variance_scale: f64,
    equation_error_sd: f64,
    inflation: f64,
    bearings: usize,
) -> Option<GainEvidence> {
    let obs = as_fitted(obs, outliers, variance_scale);
    let theta = fit.pedestal.theta();
    evidence_at(
        fit,
        &theta,
        &obs,
        equation_error_sd,
        inflation,
        bearings,
        None,
    )
}

/// [`evidence`] of `fit`'s bearing from `obs` as fitted ([`as_fitted`]'s),
/// linearised at `theta` (SI; the Newton step takes θ the rest of the way),
/// with `extra` (2×2 over the two ratios [-²]) added to the ratios'
/// covariance in their estimable directions: the share of a nuisance the
/// ratios' estimate moves with (the speed column's offset,
/// [`super::speed`]). `None` as [`evidence`].
#[allow(clippy::too_many_arguments)]
pub(crate) fn evidence_at(
    fit: &PedestalFit,
    theta: &[f64; PARAMETERS],
    obs: &[Observation],
    equation_error_sd: f64,
    inflation: f64,
    bearings: usize,
    extra: Option<&DMatrix<f64>>,
) -> Option<GainEvidence> {
    let columns: Vec<Parameter> = Parameter::ALL
        .into_iter()
        .filter(|c| !fit.fixed.iter().any(|f| f == c.name()))
        .collect();
    let theta = *theta;
    let p = columns.len();
    let n = obs.len();
    let dof = (4 * n).checked_sub(p + 2).filter(|&d| d > 0)? as f64;
    let tau2 = if equation_error_sd.is_finite() {
        equation_error_sd * equation_error_sd
    } else {
        0.0
    };
    let (_, x, t) = linearise(obs, &theta, &columns, &Weighting::equation_error(tau2))?;
    // Each channel alone: b = −X⁺t.
    let paths = -solve(&x, &t)?;
    let mut path = [[0.0; PARAMETERS]; 4];
    for c in 0..4 {
        for (k, &q) in columns.iter().enumerate() {
            path[c][q as usize] = paths[(k, c)];
        }
    }
    // The two ratios, with θ free: one Newton step of J from (θ̂, ε = 0)
    // with J's exact gradient and Hessian (module docs: J's Σ(ε) term
    // removes the errors-in-variables bias and the information a
    // Gauss–Newton form would give a direction J does not see).
    let weighting = Weighting::equation_error(tau2);
    let held_se = information_std_errs(&x)?;
    // J's gradient and Hessian over (θ free, ε_rel_y, ε_ped_y) by central
    // differences of the one definition of J (module docs), each step a
    // tenth of the value's ± (ε: 1e-3).
    let m = p + 2;
    let steps: Vec<f64> = (0..m)
        .map(|k| if k < p { 0.1 * held_se[k] } else { 1e-3 })
        .collect();
    let at = |d: &[f64]| -> Option<f64> {
        let mut th = theta;
        for (k, &c) in columns.iter().enumerate() {
            th[c as usize] += d[k];
        }
        let mut eps = [0.0; 4];
        for (j, &(a, _)) in RATIOS.iter().enumerate() {
            eps[a] = d[p + j];
        }
        objective(obs, &weighting, &th, eps)
    };
    let zero = vec![0.0; m];
    let j0 = at(&zero)?;
    let mut grad = DVector::zeros(m);
    let mut hess = DMatrix::zeros(m, m);
    let mut plus = vec![0.0; m];
    let mut minus = vec![0.0; m];
    for k in 0..m {
        let mut d = zero.clone();
        d[k] = steps[k];
        plus[k] = at(&d)?;
        d[k] = -steps[k];
        minus[k] = at(&d)?;
        grad[k] = (plus[k] - minus[k]) / (2.0 * steps[k]);
        hess[(k, k)] = (plus[k] - 2.0 * j0 + minus[k]) / (steps[k] * steps[k]);
    }
    for k in 0..m {
        for l in (k + 1)..m {
            let mut d = zero.clone();
            d[k] = steps[k];
            d[l] = steps[l];
            let pp = at(&d)?;
            d[k] = -steps[k];
            d[l] = -steps[l];
            let mm = at(&d)?;
            // f(+,+) + f(−,−) = 2f + h_k²f_kk + h_l²f_ll + 2h_kh_lf_kl.
            let v = (pp + mm
                - 2.0 * j0
                - steps[k] * steps[k] * hess[(k, k)]
                - steps[l] * steps[l] * hess[(l, l)])
                / (2.0 * steps[k] * steps[l]);
            hess[(k, l)] = v;
            hess[(l, k)] = v;
        }
    }
    // θ profiled out: H_eff = H_εε − H_εθ·H_θθ⁻¹·H_θε, g_eff likewise.
    let h_tt = hess.view((0, 0), (p, p)).into_owned();
    let h_te = hess.view((0, p), (p, 2)).into_owned();
    let h_ee = hess.view((p, p), (2, 2)).into_owned();
    let h_tt_inv = h_tt.clone().try_inverse()?;
    let h_eff = &h_ee - h_te.transpose() * &h_tt_inv * &h_te;
    let g_eff = grad.rows(p, 2).into_owned() - h_te.transpose() * &h_tt_inv * grad.rows(0, p);
    let excess = (j0 / dof).max(1.0).sqrt() * inflation.max(1.0).sqrt();
    // Per eigen-direction of H_eff: estimable where its ± (√(2/λ)·excess)
    // is below MAX_RATIO_STD_ERR; the others (e.g. all y channels alike at
    // a bearing whose table has no cross terms: J does not change) are
    // left out and the test has that many fewer degrees of freedom.
    let eig = h_eff.clone().symmetric_eigen();
    let mut g = [0.0; 2];
    let mut statistic = 0.0;
    let mut dof_test = 0usize;
    let mut c = DMatrix::<f64>::zeros(2, 2);
    let mut projector = DMatrix::<f64>::zeros(2, 2);
    for k in 0..2 {
        let lambda = eig.eigenvalues[k];
        let v = eig.eigenvectors.column(k).into_owned();
        let sd = (2.0 / lambda).sqrt() * excess;
        if !(lambda > 0.0 && sd.is_finite() && sd <= MAX_RATIO_STD_ERR) {
            continue;
        }
        // Newton step along v: −(vᵀg)/λ; its variance sd².
        let along = -(v.dot(&g_eff)) / lambda;
        g[0] += along * v[0];
        g[1] += along * v[1];
        statistic += (along / sd).powi(2);
        c += &v * v.transpose() * (sd * sd);
        projector += &v * v.transpose();
        dof_test += 1;
    }
    if dof_test == 0 {
        return None;
    }
    if let Some(extra) = extra.filter(|e| e.shape() == (2, 2)) {
        // The nuisance's share in the estimable directions; the statistic
        // ε̂ᵀC⁻¹ε̂ over them (C's pseudo-inverse there).
        c += &projector * extra * &projector;
        let gv = DVector::from_column_slice(&g);
        statistic = if dof_test == 2 {
            let inv = c.clone().try_inverse()?;
            (gv.transpose() * inv * &gv)[(0, 0)]
        } else {
            let k = if projector[(0, 0)] >= projector[(1, 1)] {
                0
            } else {
                1
            };
            let v = projector.column(k).normalize();
            let var = (v.transpose() * &c * &v)[(0, 0)];
            v.dot(&gv).powi(2) / var
        };
    }
    let threshold = significant(bearings, dof_test);
    let favoured = chi2_upper(FAVOURED_LEVEL, dof_test);
    let tr = DMatrix::from_fn(4 * n, 2, |i, j| t[(i, RATIOS[j].0)]);
    let (c00, c01, c11) = (c[(0, 0)], c[(0, 1)], c[(1, 1)]);
    // ρ and t² per θ from the ratios' joint path B = −X⁺T'.
    let joint = -solve(&x, &tr)?;
    let held = held_se;
    let mut free = DMatrix::zeros(4 * n, p + 2);
    free.columns_mut(0, p).copy_from(&x);
    free.columns_mut(p, 2).copy_from(&tr);
    let free_se = information_std_errs(&free)?;
    let mut rho = [1.0; PARAMETERS];
    let mut t_squared = [0.0; PARAMETERS];
    for (k, &q) in columns.iter().enumerate() {
        let i = q as usize;
        rho[i] = ratio(held[k], free_se[k]);
        let b = [joint[(k, 0)], joint[(k, 1)]];
        let spread = b[0] * b[0] * c00 + 2.0 * b[0] * b[1] * c01 + b[1] * b[1] * c11;
        let along = b[0] * g[0] + b[1] * g[1];
        let v = along * along / spread;
        t_squared[i] = if v.is_finite() { v } else { 0.0 };
    }
    let finite = statistic.is_finite()
        && g.iter().all(|v| v.is_finite())
        && path.iter().flatten().all(|v| v.is_finite());
    if !finite {
        return None;
    }
    let mut e = GainEvidence {
        bearing: fit.bearing.clone(),
        path,
        ratio: g,
        ratio_std_err: [c00.sqrt(), c11.sqrt()],
        ratio_correlation: c01 / (c00 * c11).sqrt(),
        statistic,
        dof: dof_test,
        threshold,
        favoured,
        rho,
        t_squared,
        verdict: "none".into(),
        speed_offset_hz: None,
    };
    e.verdict = if statistic > threshold {
        "untrusted"
    } else if statistic > favoured && !e.excluded() {
        "widened"
    } else {
        "none"
    }
    .into();
    Some(e)
}
