//! The corrections of a state re-estimated on a chosen base whose values
//! are held: Newton steps on the base's pedestal-level χ².

use super::rigid_prediction;
use crate::diagnose::correct::{corrected_on, mixes_channels, residual_noise};
use crate::diagnose::data::Prepared;
use crate::diagnose::foundation::FoundationFit;
use crate::diagnose::gap::Prediction;
use crate::diagnose::model::{Nonlinear, Term};
use crate::diagnose::state::State;
use crate::diagnose::workflow::Options;
use nalgebra::{DMatrix, DVector};

/// A parameter of a state that corrects the data: a linear term (runout,
/// cross-coupling) or a nonlinear scalar (a delay, a table's clearance).
#[derive(Clone, Copy, Debug)]
pub(super) enum Slot {
    /// The linear term at this index of the model.
    Term(usize),
    /// The nonlinear parameter at this index.
    Nonlinear(usize),
}

/// The correcting parameters of `state` ([`crate::diagnose::correct::corrected`]).
pub(super) fn correction_slots(state: &State) -> Vec<Slot> {
    let terms = state
        .model
        .terms
        .iter()
        .enumerate()
        .filter(|(_, t)| matches!(t, Term::Runout { .. } | Term::CrossStiffness { .. }))
        .map(|(i, _)| Slot::Term(i));
    let nl = state
        .model
        .nonlinear
        .iter()
        .enumerate()
        .filter(|(_, p)| {
            matches!(
                p,
                Nonlinear::Delay { .. }
                    | Nonlinear::Clearance { .. }
                    | Nonlinear::StiffnessRatio { .. }
            )
        })
        .map(|(k, _)| Slot::Nonlinear(k));
    terms.chain(nl).collect()
}

/// The value of the correcting parameter `s` of `state`.
pub(super) fn slot_value(state: &State, s: Slot) -> f64 {
    match s {
        Slot::Term(i) => state.params.beta[i],
        Slot::Nonlinear(k) => state.params.nl[k],
    }
}

/// Sets the correcting parameter `s` of `state` to `v`.
pub(super) fn set_slot(state: &mut State, s: Slot, v: f64) {
    match s {
        Slot::Term(i) => state.params.beta[i] = v,
        Slot::Nonlinear(k) => state.params.nl[k] = v,
    }
}

/// Finite-difference step of a correcting parameter: 1 % of its value,
/// at least a floor in its own unit (runout: 1e-3 of the largest runout
/// value [m]; cross-stiffness 1e3 N/m; delay 1e-6 s; a table's δ 1e-3).
fn slot_step(state: &State, s: Slot, runout_scale: f64) -> f64 {
    let v = slot_value(state, s).abs();
    let floor = match s {
        Slot::Term(i) => match state.model.terms[i] {
            Term::Runout { .. } => 1e-3 * runout_scale.max(1e-12),
            _ => 1e3,
        },
        Slot::Nonlinear(k) => match state.model.nonlinear[k] {
            Nonlinear::Delay { .. } => 1e-6,
            _ => 1e-3,
        },
    };
    (1e-2 * v).max(floor)
}

/// [`slot_step`] with the runout floor from `state`'s largest runout value.
pub(super) fn slot_step_of(state: &State, s: Slot) -> f64 {
    slot_step(state, s, runout_scale(state, &correction_slots(state)))
}

/// The largest runout value [m] among `slots` of `state` (0 without one).
fn runout_scale(state: &State, slots: &[Slot]) -> f64 {
    slots
        .iter()
        .filter(
            |s| matches!(s, Slot::Term(i) if matches!(state.model.terms[*i], Term::Runout { .. })),
        )
        .map(|&s| slot_value(state, s).abs())
        .fold(0.0, f64::max)
}

/// The pedestal-level χ² of the chosen base `fit`, its values held, on the
/// data `state` corrects ([`Prediction::chi2`]; ∞ when it cannot predict).
fn held_base_chi2(prep: &Prepared, state: &State, fit: &FoundationFit, opts: &Options) -> f64 {
    held_prediction(prep, state, fit, opts).map_or(f64::INFINITY, |(c, p)| p.chi2(&c).0)
}

