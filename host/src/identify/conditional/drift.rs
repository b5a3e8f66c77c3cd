//! What a support whose stiffness drifts over the run would do to the
//! printed values: the condition "k, c, m are constant over the run" stated
//! with its numbers, per bearing (docs/trust-lack-of-fit.md, session 49).
//!
//! In one run-down (or run-up) time and speed are tied: a stiffness that
//! changes in time is, to the fit, a stiffness that changes with speed, and
//! one that rises as the speed falls is to first order k₀ − bΩ², a mass
//! term (docs/unseen-nine.md, finding 1). No fit of one run can tell it;
//! what can be said is how far a given drift would move each value.
//!
//! The file has no time column (docs/formats.md): the time of each speed is
//! taken from its place in the speed order, linear in the row order (a
//! vector logged at a fixed interval), the run read as a run-down (the
//! speed falling in time; a run-up reverses every sign below). With r_i
//! the rank of speed i among the n rising speeds, the run's time fraction
//! is t_i = 1 − r_i/(n − 1) and its centred value s_i = t_i − ½. A support
//! whose stiffness rises by δ over the run, k_y and k_z alike,
//! k_i = k(1 + δ·s_i) (k the value half way through the run), makes the
//! data of speed i those of θ₀ + δ·s_i·(k_y, k_z, 0, 0, 0). The fit's
//! whitened residuals are linear in θ (each speed's whitening held at the
//! fit, [`crate::estimate::robust::whitened_jacobian`]: J_i), so a fit of
//! constant values minimises ‖J(θ − θ₀) − δ·v‖² with
//! v_i = s_i·(k_y·J_i,k_y + k_z·J_i,k_z), and moves the values by
//!
//! Δθ = δ·(JᵀJ)⁻¹Jᵀv
//!
//! (first order in δ; a common scale of the noise cancels). A drift that
//! does not change over the run (s constant) gives Δk = δk and nothing
//! else, as it must; centring s makes the values those of mid-run and the
//! shifts of a run-up exactly the opposite of a run-down's. A drift that
//! follows a cooling curve instead of a line in time moves the values by
//! about as much (measured on unseen-nine's `ped-drift`, the session's
//! section).

use crate::estimate::ml::Weighting;
use crate::estimate::{Observation, Pedestal};
use crate::identify::{Identification, PedestalFit};
use crate::rundir::RunDir;
use nalgebra::DVector;
use plinth_shared::regression::{Parameter, PARAMETERS};
use serde::Serialize;

/// The drift over the run the shifts are stated for [-]: 1 %.
pub const STATED_DRIFT: f64 = 0.01;

/// The condition in one sentence (`conditional_on.statement`).
pub const STATEMENT: &str = "k, c, m are taken constant over the run: in a run-down (or run-up) time and speed are tied, so a support whose stiffness drifts in time (cooling, warming, a joint settling) reads as a stiffness that changes with speed, to first order a mass term, with a fit as good as a constant support's; the lines below say, per bearing where a 1 % drift would move a value by more than its ±, how far (the file has no time column: the time is taken as linear in the speed order, the run read as a run-down; in a run-up every sign turns). Only a second run whose time runs the other way in speed (a run-up, or a run-down from another temperature) can test it: `plinth compare RUN_A RUN_B`.";

/// How one pedestal's values move under a drift of its support's
/// stiffness over the run (module docs).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DriftSensitivity {
    /// Bearing name.
    pub bearing: String,
    /// The drift δ the shifts are for: the support's k_y and k_z rising by
    /// this fraction of their mid-run values from the run's first moment to
    /// its last, linearly in time, the run read as a run-down [-].
    pub drift: f64,
    /// How the time of each speed was taken (formats.md has no time
    /// column).
    pub time_from: &'static str,
    /// The shift of each value under that drift [N/m, N/m, kg, N·s/m,
    /// N·s/m] (0 for a parameter fixed by the model).
    pub shift: Pedestal,
    /// The shift over the value [-] (NaN, `null`, where the value is 0).
    pub shift_relative: Pedestal,
    /// The shift in the value's printed standard errors [-] (NaN, `null`,
    /// where the ± is 0 or not finite).
    pub shift_in_std_err: Pedestal,
    /// The smallest drift that moves one of k_y, k_z, m by its printed ±
    /// [-] (first order: δ/|shift in ±|); NaN, `null`, when none moves.
    pub drift_at_one_std_err: f64,
    /// The value that drift moves by its ± (`k_y`, `k_z` or `m`).
    pub limited_by: String,
}

impl DriftSensitivity {
    /// True when a drift of [`STATED_DRIFT`] moves k_y, k_z or m by more
    /// than its ±: the line is printed.
    pub fn matters(&self) -> bool {
        self.drift_at_one_std_err < self.drift
    }

