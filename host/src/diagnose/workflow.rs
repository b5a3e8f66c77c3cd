//! The discrepancy workflow: fit the base model, measure the gap, then add
//! the best-supported missing effect, one at a time (forward selection over
//! the whole library, the bases included), while the evidence is
//! significant relative to the noise floor. After each effect added the
//! whole model is refitted jointly, and every earlier effect must still be
//! significant in that joint fit (backward check, Bonferroni over the
//! effects checked); one that is not is removed again. The bases
//! (`foundation_coupling`, `pedestal_sub_base`) are tried in every round on
//! the data the chosen sensor and table effects correct.

use super::bearing_table::WrittenTable;
use super::candidates::{library, Candidate, ParamRef};
pub use super::correct::corrected;
use super::correct::corrections_only;
use super::criterion::{Evidence, Inference};
use super::data::Prepared;
use super::fit::{fit_group, jacobian, profile, search_interval, Weights};
use super::foundation::{self, FoundationFit};
use super::gap::{Gap, Prediction};
use super::locate::locate;
use super::model::{Model, Nonlinear, Params, Term};
use super::noise::CHANNELS;
use super::report::{CandidateSummary, Diagnosis, Estimate, NoiseSummary, Pedestal, Step};
use super::trust::{as_pedestal_fit, conclude};
use crate::effects::EffectKind;
use crate::rundir::RunDir;
use crate::sim::oil_film::OilFilmBearing;
use anyhow::{anyhow, Result};
use nalgebra::{DMatrix, DVector};
use plinth_shared::regression::Parameter;
use std::collections::BTreeMap;

/// Settings of the workflow.
#[derive(Clone, Debug)]
pub struct Options {
    /// Parameters of the base pedestal model (default: the paper's five).
    pub base: Vec<Parameter>,
    /// Family-wise significance level per step (Bonferroni over candidates).
    pub alpha: f64,
    /// Most effects to add.
    pub max_steps: usize,
    /// A progress line on stderr (only on a terminal, after a second).
    pub progress: bool,
    /// Bootstrap replicates of the `foundation_coupling` test (0: the
    /// candidate is not tried).
    pub foundation_replicates: usize,
    /// Seed of that bootstrap.
    pub foundation_seed: u64,
    /// Oil-film geometry of bearings (by name) from the machine file: the
    /// `bearing_coefficients` candidate of those bearings
    /// ([`super::bearing_table`]).
    pub oil_films: Vec<(String, OilFilmBearing)>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            base: Parameter::ALL.to_vec(),
            alpha: 1e-3,
            max_steps: 8,
            progress: false,
            foundation_replicates: foundation::REPLICATES,
            foundation_seed: foundation::SEED,
            oil_films: Vec::new(),
        }
    }
}

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
        let beta: Vec<f64> = prep.base_fits.iter().flat_map(|f| f.params()).collect();
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
            nl[k] = s;
            fit
        }
        None => fit_group(prep, model, &nl, &state.weights, &group)?,
    };
    // Whole-machine parameters: the current values, the group refitted.
    let mut beta: Vec<f64> = model
        .terms
        .iter()
        .map(|t| {
            state
                .model
                .terms
                .iter()
                .position(|u| u == t)
                .map_or(0.0, |i| state.params.beta[i])
        })
        .collect();
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

/// Everything a diagnosis computed: the report and the fitted states (base
/// model first, then after each step) for plots.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The report.
    pub diagnosis: Diagnosis,
    /// The arranged measurements.
    pub prep: Prepared,
    /// The base model's fit, then the fit after each step.
    pub states: Vec<State>,
    /// `foundation_coupling` when chosen: the bases and pedestals on them
    /// (the last state keeps the rigid fit of the bearings on no base).
    pub foundation: Option<FoundationFit>,
}

