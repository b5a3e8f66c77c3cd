//! The support-mode test of [`super`]: does the pedestal's dynamic stiffness
//! fall faster with speed than one mass on one spring allows?
//!
//! A pedestal on something softer (its own sub-base, a frame) whose second
//! mode lies above the speed range moves there, per direction, with the
//! dynamic stiffness of a two-mass chain,
//!
//! D(Ω) = z₁ − Ω²m₁ − z₁²/(z₁ + z₂ − Ω²m₂),  zᵢ = kᵢ + iΩcᵢ,
//!
//! whose expansion in x = Ω²m₂/(k₁ + k₂) < 1 is
//! K_s − Ω²M_e − Ω⁴Q − … with K_s the series stiffness, M_e = m₁ + m₂r²
//! (r = k₁/(k₁ + k₂)) and Q = m₂²r²/(k₁ + k₂) > 0. The one-mass model
//! k − Ω²m + iΩc follows the first two terms only; the Ω⁴ term is what it
//! cannot follow, and it is not small near the top speed when the second
//! mode is just above it (the fourth unseen machine's stiff block on its
//! sub-base: x = 0.08/0.12 at 110 Hz, Ω⁴Q 5 % of K_s). A fit leaves it in
//! its residuals as a smooth curve rising to the top speed, which the
//! scan of [`super::structure`] spreads over its windows.
//!
//! This test asks the data for that term directly: the fitted model is
//! extended by −Ω⁴q_y, −Ω⁴q_z on the stiffness of each direction and the
//! whitened residuals w are projected on it with the weights of the fit
//! frozen (a score test, the two extra columns L⁻¹∂e/∂q = −Ω⁴L⁻¹∂e/∂k;
//! the equation is linear in the parameters, so its columns are exact):
//! T = |P_full w|² − |P_θ w|², the share of w only the extension explains.
//! With the noise known (noise columns) T is χ²(2) under the one-mass
//! model; nothing in it is tuned to a machine.

use super::super::gauss_helmert::{self as gh, Equations};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Degrees of freedom of the extension (one Ω⁴ term per direction) [-].
pub const EXTRA: usize = 2;

/// The support-mode test's figures ([`support_mode`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SupportMode {
    /// T: the whitened sum of squares the Ω⁴ terms explain beyond the
    /// one-mass model, in units of the noise level [-].
    pub statistic: f64,
    /// Upper-tail p-value of T under χ²([`EXTRA`]) [-].
    pub p_value: f64,
    /// The Ω⁴ coefficient fitted with the frozen weights, y and z, as a
    /// fraction of the fitted stiffness at the top speed: Ω_max⁴q/k [-]
    /// (positive: the stiffness falls faster than one mass allows).
    pub drop_at_top: [f64; 2],
}

