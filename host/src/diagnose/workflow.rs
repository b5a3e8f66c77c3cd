//! The discrepancy workflow: fit the base model, measure the gap, then add
//! the best-supported missing effect, one at a time (forward selection over
//! the whole library, the bases included), while the evidence is
//! significant relative to the noise floor. After each effect added the
//! whole model is refitted jointly, and every earlier effect must still be
//! significant in that joint fit (backward check, Bonferroni over the
//! effects checked); one that is not is removed again. The bases
//! (`foundation_coupling`, `pedestal_sub_base`) are tried in every round on
//! the data the chosen sensor and table effects correct.

use super::backward::Chosen;
use super::bases::{correction_on_base, lr_test, try_bases_on, weakest_on_base, BaseOn};
use super::bearing_table::WrittenTable;
pub use super::correct::corrected;
use super::correct::corrections_only;
use super::criterion::Evidence;
use super::data::Prepared;
pub use super::forward::{evaluate, step, Evaluated, StepOutcome};
use super::foundation::{self, FoundationFit};
use super::gap::Prediction;
use super::locate::locate;
use super::report::{Diagnosis, NoiseSummary, Step};
pub use super::state::{base_model, pedestals, GroupInference, State};
use super::summaries::{effect_estimates, held_dampings, summary, wald_test};
use super::trust::{as_pedestal_fit, conclude};
use crate::rundir::RunDir;
use crate::sim::oil_film::OilFilmBearing;
use anyhow::{Context, Result};
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
    /// The whole model after each step (aligned with `diagnosis.steps`):
    /// the state and the base it stands on, if any (`--machine`).
    pub after_steps: Vec<(State, Option<FoundationFit>)>,
}

/// Significant candidates of a step refitted jointly, best first, to find
/// one that keeps every pedestal physical.
const MAX_REFITS: usize = 4;

/// Runs the whole workflow on a run directory at the pedestal level.
///
/// `foundation_coupling` (pedestals on a shared, unmeasured base,
/// [`super::foundation`]) is tried on the base model in the first round,
/// next to the library; it wins when its bootstrap test is significant, it
/// brings the gap down, and further down than the best significant library
/// candidate does. The search then goes on with the corrections (probe
/// runout, sensor delays, a table's clearance, pedestal cross-coupling) on
/// top of the base: each applied to the data, the base refitted, tested by
/// the drop of the base's χ², with the backward check on the base
/// ([`super::bases::correction_on_base`]).
///
/// The speeds the base model's robust fit lists as outliers are left out of
/// the search and tested again under the model it chose
/// ([`super::outliers`]): those the chosen effects explain are put back and
/// the search run again with them, the others listed
/// (`Diagnosis::outlier_speeds_hz`).
pub fn diagnose(run: &RunDir, opts: &Options) -> Result<Outcome> {
    let all = Prepared::from_run(run)?;
    let listed = all.outlier_speeds_hz.clone();
    if listed.iter().all(Vec::is_empty) {
        return search(run, all, opts);
    }
    let why = "the run without the speeds the base model's robust fit lists as outliers";
    let prep = all.leaving_out(run, &listed).context(why)?;
    let first = search(run, prep, opts)?;
    let explained = super::outliers::explained(&all, &first, opts, &listed);
    let mut out = first;
    let mut left_out = listed.clone();
    if explained.iter().any(|e| !e.is_empty()) {
        let still = super::outliers::still_out(&listed, &explained);
        let prep = all.leaving_out(run, &still).context(why)?;
        let again = search(run, prep, opts)?;
        // Put back only when the search with them still names an effect
        // (the effects that explain them); otherwise they stay out.
        if !again.diagnosis.effects_added.is_empty() {
            out = again;
            left_out = still;
            out.diagnosis.outliers_explained_hz = by_name(&all, &explained);
        }
    }
    out.diagnosis.outlier_speeds_hz = by_name(&all, &left_out);
    Ok(out)
}

