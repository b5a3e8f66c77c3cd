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
//! residuals q_c − N_c/D themselves). Each step is solved by variable
//! projection: the numerators enter linearly and share one weighted basis,
//! so they are eliminated by projecting onto its orthogonal complement,
//! leaving two complex unknowns for the denominator; the numerators follow
//! from 3×3 normal equations. The same least squares as one solve over all
//! 14 unknowns, at a small part of its cost (identify runs one fit per
//! speed and bearing).

use num_complex::Complex;

/// Numerator coefficients per channel [-].
const NUMERATOR_TERMS: usize = 3;

/// Denominator coefficients beyond its constant 1 [-]: two poles, for two
/// modes within a window.
const DENOMINATOR_TERMS: usize = 2;

/// Fewest speeds a fit takes (4 channels × 5 speeds = 20 complex
/// equations for 14 complex unknowns).
pub const MIN_POINTS: usize = 5;

/// Points a fit holds in buffers on the stack (more go to the heap) [-]:
/// the flip test's windows hold up to 10 (`flips::FLIP_SIDE` on each
/// side). No larger: the buffers are zeroed on every fit.
const STACK_POINTS: usize = 10;

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
        let m = points.len();
        let zero = Complex::new(0.0, 0.0);
        // Buffers reused by every step, on the stack for a window of up to
        // STACK_POINTS speeds (one fit per speed and bearing): each speed's
        // powers x⁰..x⁴ of x = (f − centre)/span; the row weights and the
        // numerators' basis; the denominators; the denominator's columns,
        // speed by speed with the four channels side by side ([`Lanes`]).
        let mut stack_powers = [[0.0; 2 * NUMERATOR_TERMS - 1]; STACK_POINTS];
        let mut stack_real = [0.0; (NUMERATOR_TERMS + 1) * STACK_POINTS];
        let mut stack_complex = [zero; STACK_POINTS];
        let mut stack_lanes = [[0.0; LANES]; (DENOMINATOR_TERMS + 1) * STACK_POINTS];
        let (mut heap_powers, mut heap_real, mut heap_complex, mut heap_lanes);
        let (powers, real, denominators, lanes): Buffers = if m <= STACK_POINTS {
            (
                &mut stack_powers[..m],
                &mut stack_real[..(NUMERATOR_TERMS + 1) * m],
                &mut stack_complex[..m],
                &mut stack_lanes[..(DENOMINATOR_TERMS + 1) * m],
            )
        } else {
            heap_powers = vec![[0.0; 2 * NUMERATOR_TERMS - 1]; m];
            heap_real = vec![0.0; (NUMERATOR_TERMS + 1) * m];
            heap_complex = vec![zero; m];
            heap_lanes = vec![[0.0; LANES]; (DENOMINATOR_TERMS + 1) * m];
            (
                &mut heap_powers,
                &mut heap_real,
                &mut heap_complex,
                &mut heap_lanes,
            )
        };
        for (p, (f, _)) in powers.iter_mut().zip(points) {
            let x = (f - centre_hz) / span_hz;
            p[0] = 1.0;
            for t in 1..p.len() {
                p[t] = p[t - 1] * x;
            }
        }
        let powers: &[[f64; 2 * NUMERATOR_TERMS - 1]] = powers;
        let (row_weight, basis_buffer) = real.split_at_mut(m);
        row_weight.fill(1.0);
        let mut chunks = basis_buffer.chunks_exact_mut(m);
        let mut basis: [&mut [f64]; NUMERATOR_TERMS] =
            std::array::from_fn(|_| chunks.next().unwrap_or_default());
        let mut chunks = lanes.chunks_exact_mut(m);
        let mut cols: [&mut [Lanes]; DENOMINATOR_TERMS + 1] =
            std::array::from_fn(|_| chunks.next().unwrap_or_default());
        for _ in 0..ITERATIONS {
            // Orthonormal basis of the weighted numerator columns
            // row_weight·xᵗ (t < NUMERATOR_TERMS), the same for every
            // channel: Gram–Schmidt, twice for orthogonality.
            for (t, column) in basis.iter_mut().enumerate() {
                for (v, (w, p)) in column.iter_mut().zip(row_weight.iter().zip(powers)) {
                    *v = w * p[t];
                }
            }
            for t in 0..NUMERATOR_TERMS {
                let (done, rest) = basis.split_at_mut(t);
                let column = &mut rest[0];
                for _ in 0..2 {
                    for earlier in done.iter() {
                        let dot: f64 = earlier.iter().zip(column.iter()).map(|(a, b)| a * b).sum();
                        for (v, e) in column.iter_mut().zip(earlier.iter()) {
                            *v -= dot * e;
                        }
                    }
                }
                let norm = column.iter().map(|v| v * v).sum::<f64>().sqrt();
                if !(norm > 0.0 && norm.is_finite()) {
                    return None;
                }
                column.iter_mut().for_each(|v| *v /= norm);
            }
            // Variable projection: with the numerators eliminated, the
            // denominator minimises Σ_c ‖r₀ + d₁r₁ + d₂r₂‖², r_t the part
            // of channel c's weighted q·xᵗ no numerator can take. The four
            // channels side by side: each channel's figures are formed by
            // the same operations in the same order as one channel at a
            // time, in a quarter of the passes over the speeds.
            for (t, v) in cols.iter_mut().enumerate() {
                for (lane, ((point, w), x)) in v
                    .iter_mut()
                    .zip(points.iter().zip(row_weight.iter()).zip(powers))
                {
                    for (c, &weight) in weights.iter().enumerate() {
                        let scale = weight * w * x[t];
                        lane[2 * c] = point.1[c].re * scale;
                        lane[2 * c + 1] = point.1[c].im * scale;
                    }
                }
                for b in &basis {
                    let mut dot = [0.0; LANES];
                    for (lane, e) in v.iter().zip(b.iter()) {
                        for (d, z) in dot.iter_mut().zip(lane) {
                            *d += z * e;
                        }
                    }
                    for (lane, e) in v.iter_mut().zip(b.iter()) {
                        for (z, d) in lane.iter_mut().zip(&dot) {
                            *z -= d * e;
                        }
                    }
                }
            }
            let mut gram = [[zero; DENOMINATOR_TERMS]; DENOMINATOR_TERMS];
            let mut rhs = [zero; DENOMINATOR_TERMS];
            for i in 0..DENOMINATOR_TERMS {
                // The upper triangle: [`solve_hermitian_2`] reads no more.
                for j in i..DENOMINATOR_TERMS {
                    let sums = conj_dots(cols[i + 1], cols[j + 1]);
                    for s in sums {
                        gram[i][j] += s;
                    }
                }
                let sums = conj_dots(cols[i + 1], cols[0]);
                for s in sums {
                    rhs[i] -= s;
                }
            }
            model.d = solve_hermitian_2(&gram, &rhs)?;
            // The numerators for that denominator: per channel the weighted
            // least squares of N_c(x) against q_c·D(x) (3×3 normal
            // equations of the well-scaled monomials, x within ±1).
            // Entry (i, j) depends on i + j alone: each sum once.
            let moments: [f64; 2 * NUMERATOR_TERMS - 1] = std::array::from_fn(|t| {
                (0..m)
                    .map(|k| (row_weight[k] * row_weight[k]) * powers[k][t])
                    .sum::<f64>()
            });
            let normal = nalgebra::Matrix3::from_fn(|i, j| moments[i + j]);
            let cholesky = normal.cholesky()?;
            for (k, (f, _)) in points.iter().enumerate() {
                denominators[k] = model.denominator(*f);
            }
            // Every channel's right-hand sides in one pass over the speeds
            // (each sum over the speeds in the same order as one channel
            // at a time), w²·xⁱ formed once per speed.
            let mut re = [nalgebra::Vector3::<f64>::zeros(); 4];
            let mut im = [nalgebra::Vector3::<f64>::zeros(); 4];
            for k in 0..m {
                let w2 = row_weight[k] * row_weight[k];
                let wx: [f64; NUMERATOR_TERMS] = std::array::from_fn(|i| w2 * powers[k][i]);
                for c in 0..4 {
                    let target = points[k].1[c] * denominators[k];
                    for i in 0..NUMERATOR_TERMS {
                        re[c][i] += wx[i] * target.re;
                        im[c][i] += wx[i] * target.im;
                    }
                }
            }
            for c in 0..4 {
                let (re, im) = (cholesky.solve(&re[c]), cholesky.solve(&im[c]));
                for t in 0..NUMERATOR_TERMS {
                    model.numerators[c][t] = Complex::new(re[t], im[t]);
                }
            }
            for (w, den) in row_weight.iter_mut().zip(denominators.iter()) {
                let den = den.norm();
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

/// Real numbers of one speed's four channels side by side (re, im of rel
/// y, rel z, ped y, ped z) [-].
const LANES: usize = 8;

/// One speed's four complex channel values as [`LANES`] real numbers.
type Lanes = [f64; LANES];

/// A fit's working buffers: powers of x per speed, row weights and
/// numerator basis, denominators, denominator columns ([`LocalRational::fit`]).
type Buffers<'a> = (
    &'a mut [[f64; 2 * NUMERATOR_TERMS - 1]],
    &'a mut [f64],
    &'a mut [Complex<f64>],
    &'a mut [Lanes],
);

/// Per channel, Σ_k conj(a_k)·b_k over the speeds of the side-by-side
/// columns `a`, `b` ([`Lanes`]), summed from zero in speed order (the
/// figures of a complex dot product of each channel alone).
fn conj_dots(a: &[Lanes], b: &[Lanes]) -> [Complex<f64>; 4] {
    let mut re = [0.0; 4];
    let mut im = [0.0; 4];
    for (a, b) in a.iter().zip(b) {
        for c in 0..4 {
            let (ar, ai, br, bi) = (a[2 * c], a[2 * c + 1], b[2 * c], b[2 * c + 1]);
            re[c] += ar * br + ai * bi;
            im[c] += ar * bi - ai * br;
        }
    }
    std::array::from_fn(|c| Complex::new(re[c], im[c]))
}

/// The least-squares solution of the 2×2 Hermitian positive semidefinite
/// system `gram`·d = `rhs`, directions whose eigenvalue is below 1e-24 of
/// the largest left out (the minimum-norm solution, as a singular-value
/// solve with a relative tolerance of 1e-12 on the columns gives); `None`
/// when the system is not finite.
fn solve_hermitian_2(
    gram: &[[Complex<f64>; 2]; 2],
    rhs: &[Complex<f64>; 2],
) -> Option<[Complex<f64>; 2]> {
    let (a, d, b) = (gram[0][0].re, gram[1][1].re, gram[0][1]);
    if !(a.is_finite() && d.is_finite() && b.re.is_finite() && b.im.is_finite()) {
        return None;
    }
    let mean = 0.5 * (a + d);
    let radius = (0.25 * (a - d) * (a - d) + b.norm_sqr()).sqrt();
    let eigenvalues = [mean + radius, mean - radius];
    if eigenvalues[0].partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Some([Complex::new(0.0, 0.0); 2]);
    }
    // Unit eigenvectors: (b, λ − a) or (λ − d, b̄), the better scaled one.
    let vector = |l: f64| -> [Complex<f64>; 2] {
        let v1 = [b, Complex::new(l - a, 0.0)];
        let v2 = [Complex::new(l - d, 0.0), b.conj()];
        let n1 = v1[0].norm_sqr() + v1[1].norm_sqr();
        let n2 = v2[0].norm_sqr() + v2[1].norm_sqr();
        let (v, n) = if n1 >= n2 { (v1, n1) } else { (v2, n2) };
        if n > 0.0 {
            let s = n.sqrt();
            [v[0] / s, v[1] / s]
        } else if a >= d {
            [Complex::new(1.0, 0.0), Complex::new(0.0, 0.0)]
        } else {
            [Complex::new(0.0, 0.0), Complex::new(1.0, 0.0)]
        }
    };
    let first = vector(eigenvalues[0]);
    // The second eigenvector is orthogonal to the first.
    let second = [-first[1].conj(), first[0].conj()];
    let mut out = [Complex::new(0.0, 0.0); 2];
    for (l, v) in eigenvalues.into_iter().zip([first, second]) {
        if l > 1e-24 * eigenvalues[0] {
            let coefficient = (v[0].conj() * rhs[0] + v[1].conj() * rhs[1]) / l;
            out[0] += v[0] * coefficient;
            out[1] += v[1] * coefficient;
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

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
