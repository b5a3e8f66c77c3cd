//! The modal view of an identified pedestal: per direction the natural
//! frequency f_n = √(k/m)/2π [Hz] of the pedestal on its own (as if the
//! bearing were cut) and its damping ratio ζ = c/(2√(km)) [-], what a
//! vibration engineer compares with the running speed and a modal test.
//!
//! Standard errors by the delta method from the fit's covariance of
//! (k, m, c): with g the gradient of f_n or ζ, var = gᵀ·Σ·g. The k–m
//! correlation of a run-down fit is strong (both come from where the
//! dynamic stiffness k − Ω²m crosses zero), so the covariance, not the
//! standard errors alone, is needed; the test below checks the delta method
//! against a Monte-Carlo of the parameters.

use crate::estimate::params::null_is_nan;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// One direction's natural frequency and damping ratio with standard
/// errors (formats.md "modal"); `null` in JSON where not defined (k ≤ 0 or
/// m ≤ 0) or not known (no covariance).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DirectionModal {
    /// √(k/m)/2π [Hz].
    #[serde(deserialize_with = "null_is_nan")]
    pub f_n_hz: f64,
    /// Its standard error [Hz].
    #[serde(deserialize_with = "null_is_nan")]
    pub f_n_std_err: f64,
    /// c/(2√(km)) [-] (0 with a standard error of 0 when c is fixed at 0).
    #[serde(deserialize_with = "null_is_nan")]
    pub zeta: f64,
    /// Its standard error [-].
    #[serde(deserialize_with = "null_is_nan")]
    pub zeta_std_err: f64,
}

/// Both directions of one pedestal (`"modal": {"y": ..., "z": ...}`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PedestalModal {
    /// Vertical.
    pub y: DirectionModal,
    /// Horizontal.
    pub z: DirectionModal,
}

/// Pedestal parameters θ = (k_y [N/m], k_z [N/m], m [kg], c_y [N·s/m],
/// c_z [N·s/m]) and their covariance in θ order and units (zero rows and
/// columns for parameters fixed by the model).
pub type Covariance = [[f64; 5]; 5];

/// f_n and ζ of one direction from k [N/m], m [kg], c [N·s/m] and the 3×3
/// covariance of (k, m, c) (`None`: standard errors unknown, NaN).
pub fn direction(k: f64, m: f64, c: f64, cov: Option<&[[f64; 3]; 3]>) -> DirectionModal {
    direction_by_gradient(k, m, c, |g| match cov {
        Some(s) => {
            let mut v = 0.0;
            for i in 0..3 {
                for j in 0..3 {
                    v += g[i] * s[i][j] * g[j];
                }
            }
            v.max(0.0).sqrt()
        }
        None => f64::NAN,
    })
}

/// f_n and ζ of one direction from k [N/m], m [kg], c [N·s/m], with the
/// standard errors of the delta method from `std_err_of(g)`: the standard
/// error of the linear combination g·(k, m, c) under the fit's covariance,
/// in whatever form the fit holds it (a matrix, diagnose's sandwich).
pub fn direction_by_gradient(
    k: f64,
    m: f64,
    c: f64,
    std_err_of: impl Fn(&[f64; 3]) -> f64,
) -> DirectionModal {
    if !(k > 0.0 && m > 0.0 && k.is_finite() && m.is_finite() && c.is_finite()) {
        return DirectionModal {
            f_n_hz: f64::NAN,
            f_n_std_err: f64::NAN,
            zeta: f64::NAN,
            zeta_std_err: f64::NAN,
        };
    }
    let f_n = (k / m).sqrt() / TAU;
    let zeta = c / (2.0 * (k * m).sqrt());
    // Gradients with respect to (k, m, c).
    let g_f = [f_n / (2.0 * k), -f_n / (2.0 * m), 0.0];
    let g_z = [
        -zeta / (2.0 * k),
        -zeta / (2.0 * m),
        1.0 / (2.0 * (k * m).sqrt()),
    ];
    DirectionModal {
        f_n_hz: f_n,
        f_n_std_err: std_err_of(&g_f),
        zeta,
        zeta_std_err: std_err_of(&g_z),
    }
}

/// The modal view of a pedestal from θ (see [`Covariance`]) and its
/// covariance (`None`: values only, standard errors NaN).
pub fn pedestal(theta: &[f64; 5], cov: Option<&Covariance>) -> PedestalModal {
    // (k, m, c) of y are θ[0], θ[2], θ[3]; of z θ[1], θ[2], θ[4].
    let pick = |idx: [usize; 3]| -> Option<[[f64; 3]; 3]> {
        cov.map(|s| std::array::from_fn(|i| std::array::from_fn(|j| s[idx[i]][idx[j]])))
    };
    let y = pick([0, 2, 3]);
    let z = pick([1, 2, 4]);
    PedestalModal {
        y: direction(theta[0], theta[2], theta[3], y.as_ref()),
        z: direction(theta[1], theta[2], theta[4], z.as_ref()),
    }
}

