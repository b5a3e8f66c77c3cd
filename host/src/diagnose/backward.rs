//! The backward check's bookkeeping: a chosen library effect remembered by
//! what its parameters are (indices shift as the model grows), so it can be
//! tested again in a later joint refit and removed when no longer
//! significant.

use super::candidates::{Candidate, ParamRef};
use super::criterion::Evidence;
use super::data::Prepared;
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
    /// Its parameters.
    params: Vec<Param>,
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
            params: c.parameters.iter().map(|(_, r)| id(r)).collect(),
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
pub(super) fn evidence_against(
    prep: &Prepared,
    state: &State,
    bearing: usize,
    null: &[Vec<(Param, f64)>],
    checked: usize,
    n_total: usize,
) -> Option<Evidence> {
    let infs = state.inference(prep).ok()?;
    let (_, inf, refs) = infs.iter().find(|(g, _, _)| g.contains(&bearing))?;
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
    inf.evidence(&c, checked, n_total).ok()
}