/// Per-bearing lists of `prep` by bearing name, only the non-empty ones.
fn by_name(prep: &Prepared, lists: &[Vec<f64>]) -> BTreeMap<String, Vec<f64>> {
    prep.bearings
        .iter()
        .zip(lists)
        .filter(|(_, l)| !l.is_empty())
        .map(|(b, l)| (b.clone(), l.clone()))
        .collect()
}

/// The search of [`diagnose`] on the arranged data `prep` of `run`.
fn search(run: &RunDir, prep: Prepared, opts: &Options) -> Result<Outcome> {
    let mut state = State::base(&prep, &opts.base)?;
    state.model.tables = written_tables(&prep, &opts.oil_films);
    let (pred0, gap0) = state.gap(&prep);
    let where_before = locate(&prep, &state.model, &state.params, &pred0);
    let pedestals_before = pedestals(&prep, &state)?;
    let mut states = vec![state.clone()];
    let mut after_steps = Vec::new();
    let mut steps: Vec<Step> = Vec::new();
    let mut best_rejected = None;
    let try_bases = opts.base == Parameter::ALL.as_slice() && opts.foundation_replicates > 0;
    // The shared base as tried on the base model (reported whether chosen
    // or not); later rounds try it again on the data the chosen sensor and
    // table effects correct.
    let mut foundation_tried = None;
    // The library effects chosen so far (for the backward check).
    let mut chosen: Vec<Chosen> = Vec::new();
    // The chosen base, refitted on the data the chosen corrections
    // (sensor, table and cross-coupling effects) correct.
    let mut on_base: Option<BaseOn> = None;
    let mut ticker = crate::progress::Ticker::new(
        "diagnose: candidate-effect rounds",
        opts.max_steps,
        opts.progress,
    );
    for round in 0..opts.max_steps {
        ticker.tick(round);
        let outcome = step(&prep, &state, opts.alpha);
        // With a base chosen the search goes on: the corrections among the
        // candidates, each tested by the drop of the refitted base's χ²,
        // then the backward check on the base.
        if let Some(current) = on_base.clone() {
            let (tried, best, null) = correction_on_base(&prep, &state, &current, &outcome, opts);
            // The current model settled once more is the reference (and
            // where the search goes on from).
            let settled = null.is_some();
            let base = match null {
                Some((s, on)) => {
                    state = s;
                    on_base = Some(on.clone());
                    on
                }
                None => current,
            };
            let Some((i, next, on, evidence)) = best else {
                // The last step's model is the one settled further.
                if settled {
                    if let (Some(s), Some(a)) = (steps.last_mut(), after_steps.last_mut()) {
                        s.gap_after = base.fit.gap.gap;
                        s.gap_floor_after = base.fit.gap.floor;
                        *a = (state.clone(), Some(base.fit.clone()));
                    }
                    // (`states` holds no entry for the base's own step.)
                    let correction_last = steps.last().is_some_and(|s| s.foundation.is_none());
                    if correction_last && states.len() > 1 {
                        if let Some(last) = states.last_mut() {
                            *last = state.clone();
                        }
                    }
                }
                best_rejected = outcome
                    .ranked
                    .iter()
                    .find(|e| corrections_only(&e.candidate.model))
                    .map(|e| summary(&prep, e, outcome.tried));
                break;
            };
            let win = &outcome.ranked[i];
            steps.push(Step {
                effect: win.candidate.effect.name().to_string(),
                bearing: prep.bearings[win.candidate.bearing].clone(),
                gap_before: base.fit.gap.gap,
                gap_after: on.fit.gap.gap,
                gap_floor_after: on.fit.gap.floor,
                machine_gap_before: None,
                machine_gap_after: None,
                channels: win.candidate.variant.clone(),
                parameters: effect_estimates(&prep, &next, &win.candidate)?,
                test: lr_test(tried),
                foundation: None,
                evidence,
                runner_up: None,
                candidates_tried: tried,
                candidates_failed: outcome.failed.len(),
                dropped: None,
                held: held_dampings(&state, &next, &win.candidate),
            });
            chosen.push(Chosen::of(&win.candidate, steps.len() - 1));
            state = next;
            on_base = Some(on);
            if chosen.len() > 1 {
                if let Some(base) = &on_base {
                    if let Some((i, ev, without, on)) =
                        weakest_on_base(&prep, &state, base, &chosen, opts)
                    {
                        let c = chosen.remove(i);
                        steps[c.step].dropped = Some(format!(
                            "not significant on the base after step {} (ΔBIC {:.1}, adjusted p {:.2e})",
                            steps.len(),
                            ev.delta_bic,
                            ev.p_adjusted
                        ));
                        state = without;
                        on_base = Some(on);
                    }
                }
            }
            states.push(state.clone());
            after_steps.push((state.clone(), on_base.as_ref().map(|b| b.fit.clone())));
            continue;
        }
        let (before_pred, before) = state.gap(&prep);
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
        // The winner: the best significant candidate whose joint refit
        // keeps every pedestal physical. One that turns a positive pedestal
        // stiffness or mass negative is rejected, as non-physical base fits
        // are: it "explains" the gap with an impossible pedestal (a sensor
        // delay bent to mimic a sub-base's second mode).
        let negative_now = state.negative_pedestal_terms();
        let mut winner: Option<(usize, State)> = None;
        for (i, e) in outcome.ranked.iter().enumerate().take(MAX_REFITS) {
            if !(e.evidence.delta_bic > 0.0 && e.evidence.p_adjusted < opts.alpha) {
                continue;
            }
            let next = State::fit(&prep, e.candidate.model.clone(), e.params.nl.clone())?;
            if next
                .negative_pedestal_terms()
                .iter()
                .all(|t| negative_now.contains(t))
            {
                winner = Some((i, next));
                break;
            }
        }
        // No library candidate significant: the above-range sub-base where
        // the support-mode test found it (`foundation::sub_base::above_range`).
        let mut by_support = None;
        if winner.is_none() {
            if let Some(n) =
                foundation::sub_base::above_range::named_by_support(&prep, &steps, &outcome)
            {
                let e = &outcome.ranked[n.index];
                let next = State::fit(&prep, e.candidate.model.clone(), e.params.nl.clone())?;
                if next
                    .negative_pedestal_terms()
                    .iter()
                    .all(|t| negative_now.contains(t))
                {
                    winner = Some((n.index, next));
                    by_support = Some(n);
                }
            }
        }
        let to_beat = match &winner {
            Some((i, next)) => criterion(
                &Prediction::new(&prep, &next.model, &next.params),
                &prep,
                outcome.ranked[*i].candidate.null.len(),
            ),
            None => criterion(
                &Prediction::new(&prep, &state.model, &state.params),
                &prep,
                0,
            ),
        };
        if try_bases && corrections_only(&state.model) {
            let bases = try_bases_on(&prep, &state, opts, round == 0)?;
            // The bootstrap only for a base that could be chosen, best
            // penalised χ² first, until one is significant: a base that
            // cannot beat the alternative is reported untested.
            let mut fitted: Vec<(foundation::Fitted, f64)> = [bases.shared, bases.sub_base]
                .into_iter()
                .flatten()
                .map(|f| {
                    let c = criterion(&f.prediction, &bases.prep, f.grouping.q);
                    (f, c)
                })
                .collect();
            fitted.sort_by(|a, b| a.1.total_cmp(&b.1));
            let mut best_base: Option<FoundationFit> = None;
            for (f, c) in fitted {
                let could = f.score() > 0.0
                    && before_pred.above_floor(&prep, super::foundation::TRY_ABOVE_FLOOR)
                    && f.gap.gap < before.gap
                    && c < to_beat;
                let kind = f.kind;
                let tested = match (&best_base, could) {
                    (None, true) => {
                        f.tested(opts.alpha, opts.foundation_replicates, opts.foundation_seed)
                    }
                    (Some(_), _) => f.untested("another base is chosen"),
                    (None, false) => f.untested("it cannot be chosen"),
                };
                if best_base.is_none() && could && tested.test.significant(opts.alpha) {
                    best_base = Some(tested.clone());
                }
                if round == 0 && kind == foundation::Kind::Shared {
                    foundation_tried = Some(tested);
                }
            }
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
                    held: None,
                });
                on_base = Some(BaseOn::of(bases.prep, f));
                after_steps.push((state.clone(), on_base.as_ref().map(|b| b.fit.clone())));
                continue;
            }
        }
        let Some((wi, next)) = winner else {
            best_rejected = outcome
                .ranked
                .first()
                .map(|e| summary(&prep, e, outcome.tried));
            break;
        };
        let win = &outcome.ranked[wi];
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
            test: by_support
                .as_ref()
                .map_or_else(|| wald_test(outcome.tried), |n| n.test.clone()),
            foundation: None,
            evidence: by_support.as_ref().map_or(win.evidence, |n| n.evidence),
            runner_up: outcome
                .ranked
                .iter()
                .enumerate()
                .find(|(i, _)| *i != wi)
                .map(|(_, e)| summary(&prep, e, outcome.tried)),
            candidates_tried: outcome.tried,
            candidates_failed: outcome.failed.len(),
            dropped: None,
            held: held_dampings(&state, &next, &win.candidate),
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
                let nl = super::bases::carried_nonlinear(&model, &state);
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
        after_steps.push((state.clone(), None));
    }
    // A table's clearance correction on rigid ground refitted by maximum
    // likelihood, the estimator of the base model (`super::bearing_table::refine`).
    let refits = if on_base.is_none() {
        super::bearing_table::refine(&prep, &mut state, &mut steps, opts.alpha)?
    } else {
        Vec::new()
    };
    if on_base.is_none() {
        if let Some(last) = states.last_mut() {
            *last = state.clone();
        }
        if let Some(last) = after_steps.last_mut() {
            last.0 = state.clone();
        }
    }
    let (chosen_foundation, base_prep) = match on_base {
        // The reported bases' pedestals get their profile ± here, once.
        Some(b) => (Some(b.fit.with_profile_errors()), Some(b.prep)),
        None => (None, None),
    };
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
    super::bearing_table::report_refits(&prep, &refits, &mut pedestals_after);
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
    // Judged on both yardsticks: the gap as reported, the χ² the fits
    // minimise for "the model got worse" (`super::trust::got_worse`).
    let mut conclusion = conclude(
        super::gap::Agreement {
            gap: gap0,
            ..pred0.agreement(&prep)
        },
        super::gap::Agreement {
            gap: gap1,
            ..pred1.agreement(base_prep.as_ref().unwrap_or(&prep))
        },
        // The effects kept: a step removed again (backward check, a table
        // correction the ML refit did not confirm) is not in the model.
        &steps
            .iter()
            .filter(|s| s.dropped.is_none())
            .cloned()
            .collect::<Vec<_>>(),
        &physical,
        &where_after,
    );
    super::trust::judge_support(&mut conclusion, &prep, &steps);
    let unexplained = if conclusion.verdict.contains(super::trust::UNEXPLAINED) {
        super::locate::unexplained(&where_after, super::trust::AT_THE_FLOOR)
    } else {
        Vec::new()
    };
    let digits = prep.noise.digits();
    let mut bearings_noise = BTreeMap::new();
    for (b, name) in prep.bearings.iter().enumerate() {
        if let Some(summary) = prep.noise.summary(b) {
            bearings_noise.insert(name.clone(), summary);
        }
    }
    let mut diagnosis = Diagnosis {
        base_model: opts.base.iter().map(|p| p.name().to_string()).collect(),
        steps,
        effects_added,
        gap_before: gap0.gap,
        gap_after: gap1.gap,
        machine_gap_before: None,
        machine_gap_after: None,
        machine_gap_floor: None,
        machine_check_informative: None,
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
        flipped_speeds_hz: by_name(&prep, &prep.flipped_speeds_hz),
        outlier_speeds_hz: BTreeMap::new(),
        outliers_explained_hz: BTreeMap::new(),
    };
    if let Some(f) = &chosen_foundation {
        f.report_into(&mut diagnosis, &prep);
    }
    Ok(Outcome {
        diagnosis,
        prep,
        states,
        foundation: chosen_foundation,
        after_steps,
    })
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
