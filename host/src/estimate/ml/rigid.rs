//! The rigid pedestal as a Gauss–Helmert system ([`super`]'s module docs):
//! per speed the regression rows A, the right-hand side b and Σ(θ), prepared
//! once, and the whitened residuals, their analytic Jacobian and the normal
//! equations formed speed by speed in fixed-size 4×4 arithmetic.

use super::{MlError, Weighting};
use crate::estimate::gauss_helmert::{self as gh, Equations, JacobianRequest};
use crate::estimate::Observation;
use nalgebra::{DMatrix, DVector, Matrix4, SMatrix, SVector, Vector4};
use num_complex::Complex;
use plinth_shared::regression::{equations, PARAMETERS};

/// One speed of the rigid pedestal, prepared once and reused by every
/// iteration: e = A·θ − b, Σ(θ) = c·(Σ_rel + B_ped(θ)·D_ped·B_ped(θ)ᵀ + τ²·I).
#[derive(Clone, Copy, Debug)]
pub(super) struct Speed {
    pub(super) speed_hz: f64,
    pub(super) omega: f64,
    pub(super) a: SMatrix<f64, 4, PARAMETERS>,
    pub(super) b: Vector4<f64>,
    /// ∂e/∂rel = −K* as a real 4×4 matrix.
    pub(super) b_rel: Matrix4<f64>,
    /// Covariance of e from the `rel` noise through −K* (constant in θ) [N²].
    pub(super) sigma_rel: Matrix4<f64>,
    /// Noise variances of ped (y re, y im, z re, z im) [m²].
    pub(super) var_ped: [f64; 4],
    /// The covariance factor c of [`Weighting::cov_scale`] [-].
    pub(super) scale: f64,
}

/// Real 2×2 block of a complex factor `a` acting on (re, im).
fn put(j: &mut SMatrix<f64, 4, 8>, row: usize, col: usize, a: Complex<f64>) {
    j[(row, col)] = a.re;
    j[(row, col + 1)] = -a.im;
    j[(row + 1, col)] = a.im;
    j[(row + 1, col + 1)] = a.re;
}

impl Speed {
    pub(super) fn new(o: &Observation, scale: f64) -> Self {
        let (a, b) = rows(o);
        let mut b_rel = SMatrix::<f64, 4, 4>::zeros();
        for d in 0..2 {
            for c in 0..2 {
                let k = -o.kstar[d][c];
                b_rel[(2 * d, 2 * c)] = k.re;
                b_rel[(2 * d, 2 * c + 1)] = -k.im;
                b_rel[(2 * d + 1, 2 * c)] = k.im;
                b_rel[(2 * d + 1, 2 * c + 1)] = k.re;
            }
        }
        let d_rel = Matrix4::from_diagonal(&Vector4::from_fn(|i, _| o.var[i]));
        Self {
            speed_hz: o.speed_hz,
            omega: o.omega(),
            a,
            b,
            b_rel,
            sigma_rel: b_rel * d_rel * b_rel.transpose(),
            var_ped: [o.var[4], o.var[5], o.var[6], o.var[7]],
            scale,
        }
    }

    /// (Re, Im) of the pedestal's dynamic stiffness k − Ω²m + iΩc in y and z.
    pub(super) fn stiffness(&self, theta: &[f64]) -> [(f64, f64); 2] {
        let w = self.omega;
        [
            (theta[0] - w * w * theta[2], w * theta[3]),
            (theta[1] - w * w * theta[2], w * theta[4]),
        ]
    }

    /// Σ(θ) with an equation error of variance `tau2` [N²].
    pub(super) fn sigma(&self, theta: &[f64], tau2: f64) -> Matrix4<f64> {
        let mut s = self.sigma_rel;
        for (d, (re, im)) in self.stiffness(theta).into_iter().enumerate() {
            let (v1, v2) = (self.var_ped[2 * d], self.var_ped[2 * d + 1]);
            let i = 2 * d;
            s[(i, i)] += re * re * v1 + im * im * v2 + tau2;
            s[(i + 1, i + 1)] += im * im * v1 + re * re * v2 + tau2;
            let off = re * im * (v1 - v2);
            s[(i, i + 1)] += off;
            s[(i + 1, i)] += off;
        }
        s * self.scale
    }

