//! What velocity and acceleration channels are written from: the model's
//! displacement phasor and its first two derivatives in speed (five-point
//! central differences of solves), interpolated between grid speeds by a
//! quintic Hermite interpolant, and the phasor a transducer senses from them.
//!
//! Why not the natural cubic spline's derivatives: its second derivative
//! errs by O(h²) where the value errs by O(h⁴). On the damped paper machine
//! (a coupled mode at 45.1 Hz, half-width ≈ 0.09 Hz) at a 0.01 Hz grid and a
//! 20 Hz/s run-down, the X″Ω̇² term is ~40 % of an acceleration channel and
//! the spline's X″ put 2.6e-4 of the channel's peak into it (measured against
//! central differences converged between 1e-3 and 1e-4 Hz), 25× the
//! displacement's own interpolation error.

use super::*;
use crate::sim::response::UnbalanceSolver;

/// Smallest difference step [Hz]: below it the solver's rounding (relative
/// ~1e-11) divided by step² reaches the second derivative (at 1e-5 Hz a
/// three-point X″ put 2.6e-3 of an acceleration channel's peak into it; at
/// 1e-3 Hz the five-point rounding is ~3e-7 of it).
pub const MIN_DIFFERENCE_STEP_HZ: f64 = 1e-3;

/// The difference step [Hz] used with a grid step `grid_step_hz`: a tenth
/// of it (the grid resolves the response, so a tenth of a step is well
/// inside a resonance's width), never below [`MIN_DIFFERENCE_STEP_HZ`].
pub fn difference_step(grid_step_hz: f64) -> f64 {
    (0.1 * grid_step_hz).max(MIN_DIFFERENCE_STEP_HZ)
}

/// Five-point central differences: `values` at speeds f − 2d, f − d, f,
/// f + d, f + 2d [m] → [X, dX/df [m/Hz], d²X/df² [m/Hz²]] at f (truncation
/// errors d⁴X⁽⁵⁾/30 and d⁴X⁽⁶⁾/90).
pub fn five_point(values: [C64; 5], d: f64) -> [C64; 3] {
    let [a, b, c, e, g] = values;
    [
        c,
        (a - b * 8.0 + e * 8.0 - g) / (12.0 * d),
        (-a + b * 16.0 - c * 30.0 + e * 16.0 - g) / (12.0 * d * d),
    ]
}

/// The model's [X, X′, X″] (derivatives in speed, per Hz) of every pedestal
/// channel at every speed of `speeds` [Hz] by [`five_point`] with step `d`
/// [Hz]: indexed [bearing·2 + (0 for ped_y, 1 for ped_z)][speed]. Solves the
/// machine five times over `speeds`, one set at a time (memory: one
/// response plus the result).
pub fn pedestal_derivatives(
    solver: &UnbalanceSolver,
    bearings: usize,
    speeds: &[f64],
    d: f64,
) -> Result<Vec<Vec<[C64; 3]>>, SignalsError> {
    let zero = C64::new(0.0, 0.0);
    let mut stencil = vec![vec![[zero; 5]; speeds.len()]; 2 * bearings];
    for (k, offset) in [-2.0, -1.0, 0.0, 1.0, 2.0].into_iter().enumerate() {
        let shifted: Vec<f64> = speeds.iter().map(|f| f + offset * d).collect();
        let rows = solver
            .run_with(&shifted, false, &mut |_| {})?
            .measurements();
        if rows.len() != speeds.len() * bearings {
            return Err(SignalsError::Request(format!(
                "derivative solves returned {} rows for {} speeds × {bearings} bearings",
                rows.len(),
                speeds.len()
            )));
        }
        for (r, m) in rows.iter().enumerate() {
            let (s, b) = (r / bearings, r % bearings);
            stencil[2 * b][s][k] = m.ped[0];
            stencil[2 * b + 1][s][k] = m.ped[1];
        }
    }
    Ok(stencil
        .into_iter()
        .map(|ch| ch.into_iter().map(|v| five_point(v, d)).collect())
        .collect())
}

/// The phasor a transducer of `kind` senses from the displacement phasor
/// `x` [m] and its derivatives in speed `dxdf` [m/Hz], `d2xdf2` [m/Hz²] at
/// angular speed `omega` [rad/s] changing at `omega_dot` [rad/s²]: the
/// displacement itself, its time derivative (velocity, m/s) or second time
/// derivative (acceleration, m/s²) along the run-down (module docs).
pub fn sensed_phasor(
    kind: SensorKind,
    [x, dxdf, d2xdf2]: [C64; 3],
    omega: f64,
    omega_dot: f64,
) -> C64 {
    // Derivatives with respect to Ω = 2πf.
    let dx = dxdf / TAU;
    let d2x = d2xdf2 / (TAU * TAU);
    let i = C64::i();
    match kind {
        SensorKind::Displacement => x,
        SensorKind::Velocity => i * omega * x + dx * omega_dot,
        SensorKind::Acceleration => {
            i * omega_dot * x - x * (omega * omega)
                + i * (2.0 * omega * omega_dot) * dx
                + d2x * (omega_dot * omega_dot)
        }
    }
}

