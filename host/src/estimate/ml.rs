//! Maximum-likelihood errors-in-variables fit of the pedestal model.
//!
//! Per speed the pedestal equation residual (Feng & Hahn eq. 3 with eq. 2)
//!
//! ```text
//! e = H(θ)·X_ped − K*·rel,   H = diag(k_y − Ω²m + iΩc_y, k_z − Ω²m + iΩc_z),
//! K* = K_b + iΩ·C_b
//! ```
//!
//! is zero for the true phasors. The measured phasors carry noise in *both*
//! `ped` and `rel` (variances per real number from [`super::noise`]), so the
//! real 4-vector e = (Re e_y, Im e_y, Re e_z, Im e_z) at the true θ is
//! zero-mean with covariance
//!
//! ```text
//! Σ(θ) = B_ped(θ)·D_ped·B_pedᵀ + B_rel·D_rel·B_relᵀ
//! ```
//!
//! where B are the real 4×4 forms of ∂e/∂ped = H(θ) and ∂e/∂rel = −K*
//! (a complex factor a acts on (re, im) as [[Re a, −Im a], [Im a, Re a]]).
//! Σ depends on θ, correlates y and z through K*'s cross terms, and real and
//! imaginary parts when the noise of the real and imaginary parts differ.
//!
//! With Gaussian noise, eliminating the unknown true phasors from the
//! likelihood (the Gauss–Helmert model; e is linear in the measured numbers)
//! leaves the ML estimate as the minimiser of
//!
//! ```text
//! J(θ) = Σ_speeds eᵀ Σ(θ)⁻¹ e
//! ```
//!
//! found by the one Levenberg–Marquardt loop of [`super::gauss_helmert`]
//! on the whitened residuals w = L⁻¹e (Σ = L·Lᵀ), this model being its
//! [`Equations`] implementation [`Rigid`] with analytic derivatives: e is
//! linear in θ (∂e/∂θ = A, the paper's regression rows) and Σ quadratic in
//! it, so ∂w/∂θ_k = L⁻¹A_k − Φ(L⁻¹·∂Σ/∂θ_k·L⁻ᵀ)·w (Φ: the lower triangle
//! with half the diagonal, the derivative of the Cholesky factor). The
//! per-speed work that does not depend on θ (A, the right-hand side, the
//! covariance of the `rel` noise through K*) is done once, from a given
//! start (the OLS estimate). The Fisher
//! information of θ in this model is F = Σ Aᵀ Σ(θ)⁻¹ A with A = ∂e/∂θ (the
//! paper's regression rows); F⁻¹ is the Cramér–Rao bound, at the estimate the
//! covariance reported, at the truth the bound `plinth accuracy` compares with.
//! At the minimum J is χ² with 4n − p degrees of freedom when the noise model
//! is right: the check of its absolute scale.
//!
//! **Equation error.** When J is far above its degrees of freedom with a
//! noise level that was measured (noise columns, digits), the residuals hold
//! something the noise does not: a model error (bearing coefficients a little
//! off, a constant vector left on `rel`, unsteady phasors through a fast
//! resonance). Σ(θ) then says nothing about it, and the fit, free to trade
//! residual against Σ(θ), goes where the model error is small relative to
//! the *noise* (near the pedestal resonance, where H(θ)·ped is small) rather
//! than where the data are right: on field-like data it can end further from
//! the truth than OLS. [`fit_with_equation_error`] adds the paper's own error
//! model to the noise: an independent error of the same variance τ² [N²] on
//! every real equation (what OLS assumes), Σ_τ(θ) = Σ(θ) + τ²·I, with τ² set
//! so that J = 4n − p (the method of moments, iterated with θ). τ = 0 when
//! the noise explains the residuals (the ML fit unchanged); when the model
//! error dominates the fit tends to OLS, and its Fisher information, the
//! covariance of the combined model, grows accordingly.

