//! The covariance of the ML estimate where the regressors carry noise
//! comparable to their signal: a pedestal read near or below its noise.
//!
//! F = Σ AᵀΣ(θ)⁻¹A ([`super::fisher_information`]) is built from the
//! *measured* pedestal phasors. Its inverse is the covariance only when their
//! noise is small against them. The rows are A = A⁰ + U, with A⁰ from the
//! true phasors and U = Σ_j u_j·G_j from the noise u_j of the four real
//! numbers of `ped` (variance d_j; G_j = ∂A/∂ped_j, A being linear in
//! `ped`). Then, to first order in 1/n (Fuller 1987, *Measurement Error
//! Models*, §2.3 and §4.1, for the functional model with a known error
//! covariance, here per speed):
//!
//! - E[F] = M + N, with M = Σ A⁰ᵀΣ⁻¹A⁰ the information the true phasors
//!   carry and N = Σ_s Σ_j d_j·G_jᵀΣ⁻¹G_j what their noise adds: F counts
//!   the noise as information;
//! - the score of ½J at the truth is Σ (A⁰ + Ũ)ᵀΣ⁻¹e, Ũ_k = U_k − C_kΣ⁻¹e
//!   the part of U independent of e (C_k = E[U_k eᵀ] = Σ_j d_j·G_j[:,k]·
//!   (G_jθ)ᵀ), so its variance is M + Γ with
//!   Γ_kl = Σ_s [N_s,kl − tr(Σ⁻¹C_kΣ⁻¹C_lᵀ)], and the expected Hessian
//!   of ½J is M;
//! - Cov(θ̂) = M⁻¹ + M⁻¹ΓM⁻¹, M estimated by F − N.
//!
//! Where the phasors are read well (N ≪ F) this is F⁻¹ to within the share
//! σ²/|X|²; where they are read near their noise F⁻¹ is too small (the
//! scalar case: sd × 1/(1 − ρ), ρ = N/F). When F − N is not positive
//! definite the data's information about some combination of the
//! parameters is no more than their noise's: no covariance is given.

use super::rigid::{rows, Speed};
use crate::estimate::gauss_helmert as gh;
use crate::estimate::Observation;
use nalgebra::{DMatrix, Matrix4, SMatrix};
use num_complex::Complex;
use plinth_shared::regression::{Parameter, PARAMETERS};

/// The covariance of the ML estimate with its regressors' noise
/// ([module docs](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct EivCovariance {
    /// M⁻¹ + M⁻¹ΓM⁻¹ over all five parameters (θ units; zero rows and
    /// columns for fixed ones); `None` when F − N is not positive definite.
    pub covariance: Option<[[f64; PARAMETERS]; PARAMETERS]>,
    /// `covariance` − F⁻¹ (θ units): what the regressors' noise adds to the
    /// covariance a fit reports, to be added to any other widening of it.
    pub excess: Option<[[f64; PARAMETERS]; PARAMETERS]>,
    /// The largest share of the fit's information F that is its regressors'
    /// noise N: the largest eigenvalue of F⁻¹N [-] (0: read exactly; ≥ 1:
    /// some combination of the parameters is read no better than its noise).
    pub noise_share: f64,
}

/// G_j = ∂A/∂ped_j (4×5) for the four real numbers of `ped` (y re, y im,
/// z re, z im) of `o`: A is linear in `ped`, so G_j is A of a unit phasor.
fn regressor_gradients(o: &Observation) -> [SMatrix<f64, 4, PARAMETERS>; 4] {
    std::array::from_fn(|j| {
        let mut unit = [Complex::new(0.0, 0.0); 2];
        unit[j / 2] = if j % 2 == 0 {
            Complex::new(1.0, 0.0)
        } else {
            Complex::new(0.0, 1.0)
        };
        rows(&Observation { ped: unit, ..*o }).0
    })
}

