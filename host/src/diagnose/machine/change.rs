//! The noise of a step's machine-level gap change: how much the change
//! `machine_gap_after − machine_gap_before` of one step moves from one
//! noise draw to the next.
//!
//! The two models of a step are both one model (the step's, plus any
//! damping the step holds at zero) with some parameters at zero, fitted to
//! the same data, so their estimates are strongly correlated and the change
//! is far less noisy than either gap (the machine-level floor). In a
//! weighted linear fit a model without the parameters R has the larger
//! one's estimate moved along its regression on θ̂_R to θ_R = 0: both
//! estimates are linear functions of the larger model's, and the change of
//! the gap, to first order ∇g_a·θ̂_a − ∇g_b·θ̂_b, has the variance
//! `Inference::floor_change_variance` gives. The gradient is taken at both
//! models: the gap (a norm dominated by model error) bends between them,
//! and with the gradient at the step's model only (session 39) the sd was
//! a sixth of the change's seed-to-seed spread on unseen-flex's runout
//! (docs/diagnose-verdict.md "Session 40 (stepsd17)"). That holds for
//! every bearing's parameters, not only the step's: a bearing both models
//! fit alike has the same estimate in both, yet its noise moves the two
//! gaps differently (session 41, docs/diagnose-verdict.md, Session 41 (stepsd17b)). The
//! covariance is the noise floor's: the
//! measurement noise, not the misfit a model without the effect leaves
//! (that is what the step removes, not noise). Both gaps also compare the
//! readings with the same measured numbers: that noise is added
//! ([`direct_variance`]), as independent of the parameters' (an
//! approximation: the parameters are fitted to those numbers too).

use super::{machine_gap, resimulate, Readings};
use crate::diagnose::candidates::ParamRef;
use crate::diagnose::data::Prepared;
use crate::diagnose::state::State;
use crate::sim::Machine;
use anyhow::Result;

/// The standard deviation of a step's machine-level gap change [-] (module
/// docs): `before` is the model the step extends (step 1: the base model
/// refitted as the steps fit it) with its re-simulated readings and
/// machine-level gap [-], `after` the step's model with its readings and
/// gap [-]. Two parts, added as independent:
///
/// - the parameters' noise: both models are `after`'s model with the
///   parameters `before` lacks (the step's) or `after` lacks (a damping
///   the step holds at zero, docs/diagnose-held-damping.md) held at zero,
///   so the change is a linear function of the union model's estimate
///   ([`crate::diagnose::criterion::Inference::floor_change_variance`]),
///   with the gap's gradient taken at both models (each parameter's a
///   forward difference of 1 % of its ± in the union model, as
///   [`super::parameter_variance`]): the gap bends between them. The
///   groups (bearings) holding a parameter one of the models lacks change
///   their estimates; the others keep theirs, but the gap's gradient along
///   them differs between the two models, so their noise enters too
///   (u = ∇g_a − ∇g_b; without it the sd of a delay step holding a damping
///   at zero on unseen-flex was a nineteenth of its spread,
///   docs/diagnose-verdict.md, Session 41 (stepsd17b)).
/// - the measurements' own noise: both gaps compare the readings with the
///   same measured numbers ([`direct_variance`]).
///
/// `None` when the two models differ in no parameter, a block of the
/// covariance is singular, or a re-simulation fails. Steps on an
/// identified base are not passed here (its covariance is not the state's,
/// `crate::diagnose::base_floor`).
pub fn change_sd(
    machine: &Machine,
    prep: &Prepared,
    before: (&State, &Readings, f64),
    after: (&State, &Readings, f64),
) -> Result<Option<f64>> {
    let ((before, rb, gap_before), (after, ra, gap_after)) = (before, after);
    let union = union_of(after, before);
    // A union whose held damping cannot be told from the delay (a singular
    // Jacobian): the step's own parameters alone, as the nested case.
    let (union, groups) = match union.inference(prep) {
        Ok(g) => (union, g),
        Err(_) => (after.clone(), after.inference(prep)?),
    };
    let mut var = 0.0;
    let mut any = false;
    for (_, inf, refs) in groups {
        let absent = |of: &State| -> Vec<usize> {
            refs.iter()
                .enumerate()
                .filter(|(_, r)| counterpart(&union, of, **r).is_none())
                .map(|(i, _)| i)
                .collect()
        };
        let (absent_a, absent_b) = (absent(after), absent(before));
        let (mut g_a, mut g_b) = (vec![0.0; refs.len()], vec![0.0; refs.len()]);
        for (i, r) in refs.iter().enumerate() {
            let h = 0.01 * inf.std_err(i);
            if !(h.is_finite() && h > 0.0) {
                continue;
            }
            for (state, gap, g) in [(after, gap_after, &mut g_a), (before, gap_before, &mut g_b)] {
                if let Some(r) = counterpart(&union, state, *r) {
                    let Some(d) = slope(machine, prep, state, r, h, gap) else {
                        return Ok(None);
                    };
                    g[i] = d;
                }
            }
        }
        let Some(v) = inf.floor_change_variance(&g_a, &g_b, &absent_a, &absent_b) else {
            return Ok(None);
        };
        var += v;
        // A group both models fit alike (every parameter in both) moves the
        // change only through the gap's bending; it does not make a step.
        any |= !(absent_a.is_empty() && absent_b.is_empty());
    }
    if !any {
        return Ok(None);
    }
    let direct = direct_variance(prep, (rb, gap_before), (ra, gap_after));
    Ok(Some((var + direct).sqrt()))
}