    /// One line for people.
    pub fn message(&self) -> String {
        let part = |p: Parameter| {
            let (v, z) = (self.shift_relative.get(p), self.shift_in_std_err.get(p));
            format!("{} by {:+.2} % ({:+.1} ±)", p.name(), 100.0 * v, z)
        };
        format!(
            "{}: a support whose stiffness (k_y and k_z alike) rises by {:.0} % over the run, linearly in time, would move {}, {}, {} (the values then those of mid-run); a drift of {:.2} % moves {} by its ±, and one run cannot see it",
            self.bearing,
            100.0 * self.drift,
            part(Parameter::M),
            part(Parameter::Ky),
            part(Parameter::Kz),
            100.0 * self.drift_at_one_std_err,
            self.limited_by
        )
    }
}

/// The centred time fraction s_i [-] of each of `speeds_hz` [Hz] read as a
/// run-down, linear in the speed order (module docs): ½ at the top speed,
/// −½ at the bottom one; 0 for a single speed.
pub fn time_fraction(speeds_hz: &[f64]) -> Vec<f64> {
    let n = speeds_hz.len();
    if n < 2 {
        return vec![0.0; n];
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| speeds_hz[a].total_cmp(&speeds_hz[b]));
    let mut s = vec![0.0; n];
    for (rank, &i) in order.iter().enumerate() {
        s[i] = 0.5 - rank as f64 / (n - 1) as f64;
    }
    s
}

/// The shift Δθ [θ units] of the values `theta` fitted to `obs` over the
/// estimated `columns` when the support's stiffness is k(1 + δ·s_i) at
/// observation i, δ = `drift` [-], `s` the time fractions (module docs);
/// `None` when a figure is not finite or JᵀJ is singular.
pub fn shift(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    columns: &[Parameter],
    s: &[f64],
    drift: f64,
) -> Option<[f64; PARAMETERS]> {
    if s.len() != obs.len() || columns.is_empty() {
        return None;
    }
    let (_, jac) =
        crate::estimate::robust::whitened_jacobian(obs, theta, columns, &Weighting::default())?;
    let mut v = DVector::<f64>::zeros(jac.nrows());
    for (c, &p) in columns.iter().enumerate() {
        if !matches!(p, Parameter::Ky | Parameter::Kz) {
            continue;
        }
        let k = theta[p as usize];
        for (i, &si) in s.iter().enumerate() {
            for r in 4 * i..4 * i + 4 {
                v[r] += si * k * jac[(r, c)];
            }
        }
    }
    let normal = jac.tr_mul(&jac);
    let rhs = jac.tr_mul(&v) * drift;
    let d = normal.cholesky()?.solve(&rhs);
    let mut out = [0.0; PARAMETERS];
    for (c, &p) in columns.iter().enumerate() {
        out[p as usize] = d[c];
    }
    out.iter().all(|x| x.is_finite()).then_some(out)
}

/// The sensitivity of one fitted pedestal `fit` to its observations `obs`
/// (module docs); `None` when it cannot be computed.
pub fn of_fit(fit: &PedestalFit, obs: &[Observation]) -> Option<DriftSensitivity> {
    let theta = fit.pedestal.theta();
    let columns: Vec<Parameter> = Parameter::ALL
        .into_iter()
        .filter(|p| !fit.fixed.iter().any(|f| f == p.name()))
        .collect();
    let speeds: Vec<f64> = obs.iter().map(|o| o.speed_hz).collect();
    let d = shift(obs, &theta, &columns, &time_fraction(&speeds), STATED_DRIFT)?;
    let se = fit.std_err.theta();
    let rel: [f64; PARAMETERS] = std::array::from_fn(|i| {
        if theta[i] != 0.0 {
            d[i] / theta[i].abs()
        } else {
            f64::NAN
        }
    });
    let z: [f64; PARAMETERS] = std::array::from_fn(|i| {
        if se[i].is_finite() && se[i] > 0.0 {
            d[i] / se[i]
        } else {
            f64::NAN
        }
    });
    let (limited_by, largest) = [Parameter::Ky, Parameter::Kz, Parameter::M]
        .into_iter()
        .filter(|&p| columns.contains(&p) && z[p as usize].is_finite())
        .map(|p| (p, z[p as usize].abs()))
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    Some(DriftSensitivity {
        bearing: fit.bearing.clone(),
        drift: STATED_DRIFT,
        time_from: "the speed order, linear in the row order, read as a run-down",
        shift: Pedestal::from_theta(d),
        shift_relative: Pedestal::from_theta(rel),
        shift_in_std_err: Pedestal::from_theta(z),
        drift_at_one_std_err: if largest > 0.0 {
            STATED_DRIFT / largest
        } else {
            f64::NAN
        },
        limited_by: limited_by.name().to_string(),
    })
}