    /// B = ∂e/∂(measured numbers) at θ (4×12: rel, ped, equation error),
    /// what [`Equations::residual`] gives.
    fn measured_jacobian(&self, theta: &[f64]) -> SMatrix<f64, 4, 12> {
        let mut b = SMatrix::<f64, 4, 8>::zeros();
        for (d, (re, im)) in self.stiffness(theta).into_iter().enumerate() {
            put(&mut b, 2 * d, 4 + 2 * d, Complex::new(re, im));
        }
        let mut full = SMatrix::<f64, 4, 12>::zeros();
        full.fixed_view_mut::<4, 4>(0, 0).copy_from(&self.b_rel);
        full.fixed_view_mut::<4, 4>(0, 4)
            .copy_from(&b.fixed_view::<4, 4>(0, 4));
        for i in 0..4 {
            full[(i, 8 + i)] = 1.0;
        }
        full
    }

    /// Lower Cholesky factor of Σ(θ) with an equation error of variance `tau2` [N²].
    pub(super) fn factor(&self, theta: &[f64], tau2: f64) -> Result<Matrix4<f64>, MlError> {
        cholesky(self.sigma(theta, tau2), self.speed_hz)
    }

    /// ∂w/∂θ (4×5) of the whitened residual w = L⁻¹e at θ, given L⁻¹ and w
    /// (module docs): L⁻¹A_k − Φ(L⁻¹·∂Σ/∂θ_k·L⁻ᵀ)·w. ∂Σ/∂θ_k is a combination
    /// of three fixed 2×2 patterns per direction, so Φ(·)·w is formed once per
    /// pattern and combined per parameter: fixed-size, no allocation.
    pub(super) fn whitened_jacobian(
        &self,
        theta: &[f64],
        linv: &Matrix4<f64>,
        w: &Vector4<f64>,
    ) -> SMatrix<f64, 4, PARAMETERS> {
        let mut j = linv * self.a;
        // Φ(x·yᵀ)·w: x_i·(Σ_{q<i} y_q·w_q + ½·y_i·w_i).
        let phi = |x: &Vector4<f64>, y: &Vector4<f64>| -> Vector4<f64> {
            let mut out = Vector4::zeros();
            let mut acc = 0.0;
            for i in 0..4 {
                let yw = y[i] * w[i];
                out[i] = x[i] * (acc + 0.5 * yw);
                acc += yw;
            }
            out
        };
        let om = self.omega;
        let c = self.scale;
        for (d, (a, b)) in self.stiffness(theta).into_iter().enumerate() {
            let g0: Vector4<f64> = linv.column(2 * d).into_owned();
            let g1: Vector4<f64> = linv.column(2 * d + 1).into_owned();
            let p00 = phi(&g0, &g0);
            let p01 = phi(&g0, &g1) + phi(&g1, &g0);
            let p11 = phi(&g1, &g1);
            let (v1, v2) = (self.var_ped[2 * d], self.var_ped[2 * d + 1]);
            // ∂Σ's block [[s0, s1], [s1, s2]] for ∂(Re h, Im h) = (1, 0)
            // (the stiffness; the mass is −Ω² times it) and (0, Ω) (the damping).
            let stiffness =
                p00 * (2.0 * c * a * v1) + p01 * (c * b * (v1 - v2)) + p11 * (2.0 * c * a * v2);
            let damping = p00 * (2.0 * c * b * om * v2)
                + p01 * (c * a * om * (v1 - v2))
                + p11 * (2.0 * c * b * om * v1);
            let mut col = j.column_mut(d);
            col -= &stiffness;
            let mut col = j.column_mut(2);
            col += stiffness * (om * om);
            let mut col = j.column_mut(3 + d);
            col -= &damping;
        }
        j
    }
}

/// The rigid pedestal as a Gauss–Helmert system (module docs): one pedestal
/// on rigid ground, p = θ.
pub struct Rigid {
    pub(super) speeds: Vec<Speed>,
    /// τ² [N²] (module docs, "Equation error").
    pub(super) equation_var: f64,
    /// Per speed, the variances of B's columns (rel, ped, equation error)
    /// for the generic [`Equations`] methods.
    var: Vec<[f64; 12]>,
}