/// The test on the equations `eq` at the fitted parameters `theta` (model
/// units, the stiffnesses k_y, k_z at indices 0 and 1), speeds `speeds_hz`
/// [Hz] (one per block of `eq`); `None` when a weight or a projection
/// cannot be formed.
pub fn support_mode<E: Equations + ?Sized>(
    eq: &E,
    theta: &[f64],
    speeds_hz: &[f64],
) -> Option<SupportMode> {
    let n = eq.speeds();
    let np = theta.len();
    if n != speeds_hz.len() || n * 4 <= np + EXTRA || np < 2 {
        return None;
    }
    let top = speeds_hz.iter().copied().fold(0.0_f64, f64::max);
    if top.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let mut x = DMatrix::<f64>::zeros(4 * n, np + EXTRA);
    let mut w = DVector::<f64>::zeros(4 * n);
    for (s, &speed) in speeds_hz.iter().enumerate() {
        let l = gh::whitening(eq, s, theta)?;
        let e0 = eq.error(s, theta);
        let ws = l.solve_lower_triangular(&e0)?;
        w.rows_mut(4 * s, 4).copy_from(&ws);
        // (Ω/Ω_max)⁴: the extension's column, scaled to order one.
        let r4 = (speed / top).powi(4);
        for k in 0..np {
            let step = theta[k].abs().max(1e-30) * 1e-3;
            let mut p = theta.to_vec();
            p[k] += step;
            let a = (eq.error(s, &p) - &e0) / step;
            let col = l.solve_lower_triangular(&a)?;
            x.view_mut((4 * s, k), (4, 1)).copy_from(&col);
            if k < EXTRA {
                x.view_mut((4 * s, np + k), (4, 1))
                    .copy_from(&(col * (-r4)));
            }
        }
    }
    let explained = |cols: usize| -> Option<(f64, DVector<f64>)> {
        let xs = x.columns(0, cols).into_owned();
        let svd = xs.clone().svd(true, true);
        let beta = svd.solve(&w, 1e-12).ok()?;
        let fit = &xs * &beta;
        Some((fit.norm_squared(), beta))
    };
    let (null, _) = explained(np)?;
    let (full, beta) = explained(np + EXTRA)?;
    let statistic = (full - null).max(0.0);
    let p_value = ChiSquared::new(EXTRA as f64)
        .map(|d| 1.0 - d.cdf(statistic))
        .unwrap_or(f64::NAN);
    // w ≈ Xβ is the residual the parameters' change −β removes (a
    // Gauss-Newton step): the extension's coefficient is −β, Ω_max⁴q in the
    // stiffness's units, relative to the refitted stiffness θ − β.
    let drop_at_top = std::array::from_fn(|k| {
        let kk = theta[k] - beta[k];
        if kk != 0.0 {
            -beta[np + k] / kk
        } else {
            f64::NAN
        }
    });
    (statistic.is_finite() && p_value.is_finite()).then_some(SupportMode {
        statistic,
        p_value,
        drop_at_top,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    use std::f64::consts::TAU;

    /// A pedestal per direction d, (k_d − Ω²m + iΩc_d)·X_d = F_d, written
    /// as 4 real equations per speed (y re, y im, z re, z im) in the 8
    /// measured numbers X (4) then F (4), each with its own noise variance;
    /// parameters k_y, k_z, m, c_y, c_z.
    struct Pedestal {
        omega: Vec<f64>,
        /// Measured X, F per speed: [X_y, X_z, F_y, F_z] (complex).
        data: Vec<[(f64, f64); 4]>,
        var: Vec<[f64; 8]>,
    }

    fn stiffness(p: &[f64], d: usize, w: f64) -> (f64, f64) {
        (p[d] - w * w * p[2], w * p[3 + d])
    }

    impl Equations for Pedestal {
        fn speeds(&self) -> usize {
            self.omega.len()
        }
        fn residual(&self, s: usize, p: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
            let w = self.omega[s];
            let mut e = DVector::zeros(4);
            let mut b = DMatrix::zeros(4, 8);
            for d in 0..2 {
                let (zr, zi) = stiffness(p, d, w);
                let (xr, xi) = self.data[s][d];
                let (fr, fi) = self.data[s][2 + d];
                e[2 * d] = zr * xr - zi * xi - fr;
                e[2 * d + 1] = zr * xi + zi * xr - fi;
                b[(2 * d, 2 * d)] = zr;
                b[(2 * d, 2 * d + 1)] = -zi;
                b[(2 * d + 1, 2 * d)] = zi;
                b[(2 * d + 1, 2 * d + 1)] = zr;
                b[(2 * d, 4 + 2 * d)] = -1.0;
                b[(2 * d + 1, 4 + 2 * d + 1)] = -1.0;
            }
            (e, b)
        }
        fn variance(&self, s: usize) -> &[f64] {
            &self.var[s]
        }
    }

    /// Truth: k 2e8/1e8 N/m, m 500 kg, c 4e4/3e4 N·s/m, the forces X makes
    /// with the Ω⁴ term q_d (F = (k − Ω²m − Ω⁴q + iΩc)·X), 24 speeds
    /// 10-60 Hz; noise sd `sd_x` [m] on X and `sd_f` [N] on F per real
    /// number.
    const THETA: [f64; 5] = [2e8, 1e8, 500.0, 4e4, 3e4];

    fn pedestal(
        q: [f64; 2],
        sd_x: f64,
        sd_f: f64,
        rng: Option<&mut rand::rngs::StdRng>,
    ) -> Pedestal {
        let omega: Vec<f64> = (0..24)
            .map(|i| TAU * (10.0 + 50.0 * i as f64 / 23.0))
            .collect();
        let mut data = Vec::new();
        for (i, &w) in omega.iter().enumerate() {
            let x = [
                (1e-6 * (1.0 + 0.1 * i as f64), 2e-7),
                (-3e-7, 8e-7 * (1.0 + 0.05 * i as f64)),
            ];
            let mut row = [(0.0, 0.0); 4];
            for d in 0..2 {
                let (zr, zi) = stiffness(&THETA, d, w);
                let zr = zr - w.powi(4) * q[d];
                row[d] = x[d];
                row[2 + d] = (zr * x[d].0 - zi * x[d].1, zr * x[d].1 + zi * x[d].0);
            }
            data.push(row);
        }
        if let Some(rng) = rng {
            let nx = Normal::new(0.0, sd_x).unwrap();
            let nf = Normal::new(0.0, sd_f).unwrap();
            for row in &mut data {
                for (c, v) in row.iter_mut().enumerate() {
                    let n = if c < 2 { &nx } else { &nf };
                    v.0 += n.sample(rng);
                    v.1 += n.sample(rng);
                }
            }
        }
        let var = vec![
            [
                sd_x * sd_x,
                sd_x * sd_x,
                sd_x * sd_x,
                sd_x * sd_x,
                sd_f * sd_f,
                sd_f * sd_f,
                sd_f * sd_f,
                sd_f * sd_f
            ];
            omega.len()
        ];
        Pedestal { omega, data, var }
    }

    fn speeds_hz(p: &Pedestal) -> Vec<f64> {
        p.omega.iter().map(|w| w / TAU).collect()
    }

    /// Exact data with a known Ω⁴ term, tested at the one-mass truth: the
    /// extension explains the whole residual, so its coefficient is the
    /// term's own (Ω_max⁴q/k per direction) and T is what the one-mass
    /// columns leave of the whitened residual (the null model's weighted
    /// least squares, solved here by its normal equations).
    #[test]
    fn a_known_quartic_term_gives_its_coefficient_and_score() {
        let q = [1e-3, 5e-4];
        let eq = pedestal(q, 1e-9, 1.0, None);
        let hz = speeds_hz(&eq);
        let t = support_mode(&eq, &THETA, &hz).expect("test");
        let top = eq.omega.iter().copied().fold(0.0, f64::max);
        for d in 0..2 {
            let want = top.powi(4) * q[d] / THETA[d];
            assert!(
                (t.drop_at_top[d] / want - 1.0).abs() < 1e-4,
                "{d}: {} vs {want}",
                t.drop_at_top[d]
            );
        }
        // The null's residual: whitened e(θ) minus its projection on the
        // one-mass columns (∂e/∂θ exact: e is linear in θ).
        let n = eq.speeds();
        let mut x = DMatrix::zeros(4 * n, 5);
        let mut w = DVector::zeros(4 * n);
        for s in 0..n {
            let l = gh::whitening(&eq, s, &THETA).unwrap();
            let (e0, _) = eq.residual(s, &THETA);
            w.rows_mut(4 * s, 4)
                .copy_from(&l.solve_lower_triangular(&e0).unwrap());
            for k in 0..5 {
                let mut p = THETA;
                p[k] += 1.0;
                let col = eq.residual(s, &p).0 - &e0;
                x.view_mut((4 * s, k), (4, 1))
                    .copy_from(&l.solve_lower_triangular(&col).unwrap());
            }
        }
        let norms: Vec<f64> = (0..5).map(|k| x.column(k).norm()).collect();
        for (k, v) in norms.iter().enumerate() {
            x.column_mut(k).scale_mut(1.0 / v);
        }
        // Normal equations by Cholesky (a route apart from the test's SVD).
        let b = (x.transpose() * &x)
            .cholesky()
            .expect("one-mass columns independent")
            .solve(&(x.transpose() * &w));
        let left = (&w - &x * b).norm_squared();
        assert!(left > 100.0, "the term is visible: {left}");
        assert!(
            (t.statistic / left - 1.0).abs() < 1e-6,
            "T {} vs the null's residual {left}",
            t.statistic
        );
    }

    /// A one-mass pedestal with white noise on X and F: at the truth the
    /// whitened residual is standard normal and T its share on two
    /// directions, χ²(2). 400 seeded draws: mean 2 (its standard error
    /// 0.1) and 5 % beyond the 95 % point 5.99 (standard error 1.1 %).
    #[test]
    fn a_one_mass_pedestal_gives_a_chi_square_2_score_on_white_noise() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(2026);
        let runs = 400;
        let (mut sum, mut beyond) = (0.0, 0);
        for _ in 0..runs {
            let eq = pedestal([0.0; 2], 2e-8, 20.0, Some(&mut rng));
            let t = support_mode(&eq, &THETA, &speeds_hz(&eq)).expect("test");
            sum += t.statistic;
            beyond += usize::from(t.statistic > 5.991);
            assert!((t.p_value - (-t.statistic / 2.0).exp()).abs() < 1e-9);
        }
        let mean = sum / runs as f64;
        let share = beyond as f64 / runs as f64;
        assert!((mean - 2.0).abs() < 0.3, "mean T {mean}");
        assert!(
            (share - 0.05).abs() < 0.034,
            "beyond the 95 % point: {share}"
        );
    }
}
