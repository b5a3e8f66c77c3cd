//! A fitted pedestal model: the base model (the paper's eq. 3, `plinth
//! identify`'s fit), the joint refit of a model with its effects, and the
//! parameter inference of each group of pedestals.

use super::candidates::ParamRef;
use super::criterion::Inference;
use super::data::Prepared;
use super::fit::{fit_group, jacobian, profile, search_interval, Weights};
use super::gap::{Gap, Prediction};
use super::ml_final;
use super::model::{Model, Params, Term};
use super::report::Pedestal;
use anyhow::Result;
use nalgebra::DVector;
use plinth_shared::regression::Parameter;
use std::collections::BTreeMap;

/// The paper's pedestal model (eq. 3) restricted to `base`, for every bearing.
pub fn base_model(base: &[Parameter], n_bearings: usize) -> Model {
    let mut terms = Vec::new();
    for b in 0..n_bearings {
        for p in base {
            terms.push(match p {
                Parameter::Ky => Term::Stiffness { bearing: b, dir: 0 },
                Parameter::Kz => Term::Stiffness { bearing: b, dir: 1 },
                Parameter::M => Term::Mass {
                    bearing: b,
                    dir: None,
                },
                Parameter::Cy => Term::Damping { bearing: b, dir: 0 },
                Parameter::Cz => Term::Damping { bearing: b, dir: 1 },
            });
        }
    }
    Model {
        terms,
        nonlinear: Vec::new(),
        tables: Vec::new(),
    }
}

/// Inference of one group of pedestals: (bearing indices, inference, the
/// parameter of each estimate entry).
pub type GroupInference = (Vec<usize>, Inference, Vec<ParamRef>);

/// A fitted model with the weights it was fitted with.
#[derive(Clone, Debug)]
pub struct State {
    /// The model.
    pub model: Model,
    /// Its parameter values.
    pub params: Params,
    /// Noise weights propagated from these parameters.
    pub weights: Weights,
}

impl State {
    /// Fits `model` from scratch: weights from the rel noise alone, then
    /// reweighted with the fitted parameters until they settle (3 passes);
    /// nonlinear scalars start from `nl` and are re-profiled each pass.
    pub fn fit(prep: &Prepared, model: Model, nl: Vec<f64>) -> Result<Self> {
        let mut params = Params {
            beta: vec![0.0; model.terms.len()],
            nl,
        };
        for pass in 0..3 {
            let weights = Weights::propagate(prep, &model, &params);
            params = fit_all(
                prep,
                &model,
                &params,
                &weights,
                pass > 0 || params.nl.iter().all(|v| *v == 0.0),
            )?;
        }
        let weights = Weights::propagate(prep, &model, &params);
        Ok(Self {
            model,
            params,
            weights,
        })
    }

    /// The base model: with the paper's five parameters, the maximum-
    /// likelihood fit `plinth identify` makes (the same function, through
    /// [`Prepared::base_fits`]); with a reduced `--base`, the weighted fit of
    /// [`State::fit`].
    pub fn base(prep: &Prepared, base: &[Parameter]) -> Result<Self> {
        let model = base_model(base, prep.bearings.len());
        if base != Parameter::ALL.as_slice() || prep.base_fits.len() != prep.bearings.len() {
            return Self::fit(prep, model, Vec::new());
        }
        let beta: Vec<f64> = prep
            .base_fits
            .iter()
            .flat_map(|f| f.pedestal.theta())
            .collect();
        if beta.len() != model.terms.len() || !beta.iter().all(|v| v.is_finite()) {
            return Self::fit(prep, model, Vec::new());
        }
        let params = Params {
            beta,
            nl: Vec::new(),
        };
        let weights = Weights::propagate(prep, &model, &params);
        Ok(Self {
            model,
            params,
            weights,
        })
    }

    /// The pedestal stiffness and mass terms (k_y, k_z, m, m_y, m_z) whose
    /// value is negative: no passive pedestal has them.
    pub fn negative_pedestal_terms(&self) -> Vec<Term> {
        self.model
            .terms
            .iter()
            .zip(&self.params.beta)
            .filter(|(t, v)| matches!(t, Term::Stiffness { .. } | Term::Mass { .. }) && **v < 0.0)
            .map(|(t, _)| *t)
            .collect()
    }

    /// The pedestal-level prediction and gap of this state.
    pub fn gap(&self, prep: &Prepared) -> (Prediction, Gap) {
        let pred = Prediction::new(prep, &self.model, &self.params);
        let gap = pred.gap(prep, None);
        (pred, gap)
    }

    /// Parameter inference per group: (group, inference, parameter of each
    /// estimate entry).
    pub fn inference(&self, prep: &Prepared) -> Result<Vec<GroupInference>> {
        let mut out = Vec::new();
        for group in self.model.groups(prep.bearings.len()) {
            let (inf, refs) = infer_group(prep, &self.model, &self.params, &self.weights, &group)?;
            out.push((group, inf, refs));
        }
        Ok(out)
    }
}

/// Fits every group's linear parameters at the nonlinear values of `start`,
/// re-profiling each nonlinear scalar first when `profile_nl` is set.
fn fit_all(
    prep: &Prepared,
    model: &Model,
    start: &Params,
    weights: &Weights,
    profile_nl: bool,
) -> Result<Params> {
    let mut params = start.clone();
    for group in model.groups(prep.bearings.len()) {
        if profile_nl {
            for k in model.group_nonlinear(&group) {
                let full = search_interval(prep, model, k, &group);
                // Refine around the current value: ± two grid steps of the full search.
                let w = (full.1 - full.0) / 40.0;
                let s = params.nl[k];
                let around = ((s - w).max(full.0), (s + w).min(full.1));
                let (best, _) = profile(prep, model, &params.nl, weights, &group, k, around)?;
                params.nl[k] = best;
            }
        }
        let fit = fit_group(prep, model, &params.nl, weights, &group)?;
        for (t, v) in fit.terms.iter().zip(&fit.beta) {
            params.beta[*t] = *v;
        }
    }
    Ok(params)
}

