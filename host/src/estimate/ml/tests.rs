//! Tests of the ML fit: analytic derivatives, exact data, the scatter
//! against the Cramér–Rao bound, the equation error.
use super::rigid::{dynamic_stiffness, rows, Rigid};
use super::*;
use crate::estimate::gauss_helmert::{self as gh, Equations, JacobianRequest};
use crate::estimate::mul;
use nalgebra::{DMatrix, DVector};
use num_complex::Complex;
use rand::{Rng, SeedableRng};

/// A pedestal on an isotropic, cross-coupled bearing driven through its
/// resonances: true phasors from eq. 3 solved for the pedestal, then
/// Gaussian noise on rel and ped.
fn synthetic(noise: f64, seed: u64) -> (Vec<Observation>, Vec<Observation>, [f64; 5]) {
    let theta = [1.0e7, 8.0e6, 150.0, 900.0, 700.0];
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut clean = Vec::new();
    let mut noisy = Vec::new();
    for i in 0..120 {
        let f = 10.0 + i as f64;
        let omega = 2.0 * std::f64::consts::PI * f;
        let kstar = [
            [
                Complex::new(3e7, omega * 2e3),
                Complex::new(1e7, omega * 3e2),
            ],
            [
                Complex::new(-8e6, -omega * 3e2),
                Complex::new(2.5e7, omega * 1.8e3),
            ],
        ];
        let rel = [
            Complex::from_polar(2e-5, 0.01 * f),
            Complex::from_polar(1.5e-5, 1.0 - 0.02 * f),
        ];
        let force = mul(&kstar, &rel);
        let h = dynamic_stiffness(&theta, omega);
        let ped = [force[0] / h[0], force[1] / h[1]];
        let sd = [2e-5 * noise, 1.5e-5 * noise, 1e-6 * noise, 1e-6 * noise];
        let var = std::array::from_fn(|c| 0.5 * sd[c / 2] * sd[c / 2]);
        let o = Observation {
            speed_hz: f,
            rel,
            ped,
            kstar,
            var,
        };
        clean.push(o);
        let mut n = o;
        for (c, v) in n.rel.iter_mut().chain(n.ped.iter_mut()).enumerate() {
            let s = (0.5f64).sqrt() * sd[c];
            *v += Complex::new(
                s * rng.sample::<f64, _>(rand_distr::StandardNormal),
                s * rng.sample::<f64, _>(rand_distr::StandardNormal),
            );
        }
        noisy.push(n);
    }
    (clean, noisy, theta)
}

/// The analytic whitened residuals and Jacobian (with Σ's dependence on
/// θ through the Cholesky factor) against the generic Gauss–Helmert
/// whitening of B·D·Bᵀ and central differences, with unequal real and
/// imaginary noise, an equation error and per-observation scales.
#[test]
fn analytic_derivatives_match_central_differences() {
    let (_, mut obs, theta) = synthetic(0.01, 3);
    for (i, o) in obs.iter_mut().enumerate() {
        o.var[1] *= 2.0;
        o.var[5] *= 3.0;
        o.var[6] *= 0.5 + (i % 3) as f64;
    }
    let scales: Vec<f64> = (0..obs.len()).map(|i| 0.5 + (i % 4) as f64).collect();
    let eq = Rigid::new(
        &obs,
        &Weighting {
            equation_var: 10.0,
            cov_scale: Some(&scales),
        },
    );
    let p: Vec<f64> = theta.iter().map(|t| 1.02 * t).collect();
    let free = [0, 1, 2, 3, 4];
    let step: Vec<f64> = p.iter().map(|v| 1e-6 * v.abs()).collect();
    let mut jac = DMatrix::zeros(0, 0);
    let r = eq
        .whiten(
            &p,
            Some(JacobianRequest {
                free: &free,
                step: &step,
                out: &mut jac,
            }),
        )
        .unwrap();
    for s in 0..eq.speeds() {
        let l = gh::whitening(&eq, s, &p).unwrap();
        let w = l.solve_lower_triangular(&eq.error(s, &p)).unwrap();
        for i in 0..4 {
            assert!((w[i] - r[4 * s + i]).abs() <= 1e-9 * (1.0 + w[i].abs()));
        }
    }
    for (c, &k) in free.iter().enumerate() {
        let mut up = p.clone();
        up[k] += step[c];
        let mut dn = p.clone();
        dn[k] -= step[c];
        let d = (eq.whiten(&up, None).unwrap() - eq.whiten(&dn, None).unwrap()) / (2.0 * step[c]);
        let scale = d.norm();
        let err = (&d - jac.column(c)).norm();
        assert!(err <= 1e-6 * scale, "parameter {k}: {err:e} of {scale:e}");
    }
}

