//! The ± of a bearing's final pedestal values counting a sensor delay on
//! its `rel` probes or (τ̂ < 0) its `ped` pick-ups, which the search tried
//! and the data do not exclude, as unknown.
//!
//! The physics, the linearisation, the exclusion and the gate are one
//! definition shared with `plinth identify`
//! ([`crate::estimate::lack_of_fit::delay_unknown`], module docs there).
//! Here, at every bearing of a group on rigid ground (the search tried a
//! delay there at every step, [`crate::diagnose::candidates`]), the group's
//! equations are extended by a delay at τ = 0 on the `rel` probes whose
//! phase no delay of the final model frees (both where it has none,
//! `undelayed_probes`) and linearised at the final values (the same
//! construction as [`super::held_delay`] and [`super::held_free`], the
//! nuisance the other way round), each fit's ± this tool's own
//! ([`Inference::std_err`]: the larger of the floor and the
//! autocorrelation-robust value). Where the delay is counted as unknown the
//! reported ± of every pedestal value of the group is multiplied by the
//! shared widening ([`shared::widening`]: its ρ = σ(τ free)/σ(τ held) at
//! τ̂ = 0, more where the data put τ̂ away from zero, on either side); the
//! values stay the final fit's. Where the noise is correlated along the
//! run, the equations are first prewhitened by the AR(1) measured on the
//! final fit's residuals ([`super::serial`]), as identify's rule does. Only the relative phase of force and motion
//! enters the equations, so a delay on the `ped` pick-ups is one of −τ on
//! the probes: the delay is linearised on the probes and read two-sided
//! (unseen-seven `ped-delay`, 200 µs on B3's pick-ups: not counted while
//! the rule took τ ≥ 0 only, B3 c_y trusted 3.5-10.8 ± off in 20 of 23
//! runs, docs/unseen-seven.md finding 2). Measured on unseen-five `delay` (seeds
//! 3401-3420) the gated rule widens every run whose B1 c_y was beyond 3 ±
//! (12/20), and no clean run of that machine (docs/unseen.md, Session 45
//! (delay17)); unseen-five `delay` seed 2928 (150 µs on B1's probes, truth
//! c_y 2000 N·s/m) printed B1 c_y −1729 ± 800 before, trusted (z −4.66),
//! with τ 162 ± 43 µs the best rejected candidate.

use super::{linearised, serial, GroupEquations, GroupRefit};
use crate::diagnose::criterion::Inference;
use crate::diagnose::data::Prepared;
use crate::diagnose::fit::search_interval;
use crate::diagnose::model::{DelayChannels, Model, Nonlinear, Term};
use crate::diagnose::state::State;
use crate::estimate::lack_of_fit::delay_unknown::{self as shared, linearise};
use nalgebra::DVector;

/// The `rel` probes of bearing `b` whose phase no delay of `model` at `b`
/// frees (a delay on the probe, or on the pedestal channel of its
/// direction: only the relative phase of force and motion enters), as the
/// channels of the delay counted as unknown; `None` where every probe's
/// phase is free already. Both probes is the library's `rel` variant; one
/// probe where the search named a one-probe delay there (unseen-five
/// `delay` seed 2946: `rel_z` named, the delay on both probes, B1 c_y
/// 3.75 ± off).
fn undelayed_probes(model: &Model, b: usize) -> Option<DelayChannels> {
    let mut rel = [true, true];
    for p in &model.nonlinear {
        if let Nonlinear::Delay { bearing, channels } = p {
            if *bearing == b {
                for (d, free) in rel.iter_mut().enumerate() {
                    *free &= !(channels.rel[d] || channels.ped[d]);
                }
            }
        }
    }
    (rel[0] || rel[1]).then_some(DelayChannels {
        rel,
        ped: [false, false],
    })
}

/// One pedestal value's ± with the delay held at zero and free.
#[derive(Clone, Debug, PartialEq)]
pub struct Widened {
    /// Bearing index of the pedestal value.
    pub bearing: usize,
    /// Its name (`k_y`, `m`, `c_z`, ...).
    pub name: String,
    /// Its ± [SI] with the delay at zero ([`Inference::std_err`]).
    pub held: f64,
    /// Its ± [SI] with the delay free, linearised at the final values.
    pub free: f64,
    /// Whether it is a damping (c_y, c_z).
    pub damping: bool,
    /// The factor its reported ± is multiplied by
    /// ([`shared::widening`] of ρ and the delay's τ̂/σ_τ) [-].
    pub factor: f64,
}