/// The chosen base `fit`, its values held, predicting the pedestals on the
/// data `state` corrects on it, with each residual's noise carried through
/// the corrections when they mix the channels ([`residual_noise`]): the
/// corrected data and the prediction; `None` when it cannot predict.
fn held_prediction(
    prep: &Prepared,
    state: &State,
    fit: &FoundationFit,
    opts: &Options,
) -> Option<(Prepared, Prediction)> {
    let rigid = |c: &Prepared| rigid_prediction(c, state, &opts.base);
    let cprep = corrected_on(prep, state, Some(fit));
    if !mixes_channels(state) {
        let pred = fit.predict_on(&cprep, &rigid(&cprep))?;
        return Some((cprep, pred));
    }
    // The noise is carried from the measured numbers: the motion alone.
    let predict = |c: &Prepared| fit.motion_on(c, &rigid);
    let mut pred = predict(&cprep)?;
    pred.noise_var = residual_noise(prep, state, Some(fit), &predict)?;
    Some((cprep, pred))
}

/// Newton iterations of [`tuned_on_base`].
const TUNE_ITERATIONS: usize = 4;

/// The corrections of `state` re-estimated on a chosen base: the values the
/// rigid-ground fit gives them absorb what the base explains (a runout
/// fitted without the base bends to mimic the base's motion), so they are
/// moved to the minimum of the base's pedestal-level χ² with the base's
/// values held. Newton steps on a finite-difference gradient and Hessian
/// (exact for runout, in which the χ² is quadratic; nearly so for
/// cross-coupling, whose value also moves the residuals' noise,
/// [`residual_noise`]), each halved until the χ² falls. Returns the state and its χ².
pub(super) fn tuned_on_base(
    prep: &Prepared,
    state: &State,
    fit: &FoundationFit,
    opts: &Options,
) -> (State, f64) {
    let slots = correction_slots(state);
    let mut cur = state.clone();
    let mut f0 = held_base_chi2(prep, &cur, fit, opts);
    if slots.is_empty() || !f0.is_finite() {
        return (cur, f0);
    }
    let runout_scale = runout_scale(state, &slots);
    let n = slots.len();
    for _ in 0..TUNE_ITERATIONS {
        let h: Vec<f64> = slots
            .iter()
            .map(|&s| slot_step(&cur, s, runout_scale))
            .collect();
        let eval = |moves: &[(usize, f64)]| {
            let mut s = cur.clone();
            for &(i, d) in moves {
                set_slot(&mut s, slots[i], slot_value(&cur, slots[i]) + d);
            }
            held_base_chi2(prep, &s, fit, opts)
        };
        let plus: Vec<f64> = (0..n).map(|i| eval(&[(i, h[i])])).collect();
        let minus: Vec<f64> = (0..n).map(|i| eval(&[(i, -h[i])])).collect();
        let mut g = DVector::zeros(n);
        let mut hess = DMatrix::zeros(n, n);
        for i in 0..n {
            g[i] = (plus[i] - minus[i]) / (2.0 * h[i]);
            hess[(i, i)] = (plus[i] - 2.0 * f0 + minus[i]) / (h[i] * h[i]);
            for j in 0..i {
                let both = eval(&[(i, h[i]), (j, h[j])]);
                let v = (both - plus[i] - plus[j] + f0) / (h[i] * h[j]);
                hess[(i, j)] = v;
                hess[(j, i)] = v;
            }
        }
        if !g.iter().chain(hess.iter()).all(|v| v.is_finite()) {
            break;
        }
        // A Newton step where the Hessian is positive definite, else a
        // gradient step scaled by its diagonal.
        let dx = match hess.clone().cholesky() {
            Some(ch) => -ch.solve(&g),
            None => DVector::from_iterator(
                n,
                (0..n).map(|i| -g[i] / hess[(i, i)].abs().max(f64::MIN_POSITIVE)),
            ),
        };
        let mut t = 1.0;
        let mut moved = false;
        for _ in 0..8 {
            let mut s = cur.clone();
            for (i, &sl) in slots.iter().enumerate() {
                set_slot(&mut s, sl, slot_value(&cur, sl) + t * dx[i]);
            }
            let f = held_base_chi2(prep, &s, fit, opts);
            if f < f0 {
                let gain = f0 - f;
                cur = s;
                f0 = f;
                moved = gain > 1e-3;
                break;
            }
            t *= 0.5;
        }
        if !moved {
            break;
        }
    }
    (cur, f0)
}
