//! One forward step of the search: every library candidate fitted on top of
//! the current state, tested (Wald, Bonferroni over the step) and ranked.

use super::backward::{constraints, Param};
use super::candidates::{library, Candidate, ParamRef};
use super::criterion::{Evidence, Inference};
use super::data::Prepared;
use super::fit::{fit_group, gauss_helmert_rss, jacobian, profile, scalar_drop, search_interval};
use super::model::{Model, Params, Term};
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
    // The likelihood ratio of a profiled scalar (its null is 0).
    let (fit, drop) = match candidate.new_nonlinear {
        Some(k) => {
            let interval = search_interval(prep, model, k, &group);
            let (s, fit) = profile(prep, model, &nl, &state.weights, &group, k, interval)?;
            at_an_edge(model, k, s, interval)?;
            nl[k] = s;
            let drop = scalar_drop(prep, model, &nl, &state.weights, &group, k)?;
            (fit, Some(drop))
        }
        None => (fit_group(prep, model, &nl, &state.weights, &group)?, None),
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
    softens(model, &refs, &inference)?;
    let evidence = match drop {
        Some(lr) => inference.evidence_profiled(&c, lr, tried, n_total)?,
        None => inference.evidence(&c, tried, n_total)?,
    };
    Ok(Evaluated {
        candidate,
        params,
        inference,
        refs,
        evidence,
    })
}

/// Standard errors by which a fitted Ω⁴ coefficient may lie below zero
/// before the fit is refused as non-physical (one-sided: 1.3e-3 per
/// direction under a true q = 0, where the candidate is not chosen anyway).
const SOFTENING_SIGMAS: f64 = 3.0;