impl Rigid {
    /// The system of `obs` (any order) under `weighting`.
    pub fn new(obs: &[Observation], weighting: &Weighting<'_>) -> Self {
        let scale = |i: usize| {
            weighting
                .cov_scale
                .and_then(|c| c.get(i))
                .copied()
                .unwrap_or(1.0)
        };
        let speeds: Vec<Speed> = obs
            .iter()
            .enumerate()
            .map(|(i, o)| Speed::new(o, scale(i)))
            .collect();
        let var = obs
            .iter()
            .enumerate()
            .map(|(i, o)| {
                let c = scale(i);
                std::array::from_fn(|k| {
                    c * if k < 8 {
                        o.var[k]
                    } else {
                        weighting.equation_var
                    }
                })
            })
            .collect();
        Self {
            speeds,
            equation_var: weighting.equation_var,
            var,
        }
    }

    /// Sets τ² [N²].
    pub(super) fn set_equation_var(&mut self, equation_var: f64) {
        self.equation_var = equation_var;
        for (v, s) in self.var.iter_mut().zip(&self.speeds) {
            for x in &mut v[8..] {
                *x = s.scale * equation_var;
            }
        }
    }

    /// Cholesky factor of speed `s`'s Σ at θ.
    pub(super) fn factor(&self, s: usize, theta: &[f64]) -> Result<Matrix4<f64>, MlError> {
        self.speeds[s].factor(theta, self.equation_var)
    }

    /// J(θ) = Σ eᵀΣ⁻¹e [-].
    pub(super) fn cost(&self, theta: &[f64]) -> Result<f64, MlError> {
        cost_of(self.speeds.iter().copied(), theta, self.equation_var)
    }

    /// J(θ) and its slope dJ/dτ² [1/N²] at the current τ²: ∂Σ/∂τ² = c·I,
    /// so dJ/dτ² = −Σ c·|Σ⁻¹e|² with Σ⁻¹e = L⁻ᵀw.
    pub(super) fn cost_and_slope(&self, theta: &[f64]) -> Result<(f64, f64), MlError> {
        let t = theta_vector(theta);
        let (mut cost, mut slope) = (0.0, 0.0);
        for sp in &self.speeds {
            let l = sp.factor(theta, self.equation_var)?;
            let w = forward(&l, &(sp.a * t - sp.b));
            cost += w.norm_squared();
            slope -= sp.scale * backward(&l, &w).norm_squared();
        }
        Ok((cost, slope))
    }

    /// The residual of speed `s` at `theta` whitened by a lower-triangular
    /// factor `l` held fixed: L⁻¹e [-], the same figures as
    /// [`gh::whitened`] with that factor frozen (the same substitution), in
    /// fixed-size arithmetic.
    pub(crate) fn whitened_by(&self, s: usize, theta: &[f64], l: &Matrix4<f64>) -> Vector4<f64> {
        let sp = &self.speeds[s];
        forward(l, &(sp.a * theta_vector(theta) - sp.b))
    }

    /// [`gh::whitening`] of speed `s` at `theta` in fixed-size arithmetic:
    /// Σ = B·D·Bᵀ from [`Equations::residual`]'s B and
    /// [`Equations::variance`]'s D, each entry summed over the 12 measured
    /// numbers in the order nalgebra's product sums them (B's entry times
    /// its variance, times the other row's entry), its lower Cholesky
    /// factor, regularised by 1e-12 of the mean diagonal when singular:
    /// the same figures without allocation (one per speed in the outlier
    /// test and the sandwich). `None` where [`gh::whitening`] gives `None`.
    pub(crate) fn generic_factor(&self, s: usize, theta: &[f64]) -> Option<Matrix4<f64>> {
        let b = self.speeds[s].measured_jacobian(theta);
        let v = &self.var[s];
        let mut sigma = Matrix4::zeros();
        // The lower triangle and the diagonal: all the factorisation reads.
        for i in 0..4 {
            for j in 0..=i {
                let mut sum = (b[(i, 0)] * v[0]) * b[(j, 0)];
                for k in 1..12 {
                    sum += (b[(i, k)] * v[k]) * b[(j, k)];
                }
                sigma[(i, j)] = sum;
            }
        }
        let trace = sigma.trace();
        if !(trace > 0.0 && trace.is_finite()) {
            return None;
        }
        cholesky4(&sigma).or_else(|| {
            // Σ + jitter·I as nalgebra adds it (+0 off the diagonal).
            let jitter = 1e-12 * trace / 4.0;
            for i in 0..4 {
                for j in 0..=i {
                    sigma[(i, j)] += if i == j { jitter } else { 0.0 };
                }
            }
            cholesky4(&sigma)
        })
    }