impl Widened {
    /// The factor [-] its reported ± is multiplied by where the delay is
    /// counted as unknown ([`shared::widening`]: ρ = σ_free/σ_held at
    /// τ̂ = 0, more where the data put τ̂ away from zero), at least 1.
    pub fn ratio(&self) -> f64 {
        self.factor
    }

    /// ρ = σ_free/σ_held [-], at least 1.
    pub fn rho(&self) -> f64 {
        shared::ratio(self.held, self.free)
    }
}

/// A delay on a bearing's `rel` probes or (τ̂ < 0) its `ped` pick-ups the
/// data do not exclude, and the ± of the group's pedestal values with it
/// unknown.
#[derive(Clone, Debug, PartialEq)]
pub struct DelayUnknown {
    /// Bearing index of the delay.
    pub bearing: usize,
    /// Its channels (`rel` probes only: a delay on the `ped` pick-ups is
    /// one of −τ there).
    pub channels: DelayChannels,
    /// One Gauss–Newton step's τ from τ = 0 [s] (below zero: a delay on
    /// the `ped` pick-ups).
    pub tau: f64,
    /// Its ± [s] ([`Inference::std_err`]).
    pub tau_std_err: f64,
    /// Every pedestal value of the group with both ±.
    pub widened: Vec<Widened>,
}

/// The delays on `rel` probes the data do not exclude at the bearings of
/// `group` of `model` that pass the shared gate (module docs), with the group's
/// pedestal ± with each unknown; `beta`, `nl`: the model's final values;
/// `scale`: per parameter of the group's equations (its terms, then its
/// scalars) a size [SI] for the difference steps.
pub(super) fn delays_unknown(
    prep: &Prepared,
    model: &Model,
    group: &[usize],
    beta: &[f64],
    nl: &[f64],
    scale: &[f64],
) -> Vec<DelayUnknown> {
    group
        .iter()
        .filter_map(|&b| {
            let channels = undelayed_probes(model, b)?;
            delay_unknown(prep, model, group, b, channels, beta, nl, scale)
        })
        .collect()
}

