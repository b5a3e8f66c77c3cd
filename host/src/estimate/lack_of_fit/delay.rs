//! The sensor-delay test of [`super`]: do one bearing's `rel` probes read
//! late (or early), a phase error growing linearly with speed?
//!
//! A filter or an acquisition chain that delays both `rel` probes of a
//! bearing by τ multiplies their phasors by e^{−iΩτ} (formats.md,
//! `sensor_delay`). The bearing force K*·rel turns with them, and the
//! one-mass fit sees the pedestal's dynamic stiffness as Z·e^{−iΩτ} ≈
//! Z·(1 − iΩτ): a damping c − τ(k − Ω²m) and a mass term Ω²τc, in ± that
//! count noise only (150 µs on the sixth unseen machine's B2: its dampings
//! 3-10 ± off, printed `ok`, session 45).
//!
//! The extension: the `rel` phasors of the bearing multiplied by e^{iΩτ},
//! one τ shared by its two probes. The equation e = A·θ − K*·rel is linear
//! in rel, so its derivative at τ = 0 is exact: ∂e/∂τ = −iΩ·K*·rel = iΩ·e(0)
//! (e at θ = 0 is −K*·rel), per direction, as (re, im) rows. A delay on the
//! `ped` pick-ups instead makes Z·e^{+iΩτ}: its column iΩ·A·θ is the same
//! as the rel one's but for its sign and iΩ times the residual (A·θ = K*·rel
//! where the model holds), so it is not a second test: the one column sees
//! it as a negative τ̂. Only a delay common to both (which leaves Z alone)
//! cannot be seen, and does no harm.
//!
//! **The weights**: rotating a phasor leaves its noise's covariance alone
//! when its variance is split equally between the real and imaginary parts
//! (formats.md's noise columns), so Σ does not move with τ and the
//! extension's half-gradient is its frozen-weight projection X₂ᵀw; the
//! one-mass parameters' share is the efficient score of [`super::score`]
//! (weights moving with θ, as in [`super::support`]).
//!
//! **The null**: two-sided (a delay on `rel` and one on `ped` give τ of both
//! signs), b²/G is χ²(1). Made only with noise columns (the whitened
//! residuals are in their units), as the support-mode test.
//!
//! **What it cannot see**: the column's imaginary part iΩ(k − Ω²m)·X differs
//! from the damping's iΩc·X only through Ω²m's change over the run; with the
//! pedestal's resonances well above the speeds, k − Ω²m is nearly k and τ
//! and c are nearly collinear (the fifth unseen machine): the test's
//! information G is then small and τ's σ large.

use super::super::gauss_helmert::Equations;
use super::score::{efficient_score, Extension};
use nalgebra::DVector;
use serde::{Deserialize, Serialize};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// The unit of τ in the extension's column [s] (1 µs).
const MICROSECOND: f64 = 1e-6;

/// The sensor-delay test's figures ([`sensor_delay`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SensorDelay {
    /// b²/G: the whitened sum of squares a delay explains beyond the
    /// one-mass model, in units of the noise columns [-].
    pub statistic: f64,
    /// Upper-tail p-value of the statistic under χ²(1) [-].
    pub p_value: f64,
    /// The delay of the `rel` probes fitted in one step from τ = 0 (a delay
    /// of the `ped` pick-ups shows as a negative value) [µs].
    pub delay_us: f64,
    /// Its standard error 1/√G [µs].
    pub delay_std_us: f64,
}

/// The test on the equations `eq` (one bearing, 4 rows per speed: y re, y
/// im, z re, z im, e = A·θ − K*·rel) at the fitted parameters `theta`
/// (model units), weighted by the noise columns, `omega` the speeds
/// [rad/s] (one per block of `eq`); `None` when a weight or a projection
/// cannot be formed or no residual degree of freedom is left.
pub fn sensor_delay<E: Equations + ?Sized>(
    eq: &E,
    theta: &[f64],
    omega: &[f64],
) -> Option<SensorDelay> {
    if eq.speeds() != omega.len() {
        return None;
    }
    let score = efficient_score(eq, theta, 1, |at| {
        let col = delay_column(eq, at.s, omega[at.s], at.l)?;
        let wres = at.l.solve_lower_triangular(at.e0)?;
        let half = col.dot(&wres);
        Some(Extension {
            columns: vec![col],
            half_gradient: vec![half],
        })
    })?;
    let g = score.g[(0, 0)];
    let b = score.b[0];
    if g.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let statistic = b * b / g;
    let p_value = 1.0 - ChiSquared::new(1.0).ok()?.cdf(statistic);
    let out = SensorDelay {
        statistic,
        p_value,
        delay_us: -score.gamma[0],
        delay_std_us: 1.0 / g.sqrt(),
    };
    (statistic.is_finite() && p_value.is_finite() && out.delay_us.is_finite()).then_some(out)
}

