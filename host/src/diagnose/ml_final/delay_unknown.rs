//! The ± of a bearing's final pedestal values counting a sensor delay on
//! its `rel` probes, which the search tried and the data do not exclude,
//! as unknown.
//!
//! A delay τ on a bearing's rotor-relative probes multiplies the measured
//! bearing force by e^{−iΩτ}: the apparent pedestal impedance is
//! Z·(1 − iΩτ), i.e. the damping c − τ·(k − Ω²m) in place of c
//! ([`crate::diagnose::forward::non_physical_dampings`]). Where the
//! pedestal's resonance lies above the band, k − Ω²m is nearly k over it and
//! τ and c trade almost one for one; only the Ω³τm curvature and the link
//! between the two directions tell them apart. The search rejects the
//! delay at its Bonferroni level, and the final ± of c are then
//! conditional on τ = 0 exactly, a value the data did not give: unseen-five
//! `delay` seed 2928 (150 µs on B1's probes, truth c_y 2000 N·s/m) printed
//! B1 c_y −1729 ± 800, trusted (z −4.66), with τ 162 ± 43 µs the best
//! rejected candidate: k_y·σ_τ ≈ 1700 N·s/m against that ± 800
//! (docs/unseen.md, Session 44 (sweep17b), finding 1).
//!
//! Here, at every bearing of a group on rigid ground (the search tried a
//! delay there at every step, [`crate::diagnose::candidates`]), the group's
//! equations are extended by a delay at τ = 0 on the `rel` probes whose
//! phase no delay of the final model frees (both where it has none,
//! `undelayed_probes`) and linearised at the final values
//! (the same construction as [`super::held_delay`] and [`super::held_free`],
//! the nuisance the other way round: Baarda's external reliability). With
//! the inference ([`Inference`]) of the fit with τ held at zero (C_held) and
//! with τ free (C_free), each parameter's ρ = σ_free/σ_held ≥ 1; the held
//! value of a damping c moves by b·τ for a true delay τ, with
//! |b|·σ_τ = σ_held·√(ρ² − 1).
//!
//! **Excluded**: the data's interval of τ (τ̂ ± 1.96 σ_τ, τ̂ one
//! Gauss–Newton step from τ = 0, clipped at τ ≥ 0: a delay is causal)
//! moves every damping of the bearing by at most its held ±:
//! |b|·max(0, τ̂ + 1.96 σ_τ) ≤ σ_held. Then nothing changes. Otherwise the
//! reported ± of every pedestal value of the group is multiplied by its ρ
//! (the ± with τ unknown); the values stay the final fit's.
//!
//! **Only where a damping of the bearing comes out below zero, or where the
//! data favour a delay** (τ̂ > 2 σ_τ, one-sided: a delay the search's
//! Bonferroni level rejected but these data do not call chance; unseen-six
//! `delay`, B2's resonances inside the run, seeds 3615 and 3617: τ̂ at
//! 2.5 and 2.1 of its ±, the dampings positive and 3.5-4.2 ± off, trusted;
//! docs/unseen-six.md). A passive
//! pedestal's damping is ≥ 0, and a delay on the `rel` probes (τ > 0)
//! lowers the apparent damping below the resonance: a negative estimate is
//! the data's sign of a phase error. Elsewhere the delay is rarely excluded
//! either (a stiff block's c cannot be told from τ·k by any run-down: on
//! unseen-train's B1, 900 MN/m, ρ ≈ 20), and counting it there made every
//! such damping unknown on clean runs (docs/unseen.md, Session 45 (delay17): widening
//! everywhere, measured, B1 c_y ± ×20 on clean `clean-p2`). Measured on
//! unseen-five `delay` (seeds 3401-3420) the gated rule widens every run
//! whose B1 c_y was beyond 3 ± (12/20), and no clean run of that machine.