/// Runs the whole workflow on a run directory at the pedestal level.
///
/// `foundation_coupling` (pedestals on a shared, unmeasured base,
/// [`super::foundation`]) is tried on the base model in the first round,
/// next to the library; it wins when its bootstrap test is significant, it
/// brings the gap down, and further down than the best significant library
/// candidate does. Its model has no further effects on top, so the search ends
/// there.
pub fn diagnose(run: &RunDir, opts: &Options) -> Result<Outcome> {
    let prep = Prepared::from_run(run)?;
    let mut state = State::base(&prep, &opts.base)?;
    state.model.tables = written_tables(&prep, &opts.oil_films);
    let (pred0, gap0) = state.gap(&prep);
    let where_before = locate(&prep, &state.model, &state.params, &pred0);
    let pedestals_before = pedestals(&prep, &state)?;
    let mut states = vec![state.clone()];
    let mut steps = Vec::new();
    let mut best_rejected = None;
    let try_bases = opts.base == Parameter::ALL.as_slice() && opts.foundation_replicates > 0;
    // The shared base as tried on the base model (reported whether chosen
    // or not); later rounds try it again on the data the chosen sensor and
    // table effects correct.
    let mut foundation_tried = None;
    let mut chosen_foundation: Option<FoundationFit> = None;
    // The library effects chosen so far (for the backward check).
    let mut chosen: Vec<Chosen> = Vec::new();
    // The data the chosen base was fitted to (sensor and table effects
    // of the state applied).
    let mut base_prep: Option<Prepared> = None;
    let mut ticker = crate::progress::Ticker::new(
        "diagnose: candidate-effect rounds",
        opts.max_steps,
        opts.progress,
    );
    for round in 0..opts.max_steps {
        ticker.tick(round);
        let outcome = step(&prep, &state, opts.alpha);
        let (_, before) = state.gap(&prep);
        // What a base must beat: the library's best significant candidate
        // (refitted), or the current state when none is significant. The
        // tests' statistics are whitened differently, so the comparison is
        // on one yardstick, the pedestal-level χ² ([`Prediction::chi2`]),
        // with the Schwarz penalty ln N per parameter added (a base has 6
        // per base, a library effect its own few).
        let criterion = |pred: &Prediction, data: &Prepared, q: usize| {
            let (chi2, n) = pred.chi2(data);
            chi2 + q as f64 * (n.max(2) as f64).ln()
        };
        let to_beat = match outcome.ranked.first().filter(|_| outcome.accepted) {
            Some(e) => criterion(
                &Prediction::new(&prep, &e.candidate.model, &e.params),
                &prep,
                e.candidate.null.len(),
            ),
            None => criterion(
                &Prediction::new(&prep, &state.model, &state.params),
                &prep,
                0,
            ),
        };
        if try_bases && corrections_only(&state.model) {
            let bases = try_bases_on(&prep, &state, opts, round == 0)?;
            if round == 0 {
                foundation_tried = bases.shared.clone();
            }
            let best_base = [bases.shared, bases.sub_base]
                .into_iter()
                .flatten()
                .map(|f| {
                    let c = criterion(&f.prediction, &bases.prep, f.grouping.q);
                    (f, c)
                })
                .filter(|(f, c)| {
                    f.test.significant(opts.alpha)
                        && f.evidence.delta_bic > 0.0
                        && before.gap > super::foundation::TRY_ABOVE_FLOOR * before.floor
                        && f.gap.gap < before.gap
                        && *c < to_beat
                })
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(f, _)| f);
            if let Some(f) = best_base {
                let first = f.grouping.groups[0][0];
                steps.push(Step {
                    effect: f.kind.effect().to_string(),
                    bearing: prep.bearings[first].clone(),
                    gap_before: before.gap,
                    gap_after: f.gap.gap,
                    gap_floor_after: f.gap.floor,
                    machine_gap_before: None,
                    machine_gap_after: None,
                    channels: None,
                    parameters: f.parameters(&prep),
                    test: f.test.test.clone(),
                    foundation: Some(f.report(&prep)),
                    evidence: f.evidence,
                    runner_up: outcome
                        .ranked
                        .first()
                        .map(|e| summary(&prep, e, outcome.tried)),
                    candidates_tried: outcome.tried + 2,
                    candidates_failed: outcome.failed.len(),
                    dropped: None,
                });
                chosen_foundation = Some(f);
                base_prep = Some(bases.prep);
                break;
            }
        }
        if !outcome.accepted {
            best_rejected = outcome
                .ranked
                .first()
                .map(|e| summary(&prep, e, outcome.tried));
            break;
        }
        let win = &outcome.ranked[0];
        let next = State::fit(&prep, win.candidate.model.clone(), win.params.nl.clone())?;
        let (_, after) = next.gap(&prep);
        let parameters = effect_estimates(&prep, &next, &win.candidate)?;
        steps.push(Step {
            effect: win.candidate.effect.name().to_string(),
            bearing: prep.bearings[win.candidate.bearing].clone(),
            gap_before: before.gap,
            gap_after: after.gap,
            gap_floor_after: after.floor,
            machine_gap_before: None,
            machine_gap_after: None,
            channels: win.candidate.variant.clone(),
            parameters,
            test: wald_test(outcome.tried),
            foundation: None,
            evidence: win.evidence,
            runner_up: outcome
                .ranked
                .get(1)
                .map(|e| summary(&prep, e, outcome.tried)),
            candidates_tried: outcome.tried,
            candidates_failed: outcome.failed.len(),
            dropped: None,
        });
        chosen.push(Chosen::of(&win.candidate, steps.len() - 1));
        state = next;
        // Backward check: every earlier effect must still be significant in
        // the joint refit (Bonferroni over the effects checked).
        if chosen.len() > 1 {
            let n_total: usize = (0..prep.bearings.len())
                .map(|b| 4 * prep.points[b].iter().flatten().count())
                .sum();
            let earlier = chosen.len() - 1;
            let mut weakest: Option<(usize, Evidence)> = None;
            for (i, c) in chosen[..earlier].iter().enumerate() {
                let Some(ev) = c.evidence(&prep, &state, earlier, n_total) else {
                    continue;
                };
                let still = ev.delta_bic > 0.0 && ev.p_adjusted < opts.alpha;
                if !still && weakest.is_none_or(|(_, w)| ev.p_value > w.p_value) {
                    weakest = Some((i, ev));
                }
            }
            if let Some((i, ev)) = weakest {
                let c = chosen.remove(i);
                let model = c.removed_from(&state.model);
                let nl = model
                    .nonlinear
                    .iter()
                    .map(|p| {
                        state
                            .model
                            .nonlinear
                            .iter()
                            .position(|q| q == p)
                            .map_or(0.0, |k| state.params.nl[k])
                    })
                    .collect();
                state = State::fit(&prep, model, nl)?;
                steps[c.step].dropped = Some(format!(
                    "not significant in the joint refit after step {} (ΔBIC {:.1}, adjusted p {:.2e})",
                    steps.len(),
                    ev.delta_bic,
                    ev.p_adjusted
                ));
            }
        }
        states.push(state.clone());
    }
    let (pred1, gap1) = match &chosen_foundation {
        Some(f) => (f.prediction.clone(), f.gap),
        None => state.gap(&prep),
    };
    let where_after = locate(
        base_prep.as_ref().unwrap_or(&prep),
        &state.model,
        &state.params,
        &pred1,
    );
    let mut pedestals_after = pedestals(&prep, &state)?;
    if let Some(f) = &chosen_foundation {
        for (b, p) in pedestals_after.iter_mut().enumerate() {
            if let Some((theta, se)) = f.pedestal(b) {
                for (k, q) in Parameter::ALL.iter().enumerate() {
                    p.values.insert(q.name().to_string(), theta[k]);
                    p.std_err.insert(q.name().to_string(), se[k]);
                }
            }
        }
    }
    let effects_added: Vec<String> = steps
        .iter()
        .filter(|s| s.dropped.is_none())
        .map(|s| s.effect.clone())
        .collect();
    let physical: Vec<_> = pedestals_after
        .iter()
        .filter_map(|p| as_pedestal_fit(&prep, p))
        .collect();
    let conclusion = conclude(gap0, gap1, &steps, &physical);
    let unexplained = if conclusion.verdict.contains(super::trust::UNEXPLAINED) {
        super::locate::unexplained(&where_after, super::trust::AT_THE_FLOOR)
    } else {
        Vec::new()
    };
    let mut digits = BTreeMap::new();
    for (c, q) in prep.noise.columns.iter().enumerate() {
        digits.insert(CHANNELS[c].to_string(), q.digits);
    }
    let mut bearings_noise = BTreeMap::new();
    for (b, name) in prep.bearings.iter().enumerate() {
        if let Some(summary) = prep.noise.summary(b) {
            bearings_noise.insert(name.clone(), summary);
        }
    }
    let diagnosis = Diagnosis {
        base_model: opts.base.iter().map(|p| p.name().to_string()).collect(),
        steps,
        effects_added,
        gap_before: gap0.gap,
        gap_after: gap1.gap,
        machine_gap_before: None,
        machine_gap_after: None,
        noise: NoiseSummary {
            digits,
            bearings: bearings_noise,
            gap_floor_before: gap0.floor,
            gap_floor_after: gap1.floor,
        },
        where_before,
        where_after,
        pedestals_before,
        pedestals_after,
        best_rejected,
        foundation: foundation_tried.as_ref().map(|f| f.report(&prep)),
        significance_level: opts.alpha,
        verdict: conclusion.verdict,
        trusted: conclusion.trusted,
        trust_reasons: conclusion.reasons,
        unexplained,
        suspected_convention_errors: crate::identify::convention::findings_for_run(run, &opts.base),
    };
    Ok(Outcome {
        diagnosis,
        prep,
        states,
        foundation: chosen_foundation,
    })
}