/// Inference for one group: the Jacobian over its linear terms and nonlinear
/// scalars at the fitted values.
fn infer_group(
    prep: &Prepared,
    model: &Model,
    params: &Params,
    weights: &Weights,
    group: &[usize],
) -> Result<(Inference, Vec<ParamRef>)> {
    let fit = fit_group(prep, model, &params.nl, weights, group)?;
    let nl_index = model.group_nonlinear(group);
    let jac = jacobian(prep, model, &params.nl, weights, &fit, &nl_index)?;
    // The state's own values (for the base model: the maximum-likelihood
    // fit), with the covariance of the weighted fit at these weights.
    let mut estimate: Vec<f64> = fit.terms.iter().map(|&t| params.beta[t]).collect();
    estimate.extend(nl_index.iter().map(|&k| params.nl[k]));
    let mut refs: Vec<ParamRef> = fit.terms.iter().map(|&t| ParamRef::Term(t)).collect();
    refs.extend(nl_index.iter().map(|&k| ParamRef::Nonlinear(k)));
    let inf = Inference::new(
        &jac,
        &fit.residual,
        &fit.row_speed,
        DVector::from_vec(estimate),
    )?;
    Ok((inf, refs))
}

/// The inference per group whose ± [`pedestals`] reports, and whose
/// covariance every value derived from them uses (the modal view's f_n, ζ,
/// `super::cli::modal_views`): the weighted fit's ([`State::inference`]),
/// or, for a group whose values are the base model's maximum-likelihood fit
/// ([`ml_values`]), the ML engine's at those values
/// ([`ml_final::inference_at`]).
pub fn reported_inference(prep: &Prepared, state: &State) -> Result<Vec<GroupInference>> {
    Ok(state
        .inference(prep)?
        .into_iter()
        .map(|(group, inf, refs)| {
            let inf = ml_values(prep, state, &group)
                .then(|| {
                    let p = &inf.estimate;
                    let scale: Vec<f64> = (0..p.len())
                        .map(|i| p[i].abs().max(inf.std_err(i)).max(f64::MIN_POSITIVE))
                        .collect();
                    ml_final::inference_at(prep, state, &group, &scale)
                })
                .flatten()
                .unwrap_or(inf);
            (group, inf, refs)
        })
        .collect())
}

/// The pedestal parameters (k, m, c terms) of every bearing with their
/// reported standard errors ([`crate::diagnose::criterion::Inference::reported_std_err`]):
/// of the weighted fit's inference, or, at a pedestal whose values are the
/// base model's maximum-likelihood fit ([`ml_values`]), of the ML engine's
/// at those values ([`ml_final::inference_at`]).
pub fn pedestals(prep: &Prepared, state: &State) -> Result<Vec<Pedestal>> {
    let infs = reported_inference(prep, state)?;
    let mut out: Vec<Pedestal> = prep
        .bearings
        .iter()
        .map(|b| Pedestal {
            bearing: b.clone(),
            values: BTreeMap::new(),
            std_err: BTreeMap::new(),
        })
        .collect();
    for (_, inf, refs) in &infs {
        for (i, r) in refs.iter().enumerate() {
            let ParamRef::Term(k) = r else { continue };
            let t = state.model.terms[*k];
            if !t.is_pedestal() {
                continue;
            }
            if let [Some(b), None] = t.bearings() {
                out[b].values.insert(t.name(), inf.estimate[i]);
                out[b].std_err.insert(t.name(), inf.reported_std_err(i));
            }
        }
    }
    Ok(out)
}

/// Whether the values of `group` in `state` are the maximum-likelihood fit
/// of the paper's five-parameter model that `plinth identify` makes
/// ([`Prepared::base_fits`], taken over by [`State::base`]): one bearing,
/// no scalar, its five base terms valued exactly as that fit. Their ± are
/// then the ML engine's, with each speed's four real equations whitened by
/// their full covariance: the search's weights ([`Weights`]) give each
/// real equation its own variance and leave out the correlation a film's
/// cross terms put between the y and z equations, which left diagnose's ±
/// of such a pedestal 1.1-1.8 times identify's for the same values
/// (docs/unseen-six.md, "Session 46 (lowsnr17)", "4. Seen on the way").
fn ml_values(prep: &Prepared, state: &State, group: &[usize]) -> bool {
    let &[b] = group else {
        return false;
    };
    let Some(fit) = prep.base_fits.get(b) else {
        return false;
    };
    if prep.bearings.get(b) != Some(&fit.bearing) || !state.model.group_nonlinear(group).is_empty()
    {
        return false;
    }
    let terms = state.model.group_terms(group);
    let five = base_model(&Parameter::ALL, prep.bearings.len());
    let own: Vec<Term> = five
        .terms
        .iter()
        .filter(|t| t.bearings() == [Some(b), None])
        .copied()
        .collect();
    let theta = fit.pedestal.theta();
    terms.len() == own.len()
        && terms.len() == theta.len()
        && terms
            .iter()
            .zip(&own)
            .zip(&theta)
            .all(|((&t, u), v)| state.model.terms[t] == *u && state.params.beta[t] == *v)
}
