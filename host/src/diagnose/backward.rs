//! The backward check's bookkeeping: a chosen library effect remembered by
//! what its parameters are (indices shift as the model grows), so it can be
//! tested again in a later joint refit and removed when no longer
//! significant.

use super::candidates::{Candidate, ParamRef};
use super::criterion::{Evidence, Inference};
use super::data::Prepared;
use super::fit::scalar_drop;
use super::model::{Model, Nonlinear, Term};
use super::state::State;
use nalgebra::DMatrix;

/// A parameter of a model by what it is (indices shift as models change).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Param {
    Term(Term),
    Nonlinear(Nonlinear),
}

/// A library effect chosen by a step: its null hypothesis over its own
/// parameters, by identity.
#[derive(Clone, Debug)]
pub(super) struct Chosen {
    /// Index of its step.
    pub(super) step: usize,
    /// Bearing index.
    bearing: usize,
    /// The effect.
    pub(super) effect: crate::effects::EffectKind,
    /// Its parameters, with the names the step reports them by.
    params: Vec<Param>,
    /// The names of `params` (`Candidate::parameters`).
    names: Vec<String>,
    /// Null hypothesis: Σ coef·param = 0 per row.
    null: Vec<Vec<(Param, f64)>>,
}

impl Chosen {
    pub(super) fn of(c: &Candidate, step: usize) -> Self {
        let id = |r: &ParamRef| match *r {
            ParamRef::Term(k) => Param::Term(c.model.terms[k]),
            ParamRef::Nonlinear(k) => Param::Nonlinear(c.model.nonlinear[k]),
        };
        Self {
            step,
            bearing: c.bearing,
            effect: c.effect,
            params: c.parameters.iter().map(|(_, r)| id(r)).collect(),
            names: c.parameters.iter().map(|(n, _)| n.clone()).collect(),
            null: c
                .null
                .iter()
                .map(|row| row.iter().map(|(r, v)| (id(r), *v)).collect())
                .collect(),
        }
    }

    /// The effect's evidence in the joint fit of `state` (`checked`: the
    /// Bonferroni count); `None` when it cannot be tested.
    pub(super) fn evidence(
        &self,
        prep: &Prepared,
        state: &State,
        checked: usize,
        n_total: usize,
    ) -> Option<Evidence> {
        evidence_against(prep, state, self.bearing, &self.null, checked, n_total)
    }

    /// Its bearing's index.
    pub(super) fn bearing(&self) -> usize {
        self.bearing
    }

    /// Its parameters with their names, by identity.
    pub(super) fn named_params(&self) -> impl Iterator<Item = (&str, Param)> + '_ {
        self.names
            .iter()
            .map(String::as_str)
            .zip(self.params.iter().copied())
    }

    /// Number of constraints of its null hypothesis (its q).
    pub(super) fn null_len(&self) -> usize {
        self.null.len()
    }

    /// `model` without this effect (a split mass joined again).
    pub(super) fn removed_from(&self, model: &Model) -> Model {
        let mut m = model.clone();
        let split_mass = self
            .params
            .iter()
            .any(|p| matches!(p, Param::Term(Term::Mass { dir: Some(_), .. })));
        m.terms.retain(|t| !self.params.contains(&Param::Term(*t)));
        m.nonlinear
            .retain(|n| !self.params.contains(&Param::Nonlinear(*n)));
        if split_mass {
            m.terms.push(Term::Mass {
                bearing: self.bearing,
                dir: None,
            });
        }
        m
    }
}

/// The evidence in `state`'s joint fit against the constraints `null` (one
/// row of (parameter, coefficient) per constraint) on the parameters of
/// the group holding `bearing` (`checked`: the Bonferroni count, `n_total`
/// the BIC's N); `None` when they cannot be tested.
///
/// A null that sets one profiled scalar to zero (a delay, a loss factor, a
/// table's clearance or stiffness ratio) is tested by the likelihood ratio
/// the forward step chose it by ([`scalar_drop`], the same function):
/// the Wald form's curvature at the estimate overstates the drop where the
/// scalar trades against a linear term at its null (module docs of
/// `super::criterion`, "Profiled scalars"), and with the ratio in one test
/// and the Wald form in the other the backward check could drop what the
/// forward step chose, or keep what it would not have chosen. Any other
/// null: the Wald statistic.
pub(super) fn evidence_against(
    prep: &Prepared,
    state: &State,
    bearing: usize,
    null: &[Vec<(Param, f64)>],
    checked: usize,
    n_total: usize,
) -> Option<Evidence> {
    let (group, inf, c) = constraints(prep, state, bearing, null)?;
    match profiled_scalar(&state.model, null) {
        Some(k) => {
            let lr = scalar_drop(
                prep,
                &state.model,
                &state.params.nl,
                &state.weights,
                &group,
                k,
            )
            .ok()?;
            inf.evidence_profiled(&c, lr, checked, n_total).ok()
        }
        None => inf.evidence(&c, checked, n_total).ok(),
    }
}

/// The group holding `bearing` in `state`'s joint fit, its inference and
/// the constraints `null` as rows over that inference's parameters; `None`
/// when a parameter of `null` is not among them.
pub(super) fn constraints(
    prep: &Prepared,
    state: &State,
    bearing: usize,
    null: &[Vec<(Param, f64)>],
) -> Option<(Vec<usize>, Inference, DMatrix<f64>)> {
    let infs = state.inference(prep).ok()?;
    let (group, inf, refs) = infs.into_iter().find(|(g, _, _)| g.contains(&bearing))?;
    let position = |p: &Param| {
        refs.iter().position(|r| match (*r, p) {
            (ParamRef::Term(k), Param::Term(t)) => state.model.terms[k] == *t,
            (ParamRef::Nonlinear(k), Param::Nonlinear(n)) => state.model.nonlinear[k] == *n,
            _ => false,
        })
    };
    let mut c = DMatrix::zeros(null.len(), refs.len());
    for (row, constraint) in null.iter().enumerate() {
        for (p, coef) in constraint {
            c[(row, position(p)?)] = *coef;
        }
    }
    Some((group, inf, c))
}

/// The index in `model` of the one profiled scalar `null` sets to zero
/// (one constraint on one nonlinear parameter); `None` for any other null.
fn profiled_scalar(model: &Model, null: &[Vec<(Param, f64)>]) -> Option<usize> {
    let [row] = null else { return None };
    let [(Param::Nonlinear(n), coef)] = row.as_slice() else {
        return None;
    };
    if *coef == 0.0 {
        return None;
    }
    model.nonlinear.iter().position(|m| m == n)
}

#[cfg(test)]
mod tests;
