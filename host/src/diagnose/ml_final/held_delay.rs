//! The ± of a sensor delay fitted beside a pedestal damping held at zero.
//!
//! A delay τ on a bearing's channels reads as a pedestal damping −τ·k
//! (module docs of [`crate::diagnose::forward::non_physical_dampings`]).
//! Where the base model's free damping at that bearing was impossible, the
//! delay was named with the damping held at zero, the passive bound
//! ([`crate::diagnose::forward::held_at_zero`]), and freed again only where
//! the data support the damping ([`crate::diagnose::forward::freed_held`]).
//! On a stiff block they do not: c and τ·k trade, and the held fit's τ is
//! the delay less the true damping's share c/k (the fourth unseen machine's
//! B1: c/k = 10-12.5 µs, τ 132-141 µs ± 3 µs for 150 µs, session 38). The
//! held fit's ± is conditional on c = 0 exactly, a value no data gave: it
//! leaves out the damping's uncertainty and printed τ 4 ± off the truth.
//!
//! Here the ± of such a delay counts the held damping as unknown: the
//! inference ([`Inference`], the one definition of every ± of diagnose) of
//! the same ML fit with the held dampings as free parameters, linearised at
//! the held fit's values (c = 0, its residuals). The value stays the held
//! fit's, a lower bound of the delay for a passive pedestal (c ≥ 0).

use super::{linearised, serial, with_freed, GroupEquations};
use crate::diagnose::criterion::Inference;
use crate::diagnose::data::Prepared;
use crate::diagnose::forward::held_terms;
use crate::diagnose::model::{Model, Nonlinear, Term};
use nalgebra::DVector;

/// A delay whose ± counts its bearing's held pedestal dampings as unknown.
#[derive(Clone, Debug, PartialEq)]
pub struct HeldDelay {
    /// Global index of the delay among the model's nonlinear scalars.
    pub nonlinear: usize,
    /// The pedestal dampings held at zero at its bearing.
    pub held: Vec<Term>,
    /// Its ± [s] with those dampings free (linearised at the held fit).
    pub std_err: f64,
    /// Its ± [s] with them at zero exactly (the held fit's).
    pub std_err_held: f64,
}

/// The delays of `group` of `model` fitted beside dampings held at zero
/// (dampings at the delay's bearing that `base`, the base model, estimates
/// and `model` lacks; none where a loss factor stands in for them), each
/// with its ± from the fit with them free. `beta`, `nl`: the model's values after the group's ML refit; `held_fit`:
/// that refit's inference (the group's terms, then its scalars).
pub(super) fn held_delays(
    prep: &Prepared,
    model: &Model,
    base: &Model,
    group: &[usize],
    beta: &[f64],
    nl: &[f64],
    held_fit: &Inference,
) -> Vec<HeldDelay> {
    let scalars = model.group_nonlinear(group);
    let delays: Vec<(usize, Vec<Term>)> = scalars
        .iter()
        .filter_map(|&k| match model.nonlinear[k] {
            Nonlinear::Delay { bearing, .. } => Some((k, held_terms(base, model, bearing))),
            _ => None,
        })
        // A loss factor at the bearing is its damping: none is held there.
        .filter(|(k, _)| {
            let b = model.nonlinear[*k].bearing();
            !model
                .nonlinear
                .iter()
                .any(|n| matches!(n, Nonlinear::LossFactor { bearing } if *bearing == b))
        })
        .filter(|(_, held)| !held.is_empty())
        .collect();
    if delays.is_empty() {
        return Vec::new();
    }
    let mut freed: Vec<Term> = Vec::new();
    for t in delays.iter().flat_map(|(_, h)| h) {
        if !freed.contains(t) {
            freed.push(*t);
        }
    }
    let (extended, ext_beta) = with_freed(model, beta, &freed);
    let eq = GroupEquations::from_values(prep, &extended, group, &ext_beta, nl);
    let n_held = model.group_terms(group).len();
    let n_terms = eq.terms.len();
    // Units: a freed damping's scale is the damping the delay reads as,
    // τ·k [N·s/m]; none where there is no delay to trade with (τ or k
    // zero): nothing to widen.
    let Some((p, scale)) = eq.freed_start(model, beta, held_fit, |bearing, _, k| {
        let tau = delays
            .iter()
            .find(|(k, _)| model.nonlinear[*k].bearing() == bearing)
            .map_or(0.0, |(k, _)| nl[*k]);
        let s = (tau * k).abs();
        (s.is_finite() && s > 0.0).then_some(s)
    }) else {
        return Vec::new();
    };
    let Some((jac, resid, row_speed)) = linearised(&eq, &p, &scale) else {
        return Vec::new();
    };
    let Ok(inf) = serial::inference(
        prep,
        &eq.speeds,
        &jac,
        &resid,
        &row_speed,
        DVector::from_vec(p.clone()),
    ) else {
        return Vec::new();
    };
    delays
        .into_iter()
        .filter_map(|(k, held)| {
            let j = eq.nonlinear.iter().position(|&u| u == k)?;
            let std_err_held = held_fit.std_err(n_held + j);
            let free = inf.std_err(n_terms + j);
            free.is_finite().then(|| HeldDelay {
                nonlinear: k,
                held,
                std_err: free.max(std_err_held),
                std_err_held,
            })
        })
        .collect()
}
