//! The fit of one pedestal on a measured base (module docs of [`super`]).

use super::{put, spring, C};
use crate::estimate::gauss_helmert::{self as gh, Equations};
use crate::estimate::Observation;
use nalgebra::{DMatrix, DVector};

/// Most Levenberg–Marquardt iterations.
const FINAL_ITERATIONS: usize = 200;

/// One speed of a measured base: its 1X motion and the noise of each real
/// number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BaseObservation {
    /// Rotor speed [Hz].
    pub speed_hz: f64,
    /// Absolute base displacement (y, z) [m].
    pub motion: [C; 2],
    /// Noise variance [m²] of (y re, y im, z re, z im).
    pub var: [f64; 4],
}

/// One pedestal on a measured base: per speed its observation and the
/// base's; p = θ.
struct Measured {
    speeds: Vec<(Observation, BaseObservation, Vec<f64>)>,
}

impl Equations for Measured {
    fn speeds(&self) -> usize {
        self.speeds.len()
    }

    fn variance(&self, s: usize) -> &[f64] {
        &self.speeds[s].2
    }

    fn residual(&self, s: usize, p: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
        let (o, base, _) = &self.speeds[s];
        let w = o.omega();
        let mut e = DVector::zeros(4);
        let mut b = DMatrix::zeros(4, 12);
        for d in 0..2 {
            let dd = spring(p, d, w);
            let h = dd - w * w * p[2];
            let r = h * o.ped[d] - dd * base.motion[d] - o.force()[d];
            e[2 * d] = r.re;
            e[2 * d + 1] = r.im;
            put(&mut b, 2 * d, 4 + 2 * d, h);
            put(&mut b, 2 * d, 8 + 2 * d, -dd);
            for c in 0..2 {
                put(&mut b, 2 * d, 2 * c, -o.kstar[d][c]);
            }
        }
        (e, b)
    }
}

/// ML fit of one pedestal on a measured base (module docs): its
/// observations `obs`, the base motion `base` at the same speeds (matched
/// exactly; a speed without base motion is an error), from `start`
/// (e.g. the least-squares fit). Noise in rel, ped and the base motion all
/// weigh in. The result's covariance is over all five parameters.
pub fn fit_on_measured_base(
    obs: &[Observation],
    base: &[BaseObservation],
    start: &[f64; 5],
) -> Result<crate::estimate::ml::MlFit, MeasuredBaseError> {
    let mut speeds = Vec::new();
    for o in obs.iter().filter(|o| o.is_finite()) {
        let b = base.iter().find(|b| b.speed_hz == o.speed_hz).ok_or(
            MeasuredBaseError::NoBaseMotion {
                speed_hz: o.speed_hz,
            },
        )?;
        let mut var = o.var.to_vec();
        var.extend(b.var);
        speeds.push((*o, *b, var));
    }
    let n_eq = 4 * speeds.len();
    if n_eq <= 5 {
        return Err(MeasuredBaseError::TooFewEquations { equations: n_eq });
    }
    let w_mid = {
        let lo = speeds
            .iter()
            .map(|s| s.0.omega())
            .fold(f64::INFINITY, f64::min);
        let hi = speeds.iter().map(|s| s.0.omega()).fold(0.0, f64::max);
        (lo * hi).sqrt().max(f64::MIN_POSITIVE)
    };
    let k = start[0].abs().max(start[1].abs()).max(1.0);
    let scale = [
        start[0].abs().max(1e-3 * k),
        start[1].abs().max(1e-3 * k),
        start[2].abs().max(1e-3 * k / (w_mid * w_mid)),
        start[3].abs().max(1e-3 * k / w_mid),
        start[4].abs().max(1e-3 * k / w_mid),
    ];
    let eq = Measured { speeds };
    let m = gh::fit(&eq, start, &scale, &[true; 5], None, FINAL_ITERATIONS)
        .ok_or(MeasuredBaseError::NotEvaluable)?;
    let f = gh::fisher(&eq, &m.p, &scale).ok_or(MeasuredBaseError::NotEvaluable)?;
    let inv = gh::inverse_psd(&f);
    let condition_number = gh::condition_number(&f);
    let residual_rms = ((0..eq.speeds())
        .map(|s| eq.residual(s, &m.p).0.norm_squared())
        .sum::<f64>()
        / n_eq as f64)
        .sqrt();
    Ok(crate::estimate::ml::MlFit {
        theta: std::array::from_fn(|i| m.p[i]),
        covariance: std::array::from_fn(|r| std::array::from_fn(|c| inv[(r, c)])),
        chi2: m.cost,
        dof: n_eq - 5,
        iterations: m.iterations,
        converged: m.converged,
        condition_number,
        residual_rms,
    })
}

/// Why a measured-base fit could not run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeasuredBaseError {
    /// A pedestal speed without base motion at exactly that speed.
    #[error("no base motion at {speed_hz} Hz")]
    NoBaseMotion {
        /// The speed [Hz].
        speed_hz: f64,
    },
    /// No more equations than parameters.
    #[error("{equations} equations for 5 parameters")]
    TooFewEquations {
        /// Real equations.
        equations: usize,
    },
    /// The noise model gives no noise, or the data are not finite.
    #[error("the likelihood cannot be evaluated (no noise at some speed, or non-finite data)")]
    NotEvaluable,
}
