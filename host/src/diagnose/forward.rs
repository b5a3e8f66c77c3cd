//! One forward step of the search: every library candidate fitted on top of
//! the current state, tested (Wald, Bonferroni over the step) and ranked.

use super::candidates::{library, Candidate, ParamRef};
use super::criterion::{Evidence, Inference};
use super::data::Prepared;
use super::fit::{fit_group, jacobian, profile, search_interval};
use super::model::Params;
use super::state::State;
use anyhow::{anyhow, bail, Result};
use nalgebra::{DMatrix, DVector};

/// A candidate fitted and tested.
#[derive(Clone, Debug)]
pub struct Evaluated {
    /// The candidate.
    pub candidate: Candidate,
    /// Parameters of the augmented model (whole machine).
    pub params: Params,
    /// Inference over the candidate's group.
    pub inference: Inference,
    /// Parameter of each inference entry.
    pub refs: Vec<ParamRef>,
    /// Evidence for the effect.
    pub evidence: Evidence,
}

impl Evaluated {
    /// The effect's own parameters: (name, value, standard error), SI units.
    pub fn effect_parameters(&self) -> Vec<(String, f64, f64)> {
        self.candidate
            .parameters
            .iter()
            .filter_map(|(name, r)| {
                let i = self.refs.iter().position(|x| x == r)?;
                Some((
                    name.clone(),
                    self.inference.estimate[i],
                    self.inference.std_err(i),
                ))
            })
            .collect()
    }
}

/// Fits a candidate on top of `state` and tests its null hypothesis.
pub fn evaluate(
    prep: &Prepared,
    state: &State,
    candidate: Candidate,
    tried: usize,
    n_total: usize,
) -> Result<Evaluated> {
    let model = &candidate.model;
    let nb = prep.bearings.len();
    let group = model
        .groups(nb)
        .into_iter()
        .find(|g| g.contains(&candidate.bearing))
        .ok_or_else(|| anyhow!("bearing index {} out of range", candidate.bearing))?;
    let mut nl = state.params.nl.clone();
    nl.resize(model.nonlinear.len(), 0.0);
    let fit = match candidate.new_nonlinear {
        Some(k) => {
            let interval = search_interval(prep, model, k, &group);
            let (s, fit) = profile(prep, model, &nl, &state.weights, &group, k, interval)?;
            at_an_edge(model, k, s, interval)?;
            nl[k] = s;
            fit
        }
        None => fit_group(prep, model, &nl, &state.weights, &group)?,
    };
    // Whole-machine parameters: the current values, the group refitted.
    let mut beta = super::bases::carried_linear(model, state);
    for (t, v) in fit.terms.iter().zip(&fit.beta) {
        beta[*t] = *v;
    }
    let params = Params { beta, nl };
    let nl_index = model.group_nonlinear(&group);
    let jac = jacobian(prep, model, &params.nl, &state.weights, &fit, &nl_index)?;
    let mut estimate = fit.beta.clone();
    estimate.extend(nl_index.iter().map(|&k| params.nl[k]));
    let mut refs: Vec<ParamRef> = fit.terms.iter().map(|&t| ParamRef::Term(t)).collect();
    refs.extend(nl_index.iter().map(|&k| ParamRef::Nonlinear(k)));
    let inference = Inference::new(
        &jac,
        &fit.residual,
        &fit.row_speed,
        DVector::from_vec(estimate),
    )?;
    let mut c = DMatrix::zeros(candidate.null.len(), refs.len());
    for (row, constraint) in candidate.null.iter().enumerate() {
        for (r, coef) in constraint {
            let col = refs
                .iter()
                .position(|x| x == r)
                .ok_or_else(|| anyhow!("constraint on a parameter outside the group"))?;
            c[(row, col)] = *coef;
        }
    }
    let evidence = inference.evidence(&c, tried, n_total)?;
    Ok(Evaluated {
        candidate,
        params,
        inference,
        refs,
        evidence,
    })
}

/// A bearing-table correction (clearance, stiffness ratio) whose profile
/// ends at an edge of its searched range is not an interior maximum of the
/// likelihood: the data do not determine it there (e.g. a stiff, nearly
/// undamped table, whose stiffness ratio is confounded with the pedestal's
/// scale, fitted to the noise law's leverage), and its Wald statistic does
/// not hold. The candidate is refused with the reason. Their nulls
/// (δ = 0) lie inside the range; the delay's and loss factor's nulls are
/// their edges and are not judged here.
fn at_an_edge(model: &super::model::Model, k: usize, s: f64, (lo, hi): (f64, f64)) -> Result<()> {
    use super::model::Nonlinear;
    let table = matches!(
        model.nonlinear[k],
        Nonlinear::Clearance { .. } | Nonlinear::StiffnessRatio { .. }
    );
    let tolerance = 1e-6 * (hi - lo);
    if table && (s - lo <= tolerance || hi - s <= tolerance) {
        bail!(
            "its fit ended at the edge of the searched range [{:.3}, {:.3}] of {} − 1: not determined by these data",
            lo,
            hi,
            model.nonlinear[k].name()
        );
    }
    Ok(())
}

/// The outcome of one step of the greedy search.
#[derive(Clone, Debug)]
pub struct StepOutcome {
    /// Candidates tried (all count in the Bonferroni correction).
    pub tried: usize,
    /// Candidates that could be fitted, best first (largest ΔBIC).
    pub ranked: Vec<Evaluated>,
    /// Candidates that could not be fitted, with the reason.
    pub failed: Vec<(Candidate, String)>,
    /// Whether the best candidate is significant.
    pub accepted: bool,
}

/// Tries every candidate on `state` and ranks them.
pub fn step(prep: &Prepared, state: &State, alpha: f64) -> StepOutcome {
    let cands = library(&state.model, prep.bearings.len());
    let tried = cands.len();
    let n_total: usize = (0..prep.bearings.len())
        .map(|b| 4 * prep.points[b].iter().flatten().count())
        .sum();
    let mut ranked = Vec::new();
    let mut failed = Vec::new();
    for c in cands {
        match evaluate(prep, state, c.clone(), tried, n_total) {
            Ok(e) if e.evidence.wald.is_finite() => ranked.push(e),
            Ok(_) => failed.push((c, "non-finite test statistic".to_string())),
            Err(err) => failed.push((c, format!("{err:#}"))),
        }
    }
    ranked.sort_by(|a, b| b.evidence.delta_bic.total_cmp(&a.evidence.delta_bic));
    let accepted = ranked
        .first()
        .is_some_and(|e| e.evidence.delta_bic > 0.0 && e.evidence.p_adjusted < alpha);
    StepOutcome {
        tried,
        ranked,
        failed,
        accepted,
    }
}
