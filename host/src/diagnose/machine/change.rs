//! The noise of a step's machine-level gap change: how much the change
//! `machine_gap_after − machine_gap_before` of one step moves from one
//! noise draw to the next.
//!
//! The two models of a step are nested (the step's model is the one before
//! it plus the effect's parameters γ) and fitted to the same data, so their
//! estimates are strongly correlated and the change is far less noisy than
//! either gap (the machine-level floor). In a weighted linear fit the
//! smaller model's estimate is the larger one's moved along its regression
//! on γ̂ to γ = 0: the change of the parameters is a linear function of γ̂
//! alone, and the change of the gap, to first order ∇g·(θ̂_a − θ̂_b) with
//! ∇g the machine-level gap's gradient at the step's model, has variance
//! wᵀC_γγ⁻¹w, w = Cov(γ̂, ∇g·θ̂), from the step's model's covariance alone
//! (`Inference::floor_change_variance`). The covariance is the noise
//! floor's: the measurement noise, not the misfit a model without the
//! effect leaves (that is what the step removes, not noise). Measured
//! against the spread of the change over fresh noise draws in
//! docs/diagnose-verdict.md ("Session 39").

use super::{machine_gap, resimulate};
use crate::diagnose::candidates::ParamRef;
use crate::diagnose::data::Prepared;
use crate::diagnose::state::State;
use crate::sim::Machine;
use anyhow::Result;

/// The standard deviation of a step's machine-level gap change [-] (module
/// docs): `before` is the model the step extends (step 1: the base model
/// refitted as the steps fit it), `after` the step's model, `gap_after`
/// [-] the machine-level gap of `after`. The step's parameters are those
/// of `after` that `before` lacks; only their groups change. Each
/// parameter's gradient is a forward difference of 1 % of its ± (as
/// [`super::parameter_variance`]). A parameter `before` has and `after`
/// lacks (a damping the step holds, docs/diagnose-held-damping.md) is not
/// counted: the models are then nested only approximately.
///
/// `None` when the step adds no parameter, its block of the covariance is
/// singular, or a re-simulation fails. Steps on an identified base are not
/// passed here (its covariance is not the state's,
/// `crate::diagnose::base_floor`).
pub fn change_sd(
    machine: &Machine,
    prep: &Prepared,
    before: &State,
    after: &State,
    gap_after: f64,
) -> Result<Option<f64>> {
    let mut var = 0.0;
    let mut any = false;
    for (_, inf, refs) in after.inference(prep)? {
        // The step's own parameters: those `before` lacks. A group without
        // any is refitted to the same values (`State::fit` per group).
        let added: Vec<usize> = refs
            .iter()
            .enumerate()
            .filter(|(_, r)| counterpart(after, before, **r).is_none())
            .map(|(i, _)| i)
            .collect();
        if added.is_empty() {
            continue;
        }
        let mut g = Vec::with_capacity(refs.len());
        for (i, r) in refs.iter().enumerate() {
            let h = 0.01 * inf.std_err(i);
            if !(h.is_finite() && h > 0.0) {
                g.push(0.0);
                continue;
            }
            let mut shifted = after.clone();
            *value_mut(&mut shifted, *r) += h;
            let Ok(readings) = resimulate(machine, prep, &shifted, None) else {
                return Ok(None);
            };
            g.push((machine_gap(prep, &readings) - gap_after) / h);
        }
        let Some(v) = inf.floor_change_variance(&g, &added) else {
            return Ok(None);
        };
        var += v;
        any = true;
    }
    Ok(any.then(|| var.sqrt()))
}

/// The parameter `r` of `state` as a mutable value.
fn value_mut(state: &mut State, r: ParamRef) -> &mut f64 {
    match r {
        ParamRef::Term(k) => &mut state.params.beta[k],
        ParamRef::Nonlinear(k) => &mut state.params.nl[k],
    }
}

/// The parameter of `other` that is `of`'s `r` (the same term or
/// nonlinear scalar); `None` when `other` lacks it.
fn counterpart(of: &State, other: &State, r: ParamRef) -> Option<ParamRef> {
    match r {
        ParamRef::Term(k) => {
            let t = of.model.terms.get(k)?;
            other
                .model
                .terms
                .iter()
                .position(|u| u == t)
                .map(ParamRef::Term)
        }
        ParamRef::Nonlinear(k) => {
            let n = of.model.nonlinear.get(k)?;
            other
                .model
                .nonlinear
                .iter()
                .position(|u| u == n)
                .map(ParamRef::Nonlinear)
        }
    }
}