    /// RMS of the unweighted equation residuals e [N].
    pub(super) fn residual_rms(&self, theta: &[f64]) -> f64 {
        let sum: f64 = self
            .speeds
            .iter()
            .map(|sp| (sp.a * theta_vector(theta) - sp.b).norm_squared())
            .sum();
        (sum / (4 * self.speeds.len()).max(1) as f64).sqrt()
    }
}

/// J(θ) = Σ eᵀΣ⁻¹e [-] over `speeds` (unit covariance factor), with an
/// equation error of variance `tau2` [N²]: [`Rigid::cost`], one speed at a
/// time (a single evaluation need not hold every speed's data).
pub(super) fn cost_of(
    speeds: impl IntoIterator<Item = Speed>,
    theta: &[f64],
    tau2: f64,
) -> Result<f64, MlError> {
    let t = theta_vector(theta);
    let mut sum = 0.0;
    for sp in speeds {
        let l = sp.factor(theta, tau2)?;
        sum += forward(&l, &(sp.a * t - sp.b)).norm_squared();
    }
    Ok(sum)
}

pub(super) fn theta_vector(theta: &[f64]) -> nalgebra::SVector<f64, PARAMETERS> {
    nalgebra::SVector::from_fn(|i, _| theta[i])
}

impl Equations for Rigid {
    fn speeds(&self) -> usize {
        self.speeds.len()
    }

    fn variance(&self, s: usize) -> &[f64] {
        &self.var[s]
    }

    fn residual(&self, s: usize, p: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
        let sp = &self.speeds[s];
        let e = sp.a * theta_vector(p) - sp.b;
        let full = sp.measured_jacobian(p);
        (
            DVector::from_column_slice(e.as_slice()),
            DMatrix::from_column_slice(4, 12, full.as_slice()),
        )
    }