/// [`delays_unknown`] at bearing `b`, the delay on `channels`: `None`
/// where the gate is shut (the data do not favour a delay with the
/// dampings of `b` held passive, [`shared::evidence`]),
/// the data exclude the delay or
/// the linearisation fails.
#[allow(clippy::too_many_arguments)]
fn delay_unknown(
    prep: &Prepared,
    model: &Model,
    group: &[usize],
    b: usize,
    channels: DelayChannels,
    beta: &[f64],
    nl: &[f64],
    scale: &[f64],
) -> Option<DelayUnknown> {
    let mut extended = model.clone();
    extended.nonlinear.push(Nonlinear::Delay {
        bearing: b,
        channels,
    });
    let k = extended.nonlinear.len() - 1;
    let mut ext_nl = nl.to_vec();
    ext_nl.push(0.0);
    let eq = GroupEquations::from_values(prep, &extended, group, beta, &ext_nl);
    let p = eq.pack(beta, &ext_nl);
    let j = eq.nonlinear.iter().position(|&u| u == k)? + eq.terms.len();
    // The group's p without the delay is p with entry j removed.
    let (lo, hi) = search_interval(prep, &extended, k, group);
    let mut ext_scale = scale.to_vec();
    ext_scale.insert(j, 0.01 * (hi - lo));
    if ext_scale.len() != p.len() || !ext_scale.iter().all(|s| s.is_finite() && *s > 0.0) {
        return None;
    }
    let (jac, resid, row_speed) = linearised(&eq, &p, &ext_scale)?;
    // Under noise correlated along the run, the equations prewhitened by
    // the AR(1) measured on the final fit's residuals (τ = 0 here), as
    // identify's rule takes them: the generalised fit's τ̂, σ_τ and ρ, so
    // a slowly wandering noise is not read as a delay ([`super::serial`]).
    let (jac, resid) = match serial::measured(prep, &eq.speeds, &resid) {
        Some((rho, rows)) => serial::prewhitened(&jac, &resid, rows, rho),
        None => (jac, resid),
    };
    let lin = linearise(&jac, &resid, j, |jac, resid| {
        let mut estimate = p.clone();
        if jac.ncols() < estimate.len() {
            estimate.remove(j);
        }
        let inf = Inference::new(jac, resid, &row_speed, DVector::from_vec(estimate)).ok()?;
        Some((0..jac.ncols()).map(|i| inf.std_err(i)).collect())
    })?;
    // The parameters of the group less τ, in order (τ's column is j).
    let widened: Vec<Widened> = eq
        .terms
        .iter()
        .enumerate()
        .filter_map(|(i, &t)| {
            let term = extended.terms[t];
            let [Some(bearing), None] = term.bearings() else {
                return None;
            };
            let at = if i < j { i } else { i - 1 };
            term.is_pedestal().then(|| Widened {
                bearing,
                name: term.name(),
                held: lin.held[at],
                free: lin.free[at],
                damping: matches!(term, Term::Damping { .. }),
                factor: shared::widening(
                    shared::ratio(lin.held[at], lin.free[at]),
                    lin.tau,
                    lin.tau_std_err,
                ),
            })
        })
        .collect();
    if !widened.iter().all(|w| w.held > 0.0 && w.free.is_finite()) {
        return None;
    }
    // The dampings of b as the shared gate reads them (value, held ±, ρ,
    // shift per unit τ).
    let dampings: Vec<shared::HeldDamping> = eq
        .terms
        .iter()
        .enumerate()
        .filter(
            |&(_, &t)| matches!(extended.terms[t], Term::Damping { bearing, .. } if bearing == b),
        )
        .map(|(i, _)| {
            let at = if i < j { i } else { i - 1 };
            shared::HeldDamping {
                value: p[i],
                std_err: lin.held[at],
                ratio: shared::ratio(lin.held[at], lin.free[at]),
                path: lin.path[at],
            }
        })
        .collect();
    if !shared::counted_unknown(lin.tau, lin.tau_std_err, &dampings) {
        return None;
    }
    let (tau, tau_se) = (lin.tau, lin.tau_std_err);
    Some(DelayUnknown {
        bearing: b,
        channels,
        tau,
        tau_std_err: tau_se,
        widened,
    })
}

/// Adds to `refits` the delays on `rel` probes the data do not exclude at
/// every group of `state` ([`delay_unknown`]), linearised at the state's
/// final values: a refitted group's entry takes them, a group not refitted
/// gets an entry of its own carrying only them.
pub(super) fn with_delays_unknown(prep: &Prepared, state: &State, refits: &mut Vec<GroupRefit>) {
    let inferences = state.inference(prep).unwrap_or_default();
    for group in state.model.groups(prep.bearings.len()) {
        let eq = GroupEquations::new(prep, &state.model, &group, state);
        let p = eq.pack(&state.params.beta, &state.params.nl);
        let at = refits.iter().position(|r| r.group == group);
        let inference = match at {
            Some(i) => &refits[i].inference,
            None => match inferences.iter().find(|(g, _, _)| *g == group) {
                Some((_, inf, _)) => inf,
                None => continue,
            },
        };
        if inference.estimate.len() != p.len() {
            continue;
        }
        // Units: each parameter's scale is the larger of its size and its ±
        // (as in `refit`).
        let scale: Vec<f64> = p
            .iter()
            .enumerate()
            .map(|(i, v)| v.abs().max(inference.std_err(i)).max(f64::MIN_POSITIVE))
            .collect();
        let unknown = delays_unknown(
            prep,
            &state.model,
            &group,
            &state.params.beta,
            &state.params.nl,
            &scale,
        );
        if unknown.is_empty() {
            continue;
        }
        match at {
            Some(i) => refits[i].delay_unknown = unknown,
            None => {
                let inference = inference.clone();
                refits.push(GroupRefit {
                    group,
                    terms: Vec::new(),
                    nonlinear: Vec::new(),
                    inference,
                    held_delays: Vec::new(),
                    held_against_data: Vec::new(),
                    freed: Vec::new(),
                    held_unknown: None,
                    delay_unknown: unknown,
                })
            }
        }
    }
}