use super::{linearised, GroupEquations, GroupRefit};
use crate::diagnose::criterion::Inference;
use crate::diagnose::data::Prepared;
use crate::diagnose::fit::search_interval;
use crate::diagnose::model::{DelayChannels, Model, Nonlinear, Term};
use crate::diagnose::state::State;
use nalgebra::DVector;

/// Standard normal quantile of the delay's two-sided 95 % interval [-].
const Z_INTERVAL: f64 = 1.96;

/// A delay the data favour: τ̂ beyond this many of its ± [-] (one-sided,
/// 2.3 % per bearing under the null; τ̂/σ_τ on 180 clean bearings of five
/// ROSS machines: RMS 0.98, 4 beyond 2).
const Z_FAVOURED: f64 = 2.0;

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
}

impl Widened {
    /// ρ = σ_free/σ_held [-], at least 1.
    pub fn ratio(&self) -> f64 {
        (self.free / self.held).max(1.0)
    }
}

/// A delay on a bearing's `rel` probes the data do not exclude, and the ±
/// of the group's pedestal values with it unknown.
#[derive(Clone, Debug, PartialEq)]
pub struct DelayUnknown {
    /// Bearing index of the delay.
    pub bearing: usize,
    /// Its channels (`rel` probes only).
    pub channels: DelayChannels,
    /// One Gauss–Newton step's τ from τ = 0 [s].
    pub tau: f64,
    /// Its ± [s] ([`Inference::std_err`]).
    pub tau_std_err: f64,
    /// Every pedestal value of the group with both ±.
    pub widened: Vec<Widened>,
}

/// The delays on `rel` probes the data do not exclude at the bearings of
/// `group` of `model` where a damping comes out below zero (module docs), with the group's
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
/// where no damping of `b` is below zero, the data exclude the delay or
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
    let negative = model
        .terms
        .iter()
        .zip(beta)
        .any(|(t, v)| matches!(t, Term::Damping { bearing, .. } if *bearing == b) && *v < 0.0);
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
    let free = Inference::new(&jac, &resid, &row_speed, DVector::from_vec(p.clone())).ok()?;
    let held_jac = jac.clone().remove_column(j);
    let mut held_p = p.clone();
    held_p.remove(j);
    let held = Inference::new(&held_jac, &resid, &row_speed, DVector::from_vec(held_p)).ok()?;
    // One Gauss–Newton step of the whitened equations from τ = 0.
    let step = jac.clone().svd(true, true).solve(&(-&resid), 1e-14).ok()?;
    let (tau, tau_se) = (step[j], free.std_err(j));
    let tau_max = (tau + Z_INTERVAL * tau_se).max(0.0);
    let widened: Vec<Widened> = eq
        .terms
        .iter()
        .enumerate()
        .filter_map(|(i, &t)| {
            let term = extended.terms[t];
            let [Some(bearing), None] = term.bearings() else {
                return None;
            };
            term.is_pedestal().then(|| Widened {
                bearing,
                name: term.name(),
                held: held.std_err(i),
                free: free.std_err(i),
                damping: matches!(term, Term::Damping { .. }),
            })
        })
        .collect();
    let finite = tau.is_finite() && tau_se.is_finite() && tau_se > 0.0;
    if !finite || !widened.iter().all(|w| w.held > 0.0 && w.free.is_finite()) {
        return None;
    }
    // The gate (module docs): a damping below zero, or the data favour a
    // causal delay beyond [`Z_FAVOURED`] of its ±.
    if !negative && tau <= Z_FAVOURED * tau_se {
        return None;
    }
    // Excluded: no τ in the data's interval moves a damping of the bearing
    // by more than its held ± (|b|·σ_τ = σ_held·√(ρ² − 1)).
    let moves = |w: &Widened| {
        let b_abs = w.held * (w.ratio().powi(2) - 1.0).sqrt() / tau_se;
        b_abs * tau_max > w.held
    };
    if !widened
        .iter()
        .any(|w| w.damping && w.bearing == b && moves(w))
    {
        return None;
    }
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