/// [`EivCovariance`] of the estimate `theta` of `obs` over `columns`, with
/// an equation error of variance `equation_var` [N²] per real equation in Σ
/// (0 for the plain ML fit). `None` when a Σ cannot be inverted or a figure
/// is not finite.
pub fn eiv_covariance(
    obs: &[Observation],
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
    equation_var: f64,
) -> Option<EivCovariance> {
    let p = columns.len();
    if p == 0 {
        return None;
    }
    let pick = |m: &SMatrix<f64, 4, PARAMETERS>| {
        DMatrix::from_fn(4, p, |r, c| m[(r, columns[c] as usize)])
    };
    let th = nalgebra::SVector::<f64, PARAMETERS>::from_fn(|i, _| theta[i]);
    let mut f = DMatrix::<f64>::zeros(p, p);
    let mut n = DMatrix::<f64>::zeros(p, p);
    let mut gamma = DMatrix::<f64>::zeros(p, p);
    for o in obs {
        let sp = Speed::new(o, 1.0);
        let s_inv: Matrix4<f64> = sp.sigma(theta, equation_var).try_inverse()?;
        let s_inv = DMatrix::from_fn(4, 4, |r, c| s_inv[(r, c)]);
        let a = pick(&sp.a);
        f += a.transpose() * &s_inv * &a;
        let grads = regressor_gradients(o);
        // C_k = Σ_j d_j·G_j[:,k]·g_jᵀ with g_j = G_j·θ (= ∂e/∂ped_j).
        let mut c_k = vec![DMatrix::<f64>::zeros(4, 4); p];
        let mut n_s = DMatrix::<f64>::zeros(p, p);
        for (j, g) in grads.iter().enumerate() {
            let d = sp.var_ped[j];
            if d == 0.0 {
                continue;
            }
            let gj = pick(g);
            let e_j = g * th;
            n_s += (gj.transpose() * &s_inv * &gj) * d;
            for (k, ck) in c_k.iter_mut().enumerate() {
                for r in 0..4 {
                    for c in 0..4 {
                        ck[(r, c)] += d * gj[(r, k)] * e_j[c];
                    }
                }
            }
        }
        let left: Vec<DMatrix<f64>> = c_k.iter().map(|ck| &s_inv * ck).collect();
        let right: Vec<DMatrix<f64>> = c_k.iter().map(|ck| &s_inv * ck.transpose()).collect();
        for k in 0..p {
            for l in 0..p {
                // tr(Σ⁻¹C_k·Σ⁻¹C_lᵀ).
                let t = (&left[k] * &right[l]).trace();
                gamma[(k, l)] += n_s[(k, l)] - t;
            }
        }
        n += n_s;
    }
    if !f
        .iter()
        .chain(n.iter())
        .chain(gamma.iter())
        .all(|v| v.is_finite())
    {
        return None;
    }
    let f_inv = gh::inverse_psd(&f);
    if !f_inv.iter().all(|v| v.is_finite()) {
        return None;
    }
    let noise_share = largest_generalised_eigenvalue(&f, &n)?;
    let m = &f - &n;
    let covariance = (noise_share < 1.0)
        .then(|| {
            let m_inv = gh::inverse_psd(&m);
            let cov = &m_inv + &m_inv * &gamma * &m_inv;
            let mut out = [[0.0; PARAMETERS]; PARAMETERS];
            for (r, &pr) in columns.iter().enumerate() {
                for (c, &pc) in columns.iter().enumerate() {
                    out[pr as usize][pc as usize] = cov[(r, c)];
                }
            }
            out
        })
        .filter(|c| {
            columns
                .iter()
                .all(|&k| c[k as usize][k as usize].is_finite() && c[k as usize][k as usize] > 0.0)
        });
    let excess = covariance.map(|c| {
        let mut out = c;
        for (r, &pr) in columns.iter().enumerate() {
            for (k, &pc) in columns.iter().enumerate() {
                out[pr as usize][pc as usize] -= f_inv[(r, k)];
            }
        }
        out
    });
    Some(EivCovariance {
        covariance,
        excess,
        noise_share,
    })
}