/// Every pedestal of `identification` (of `run`, as fitted) on rigid
/// ground: its sensitivity to a drift of its support over the run.
/// Pedestals fitted on a base are left out (their equations hold the
/// base's motion too).
pub fn of(run: &RunDir, identification: &Identification) -> Vec<DriftSensitivity> {
    let prepared = crate::identify::data::Prepared::new(
        run,
        None,
        crate::estimate::noise::Quantisation::Rounding,
    );
    identification
        .pedestals
        .iter()
        .filter(|p| p.base.is_none() && p.base_measured.is_none())
        .filter_map(|p| {
            let (obs, _) = prepared.bearing(&p.bearing).ok()?;
            of_fit(p, obs)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_complex::Complex64;
    use plinth_shared::bearing::BearingCoefficients;

    /// Exact data of a pedestal whose stiffness is k(1 + δ·s_i) at speed
    /// i: the bearing force of a given rel, the pedestal's motion from it.
    fn drifting(drift: f64) -> (Vec<Observation>, [f64; PARAMETERS]) {
        let theta = [2.0e8, 1.0e8, 40.0, 4.0e3, 3.0e3];
        let speeds: Vec<f64> = (0..60).map(|i| 100.0 + 5.0 * i as f64).collect();
        let s = time_fraction(&speeds);
        let coeffs = BearingCoefficients {
            k: [[3.0e7, 1.0e7], [-1.0e7, 2.5e7]],
            c: [[2.0e4, 0.0], [0.0, 1.8e4]],
        };
        let obs = speeds
            .iter()
            .zip(&s)
            .map(|(&f, &si)| {
                let w = plinth_shared::phasor::omega_from_hz(f);
                let rel = [Complex64::new(1e-6, 2e-7), Complex64::new(3e-7, -8e-7)];
                let mut o = Observation::without_noise(f, rel, rel, &coeffs);
                let force = o.force();
                let g = 1.0 + drift * si;
                let z = [
                    Complex64::new(theta[0] * g - w * w * theta[2], w * theta[3]),
                    Complex64::new(theta[1] * g - w * w * theta[2], w * theta[4]),
                ];
                o.ped = [force[0] / z[0], force[1] / z[1]];
                // Noise of 0.1 % of each phasor.
                let var = std::array::from_fn(|c| (1e-3 * o.magnitude(c)).powi(2));
                o.var = var;
                o
            })
            .collect();
        (obs, theta)
    }

    #[test]
    fn the_time_fraction_runs_from_the_top_speed_down() {
        assert_eq!(time_fraction(&[300.0, 100.0, 200.0]), vec![-0.5, 0.5, 0.0]);
        assert_eq!(time_fraction(&[5.0]), vec![0.0]);
    }

    #[test]
    fn a_constant_drift_moves_k_alone_and_a_reversed_one_turns_every_sign() {
        let (obs, theta) = drifting(0.0);
        let all = Parameter::ALL.to_vec();
        let d = shift(&obs, &theta, &all, &vec![1.0; obs.len()], 0.01).expect("shift");
        assert!((d[0] / (0.01 * theta[0]) - 1.0).abs() < 1e-6, "{d:?}");
        assert!((d[1] / (0.01 * theta[1]) - 1.0).abs() < 1e-6, "{d:?}");
        assert!(d[2].abs() < 1e-6 * theta[2], "{d:?}");
        let speeds: Vec<f64> = obs.iter().map(|o| o.speed_hz).collect();
        let s = time_fraction(&speeds);
        let down = shift(&obs, &theta, &all, &s, 0.01).expect("shift");
        let up: Vec<f64> = s.iter().map(|v| -v).collect();
        let up = shift(&obs, &theta, &all, &up, 0.01).expect("shift");
        for i in 0..PARAMETERS {
            assert!(
                (down[i] + up[i]).abs() <= 1e-9 * down[i].abs().max(1e-9),
                "{i}"
            );
        }
        // Stiffness rising as the speed falls: a mass term, m read high.
        assert!(down[2] > 0.0, "{down:?}");
    }

    /// The linearised shift against a fit of data made with the drift: the
    /// constant-θ least-squares fit of exact drifting data is θ₀ + Δθ to
    /// first order (here δ = 0.1 %, so within a few % of the shift).
    #[test]
    fn the_shift_is_what_a_fit_of_drifting_data_gives() {
        let drift = 0.001;
        let (obs, theta) = drifting(drift);
        let all = Parameter::ALL.to_vec();
        let speeds: Vec<f64> = obs.iter().map(|o| o.speed_hz).collect();
        let s = time_fraction(&speeds);
        let predicted = shift(&obs, &theta, &all, &s, drift).expect("shift");
        // Fit constant θ on the drifting data: one Gauss-Newton step from
        // θ₀ is exact for residuals linear in θ.
        let (w, jac) =
            crate::estimate::robust::whitened_jacobian(&obs, &theta, &all, &Weighting::default())
                .expect("jacobian");
        let step = jac
            .tr_mul(&jac)
            .cholesky()
            .expect("spd")
            .solve(&(jac.tr_mul(&w)));
        for i in [0, 1, 2] {
            let fitted = -step[i];
            assert!(
                (fitted / predicted[i] - 1.0).abs() < 0.05,
                "{i}: fitted {fitted:e}, predicted {:e}",
                predicted[i]
            );
        }
    }
}