/// A quintic Hermite interpolant of complex values: on each interval the
/// degree-5 polynomial matching value, first and second derivative at both
/// ends, so its own first and second derivatives are accurate to O(h⁴)
/// (a cubic spline's second derivative: O(h²)).
#[derive(Clone, Debug, PartialEq)]
pub struct QuinticHermite {
    x: Vec<f64>,
    /// [value, derivative, second derivative] at each knot.
    y: Vec<[C64; 3]>,
}

impl QuinticHermite {
    /// Through the knots `x` (finite, strictly increasing, ≥ 2) with
    /// [value, d/dx, d²/dx²] at each.
    pub fn new(x: Vec<f64>, y: Vec<[C64; 3]>) -> Result<QuinticHermite, String> {
        if x.len() < 2 || y.len() != x.len() {
            return Err(format!(
                "Hermite interpolant needs ≥ 2 knots and as many values (got {}, {})",
                x.len(),
                y.len()
            ));
        }
        if x.iter().any(|v| !v.is_finite()) || x.windows(2).any(|w| w[1] <= w[0]) {
            return Err("Hermite knots must be finite and strictly increasing".into());
        }
        Ok(QuinticHermite { x, y })
    }

    /// [value, first, second derivative] at `x` (polynomial extension
    /// beyond the ends: callers stay inside the knots).
    pub fn eval(&self, x: f64) -> [C64; 3] {
        let n = self.x.len();
        let i = match self.x.partition_point(|&k| k <= x) {
            0 => 0,
            i if i >= n => n - 2,
            i => i - 1,
        };
        let h = self.x[i + 1] - self.x[i];
        let t = (x - self.x[i]) / h;
        let (t2, t3) = (t * t, t * t * t);
        let (t4, t5) = (t3 * t, t3 * t2);
        // Basis (value, d/dt, d²/dt²) for y0, h·y0′, h²·y0″, h²·y1″, h·y1′, y1.
        let basis: [[f64; 3]; 6] = [
            [
                1.0 - 10.0 * t3 + 15.0 * t4 - 6.0 * t5,
                -30.0 * t2 + 60.0 * t3 - 30.0 * t4,
                -60.0 * t + 180.0 * t2 - 120.0 * t3,
            ],
            [
                t - 6.0 * t3 + 8.0 * t4 - 3.0 * t5,
                1.0 - 18.0 * t2 + 32.0 * t3 - 15.0 * t4,
                -36.0 * t + 96.0 * t2 - 60.0 * t3,
            ],
            [
                0.5 * (t2 - 3.0 * t3 + 3.0 * t4 - t5),
                0.5 * (2.0 * t - 9.0 * t2 + 12.0 * t3 - 5.0 * t4),
                0.5 * (2.0 - 18.0 * t + 36.0 * t2 - 20.0 * t3),
            ],
            [
                0.5 * (t3 - 2.0 * t4 + t5),
                0.5 * (3.0 * t2 - 8.0 * t3 + 5.0 * t4),
                0.5 * (6.0 * t - 24.0 * t2 + 20.0 * t3),
            ],
            [
                -4.0 * t3 + 7.0 * t4 - 3.0 * t5,
                -12.0 * t2 + 28.0 * t3 - 15.0 * t4,
                -24.0 * t + 84.0 * t2 - 60.0 * t3,
            ],
            [
                10.0 * t3 - 15.0 * t4 + 6.0 * t5,
                30.0 * t2 - 60.0 * t3 + 30.0 * t4,
                60.0 * t - 180.0 * t2 + 120.0 * t3,
            ],
        ];
        let (a, b) = (self.y[i], self.y[i + 1]);
        let coef = [
            a[0],
            a[1] * h,
            a[2] * (h * h),
            b[2] * (h * h),
            b[1] * h,
            b[0],
        ];
        let mut out = [C64::new(0.0, 0.0); 3];
        for (c, w) in coef.iter().zip(basis) {
            for (o, wk) in out.iter_mut().zip(w) {
                *o += c * wk;
            }
        }
        [out[0], out[1] / h, out[2] / (h * h)]
    }
}