/// The whitened column of a delay on both `rel` probes at τ = 0 at speed
/// `s` of `eq` (4 rows: y re, y im, z re, z im), per µs of τ: L_s⁻¹·iΩ·e_s(0)
/// (module docs), `omega` the speed [rad/s], `l` the speed's whitening
/// factor; `None` when the speed's block is not 4 rows or L is singular.
pub(super) fn delay_column<E: Equations + ?Sized>(
    eq: &E,
    s: usize,
    omega: f64,
    l: &nalgebra::DMatrix<f64>,
) -> Option<DVector<f64>> {
    // e at θ = 0 is −K*·rel (the equations are linear in θ).
    let zero = vec![0.0; plinth_shared::regression::PARAMETERS];
    let f = eq.error(s, &zero);
    if f.len() != 4 {
        return None;
    }
    let w = omega * MICROSECOND;
    let raw = DVector::from_vec(vec![-w * f[1], w * f[0], -w * f[3], w * f[2]]);
    l.solve_lower_triangular(&raw)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::ml::{Rigid, Weighting};
    use crate::estimate::{mul, Observation};
    use num_complex::Complex;
    use rand::{Rng, SeedableRng};
    use std::f64::consts::TAU;

    /// Truth: k 1e7/4e6 N/m, m 150 kg, c 900/700 N·s/m (resonances 41 and
    /// 26 Hz, inside the run).
    const THETA: [f64; 5] = [1.0e7, 4.0e6, 150.0, 900.0, 700.0];

    /// A pedestal on a cross-coupled bearing (the elements of the
    /// simulator: F = K*·rel, (k − Ω²m + iΩc)·ped = F per direction) over 40
    /// speeds 10-80 Hz: the true phasors, then the `rel` probes read `tau_rel`
    /// [s] late and the `ped` pick-ups `tau_ped` [s] late (e^{−iΩτ}), then
    /// complex Gaussian noise of sd 1 % of each channel's largest phasor,
    /// split equally between re and im (formats.md's noise columns), its
    /// variances given as the columns would.
    fn run(tau_rel: f64, tau_ped: f64, rng: &mut rand::rngs::StdRng) -> Vec<Observation> {
        let speeds: Vec<f64> = (0..40).map(|i| 10.0 + 70.0 * i as f64 / 39.0).collect();
        let mut obs: Vec<Observation> = speeds
            .iter()
            .map(|&f| {
                let omega = TAU * f;
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
                let z = |d: usize| {
                    Complex::new(THETA[d] - omega * omega * THETA[2], omega * THETA[3 + d])
                };
                let ped = [force[0] / z(0), force[1] / z(1)];
                let lag = |tau: f64| Complex::from_polar(1.0, -omega * tau);
                Observation {
                    speed_hz: f,
                    rel: [rel[0] * lag(tau_rel), rel[1] * lag(tau_rel)],
                    ped: [ped[0] * lag(tau_ped), ped[1] * lag(tau_ped)],
                    kstar,
                    var: [0.0; 8],
                }
            })
            .collect();
        let peak = |c: usize| {
            obs.iter()
                .map(|o| if c < 2 { o.rel[c] } else { o.ped[c - 2] }.norm())
                .fold(0.0, f64::max)
        };
        let sd: [f64; 4] = std::array::from_fn(|c| 0.01 * peak(c));
        for o in &mut obs {
            o.var = std::array::from_fn(|c| 0.5 * sd[c / 2] * sd[c / 2]);
            for (c, v) in o.rel.iter_mut().chain(o.ped.iter_mut()).enumerate() {
                let s = (0.5f64).sqrt() * sd[c];
                *v += Complex::new(
                    s * rng.sample::<f64, _>(rand_distr::StandardNormal),
                    s * rng.sample::<f64, _>(rand_distr::StandardNormal),
                );
            }
        }
        obs
    }

    fn test(obs: &[Observation]) -> SensorDelay {
        let eq = Rigid::new(obs, &Weighting::default());
        let omega: Vec<f64> = obs.iter().map(|o| o.omega()).collect();
        sensor_delay(&eq, &THETA, &omega).expect("test")
    }

    /// Without a delay the statistic is χ²(1) and the p-value uniform: 400
    /// seeded runs, 5 % below 0.05 (standard error 1.1 %) and 20 % below
    /// 0.2 (2 %); τ̂/σ has mean 0 and sd 1.
    #[test]
    fn the_delay_score_is_calibrated_without_a_delay() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(4301);
        let runs = 400;
        let (mut below5, mut below20, mut sum, mut sum2) = (0, 0, 0.0, 0.0);
        for _ in 0..runs {
            let t = test(&run(0.0, 0.0, &mut rng));
            below5 += usize::from(t.p_value < 0.05);
            below20 += usize::from(t.p_value < 0.2);
            let z = t.delay_us / t.delay_std_us;
            sum += z;
            sum2 += z * z;
        }
        let (p5, p20) = (below5 as f64 / runs as f64, below20 as f64 / runs as f64);
        assert!((p5 - 0.05).abs() < 0.034, "below 0.05: {p5}");
        assert!((p20 - 0.2).abs() < 0.06, "below 0.2: {p20}");
        let mean = sum / runs as f64;
        let rms = (sum2 / runs as f64).sqrt();
        assert!(mean.abs() < 0.2, "mean z {mean}");
        assert!((rms - 1.0).abs() < 0.15, "RMS z {rms}");
    }

    /// The linearisation of the shared delay rule
    /// ([`super::super::delay_unknown::delay_nuisance`]) on the same runs:
    /// without a delay τ̂/σ_τ has mean 0 and RMS 1 over 200 runs (its ± is
    /// right) and ρ ≥ 1; with 150 µs on the `rel` probes τ̂ is within 3 σ_τ
    /// of it (the sign is a delay's, not an advance's).
    #[test]
    fn the_linearised_delay_is_calibrated_and_finds_a_delay() {
        use super::super::delay_unknown::delay_nuisance;
        use plinth_shared::regression::Parameter;
        let nuisance = |obs: &[Observation]| {
            let eq = Rigid::new(obs, &Weighting::default());
            let omega: Vec<f64> = obs.iter().map(|o| o.omega()).collect();
            delay_nuisance(&eq, &THETA, &omega, &Parameter::ALL, None).expect("linearised")
        };
        let mut rng = rand::rngs::StdRng::seed_from_u64(5100);
        let runs = 200;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..runs {
            let d = nuisance(&run(0.0, 0.0, &mut rng));
            assert!(d.ratio.iter().all(|r| *r >= 1.0), "{d:?}");
            let z = d.delay_us / d.delay_std_us;
            sum += z;
            sum2 += z * z;
        }
        let mean = sum / runs as f64;
        let rms = (sum2 / runs as f64).sqrt();
        assert!(mean.abs() < 0.25, "mean z {mean}");
        assert!((rms - 1.0).abs() < 0.15, "RMS z {rms}");
        let d = nuisance(&run(150e-6, 0.0, &mut rng));
        assert!((d.delay_us - 150.0).abs() < 3.0 * d.delay_std_us, "{d:?}");
    }

    /// 150 µs on the `rel` probes is found with its value (within 3 σ) and
    /// the same on the `ped` pick-ups shows as −150 µs; 150 µs on both
    /// leaves Z alone and is not seen.
    #[test]
    fn a_delay_is_found_with_its_size_and_side() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(4302);
        let t = test(&run(150e-6, 0.0, &mut rng));
        assert!(t.p_value < 1e-6, "{t:?}");
        assert!((t.delay_us - 150.0).abs() < 3.0 * t.delay_std_us, "{t:?}");
        let t = test(&run(0.0, 150e-6, &mut rng));
        assert!(t.p_value < 1e-6, "{t:?}");
        assert!((t.delay_us + 150.0).abs() < 3.0 * t.delay_std_us, "{t:?}");
        let t = test(&run(150e-6, 150e-6, &mut rng));
        assert!(t.p_value > 1e-3, "{t:?}");
    }
}
