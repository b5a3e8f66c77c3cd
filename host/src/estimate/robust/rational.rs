//! A local model of one bearing's four phasors over a few neighbouring
//! speeds that follows a resonance: each channel a quadratic over one shared
//! quadratic denominator in speed, q_c(f) ≈ (a_c + b_c·x + e_c·x²)/(1 +
//! d₁x + d₂x²),
//! x = (f − centre)/span, every coefficient complex. Near a lightly damped
//! resonance every channel carries the same factor 1/(ω₀² − Ω² + iΩc) ≈
//! −1/(2ω₀(Ω − ω₀ − iζω₀)): one complex pole in speed, shared by the
//! channels (the mode shape, the numerators, changes slowly); two poles
//! follow two modes within the window. With d = 0 the model is the
//! quadratic in speed. Fitted by Sanathanan–Koerner iteration
//! (the linearised problem N_c(x) − q_c·(D(x) − 1) = q_c, reweighted by 1/|D(x)|
//! of the previous step, so that it converges to the least squares of the
//! residuals q_c − N_c/D themselves).

use nalgebra::{DMatrix, DVector};
use num_complex::Complex;

/// Numerator coefficients per channel [-].
const NUMERATOR_TERMS: usize = 3;

/// Denominator coefficients beyond its constant 1 [-]: two poles, for two
/// modes within a window.
const DENOMINATOR_TERMS: usize = 2;

/// Complex unknowns of the fit: the numerators of the four channels and
/// the denominator's.
const UNKNOWNS: usize = 4 * NUMERATOR_TERMS + DENOMINATOR_TERMS;

/// Fewest speeds a fit takes (4 channels × 5 speeds = 20 complex
/// equations for 14 complex unknowns).
pub const MIN_POINTS: usize = 5;

/// Sanathanan–Koerner reweighting steps [-].
const ITERATIONS: usize = 4;

/// One speed's four phasors (rel y, rel z, ped y, ped z [m]) at `speed_hz`.
pub type Point = (f64, [Complex<f64>; 4]);

/// The fitted local model.
#[derive(Clone, Debug)]
pub struct LocalRational {
    centre_hz: f64,
    span_hz: f64,
    numerators: [[Complex<f64>; NUMERATOR_TERMS]; 4],
    d: [Complex<f64>; DENOMINATOR_TERMS],
}

impl LocalRational {
    /// Least-squares fit to `points` (at least [`MIN_POINTS`]), each
    /// channel c's residual weighted by `weights[c]` [1/m] (one over its
    /// noise sd: the channels' sizes differ by orders of magnitude),
    /// speeds measured from `centre_hz`. `None` when the points are too
    /// few, span no speed, or the solve fails.
    pub fn fit(points: &[Point], centre_hz: f64, weights: &[f64; 4]) -> Option<Self> {
        if points.len() < MIN_POINTS {
            return None;
        }
        let span_hz = points
            .iter()
            .map(|(f, _)| (f - centre_hz).abs())
            .fold(0.0, f64::max);
        if !(span_hz > 0.0 && span_hz.is_finite()) {
            return None;
        }
        let mut model = LocalRational {
            centre_hz,
            span_hz,
            numerators: [[Complex::new(0.0, 0.0); NUMERATOR_TERMS]; 4],
            d: [Complex::new(0.0, 0.0); DENOMINATOR_TERMS],
        };
        let mut row_weight = vec![1.0; points.len()];
        for _ in 0..ITERATIONS {
            let rows = 4 * points.len();
            let mut a = DMatrix::<Complex<f64>>::zeros(rows, UNKNOWNS);
            let mut b = DVector::<Complex<f64>>::zeros(rows);
            for (k, (f, q)) in points.iter().enumerate() {
                let x = (f - centre_hz) / span_hz;
                for c in 0..4 {
                    let g = weights[c] * row_weight[k];
                    let r = 4 * k + c;
                    let mut power = 1.0;
                    for t in 0..NUMERATOR_TERMS {
                        a[(r, NUMERATOR_TERMS * c + t)] = Complex::new(g * power, 0.0);
                        power *= x;
                    }
                    let mut power = x;
                    for t in 0..DENOMINATOR_TERMS {
                        a[(r, 4 * NUMERATOR_TERMS + t)] = -q[c] * (g * power);
                        power *= x;
                    }
                    b[r] = q[c] * g;
                }
            }
            let svd = a.svd(true, true);
            let largest = svd.singular_values.iter().copied().fold(0.0, f64::max);
            let u = svd.solve(&b, 1e-12 * largest).ok()?;
            for c in 0..4 {
                for t in 0..NUMERATOR_TERMS {
                    model.numerators[c][t] = u[NUMERATOR_TERMS * c + t];
                }
            }
            for t in 0..DENOMINATOR_TERMS {
                model.d[t] = u[4 * NUMERATOR_TERMS + t];
            }
            for (w, (f, _)) in row_weight.iter_mut().zip(points) {
                let den = model.denominator(*f).norm();
                if !(den > 0.0 && den.is_finite()) {
                    return None;
                }
                *w = 1.0 / den;
            }
        }
        let finite = model
            .numerators
            .iter()
            .flatten()
            .chain(&model.d)
            .all(|z| z.re.is_finite() && z.im.is_finite());
        finite.then_some(model)
    }