/// A support below its second mode softens with speed: expanding
/// k_p − k_p²/(k_p + K_s − Ω²M_s) gives −Ω⁴·k_p²M_s²/(k_p + K_s)³, so the
/// Ω⁴ coefficient q [N·s⁴/m] of `pedestal_sub_base` above the range is
/// positive. A fit with q below zero by more than [`SOFTENING_SIGMAS`]
/// standard errors follows something else that stiffens the reading with
/// speed (a probe bracket's own resonance, a mode in the range) and is
/// refused with the reason, as the issue asks of non-physical fits.
fn softens(model: &super::model::Model, refs: &[ParamRef], inference: &Inference) -> Result<()> {
    for (i, r) in refs.iter().enumerate() {
        let ParamRef::Term(t) = r else { continue };
        let Some(Term::Quartic { dir, .. }) = model.terms.get(*t) else {
            continue;
        };
        let (q, s) = (inference.estimate[i], inference.std_err(i));
        if q < -SOFTENING_SIGMAS * s {
            bail!(
                "its Ω⁴ coefficient q_{} = {q:.3e} ± {s:.2e} N·s⁴/m is negative by {:.1} standard errors: a support below its second mode softens with speed (q > 0), this one stiffens",
                super::model::DIR_NAMES[*dir],
                -q / s
            );
        }
    }
    Ok(())
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

/// Tries every candidate on `state` and ranks them. Where the current
/// state has a non-physical pedestal damping ([`non_physical_dampings`]),
/// every candidate at that bearing that adds no damping is also tried with
/// those dampings held at zero, the bound of a passive pedestal
/// ([`held_at_zero`]); each such variant counts as a candidate.
pub fn step(prep: &Prepared, state: &State, alpha: f64) -> StepOutcome {
    let mut cands = library(&state.model, prep.bearings.len());
    let held = non_physical_dampings(prep, state);
    if !held.is_empty() {
        let variants: Vec<Candidate> = cands
            .iter()
            .filter_map(|c| held_at_zero(c, &held))
            .collect();
        cands.extend(variants);
    }
    let tried = cands.len();
    let n_total = prep.real_equations();
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

/// The pedestal dampings of `state` that no passive pedestal can have:
/// negative beyond [`crate::identify::physical::sigmas_below_zero`] standard
/// errors for the family of every damping the model estimates and
/// materially so ([`crate::identify::physical::damping_impossible`], the
/// rule `plinth identify` untrusts a pedestal by, 1 % family-wise per run).
///
/// Why: a channel effect can read exactly as a pedestal damping. A delay τ
/// on a bearing's rel probes turns the measured bearing force F into
/// F·e^{−iΩτ} ≈ F − iΩτ·(k − Ω²m + iΩc)·X: a damping −τ·k, plus terms
/// Ω³τm and Ω²τc that are a few % of it on a pedestal much stiffer than
/// its bearing (150 µs on a 3 GN/m block: −4.5e5 N·s/m against a true
/// 3e4, the Ω³τm term 7 % of it at 110 Hz). With the damping free the delay
/// adds nothing the damping cannot take (ΔBIC −2) and the pedestal is left
/// with an impossible damping; held at the physical bound, the delay
/// explains it.
pub fn non_physical_dampings(prep: &Prepared, state: &State) -> Vec<Term> {
    use crate::identify::physical::{damping_impossible, sigmas_below_zero};
    let family = state
        .model
        .terms
        .iter()
        .filter(|t| matches!(t, Term::Damping { .. }))
        .count();
    if family == 0 {
        return Vec::new();
    }
    let sigmas = sigmas_below_zero(family);
    let omega_max = 2.0 * std::f64::consts::PI * prep.speeds_hz.last().copied().unwrap_or(0.0);
    let Ok(infs) = state.inference(prep) else {
        return Vec::new();
    };
    let value = |t: &Term| {
        let i = state.model.terms.iter().position(|u| u == t)?;
        state.params.beta.get(i).copied()
    };
    let mut out = Vec::new();
    for (_, inf, refs) in &infs {
        for (i, r) in refs.iter().enumerate() {
            let ParamRef::Term(k) = r else { continue };
            let Some(&t) = state.model.terms.get(*k) else {
                continue;
            };
            let Term::Damping { bearing, dir } = t else {
                continue;
            };
            let c = inf.estimate[i];
            let se = inf.std_err(i);
            let stiffness = value(&Term::Stiffness { bearing, dir }).unwrap_or(0.0);
            if damping_impossible(c, se, stiffness, omega_max, sigmas) {
                out.push(t);
            }
        }
    }
    out
}

/// `next`, the joint refit with a step's winner at `bearing`, with the
/// pedestal dampings it held at zero ([`held_at_zero`]: dampings at
/// `bearing` that `before` estimated and `next` lacks) freed again when
/// the refit with them free leaves none of them impossible
/// ([`non_physical_dampings`]) and the data support them at the search's
/// level `alpha` (the test a `pedestal_damping` step would pass: ΔBIC > 0,
/// p < `alpha`; beside a profiled scalar by the likelihood ratio,
/// [`freed_evidence`]); else `next` unchanged.
///
/// Why: those dampings are the base model's own parameters, held at the
/// passive bound only because, without the effect, their free values were
/// impossible (a runout or a delay the model lacked read as a negative
/// damping). With the effect in the model, a physical free value says the
/// damping itself was never wrong; left held at zero, the next step frees
/// it again and names it a `pedestal_damping` effect, which is only the
/// base model restored (a ROSS overhung runout: c_z 1257 ± 145 N·s/m
/// against a true 1300, named as an effect and trusted). Where the data
/// cannot tell the damping from the effect (a delay on a stiff block reads
/// as −τ·k, collinear with c when c/k is a few µs), freed they only trade
/// against each other (ROSS fourth machine: τ 368 ± 94 µs, c_y 6.4e5 ±
/// 2.7e5 N·s/m against 150 µs and 3e4): they stay held, τ a lower bound.
pub fn freed_held(
    prep: &Prepared,
    before: &State,
    next: State,
    bearing: usize,
    alpha: f64,
) -> State {
    let held = held_terms(&before.model, &next.model, bearing);
    if held.is_empty() {
        return next;
    }
    // Appended: the winner's parameter references stay valid.
    let mut model = next.model.clone();
    model.terms.extend(held.iter().copied());
    let Ok(freed) = State::fit(prep, model, next.params.nl.clone()) else {
        return next;
    };
    let impossible = non_physical_dampings(prep, &freed);
    if held.iter().any(|t| impossible.contains(t)) {
        return next;
    }
    match freed_evidence(prep, &next, &freed, bearing, &held) {
        Some(ev) if ev.delta_bic > 0.0 && ev.p_value < alpha => freed,
        _ => next,
    }
}

/// The evidence for the dampings `held` at `bearing` in `freed`, the
/// joint refit of `next` with them free (one test, no Bonferroni count).
/// Where their group holds a profiled scalar (the held variant's delay or
/// loss factor, re-profiled in both fits), by the likelihood ratio: the
/// drop of the criterion the profile minimises
/// ([`super::fit::gauss_helmert_rss`], the one the forward step's
/// [`scalar_drop`] takes its drop of) from `next` to `freed`, each at its
/// own scalars, scaled robustly as the forward step's
/// ([`Inference::evidence_profiled`]). The Wald form at `freed` would carry
/// its curvature back to the held fit, where the damping and the delay's
/// −τ·k trade (module docs of `super::criterion`, "Profiled scalars").
/// Without a scalar in the group: the Wald statistic, whose floor form is
/// the drop for linear terms.
fn freed_evidence(
    prep: &Prepared,
    next: &State,
    freed: &State,
    bearing: usize,
    held: &[Term],
) -> Option<Evidence> {
    let null: Vec<_> = held.iter().map(|t| vec![(Param::Term(*t), 1.0)]).collect();
    let n_total = prep.real_equations();
    let (group, inf, c) = constraints(prep, freed, bearing, &null)?;
    if freed.model.group_nonlinear(&group).is_empty() {
        return inf.evidence(&c, 1, n_total).ok();
    }
    let criterion =
        |s: &State| gauss_helmert_rss(prep, &s.model, &s.params.nl, &next.weights, &group);
    let lr = criterion(next).ok()? - criterion(freed).ok()?;
    inf.evidence_profiled(&c, lr, 1, n_total).ok()
}

/// The pedestal dampings at `bearing` that `before` estimates and `after`
/// lacks: those a held variant ([`held_at_zero`]) holds at zero.
pub fn held_terms(before: &Model, after: &Model, bearing: usize) -> Vec<Term> {
    (0..2)
        .map(|dir| Term::Damping { bearing, dir })
        .filter(|t| before.terms.contains(t) && !after.terms.contains(t))
        .collect()
}

/// `candidate` with the dampings in `held` at its bearing removed from its
/// model (held at zero), its parameter references moved with the terms;
/// `None` when none of them is at its bearing or the candidate adds a
/// damping itself (viscous or structural: holding the damping it adds at
/// zero is no candidate).
fn held_at_zero(candidate: &Candidate, held: &[Term]) -> Option<Candidate> {
    use crate::effects::EffectKind;
    if matches!(
        candidate.effect,
        EffectKind::PedestalDamping | EffectKind::StructuralDamping
    ) {
        return None;
    }
    let at: Vec<Term> = held
        .iter()
        .copied()
        .filter(|t| t.bearings()[0] == Some(candidate.bearing))
        .filter(|t| candidate.model.terms.contains(t))
        .collect();
    if at.is_empty() {
        return None;
    }
    // New index of each old term (None: removed).
    let mut moved = Vec::with_capacity(candidate.model.terms.len());
    let mut next = 0;
    for t in &candidate.model.terms {
        if at.contains(t) {
            moved.push(None);
        } else {
            moved.push(Some(next));
            next += 1;
        }
    }
    let remap = |r: &ParamRef| match *r {
        ParamRef::Term(k) => moved.get(k).copied().flatten().map(ParamRef::Term),
        ParamRef::Nonlinear(k) => Some(ParamRef::Nonlinear(k)),
    };
    let mut c = candidate.clone();
    c.model.terms.retain(|t| !at.contains(t));
    c.parameters = candidate
        .parameters
        .iter()
        .map(|(n, r)| Some((n.clone(), remap(r)?)))
        .collect::<Option<_>>()?;
    c.null = candidate
        .null
        .iter()
        .map(|row| {
            row.iter()
                .map(|(r, v)| Some((remap(r)?, *v)))
                .collect::<Option<Vec<_>>>()
        })
        .collect::<Option<_>>()?;
    Some(c)
}

#[cfg(test)]
mod tests;