#[test]
fn exact_data_give_the_truth_and_zero_cost() {
    let (clean, _, theta) = synthetic(0.01, 1);
    let start = [0.9e7, 0.9e7, 140.0, 0.0, 0.0];
    let fit = fit(&clean, &Parameter::ALL, &start).unwrap();
    for (a, b) in fit.theta.iter().zip(&theta) {
        assert!((a - b).abs() <= 1e-6 * b.abs(), "{a} vs {b}");
    }
    assert!(fit.chi2 < 1e-6, "{}", fit.chi2);
}

#[test]
fn noisy_fits_scatter_as_the_bound_says() {
    let (clean, _, theta) = synthetic(0.01, 1);
    let (crb, _) = bound(&clean, &Parameter::ALL, &theta).unwrap();
    let draws = 60;
    let mut sq = [0.0; 5];
    let mut chi2 = 0.0;
    for s in 0..draws {
        let (_, noisy, _) = synthetic(0.01, 100 + s);
        let f = fit(&noisy, &Parameter::ALL, &theta).unwrap();
        assert!(f.converged);
        chi2 += f.chi2_per_dof() / draws as f64;
        for i in 0..5 {
            sq[i] += (f.theta[i] - theta[i]).powi(2) / draws as f64;
        }
    }
    for i in 0..5 {
        let ratio = sq[i].sqrt() / crb[i][i].sqrt();
        assert!(
            (0.75..1.3).contains(&ratio),
            "parameter {i}: rms/crb {ratio}"
        );
    }
    assert!((chi2 - 1.0).abs() < 0.05, "χ²/dof {chi2}");
}

/// A model error the noise does not explain (a constant vector left on
/// every `rel` reading, as after an imperfect slow-roll subtraction,
/// far above the stated noise): the combined model's fit stays within
/// 1.5 × OLS's error, its τ² brings χ²/dof to 1, and on data the noise
/// explains it adds nothing.
#[test]
fn equation_error_absorbs_a_model_error() {
    let (clean, noisy, theta) = synthetic(0.001, 7);
    let offset = [
        Complex::from_polar(4e-7, 0.3),
        Complex::from_polar(3e-7, -1.2),
    ];
    let spoiled: Vec<Observation> = noisy
        .iter()
        .map(|o| {
            let mut o = *o;
            o.rel[0] += offset[0];
            o.rel[1] += offset[1];
            o
        })
        .collect();
    let worst = |t: &[f64; 5]| -> f64 {
        (0..3)
            .map(|i| ((t[i] - theta[i]) / theta[i]).abs())
            .fold(0.0, f64::max)
    };
    // OLS on the regression rows (the same rows, equal weights).
    let ols = {
        let mut ata = DMatrix::<f64>::zeros(5, 5);
        let mut atb = DVector::<f64>::zeros(5);
        for o in &spoiled {
            let (a, b) = rows(o);
            let a = DMatrix::from_fn(4, 5, |r, c| a[(r, c)]);
            let b = DVector::from_fn(4, |r, _| b[r]);
            ata += a.transpose() * &a;
            atb += a.transpose() * b;
        }
        let d: Vec<f64> = (0..5).map(|i| ata[(i, i)].sqrt()).collect();
        let scaled = DMatrix::from_fn(5, 5, |r, c| ata[(r, c)] / (d[r] * d[c]));
        let x = scaled
            .lu()
            .solve(&DVector::from_fn(5, |r, _| atb[r] / d[r]))
            .unwrap();
        let t: [f64; 5] = std::array::from_fn(|i| x[i] / d[i]);
        t
    };
    let plain = fit(&spoiled, &Parameter::ALL, &ols).unwrap();
    assert!(plain.chi2_per_dof() > 100.0, "{}", plain.chi2_per_dof());
    let (combined, settled) = fit_with_equation_error(&spoiled, &Parameter::ALL, &ols).unwrap();
    assert!(settled);
    assert!(combined.equation_var > 0.0);
    assert!(
        (combined.chi2_per_dof() - 1.0).abs() < 0.01,
        "{}",
        combined.chi2_per_dof()
    );
    let (e_ols, e_plain, e_comb) = (worst(&ols), worst(&plain.theta), worst(&combined.theta));
    assert!(
        e_comb <= 1.5 * e_ols,
        "OLS {e_ols}, ML {e_plain}, ML with equation error {e_comb}"
    );
    // Noise alone: τ² = 0 and the plain ML fit.
    let (_, noisy, _) = synthetic(0.01, 8);
    let start = theta;
    let (f, _) = fit_with_equation_error(&noisy, &Parameter::ALL, &start).unwrap();
    let g = fit(&noisy, &Parameter::ALL, &start).unwrap();
    if g.chi2 <= g.dof as f64 {
        assert_eq!(f.equation_var, 0.0);
        assert_eq!(f.theta, g.theta);
    }
    let _ = clean;
}

#[test]
fn chi2_p_values() {
    assert!(chi2_two_sided_p(100.0, 100) > 0.9);
    assert!(chi2_two_sided_p(200.0, 100) < 1e-6);
    assert!(chi2_two_sided_p(40.0, 100) < 1e-6);
}