/// Every pedestal of an identification gets its modal view from its
/// parameters and covariance (`identify --json`'s `modal`).
pub fn attach(identification: &mut crate::identify::Identification) {
    for p in &mut identification.pedestals {
        p.modal = Some(pedestal(&p.pedestal.theta(), p.covariance.as_ref()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    #[test]
    fn closed_form_values() {
        // k = 4π²·100 N/m, m = 1 kg: f_n = 10 Hz; c = 2√(km)·0.05.
        let k = TAU * TAU * 100.0;
        let c = 0.1 * k.sqrt();
        let d = direction(k, 1.0, c, None);
        assert!((d.f_n_hz - 10.0).abs() < 1e-12);
        assert!((d.zeta - 0.05).abs() < 1e-12);
        assert!(d.f_n_std_err.is_nan());
        let neg = direction(-1.0, 1.0, 0.0, None);
        assert!(neg.f_n_hz.is_nan() && neg.zeta.is_nan());
        // A fixed c (zero variance, value 0): ζ = 0 ± 0.
        let s = [[1e6, 0.0, 0.0], [0.0, 1e-2, 0.0], [0.0, 0.0, 0.0]];
        let d = direction(1e7, 100.0, 0.0, Some(&s));
        assert_eq!((d.zeta, d.zeta_std_err), (0.0, 0.0));
        assert!(d.f_n_std_err > 0.0);
    }

    /// The delta method against a Monte-Carlo of correlated (k, m, c) at
    /// the size of a real run-down fit's scatter (0.1-1 %): the standard
    /// deviations agree within the Monte-Carlo's own error.
    #[test]
    fn delta_method_matches_monte_carlo() {
        let theta = [1.0e7, 1.5e7, 100.0, 800.0, 1200.0];
        let sd = [2.0e4, 4.0e4, 0.3, 60.0, 90.0];
        // Strong k–m correlation (0.9), c mildly correlated with k.
        let mut corr = [[0.0; 5]; 5];
        for (i, row) in corr.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        for (a, b, r) in [
            (0, 2, 0.9),
            (1, 2, 0.85),
            (0, 1, 0.7),
            (3, 0, 0.2),
            (4, 1, -0.3),
        ] {
            corr[a][b] = r;
            corr[b][a] = r;
        }
        let cov: Covariance =
            std::array::from_fn(|i| std::array::from_fn(|j| corr[i][j] * sd[i] * sd[j]));
        let l = nalgebra::Matrix5::from_fn(|i, j| cov[i][j])
            .cholesky()
            .expect("positive definite")
            .l();
        let delta = pedestal(&theta, Some(&cov));
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let n = 40_000;
        let mut samples: Vec<[f64; 4]> = Vec::with_capacity(n);
        for _ in 0..n {
            let e = nalgebra::Vector5::from_fn(|_, _| StandardNormal.sample(&mut rng));
            let x = nalgebra::Vector5::from_column_slice(&theta) + l * e;
            let p = pedestal(&[x[0], x[1], x[2], x[3], x[4]], None);
            samples.push([p.y.f_n_hz, p.z.f_n_hz, p.y.zeta, p.z.zeta]);
        }
        let expected = [
            delta.y.f_n_std_err,
            delta.z.f_n_std_err,
            delta.y.zeta_std_err,
            delta.z.zeta_std_err,
        ];
        for (q, want) in expected.iter().enumerate() {
            let mean = samples.iter().map(|s| s[q]).sum::<f64>() / n as f64;
            let var = samples.iter().map(|s| (s[q] - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
            let sd_mc = var.sqrt();
            // The sd of a sample sd is sd/√(2n) ≈ 0.35 %: 3 % covers it
            // and the delta method's second-order error at this scatter.
            assert!(
                (sd_mc / want - 1.0).abs() < 0.03,
                "quantity {q}: Monte-Carlo {sd_mc:.4e}, delta method {want:.4e}"
            );
        }
        // Ignoring the k–m correlation would be wrong by far more: the
        // check above can fail.
        let diagonal: Covariance =
            std::array::from_fn(|i| std::array::from_fn(|j| if i == j { cov[i][j] } else { 0.0 }));
        let naive = pedestal(&theta, Some(&diagonal));
        assert!((naive.y.f_n_std_err / delta.y.f_n_std_err - 1.0).abs() > 0.5);
    }
}