/// The largest λ with N·v = λ·F·v (F positive definite, N symmetric) [-].
fn largest_generalised_eigenvalue(f: &DMatrix<f64>, n: &DMatrix<f64>) -> Option<f64> {
    let p = f.nrows();
    let d: Vec<f64> = (0..p).map(|i| f[(i, i)].sqrt()).collect();
    if !d.iter().all(|x| *x > 0.0 && x.is_finite()) {
        return None;
    }
    let fs = DMatrix::from_fn(p, p, |r, c| f[(r, c)] / (d[r] * d[c]));
    let ns = DMatrix::from_fn(p, p, |r, c| n[(r, c)] / (d[r] * d[c]));
    let l = fs.cholesky()?.l();
    let l_inv = l.try_inverse()?;
    let w = &l_inv * ns * l_inv.transpose();
    let w = (&w + w.transpose()) * 0.5;
    w.symmetric_eigen()
        .eigenvalues
        .iter()
        .copied()
        .fold(None, |a: Option<f64>, v| Some(a.map_or(v, |a| a.max(v))))
        .filter(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::ml;
    use plinth_shared::bearing::BearingCoefficients;

    fn machine() -> ([f64; PARAMETERS], BearingCoefficients<f64>) {
        let theta = [9.0e8, 6.5e8, 320.0, 2.0e5, 1.5e5];
        let bearing = BearingCoefficients {
            k: [[2.0e8, 1.0e7], [-1.0e7, 3.0e8]],
            c: [[2.0e5, 0.0], [0.0, 3.0e5]],
        };
        (theta, bearing)
    }

    /// Exact observations of a pedestal driven by a unit force, with noise
    /// sd `ped_sd`, `rel_sd` [m] on every real number (not drawn: only the
    /// variances matter here).
    fn exact(ped_sd: f64, rel_sd: f64) -> Vec<Observation> {
        let (theta, bearing) = machine();
        (0..200)
            .map(|i| {
                let hz = 5.0 + i as f64;
                let w = plinth_shared::phasor::omega_from_hz(hz);
                let h = |k: f64, c: f64| Complex::new(k - w * w * theta[2], w * c);
                // ped = H⁻¹·F, F = K*·rel: pick rel, derive ped.
                let rel = [Complex::new(1e-6, 2e-7), Complex::new(-3e-7, 8e-7)];
                let mut o =
                    Observation::without_noise(hz, rel, [Complex::new(0.0, 0.0); 2], &bearing);
                let force = o.force();
                o.ped = [
                    force[0] / h(theta[0], theta[3]),
                    force[1] / h(theta[1], theta[4]),
                ];
                let (vr, vp) = (rel_sd * rel_sd, ped_sd * ped_sd);
                o.var = [vr, vr, vr, vr, vp, vp, vp, vp];
                o
            })
            .collect()
    }

    #[test]
    fn well_read_regressors_leave_the_fisher_bound() {
        let (theta, _) = machine();
        let obs = exact(1e-12, 1e-10);
        let e = eiv_covariance(&obs, &Parameter::ALL, &theta, 0.0).unwrap();
        let (bound, _) = ml::bound(&obs, &Parameter::ALL, &theta).unwrap();
        let cov = e.covariance.unwrap();
        assert!(e.noise_share < 1e-3, "{}", e.noise_share);
        for k in 0..PARAMETERS {
            let r = cov[k][k] / bound[k][k];
            assert!((1.0..1.01).contains(&r), "{k}: {r}");
        }
    }

    /// RMS over parameters and draws of (θ̂ − θ)/sd [-], the sd from
    /// `covariance`, for the draws it gives one.
    fn rms_z(z: &[f64]) -> f64 {
        (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt()
    }

    #[test]
    fn regressors_read_near_their_noise_widen_the_covariance() {
        use rand::{Rng, SeedableRng};
        let (theta, _) = machine();
        // The pedestal's phasors are 1.6e-7 .. 3e-7 m: noise of 3e-7 m on
        // each (complex sd): a signal-to-noise ratio near 1 in amplitude.
        let (ped_sd, rel_sd) = (3e-7, 1e-9);
        let clean = exact(ped_sd, rel_sd);
        let mut rng = rand::rngs::StdRng::seed_from_u64(17);
        let (mut z_fisher, mut z_eiv, mut shares) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..60 {
            let noisy: Vec<Observation> = clean
                .iter()
                .map(|o| {
                    let mut n = *o;
                    for (c, v) in n.rel.iter_mut().chain(n.ped.iter_mut()).enumerate() {
                        let s = (0.5f64).sqrt() * if c < 2 { rel_sd } else { ped_sd };
                        *v += Complex::new(
                            s * rng.sample::<f64, _>(rand_distr::StandardNormal),
                            s * rng.sample::<f64, _>(rand_distr::StandardNormal),
                        );
                    }
                    n
                })
                .collect();
            let Ok(fit) = ml::fit(&noisy, &Parameter::ALL, &theta) else {
                continue;
            };
            let Some(e) = eiv_covariance(&noisy, &Parameter::ALL, &fit.theta, 0.0) else {
                continue;
            };
            shares.push(e.noise_share);
            let Some(cov) = e.covariance else { continue };
            for k in 0..3 {
                let d = fit.theta[k] - theta[k];
                z_fisher.push(d / fit.covariance[k][k].sqrt());
                z_eiv.push(d / cov[k][k].sqrt());
            }
        }
        let share = shares.iter().sum::<f64>() / shares.len() as f64;
        assert!(z_eiv.len() >= 150, "{} of 180", z_eiv.len());
        let (f, e) = (rms_z(&z_fisher), rms_z(&z_eiv));
        let said = format!("noise share {share:.3}, RMS z {f:.3} (F⁻¹), {e:.3} (EIV)");
        eprintln!("{said}");
        assert!(share > 0.2, "{said}");
        // Measured (seed 17): share 0.65, RMS z 0.79 under F⁻¹ and 0.54
        // under the EIV covariance: on this machine both are conservative and
        // the EIV covariance is the wider; it is never the narrower, and the
        // estimate is never more than its ± off in RMS
        // (docs/estimation.md, Session 42 (lowsnrpm17): on the unseen-train recording F⁻¹
        // gives RMS z ≈ 3 and the EIV covariance ≈ 1).
        assert!(e < f && e < 1.3, "{said}");
    }
}