use super::gauss_helmert::{self as gh, Equations, JacobianRequest};
use super::Observation;
use nalgebra::{DMatrix, DVector, Matrix4, SMatrix, SVector, Vector4};
use num_complex::Complex;
use plinth_shared::regression::{equations, Parameter, PARAMETERS};

/// Why an ML fit could not run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MlError {
    /// No more equations than parameters.
    #[error("{equations} equations for {parameters} parameters: nothing to fit")]
    TooFewEquations {
        /// Real equations available.
        equations: usize,
        /// Parameters estimated.
        parameters: usize,
    },
    /// The noise model gives no noise at all at some speed.
    #[error("the noise model gives zero noise at {speed_hz} Hz: the equation cannot be weighted")]
    NoNoise {
        /// The speed [Hz].
        speed_hz: f64,
    },
    /// A non-finite number in the data or the start.
    #[error("non-finite number in the data or the starting estimate")]
    NonFinite,
}

/// The result of [`fit`].
#[derive(Clone, Debug, PartialEq)]
pub struct MlFit {
    /// θ = (k_y [N/m], k_z [N/m], m [kg], c_y [N·s/m], c_z [N·s/m]); fixed
    /// parameters stay at their start value.
    pub theta: [f64; PARAMETERS],
    /// F⁻¹ at the estimate in θ units, over all five parameters (zero rows
    /// and columns for fixed ones, infinite diagonal when not estimable):
    /// the covariance if the noise model's absolute scale is right.
    pub covariance: [[f64; PARAMETERS]; PARAMETERS],
    /// The equation error's variance the fit assumed [N²] per real equation
    /// (0 unless [`fit_with_equation_error`]; see [`fit_with_equation_error`]).
    pub equation_var: f64,
    /// J(θ̂) = Σ eᵀΣ⁻¹e at the estimate [-].
    pub chi2: f64,
    /// Degrees of freedom 4n − p.
    pub dof: usize,
    /// Levenberg–Marquardt iterations taken.
    pub iterations: usize,
    /// True when the iteration met its convergence test.
    pub converged: bool,
    /// Condition number of the whitened, column-normalised regression [-].
    pub condition_number: f64,
    /// RMS of the unweighted equation residuals e [N].
    pub residual_rms: f64,
}

impl MlFit {
    /// Standard errors sqrt(variance_scale·diag(F⁻¹)) in θ units.
    pub fn std_err(&self, variance_scale: f64) -> [f64; PARAMETERS] {
        std::array::from_fn(|i| (variance_scale * self.covariance[i][i]).sqrt())
    }

    /// χ²/dof: 1 when the noise model's absolute scale is right.
    pub fn chi2_per_dof(&self) -> f64 {
        self.chi2 / self.dof.max(1) as f64
    }
}

/// What a fit assumes beyond the observations' own noise: the equation
/// error (module docs) and a factor on each observation's covariance (a
/// robust reweighting layered on top sets it to 1/weight).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Weighting<'a> {
    /// Variance τ² [N²] of an equation error on every real equation.
    pub equation_var: f64,
    /// Per observation (same order), the factor its covariance
    /// Σ_i(θ) + τ²·I is multiplied by [-]; `None`: 1 for all.
    pub cov_scale: Option<&'a [f64]>,
}

impl Weighting<'_> {
    /// Only an equation error of variance `equation_var` [N²].
    pub fn equation_error(equation_var: f64) -> Self {
        Self {
            equation_var,
            cov_scale: None,
        }
    }
}

/// One speed of the rigid pedestal, prepared once and reused by every
/// iteration: e = A·θ − b, Σ(θ) = c·(Σ_rel + B_ped(θ)·D_ped·B_ped(θ)ᵀ + τ²·I).
#[derive(Clone, Copy, Debug)]
struct Speed {
    speed_hz: f64,
    omega: f64,
    a: SMatrix<f64, 4, PARAMETERS>,
    b: Vector4<f64>,
    /// ∂e/∂rel = −K* as a real 4×4 matrix.
    b_rel: Matrix4<f64>,
    /// Covariance of e from the `rel` noise through −K* (constant in θ) [N²].
    sigma_rel: Matrix4<f64>,
    /// Noise variances of ped (y re, y im, z re, z im) [m²].
    var_ped: [f64; 4],
    /// The covariance factor c of [`Weighting::cov_scale`] [-].
    scale: f64,
}