    /// 1 + d₁x + d₂x² at `speed_hz` [-].
    fn denominator(&self, speed_hz: f64) -> Complex<f64> {
        let x = (speed_hz - self.centre_hz) / self.span_hz;
        Complex::new(1.0, 0.0) + self.d[0] * x + self.d[1] * (x * x)
    }

    /// The model's four phasors [m] at `speed_hz`; `None` at its pole.
    pub fn at(&self, speed_hz: f64) -> Option<[Complex<f64>; 4]> {
        let x = (speed_hz - self.centre_hz) / self.span_hz;
        let den = self.denominator(speed_hz);
        if den.norm() <= f64::EPSILON {
            return None;
        }
        Some(std::array::from_fn(|c| {
            let mut power = 1.0;
            let mut num = Complex::new(0.0, 0.0);
            for t in 0..NUMERATOR_TERMS {
                num += self.numerators[c][t] * power;
                power *= x;
            }
            num / den
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mode(f: f64, f0: f64, zeta: f64) -> Complex<f64> {
        let r = f / f0;
        Complex::new(1.0, 0.0) / Complex::new(1.0 - r * r, 2.0 * zeta * r)
    }

    /// A resonance the speed steps do not resolve (half-power width 1.2 Hz,
    /// steps of 2.5 Hz): the quadratic through the neighbours misses the
    /// reading between them by more than the reading itself; the rational
    /// model, fitted to the same neighbours, predicts it.
    #[test]
    fn a_resonance_between_the_speeds_is_followed() {
        let shapes = [
            Complex::new(1e-6, 0.0),
            Complex::new(0.0, 2e-6),
            Complex::new(3e-7, 1e-7),
            Complex::new(-2e-7, 0.0),
        ];
        let speeds: Vec<f64> = (0..11).map(|i| 30.0 + 2.5 * i as f64).collect();
        let truth = |f: f64| -> [Complex<f64>; 4] {
            std::array::from_fn(|c| {
                shapes[c] * mode(f, 43.0, 0.015) + shapes[(c + 1) % 4] * (f / 100.0)
            })
        };
        let left_out = 5; // 42.5 Hz, half a width from the peak
        let points: Vec<Point> = speeds
            .iter()
            .enumerate()
            .filter(|&(i, _)| i != left_out)
            .map(|(_, &f)| (f, truth(f)))
            .collect();
        let w = [1e6, 1e6, 3e6, 5e6];
        let model = LocalRational::fit(&points, speeds[left_out], &w).expect("fit");
        let f = speeds[left_out];
        let p = model.at(f).expect("prediction");
        let q = truth(f);
        for c in 0..4 {
            let err = (p[c] - q[c]).norm() / q[c].norm();
            assert!(err < 0.05, "channel {c}: relative error {err}");
        }
        // The quadratic through the six nearest speeds is far off.
        let near = [4usize, 6, 3, 7, 2, 8];
        let a = DMatrix::from_fn(6, 3, |r, c| ((speeds[near[r]] - f) / 7.5).powi(c as i32));
        let g = (a.transpose() * &a).try_inverse().expect("inverse") * a.transpose();
        let quad: Complex<f64> = near
            .iter()
            .enumerate()
            .map(|(k, &j)| truth(speeds[j])[0] * g[(0, k)])
            .sum();
        assert!((quad - q[0]).norm() > 0.5 * q[0].norm());
    }
}