/// A parameter of a model by what it is (indices shift as models change).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Param {
    Term(Term),
    Nonlinear(Nonlinear),
}

/// A library effect chosen by a step: its null hypothesis over its own
/// parameters, by identity.
#[derive(Clone, Debug)]
struct Chosen {
    /// Index of its step.
    step: usize,
    /// Bearing index.
    bearing: usize,
    /// Its parameters.
    params: Vec<Param>,
    /// Null hypothesis: Σ coef·param = 0 per row.
    null: Vec<Vec<(Param, f64)>>,
}

impl Chosen {
    fn of(c: &Candidate, step: usize) -> Self {
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
    fn evidence(
        &self,
        prep: &Prepared,
        state: &State,
        checked: usize,
        n_total: usize,
    ) -> Option<Evidence> {
        let infs = state.inference(prep).ok()?;
        let (_, inf, refs) = infs.iter().find(|(g, _, _)| g.contains(&self.bearing))?;
        let position = |p: &Param| {
            refs.iter().position(|r| match (*r, p) {
                (ParamRef::Term(k), Param::Term(t)) => state.model.terms[k] == *t,
                (ParamRef::Nonlinear(k), Param::Nonlinear(n)) => state.model.nonlinear[k] == *n,
                _ => false,
            })
        };
        let mut c = DMatrix::zeros(self.null.len(), refs.len());
        for (row, constraint) in self.null.iter().enumerate() {
            for (p, coef) in constraint {
                c[(row, position(p)?)] = *coef;
            }
        }
        inf.evidence(&c, checked, n_total).ok()
    }

    /// `model` without this effect (a split mass joined again).
    fn removed_from(&self, model: &Model) -> Model {
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

/// The base candidates of one round, fitted to the data the state corrects.
struct BaseCandidates {
    /// The corrected data.
    prep: Prepared,
    /// `foundation_coupling`, when it could be fitted.
    shared: Option<FoundationFit>,
    /// `pedestal_sub_base`, when it could be fitted.
    sub_base: Option<FoundationFit>,
}

/// Fits and tests both base models on the data `state` corrects, starting
/// from (and simulating the null from) the state's pedestals; on the base
/// model (`first`) from `plinth identify`'s fits, as before any effect.
fn try_bases_on(
    prep: &Prepared,
    state: &State,
    opts: &Options,
    first: bool,
) -> Result<BaseCandidates> {
    let cprep = corrected(prep, state);
    let nb = prep.bearings.len();
    let start: Option<Vec<[f64; 5]>> = if first {
        None
    } else {
        let value = |t: Term| {
            state
                .model
                .terms
                .iter()
                .position(|u| *u == t)
                .map(|i| state.params.beta[i])
        };
        (0..nb)
            .map(|b| {
                Some([
                    value(Term::Stiffness { bearing: b, dir: 0 })?,
                    value(Term::Stiffness { bearing: b, dir: 1 })?,
                    value(Term::Mass {
                        bearing: b,
                        dir: None,
                    })?,
                    value(Term::Damping { bearing: b, dir: 0 })?,
                    value(Term::Damping { bearing: b, dir: 1 })?,
                ])
            })
            .collect()
    };
    if !first && start.is_none() {
        return Ok(BaseCandidates {
            prep: cprep,
            shared: None,
            sub_base: None,
        });
    }
    // The rigid model on the corrected data: the state less its corrections.
    let rigid = base_model(&opts.base, nb);
    let params = Params {
        beta: rigid
            .terms
            .iter()
            .map(|t| {
                state
                    .model
                    .terms
                    .iter()
                    .position(|u| u == t)
                    .map_or(0.0, |i| state.params.beta[i])
            })
            .collect(),
        nl: Vec::new(),
    };
    let pred = Prediction::new(&cprep, &rigid, &params);
    let gap = pred.gap(&cprep, None);
    // A base fit that cannot run is "not tried", not an error.
    let run = |kind| {
        foundation::evaluate(
            &cprep,
            &pred,
            gap,
            opts.alpha,
            opts.foundation_replicates,
            opts.foundation_seed,
            kind,
            start.clone(),
        )
        .ok()
        .flatten()
    };
    let shared = run(foundation::Kind::Shared);
    let sub_base = run(foundation::Kind::SubBase);
    Ok(BaseCandidates {
        prep: cprep,
        shared,
        sub_base,
    })
}

/// The name of the library's test, with the Bonferroni count.
fn wald_test(tried: usize) -> String {
    format!("Wald, χ² with Bonferroni over {tried} candidates")
}

/// The candidate as a report entry (`tried`: candidates of its step).
fn summary(prep: &Prepared, e: &Evaluated, tried: usize) -> CandidateSummary {
    CandidateSummary {
        effect: e.candidate.effect.name().to_string(),
        bearing: prep.bearings[e.candidate.bearing].clone(),
        channels: e.candidate.variant.clone(),
        test: wald_test(tried),
        evidence: e.evidence,
        parameters: as_reported(
            &e.candidate.model,
            e.candidate.bearing,
            e.candidate.effect,
            e.effect_parameters()
                .into_iter()
                .map(|(name, value, std_err)| Estimate {
                    name,
                    value,
                    std_err,
                })
                .collect(),
        ),
    }
}

/// The oil-film table of every bearing of `prep` whose geometry `films`
/// gives and whose table it reproduces ([`WrittenTable::matched`]).
pub fn written_tables(
    prep: &Prepared,
    films: &[(String, OilFilmBearing)],
) -> Vec<Option<WrittenTable>> {
    prep.bearings
        .iter()
        .enumerate()
        .map(|(b, name)| {
            let (_, film) = films.iter().find(|(n, _)| n == name)?;
            let table: Vec<_> = prep.points[b]
                .iter()
                .flatten()
                .map(|p| (p.speed_hz, p.kstar))
                .collect();
            WrittenTable::matched(film, &table)
        })
        .collect()
}

/// An effect's estimates as reported: the clearance scalar δ of
/// `bearing_coefficients` as `clearance_ratio` = 1 + δ, with the written
/// and the true clearance [m].
fn as_reported(
    model: &Model,
    bearing: usize,
    effect: EffectKind,
    raw: Vec<Estimate>,
) -> Vec<Estimate> {
    if effect.name() != super::candidates::BEARING_COEFFICIENTS {
        return raw;
    }
    let Some(table) = model.tables.get(bearing).copied().flatten() else {
        return raw;
    };
    let mut out = Vec::new();
    for e in raw {
        if e.name == "clearance_ratio" {
            let c_w = table.film.clearance;
            out.push(Estimate {
                name: e.name,
                value: 1.0 + e.value,
                std_err: e.std_err,
            });
            out.push(Estimate {
                name: "clearance_true".into(),
                value: c_w * (1.0 + e.value),
                std_err: c_w * e.std_err,
            });
            out.push(Estimate {
                name: "clearance_written".into(),
                value: c_w,
                std_err: 0.0,
            });
        } else {
            out.push(e);
        }
    }
    out
}

/// The effect's own parameters in a refitted state.
fn effect_estimates(prep: &Prepared, state: &State, cand: &Candidate) -> Result<Vec<Estimate>> {
    let infs = state.inference(prep)?;
    let mut out = Vec::new();
    for (name, r) in &cand.parameters {
        for (_, inf, refs) in &infs {
            if let Some(i) = refs.iter().position(|x| x == r) {
                out.push(Estimate {
                    name: name.clone(),
                    value: inf.estimate[i],
                    std_err: inf.std_err(i),
                });
            }
        }
    }
    Ok(as_reported(&state.model, cand.bearing, cand.effect, out))
}

/// The pedestal parameters (k, m, c terms) of every bearing with standard errors.
pub fn pedestals(prep: &Prepared, state: &State) -> Result<Vec<Pedestal>> {
    let infs = state.inference(prep)?;
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
                out[b].std_err.insert(t.name(), inf.std_err(i));
            }
        }
    }
    Ok(out)
}