    fn whiten(&self, p: &[f64], jacobian: Option<JacobianRequest<'_>>) -> Option<DVector<f64>> {
        let n = self.speeds.len();
        let theta = theta_vector(p);
        let mut r = DVector::zeros(4 * n);
        let mut jacobian = jacobian;
        if let Some(j) = jacobian.as_mut() {
            *j.out = DMatrix::zeros(4 * n, j.free.len());
        }
        for (s, sp) in self.speeds.iter().enumerate() {
            let l = sp.factor(p, self.equation_var).ok()?;
            let e = sp.a * theta - sp.b;
            let Some(j) = jacobian.as_mut() else {
                r.fixed_rows_mut::<4>(4 * s).copy_from(&forward(&l, &e));
                continue;
            };
            let linv = lower_inverse(&l);
            let w = linv * e;
            r.fixed_rows_mut::<4>(4 * s).copy_from(&w);
            let dw = sp.whitened_jacobian(p, &linv, &w);
            for (c, &k) in j.free.iter().enumerate() {
                for i in 0..4 {
                    j.out[(4 * s + i, c)] = dw[(i, k)];
                }
            }
        }
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    fn objective(&self, p: &[f64]) -> Option<f64> {
        self.cost(p).ok().filter(|c| c.is_finite())
    }

    fn normal_equations(&self, p: &[f64], free: &[usize], _step: &[f64]) -> Option<gh::Normal> {
        let theta = theta_vector(p);
        let mut hess = SMatrix::<f64, PARAMETERS, PARAMETERS>::zeros();
        let mut grad = SVector::<f64, PARAMETERS>::zeros();
        let mut cost = 0.0;
        for sp in &self.speeds {
            let l = sp.factor(p, self.equation_var).ok()?;
            let linv = lower_inverse(&l);
            let w = linv * (sp.a * theta - sp.b);
            let dw = sp.whitened_jacobian(p, &linv, &w);
            hess += dw.tr_mul(&dw);
            grad += dw.tr_mul(&w);
            cost += w.norm_squared();
        }
        let q = free.len();
        let normal = gh::Normal {
            hess: DMatrix::from_fn(q, q, |a, b| hess[(free[a], free[b])]),
            grad: DVector::from_fn(q, |a, _| grad[free[a]]),
            cost,
        };
        (cost.is_finite()
            && normal
                .hess
                .iter()
                .chain(normal.grad.iter())
                .all(|v| v.is_finite()))
        .then_some(normal)
    }

    fn information(&self, s: usize, p: &[f64], _scale: &[f64]) -> Option<DMatrix<f64>> {
        let l = self.factor(s, p).ok()?;
        let w = lower_inverse(&l) * self.speeds[s].a;
        let f = w.transpose() * w;
        Some(DMatrix::from_fn(PARAMETERS, PARAMETERS, |r, c| f[(r, c)]))
    }
}

/// The pedestal's dynamic stiffness (y, z) k − Ω²m + iΩc [N/m] at Ω [rad/s].
#[cfg(test)]
pub(super) fn dynamic_stiffness(theta: &[f64; PARAMETERS], omega: f64) -> [Complex<f64>; 2] {
    let w2 = omega * omega;
    [
        Complex::new(theta[0] - w2 * theta[2], omega * theta[3]),
        Complex::new(theta[1] - w2 * theta[2], omega * theta[4]),
    ]
}

/// Σ(θ) of one speed (module docs) [N²].
pub fn equation_covariance(o: &Observation, theta: &[f64; PARAMETERS]) -> Matrix4<f64> {
    Speed::new(o, 1.0).sigma(theta, 0.0)
}

/// The regression rows A (4×5, eq. 4 in (y re, y im, z re, z im) order) and
/// right-hand side of one speed, from the shared definition.
pub(crate) fn rows(o: &Observation) -> (SMatrix<f64, 4, PARAMETERS>, Vector4<f64>) {
    let eqs = equations(o.omega(), &o.ped, &o.force());
    let a = SMatrix::<f64, 4, PARAMETERS>::from_fn(|r, c| eqs[r].row[c]);
    let rhs = Vector4::from_fn(|r, _| eqs[r].rhs);
    (a, rhs)
}

/// The residual e = A·θ − b of one speed [N].
pub fn equation_residual(o: &Observation, theta: &[f64; PARAMETERS]) -> Vector4<f64> {
    let (a, rhs) = rows(o);
    a * theta_vector(theta) - rhs
}

/// Lower Cholesky factor of Σ, regularised by 1e-12 of its mean diagonal
/// when it is singular (a channel without noise).
pub(super) fn cholesky(s: Matrix4<f64>, speed_hz: f64) -> Result<Matrix4<f64>, MlError> {
    let trace = s.trace();
    if !(trace > 0.0 && trace.is_finite()) {
        return Err(MlError::NoNoise { speed_hz });
    }
    if let Some(l) = cholesky4(&s) {
        return Ok(l);
    }
    let jitter = Matrix4::identity() * (1e-12 * trace / 4.0);
    cholesky4(&(s + jitter)).ok_or(MlError::NoNoise { speed_hz })
}

/// The lower Cholesky factor of a symmetric 4×4 matrix, written out (the
/// innermost work of every iteration); `None` unless positive definite.
#[inline]
pub(super) fn cholesky4(s: &Matrix4<f64>) -> Option<Matrix4<f64>> {
    let mut l = Matrix4::zeros();
    for j in 0..4 {
        let mut d = s[(j, j)];
        for k in 0..j {
            d -= l[(j, k)] * l[(j, k)];
        }
        if !(d > 0.0 && d.is_finite()) {
            return None;
        }
        let djj = d.sqrt();
        l[(j, j)] = djj;
        for i in j + 1..4 {
            let mut v = s[(i, j)];
            for k in 0..j {
                v -= l[(i, k)] * l[(j, k)];
            }
            l[(i, j)] = v / djj;
        }
    }
    Some(l)
}

/// L⁻¹·b for a lower-triangular L with a positive diagonal.
#[inline]
pub(super) fn forward(l: &Matrix4<f64>, b: &Vector4<f64>) -> Vector4<f64> {
    let mut x = Vector4::zeros();
    for i in 0..4 {
        let mut v = b[i];
        for k in 0..i {
            v -= l[(i, k)] * x[k];
        }
        x[i] = v / l[(i, i)];
    }
    x
}

/// L⁻ᵀ·b for a lower-triangular L with a positive diagonal.
#[inline]
pub(super) fn backward(l: &Matrix4<f64>, b: &Vector4<f64>) -> Vector4<f64> {
    let mut x = Vector4::zeros();
    for i in (0..4).rev() {
        let mut v = b[i];
        for k in i + 1..4 {
            v -= l[(k, i)] * x[k];
        }
        x[i] = v / l[(i, i)];
    }
    x
}

/// L⁻¹ of a lower-triangular L with a positive diagonal.
#[inline]
pub(super) fn lower_inverse(l: &Matrix4<f64>) -> Matrix4<f64> {
    let mut inv = Matrix4::zeros();
    for c in 0..4 {
        let x = forward(l, &Vector4::ith(c, 1.0));
        inv.set_column(c, &x);
    }
    inv
}
