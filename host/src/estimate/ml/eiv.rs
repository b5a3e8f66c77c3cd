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
    /// In the direction of `noise_share`, the information the true phasors
    /// carry (estimated by F − N) in standard deviations of its own
    /// estimate's noise [-] (≤ 0 where `noise_share` ≥ 1): small where the
    /// first-order covariance cannot be trusted.
    pub information_sigmas: f64,
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
    // Per speed: Σ⁻¹, the rows A and the variance-weighted G_j (for the
    // noise of F in the direction of the noise share).
    let mut kept: Vec<(DMatrix<f64>, DMatrix<f64>, Vec<(f64, DMatrix<f64>)>)> =
        Vec::with_capacity(obs.len());
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
        let mut g_kept = Vec::with_capacity(4);
        for (j, g) in grads.iter().enumerate() {
            let d = sp.var_ped[j];
            if d == 0.0 {
                continue;
            }
            let gj = pick(g);
            g_kept.push((d, gj.clone()));
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
        kept.push((s_inv, a, g_kept));
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
    let (noise_share, v) = largest_generalised_eigenvalue(&f, &n)?;
    let information_sigmas = (1.0 - noise_share) / f_noise_sd(&kept, &v);
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
        information_sigmas,
    })
}

/// The standard deviation of vᵀFv [-] from the regressors' noise (vᵀFv = 1):
/// per speed, with a = Σ^{-½}A·v and S = Σ_j d_j·(Σ^{-½}G_j·v)(…)ᵀ,
/// Var |a⁰ + noise|² = 4·a⁰ᵀSa⁰ + 2·tr S², a⁰ᵀSa⁰ estimated from the
/// measured a as aᵀSa − tr S² (its mean being a⁰ᵀSa⁰ + tr S²).
fn f_noise_sd(
    kept: &[(DMatrix<f64>, DMatrix<f64>, Vec<(f64, DMatrix<f64>)>)],
    v: &nalgebra::DVector<f64>,
) -> f64 {
    let mut var = 0.0;
    for (s_inv, a, gs) in kept {
        let av = a * v;
        let gv: Vec<(f64, nalgebra::DVector<f64>)> = gs.iter().map(|(d, g)| (*d, g * v)).collect();
        // aᵀSa = Σ_j d_j (aᵀΣ⁻¹G_jv)², tr S² = Σ_jk d_j d_k (vᵀG_jᵀΣ⁻¹G_kv)².
        let asa: f64 = gv
            .iter()
            .map(|(d, g)| d * av.dot(&(s_inv * g)).powi(2))
            .sum();
        let tr_s2: f64 = gv
            .iter()
            .flat_map(|(dj, gj)| {
                gv.iter()
                    .map(move |(dk, gk)| dj * dk * gj.dot(&(s_inv * gk)).powi(2))
            })
            .sum();
        var += 4.0 * (asa - tr_s2).max(0.0) + 2.0 * tr_s2;
    }
    var.sqrt()
}

/// The largest λ with N·v = λ·F·v (F positive definite, N symmetric) [-],
/// and its v, scaled to vᵀFv = 1.
fn largest_generalised_eigenvalue(
    f: &DMatrix<f64>,
    n: &DMatrix<f64>,
) -> Option<(f64, nalgebra::DVector<f64>)> {
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
    let eig = w.symmetric_eigen();
    let (i, &lambda) = eig
        .eigenvalues
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))?;
    // x = L⁻ᵀy in the scaled coordinates (xᵀ·fs·x = 1), v = D⁻¹x.
    let x = l_inv.transpose() * eig.eigenvectors.column(i);
    let v = nalgebra::DVector::from_fn(p, |r, _| x[r] / d[r]);
    (lambda.is_finite() && v.iter().all(|x| x.is_finite())).then_some((lambda, v))
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

    /// Sweep (exploration): RMS z of k_y, k_z, m under F⁻¹ and the EIV
    /// covariance, the noise declared as drawn.
    #[test]
    #[ignore]
    fn sweep_signal_to_noise() {
        use rand::{Rng, SeedableRng};
        let (theta, _) = machine();
        for &every in &[1usize, 2, 4, 10] {
            for &ped_sd in &[3e-7, 6e-7, 1e-6, 1.3e-6, 1.6e-6, 2e-6, 2.5e-6] {
                let rel_sd = 1e-9;
                let mut clean = exact(ped_sd, rel_sd);
                for o in clean.iter_mut() {
                    for v in o.var.iter_mut() {
                        *v *= 0.5;
                    }
                }
                let clean: Vec<Observation> = clean.into_iter().step_by(every).collect();
                let mut rng = rand::rngs::StdRng::seed_from_u64(2103);
                let (mut zf, mut ze, mut shares, mut none, mut fail) =
                    (Vec::new(), Vec::new(), Vec::new(), 0, 0);
                let mut zp = vec![Vec::new(); 5];
                for _ in 0..100 {
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
                        fail += 1;
                        continue;
                    };
                    let Some(e) = eiv_covariance(&noisy, &Parameter::ALL, &fit.theta, 0.0) else {
                        fail += 1;
                        continue;
                    };
                    shares.push(e.noise_share);
                    let Some(cov) = e.covariance else {
                        none += 1;
                        continue;
                    };
                    let zs: Vec<f64> = (0..5)
                        .map(|k| (fit.theta[k] - theta[k]) / cov[k][k].sqrt())
                        .collect();
                    eprintln!(
                        "FIT {} {ped_sd:e} {:.4} {:.4} {:?}",
                        clean.len(),
                        e.noise_share,
                        e.information_sigmas,
                        zs
                    );
                    for k in 0..5 {
                        let d = fit.theta[k] - theta[k];
                        zf.push(d / fit.covariance[k][k].sqrt());
                        ze.push(d / cov[k][k].sqrt());
                        zp[k].push(d / cov[k][k].sqrt());
                    }
                }
                let share = shares.iter().sum::<f64>() / shares.len() as f64;
                let smax = shares.iter().copied().fold(0.0, f64::max);
                eprintln!(
                "n {} ped_sd {ped_sd:e}: share {share:.3} (max {smax:.3}), none {none}, fail {fail}, RMS z F⁻¹ {:.3} EIV {:.3} per k {:.2} {:.2} {:.2} {:.2} {:.2} ({} fits)",
                clean.len(),
                rms_z(&zf),
                rms_z(&ze),
                rms_z(&zp[0]), rms_z(&zp[1]), rms_z(&zp[2]), rms_z(&zp[3]), rms_z(&zp[4]),
                zp[0].len()
            );
            }
        }
    }
}