/// Real 2×2 block of a complex factor `a` acting on (re, im).
fn put(j: &mut SMatrix<f64, 4, 8>, row: usize, col: usize, a: Complex<f64>) {
    j[(row, col)] = a.re;
    j[(row, col + 1)] = -a.im;
    j[(row + 1, col)] = a.im;
    j[(row + 1, col + 1)] = a.re;
}

impl Speed {
    fn new(o: &Observation, scale: f64) -> Self {
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
    fn stiffness(&self, theta: &[f64]) -> [(f64, f64); 2] {
        let w = self.omega;
        [
            (theta[0] - w * w * theta[2], w * theta[3]),
            (theta[1] - w * w * theta[2], w * theta[4]),
        ]
    }

    /// Σ(θ) with an equation error of variance `tau2` [N²].
    fn sigma(&self, theta: &[f64], tau2: f64) -> Matrix4<f64> {
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

    /// Lower Cholesky factor of Σ(θ) with an equation error of variance `tau2` [N²].
    fn factor(&self, theta: &[f64], tau2: f64) -> Result<Matrix4<f64>, MlError> {
        cholesky(self.sigma(theta, tau2), self.speed_hz)
    }

    /// ∂w/∂θ (4×5) of the whitened residual w = L⁻¹e at θ, given L⁻¹ and w
    /// (module docs): L⁻¹A_k − Φ(L⁻¹·∂Σ/∂θ_k·L⁻ᵀ)·w. ∂Σ/∂θ_k is a combination
    /// of three fixed 2×2 patterns per direction, so Φ(·)·w is formed once per
    /// pattern and combined per parameter: fixed-size, no allocation.
    fn whitened_jacobian(
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
    speeds: Vec<Speed>,
    /// τ² [N²] (module docs, "Equation error").
    equation_var: f64,
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
    fn set_equation_var(&mut self, equation_var: f64) {
        self.equation_var = equation_var;
        for (v, s) in self.var.iter_mut().zip(&self.speeds) {
            for x in &mut v[8..] {
                *x = s.scale * equation_var;
            }
        }
    }

    /// Cholesky factor of speed `s`'s Σ at θ.
    fn factor(&self, s: usize, theta: &[f64]) -> Result<Matrix4<f64>, MlError> {
        self.speeds[s].factor(theta, self.equation_var)
    }

    /// J(θ) = Σ eᵀΣ⁻¹e [-].
    fn cost(&self, theta: &[f64]) -> Result<f64, MlError> {
        let t = theta_vector(theta);
        let mut sum = 0.0;
        for sp in &self.speeds {
            let l = sp.factor(theta, self.equation_var)?;
            sum += forward(&l, &(sp.a * t - sp.b)).norm_squared();
        }
        Ok(sum)
    }

    /// J(θ) and its slope dJ/dτ² [1/N²] at the current τ²: ∂Σ/∂τ² = c·I,
    /// so dJ/dτ² = −Σ c·|Σ⁻¹e|² with Σ⁻¹e = L⁻ᵀw.
    fn cost_and_slope(&self, theta: &[f64]) -> Result<(f64, f64), MlError> {
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

    /// RMS of the unweighted equation residuals e [N].
    fn residual_rms(&self, theta: &[f64]) -> f64 {
        let sum: f64 = self
            .speeds
            .iter()
            .map(|sp| (sp.a * theta_vector(theta) - sp.b).norm_squared())
            .sum();
        (sum / (4 * self.speeds.len()).max(1) as f64).sqrt()
    }
}

fn theta_vector(theta: &[f64]) -> nalgebra::SVector<f64, PARAMETERS> {
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
        let mut b = SMatrix::<f64, 4, 8>::zeros();
        for (d, (re, im)) in sp.stiffness(p).into_iter().enumerate() {
            put(&mut b, 2 * d, 4 + 2 * d, Complex::new(re, im));
        }
        let mut full = DMatrix::zeros(4, 12);
        full.view_mut((0, 0), (4, 4)).copy_from(&sp.b_rel);
        full.view_mut((0, 4), (4, 4))
            .copy_from(&b.fixed_view::<4, 4>(0, 4));
        for i in 0..4 {
            full[(i, 8 + i)] = 1.0;
        }
        (DVector::from_column_slice(e.as_slice()), full)
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
fn dynamic_stiffness(theta: &[f64; PARAMETERS], omega: f64) -> [Complex<f64>; 2] {
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
fn rows(o: &Observation) -> (SMatrix<f64, 4, PARAMETERS>, Vector4<f64>) {
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
fn cholesky(s: Matrix4<f64>, speed_hz: f64) -> Result<Matrix4<f64>, MlError> {
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
fn cholesky4(s: &Matrix4<f64>) -> Option<Matrix4<f64>> {
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
fn forward(l: &Matrix4<f64>, b: &Vector4<f64>) -> Vector4<f64> {
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
fn backward(l: &Matrix4<f64>, b: &Vector4<f64>) -> Vector4<f64> {
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
fn lower_inverse(l: &Matrix4<f64>) -> Matrix4<f64> {
    let mut inv = Matrix4::zeros();
    for c in 0..4 {
        let x = forward(l, &Vector4::ith(c, 1.0));
        inv.set_column(c, &x);
    }
    inv
}

/// J(θ) = Σ eᵀΣ(θ)⁻¹e over the speeds [-].
pub fn cost(obs: &[Observation], theta: &[f64; PARAMETERS]) -> Result<f64, MlError> {
    cost_with(obs, theta, 0.0)
}

/// J(θ) with an equation error of variance `equation_var` [N²] per real
/// equation ([`fit_with_equation_error`]) [-].
pub fn cost_with(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    equation_var: f64,
) -> Result<f64, MlError> {
    Rigid::new(obs, &Weighting::equation_error(equation_var)).cost(theta)
}

/// Fisher information Σ Aᵀ Σ(θ)⁻¹ A over `columns` (θ units) at `theta`:
/// its inverse is the Cramér–Rao bound when the observations hold the true
/// phasors and the true noise.
pub fn fisher_information(
    obs: &[Observation],
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
) -> Result<DMatrix<f64>, MlError> {
    fisher_of(&Rigid::new(obs, &Weighting::default()), columns, theta)
}

fn fisher_of(
    eq: &Rigid,
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
) -> Result<DMatrix<f64>, MlError> {
    let full = match gh::fisher(eq, theta, &[1.0; PARAMETERS]) {
        Some(f) => f,
        None => return Err(first_failure(eq, theta)),
    };
    Ok(DMatrix::from_fn(columns.len(), columns.len(), |r, c| {
        full[(columns[r] as usize, columns[c] as usize)]
    }))
}

/// The error of the first speed whose Σ cannot be factored at θ.
fn first_failure(eq: &Rigid, theta: &[f64]) -> MlError {
    (0..eq.speeds.len())
        .find_map(|s| eq.factor(s, theta).err())
        .unwrap_or(MlError::NonFinite)
}

/// F⁻¹ over all five parameters from the Fisher information `f` over
/// `columns` (zero rows and columns for the others), with the condition
/// number of the whitened column-normalised regression.
fn spread(f: &DMatrix<f64>, columns: &[Parameter]) -> ([[f64; PARAMETERS]; PARAMETERS], f64) {
    let inv = gh::inverse_psd(f);
    let mut cov = [[0.0; PARAMETERS]; PARAMETERS];
    for (r, &pr) in columns.iter().enumerate() {
        for (c, &pc) in columns.iter().enumerate() {
            cov[pr as usize][pc as usize] = inv[(r, c)];
        }
    }
    (cov, gh::condition_number(f))
}

/// The covariance F⁻¹ (θ units) over all five parameters at `theta`, and the
/// condition number of the whitened column-normalised regression.
pub fn bound(
    obs: &[Observation],
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
) -> Result<([[f64; PARAMETERS]; PARAMETERS], f64), MlError> {
    Ok(spread(&fisher_information(obs, columns, theta)?, columns))
}

/// The true covariance of the paper's OLS estimate under the noise model
/// (θ units, all five parameters), the sandwich
/// (AᵀA)⁻¹·(Σ Aᵀ Σ(θ) A)·(AᵀA)⁻¹ with Σ at `theta`: what OLS's scatter
/// really is, to compare with [`bound`].
pub fn ols_covariance(
    obs: &[Observation],
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
) -> [[f64; PARAMETERS]; PARAMETERS] {
    ols_covariance_with(obs, columns, theta, 0.0)
}

/// [`ols_covariance`] with an equation error of variance `equation_var`
/// [N²] per real equation ([`fit_with_equation_error`]).
pub fn ols_covariance_with(
    obs: &[Observation],
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
    equation_var: f64,
) -> [[f64; PARAMETERS]; PARAMETERS] {
    let p = columns.len();
    let mut ata = DMatrix::zeros(p, p);
    let mut meat = DMatrix::zeros(p, p);
    for o in obs {
        let sp = Speed::new(o, 1.0);
        let sel = DMatrix::from_fn(4, p, |r, c| sp.a[(r, columns[c] as usize)]);
        let s = sp.sigma(theta, equation_var);
        let s_dyn = DMatrix::from_fn(4, 4, |r, c| s[(r, c)]);
        ata += sel.transpose() * &sel;
        meat += sel.transpose() * s_dyn * &sel;
    }
    let inv = gh::inverse_psd(&ata);
    let cov = &inv * meat * &inv;
    let mut out = [[0.0; PARAMETERS]; PARAMETERS];
    for (r, &pr) in columns.iter().enumerate() {
        for (c, &pc) in columns.iter().enumerate() {
            out[pr as usize][pc as usize] = if inv[(r, r)].is_finite() {
                cov[(r, c)]
            } else {
                f64::INFINITY
            };
        }
    }
    out
}

/// When the ML iteration stops: at most 200 iterations, a step below 1e-7
/// standard errors or a relative decrease of J below 1e-13.
const SETTINGS: gh::Settings = gh::Settings {
    max_iterations: 200,
    step_tol: 1e-7,
    decrease_tol: 1e-13,
};

/// The ML estimate (module docs) of the parameters in `columns` from `start`
/// (the others held at their `start` values, normally 0).
pub fn fit(
    obs: &[Observation],
    columns: &[Parameter],
    start: &[f64; PARAMETERS],
) -> Result<MlFit, MlError> {
    fit_weighted(obs, columns, start, &Weighting::default())
}

/// [`fit`] with an equation error of variance `equation_var` [N²] on every
/// real equation ([`fit_with_equation_error`]).
pub fn fit_with(
    obs: &[Observation],
    columns: &[Parameter],
    start: &[f64; PARAMETERS],
    equation_var: f64,
) -> Result<MlFit, MlError> {
    fit_weighted(
        obs,
        columns,
        start,
        &Weighting::equation_error(equation_var),
    )
}

/// The ML fit of one pedestal on rigid ground from its observations (each
/// with the noise variance of every measured number) under `weighting`
/// (equation error, per-observation covariance factors): the estimation
/// core's entry point for one pedestal.
pub fn fit_weighted(
    obs: &[Observation],
    columns: &[Parameter],
    start: &[f64; PARAMETERS],
    weighting: &Weighting<'_>,
) -> Result<MlFit, MlError> {
    let eq = Rigid::new(obs, weighting);
    fit_system(&eq, obs.len(), columns, start)
}

fn fit_system(
    eq: &Rigid,
    n_obs: usize,
    columns: &[Parameter],
    start: &[f64; PARAMETERS],
) -> Result<MlFit, MlError> {
    let p = columns.len();
    let n_eq = 4 * n_obs;
    if n_eq <= p {
        return Err(MlError::TooFewEquations {
            equations: n_eq,
            parameters: p,
        });
    }
    let finite = |sp: &Speed| {
        sp.a.iter()
            .chain(sp.b.iter())
            .chain(sp.sigma_rel.iter())
            .all(|v| v.is_finite())
            && sp.var_ped.iter().all(|v| v.is_finite() && *v >= 0.0)
            && sp.scale.is_finite()
            && sp.scale > 0.0
    };
    if !eq.speeds.iter().all(finite) || !start.iter().all(|v| v.is_finite()) {
        return Err(MlError::NonFinite);
    }
    // Unknowns in units where each explains the right-hand side: u_i = θ_i/s_i.
    let mut a_norm = [0.0f64; PARAMETERS];
    let mut b_norm = 0.0;
    for sp in &eq.speeds {
        for (c, v) in a_norm.iter_mut().enumerate() {
            *v += sp.a.column(c).norm_squared();
        }
        b_norm += sp.b.norm_squared();
    }
    let b_norm = b_norm.sqrt().max(f64::MIN_POSITIVE);
    let scale: [f64; PARAMETERS] = std::array::from_fn(|c| {
        let s = b_norm / a_norm[c].sqrt();
        if s.is_finite() && s > 0.0 {
            s
        } else {
            1.0
        }
    });
    let free: [bool; PARAMETERS] =
        std::array::from_fn(|k| columns.iter().any(|&c| c as usize == k));
    // J must be evaluable at the start: its failure names the speed.
    eq.cost(start)?;
    let m = gh::minimise(eq, start, &scale, &free, None, &SETTINGS)
        .ok_or_else(|| first_failure(eq, start))?;
    let theta: [f64; PARAMETERS] = std::array::from_fn(|i| m.p[i]);
    let (covariance, condition_number) = spread(&fisher_of(eq, columns, &theta)?, columns);
    Ok(MlFit {
        theta,
        covariance,
        equation_var: eq.equation_var,
        chi2: m.cost,
        dof: n_eq - p,
        iterations: m.iterations,
        converged: m.converged,
        condition_number,
        residual_rms: eq.residual_rms(&theta),
    })
}

/// The equation error's variance τ² [N²] (module docs) under which
/// J(θ) = `dof` at `theta`: 0 when J(θ) ≤ `dof` with the noise alone.
/// J falls monotonically with τ², and with τ² = Σ|e|²/dof alone it is at
/// most `dof`, so bisection between the two finds it.
pub fn equation_var_for_chi2(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    dof: usize,
) -> Result<f64, MlError> {
    let mut eq = Rigid::new(obs, &Weighting::default());
    var_for_chi2(&mut eq, theta, dof)
}

/// τ² with J(θ; τ²) = `dof` (see [`equation_var_for_chi2`]) by safeguarded
/// Newton steps on 1/J, nearly linear in τ² (exactly so when the equation
/// error dominates), inside a bracket that bisects when a step leaves it.
fn var_for_chi2(eq: &mut Rigid, theta: &[f64; PARAMETERS], dof: usize) -> Result<f64, MlError> {
    let target = dof.max(1) as f64;
    eq.set_equation_var(0.0);
    let (mut cost, mut slope) = eq.cost_and_slope(theta)?;
    if cost <= target {
        return Ok(0.0);
    }
    let sum_sq: f64 = eq
        .speeds
        .iter()
        .map(|sp| (sp.a * theta_vector(theta) - sp.b).norm_squared())
        .sum();
    let (mut lo, mut hi) = (0.0, sum_sq / target);
    if !(hi.is_finite() && hi > 0.0) {
        return Err(MlError::NonFinite);
    }
    let mut x = 0.0;
    for _ in 0..200 {
        if cost > target {
            lo = x;
        } else {
            hi = x;
        }
        // Newton on 1/J − 1/target: x + (J/J')·(1 − J/target).
        let newton = x + (cost / slope) * (1.0 - cost / target);
        let next = if newton.is_finite() && newton > lo && newton < hi {
            newton
        } else if lo > 0.0 {
            (lo * hi).sqrt()
        } else {
            0.5 * hi
        };
        if (next - x).abs() <= 1e-9 * next || hi - lo <= 1e-6 * hi {
            return Ok(next);
        }
        x = next;
        eq.set_equation_var(x);
        (cost, slope) = eq.cost_and_slope(theta)?;
    }
    Ok(x)
}

/// Most outer iterations of [`fit_with_equation_error`] (θ, then τ²).
const MAX_EQUATION_ERROR_ITERATIONS: usize = 10;

/// Relative change of τ² at which [`fit_with_equation_error`] stops.
const EQUATION_ERROR_TOLERANCE: f64 = 1e-2;

/// Σ ln det Σ_i over the speeds, Σ_i the covariance of speed i's four
/// equations with an equation error of variance `equation_var` [N²]:
/// with J, the Gaussian log-likelihood of the residuals is
/// −½(J + Σ ln det Σ_i) + const, which compares two noise hypotheses with
/// the same number of free parameters (e.g. a rescaled noise against an
/// added equation error).
pub fn log_det(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    equation_var: f64,
) -> Result<f64, MlError> {
    let eq = Rigid::new(obs, &Weighting::equation_error(equation_var));
    let mut sum = 0.0;
    for s in 0..eq.speeds.len() {
        let l = eq.factor(s, theta)?;
        sum += 2.0 * (0..4).map(|k| l[(k, k)].ln()).sum::<f64>();
    }
    Ok(sum)
}

/// The ML fit of the combined model (module docs, "Equation error"): noise
/// in the variables plus an equation error of variance τ² set by χ² = 4n − p,
/// iterated with θ from `start` until τ² changes by less than 1 %.
/// Returns the fit (its `equation_var` is τ²) and whether the iteration
/// settled.
pub fn fit_with_equation_error(
    obs: &[Observation],
    columns: &[Parameter],
    start: &[f64; PARAMETERS],
) -> Result<(MlFit, bool), MlError> {
    let mut eq = Rigid::new(obs, &Weighting::default());
    let mut fit = fit_system(&eq, obs.len(), columns, start)?;
    let dof = fit.dof;
    for _ in 0..MAX_EQUATION_ERROR_ITERATIONS {
        let var = var_for_chi2(&mut eq, &fit.theta, dof)?;
        let settled =
            (var - fit.equation_var).abs() <= EQUATION_ERROR_TOLERANCE * var.max(fit.equation_var);
        eq.set_equation_var(var);
        fit = fit_system(&eq, obs.len(), columns, &fit.theta)?;
        if settled {
            return Ok((fit, true));
        }
    }
    Ok((fit, false))
}

/// Where χ² = `chi2` falls in the χ²(`dof`) distribution: the probability of
/// a value at least this far into the upper or lower tail (two-sided p).
pub fn chi2_two_sided_p(chi2: f64, dof: usize) -> f64 {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    match ChiSquared::new(dof.max(1) as f64) {
        Ok(d) => {
            let lower = d.cdf(chi2);
            (2.0 * lower.min(1.0 - lower)).clamp(0.0, 1.0)
        }
        Err(_) => f64::NAN,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::mul;
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
            let d =
                (eq.whiten(&up, None).unwrap() - eq.whiten(&dn, None).unwrap()) / (2.0 * step[c]);
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
}