/// `after`'s model with the linear terms `before` has and `after` lacks
/// (dampings the step holds at zero) appended, at zero: the model both are
/// restrictions of.
fn union_of(after: &State, before: &State) -> State {
    let mut union = after.clone();
    for t in &before.model.terms {
        if !union.model.terms.contains(t) {
            union.model.terms.push(*t);
            union.params.beta.push(0.0);
        }
    }
    union
}

/// The variance [-²] of a step's gap change from the measured numbers'
/// own noise, the parameters held: the gap g = √(Σ|x − y|² / Σ|y|²) of
/// readings x against measurements y moves with y by
/// ∂g/∂y = −((x − y) + g²·y) / (g·Σ|y|²), so the change g_after − g_before
/// by the difference of the two, each real number weighted by its noise
/// variance (`Observation::var`). `before`, `after`: each model's
/// re-simulated readings and gap [-].
fn direct_variance(prep: &Prepared, before: (&Readings, f64), after: (&Readings, f64)) -> f64 {
    let mut den = 0.0;
    for p in prep.points.iter().flatten().flatten() {
        for d in 0..2 {
            den += p.rel[d].norm_sqr() + p.ped[d].norm_sqr();
        }
    }
    if !(den > 0.0 && before.1 > 0.0 && after.1 > 0.0) {
        return 0.0;
    }
    let mut v = 0.0;
    for (b, row) in prep.points.iter().enumerate() {
        for (j, p) in row.iter().enumerate() {
            let Some(p) = p else { continue };
            let (Some((ra, pa)), Some((rb, pb))) = (after.0[b][j], before.0[b][j]) else {
                continue;
            };
            // Channels in `Observation::var`'s order: rel y, rel z, ped y, ped z.
            let y = [p.rel[0], p.rel[1], p.ped[0], p.ped[1]];
            let xa = [ra[0], ra[1], pa[0], pa[1]];
            let xb = [rb[0], rb[1], pb[0], pb[1]];
            for k in 0..4 {
                let slope =
                    |x: num_complex::Complex<f64>, g: f64| -((x - y[k]) + y[k] * g * g) / (g * den);
                let d = slope(xa[k], after.1) - slope(xb[k], before.1);
                v += d.re * d.re * p.var[2 * k] + d.im * d.im * p.var[2 * k + 1];
            }
        }
    }
    v
}

/// The machine-level gap's slope [1/unit of the parameter] along the
/// parameter `r` of `state` (whose gap is `gap` [-]): a forward difference
/// of `h`. `None` when the shifted model cannot be simulated.
fn slope(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    r: ParamRef,
    h: f64,
    gap: f64,
) -> Option<f64> {
    let mut shifted = state.clone();
    *value_mut(&mut shifted, r) += h;
    let readings = resimulate(machine, prep, &shifted, None).ok()?;
    Some((machine_gap(prep, &readings) - gap) / h)
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
