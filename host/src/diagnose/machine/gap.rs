//! The machine-level gap and its noise floor: the re-simulated readings
//! ([`super::resimulate`]) against every measured channel, and what an exact
//! model would leave (the measurement noise and the identified parameters'
//! own uncertainty).

use super::{replaced_bases, resimulate, Readings};
use crate::diagnose::data::Prepared;
use crate::diagnose::foundation::FoundationFit;
use crate::diagnose::state::State;
use crate::sim::Machine;
use anyhow::{anyhow, Result};

/// The machine-level gap (the definition of `crate::diagnose::gap`, over the rel and
/// ped channels, y and z, of every bearing and speed) [-].
pub fn machine_gap(prep: &Prepared, predicted: &Readings) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (b, row) in prep.points.iter().enumerate() {
        for (j, p) in row.iter().enumerate() {
            let Some(p) = p else { continue };
            let pred = predicted[b][j];
            for d in 0..2 {
                den += p.rel[d].norm_sqr() + p.ped[d].norm_sqr();
                match pred {
                    Some((rel, ped)) => {
                        num += (rel[d] - p.rel[d]).norm_sqr() + (ped[d] - p.ped[d]).norm_sqr();
                    }
                    None => num += p.rel[d].norm_sqr() + p.ped[d].norm_sqr(),
                }
            }
        }
    }
    if den > 0.0 {
        (num / den).sqrt()
    } else {
        0.0
    }
}

/// The machine-level gap's noise floor: the gap an exact model would leave
/// [-]. Two parts, over the same numbers as [`machine_gap`]: the
/// measurement noise, Σ σ² (σ of each real number,
/// `crate::diagnose::data::Point::sigma`), and the identified parameters' own
/// uncertainty carried through the re-simulation ([`parameter_variance`],
/// and a chosen base's, [`crate::diagnose::base_floor::base_variance`]);
/// the re-simulation is open-loop (unbalance to response), so near the
/// machine's resonances a parameter error of a fraction of its ± moves the
/// response more than the noise does. floor = sqrt((Σ σ² + Σ Var X̂) / Σ |X|²).
pub fn machine_floor(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    foundation: Option<&FoundationFit>,
    readings: &Readings,
) -> Result<f64> {
    let (mut var, mut den) = (0.0, 0.0);
    for p in prep.points.iter().flatten().flatten() {
        var += p.var.iter().sum::<f64>();
        for d in 0..2 {
            den += p.rel[d].norm_sqr() + p.ped[d].norm_sqr();
        }
    }
    var += parameter_variance(machine, prep, state, foundation, readings)?;
    var += crate::diagnose::base_floor::base_variance(machine, prep, state, foundation, readings)?;
    Ok(if den > 0.0 { (var / den).sqrt() } else { 0.0 })
}

/// The re-simulated readings as real numbers (rel y, z then ped y, z, real
/// and imaginary parts) in a fixed order; unmeasured points give none.
pub(in crate::diagnose) fn flat(readings: &Readings) -> Vec<f64> {
    let mut out = Vec::new();
    for (rel, ped) in readings.iter().flatten().flatten() {
        for z in rel.iter().chain(ped) {
            out.push(z.re);
            out.push(z.im);
        }
    }
    out
}

/// Σ Var X̂ [m²] of the re-simulated readings `readings` from the state's
/// parameter covariance (delta method: each reading's gradient by a
/// forward difference of 1 % of the parameter's ±, through
/// [`crate::diagnose::criterion::Inference::std_err_of`]). A chosen base's own
/// parameters are [`crate::diagnose::base_floor::base_variance`]'s.
pub fn parameter_variance(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    foundation: Option<&FoundationFit>,
    readings: &Readings,
) -> Result<f64> {
    let n = flat(readings).len();
    let mut total = 0.0;
    for (inf, grads) in gradients(machine, prep, state, foundation, readings)? {
        for o in 0..n {
            let c: Vec<f64> = grads.iter().map(|g| g[o]).collect();
            let se = inf.std_err_of(&c);
            if se.is_finite() {
                total += se * se;
            }
        }
    }
    Ok(total)
}

/// Var(Σ w_o X̂_o) [m²] of a weighted sum of the re-simulated readings
/// `readings` (`w` in [`flat`]'s order [-]) from the state's parameter
/// covariance, by the delta method of [`parameter_variance`] (the groups
/// independent, as there).
pub fn parameter_variance_of(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    readings: &Readings,
    w: &[f64],
) -> Result<f64> {
    let mut total = 0.0;
    for (inf, grads) in gradients(machine, prep, state, None, readings)? {
        let c: Vec<f64> = grads
            .iter()
            .map(|g| g.iter().zip(w).map(|(a, b)| a * b).sum())
            .collect();
        let se = inf.std_err_of(&c);
        if se.is_finite() {
            total += se * se;
        }
    }
    Ok(total)
}

/// Per inference group of `state`, its inference and the gradient of every
/// re-simulated reading ([`flat`]'s order) by each of its parameters
/// (forward difference of 1 % of the parameter's ±; zero where that ± is
/// not finite) [m / SI].
fn gradients(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    foundation: Option<&FoundationFit>,
    readings: &Readings,
) -> Result<Vec<(crate::diagnose::criterion::Inference, Vec<Vec<f64>>)>> {
    use crate::diagnose::candidates::ParamRef;
    let x0 = flat(readings);
    let mut out = Vec::new();
    for (_, inf, refs) in state.inference(prep)? {
        let mut grads: Vec<Vec<f64>> = Vec::with_capacity(refs.len());
        for (i, r) in refs.iter().enumerate() {
            let se = inf.std_err(i);
            let mut shifted = state.clone();
            let h = 0.01 * se;
            let value = match *r {
                ParamRef::Term(k) => &mut shifted.params.beta[k],
                ParamRef::Nonlinear(k) => &mut shifted.params.nl[k],
            };
            if !(h.is_finite() && h > 0.0) {
                grads.push(vec![0.0; x0.len()]);
                continue;
            }
            *value += h;
            let x = flat(&resimulate(machine, prep, &shifted, foundation)?);
            grads.push(x.iter().zip(&x0).map(|(a, b)| (a - b) / h).collect());
        }
        out.push((inf, grads));
    }
    Ok(out)
}

/// The base model `first` refitted as every step's joint refit fits its
/// model (`State::fit`: the weighted fit of the pedestal equations,
/// reweighted until the weights settle), where the base model itself is
/// `plinth identify`'s maximum-likelihood fit (`State::base`). A step's
/// machine-level gap is judged against the model it extends fitted the same
/// way: between the base model and step 1's refit every pedestal changes by
/// the change of estimator, a fraction of its ±, and near a lightly damped
/// pedestal's resonance the open-loop re-simulation magnifies that more
/// than the effect's own change (docs/diagnose-verdict.md, "Session 34").
pub fn refitted_base(prep: &Prepared, first: &State) -> Result<State> {
    State::fit(prep, first.model.clone(), first.params.nl.clone())
}

/// The machine-level check of a whole diagnosis (`--machine`): the
/// re-simulated machine's gap with the base model and after each step.
#[derive(Clone, Debug)]
pub struct MachineCheck {
    /// Gap of the base model; `None` where it cannot be simulated (a
    /// pedestal mass below zero: the base model fitted on rigid ground to
    /// pedestals that stand on something softer; the reason in `warnings`)
    /// [-].
    pub gap_before: Option<f64>,
    /// Gap of the base model as the steps' joint refits fit it
    /// ([`refitted_base`]): what step 1 is judged against (`None` where it
    /// cannot be simulated or refitted, the reason in `warnings`) [-].
    pub gap_refitted: Option<f64>,
    /// Gap after each step (aligned with the diagnosis's steps: the model
    /// after step i, a chosen base included); `None` where the identified
    /// model cannot be simulated (the reason in `warnings`) [-].
    pub gaps_after: Vec<Option<f64>>,
    /// The standard deviation of each step's machine-level gap change
    /// ([`super::change::change_sd`], aligned with `gaps_after`), given
    /// where the gap did not fall (the only steps [`crate::diagnose::trust::judge_steps`]
    /// weighs it for); `None` elsewhere, on a step that stands on an
    /// identified base or extends one, and where it cannot be computed [-].
    pub change_sds: Vec<Option<f64>>,
    /// The final model's machine-level floor ([`machine_floor`]) [-].
    pub floor: f64,
    /// The base model's re-simulated readings (figures; every point `None`
    /// when it cannot be simulated).
    pub before: Readings,
    /// The final model's, when it could be simulated (figures).
    pub after: Option<Readings>,
    /// Why a step's model could not be simulated.
    pub warnings: Vec<String>,
    /// The machine file's bases the re-simulation replaced
    /// ([`replaced_bases`]), said in the verdict (text and JSON).
    pub replaced: Option<String>,
    /// The bearings whose base model failed the support-mode test or the
    /// lack-of-fit rule, with the reason
    /// ([`crate::diagnose::trust::base_model_findings`]): unexplained again
    /// when the step at them does not lower the machine-level gap.
    pub support: Vec<(String, String)>,
    /// When the final model fails the check: a scale on the transducers
    /// of one kind (every bearing's or one bearing's) that brings the base
    /// model within it ([`super::unit_scale::find`]), said as the likely
    /// cause; when it passes with a scale-like effect named, a scale at
    /// that effect's bearing that passes too (neither trusted).
    pub unit_scale: Option<super::unit_scale::UnitScale>,
    /// When the final model passes and no scale is found: the scales on
    /// one bearing's transducers the check cannot see
    /// ([`super::unit_scale::blind`]), said in the verdict.
    pub blind: Vec<super::unit_scale::Blind>,
}

impl MachineCheck {
    /// Re-simulates `machine` with the base model and with the model after
    /// each step of `outcome` (`Outcome::after_steps`).
    pub fn of(machine: &Machine, outcome: &crate::diagnose::Outcome) -> Result<Self> {
        let prep = &outcome.prep;
        let first = outcome
            .states
            .first()
            .ok_or_else(|| anyhow!("no fitted base model"))?;
        let mut warnings = Vec::new();
        // A base model the simulator cannot hold (a negative mass) is no
        // reason to lose the whole diagnosis: its check is left out, said.
        let simulated = match resimulate(machine, prep, first, None) {
            Ok(r) => Some(r),
            Err(e) => {
                warnings.push(format!("no machine-level check of the base model: {e:#}"));
                None
            }
        };
        let gap_before = simulated.as_ref().map(|r| machine_gap(prep, r));
        let refitted = refitted_base(prep, first).ok();
        // The refitted base model with its readings and gap: step 1's
        // "before" for the change's sd.
        let refitted = match refitted
            .ok_or_else(|| anyhow!("the refit failed"))
            .and_then(|state| resimulate(machine, prep, &state, None).map(|r| (state, r)))
        {
            Ok((state, r)) => {
                let gap = machine_gap(prep, &r);
                Some((state, r, gap))
            }
            Err(e) => {
                warnings.push(format!(
                    "no machine-level check of the base model as the steps refit it: {e:#}"
                ));
                None
            }
        };
        let gap_refitted = refitted.as_ref().map(|(_, _, g)| *g);
        let before = simulated
            .unwrap_or_else(|| vec![vec![None; prep.speeds_hz.len()]; prep.bearings.len()]);
        let mut gaps_after = Vec::new();
        let mut readings_after = Vec::new();
        for (i, (state, base)) in outcome.after_steps.iter().enumerate() {
            match resimulate(machine, prep, state, base.as_ref()) {
                Ok(r) => {
                    gaps_after.push(Some(machine_gap(prep, &r)));
                    readings_after.push(Some(r));
                }
                // A base the simulator cannot hold (negative stiffness:
                // the diagnosis is then untrusted anyway).
                Err(e) => {
                    gaps_after.push(None);
                    readings_after.push(None);
                    warnings.push(format!(
                        "no machine-level check of the model after step {}: {e:#}",
                        i + 1
                    ));
                }
            }
        }
        let change_sds = change_sds(
            machine,
            prep,
            outcome,
            refitted.as_ref().map(|(state, r, gap)| (state, r, *gap)),
            &readings_after,
            &gaps_after,
        );
        let after = readings_after.pop().flatten();
        // The floor of the final model (the base model's when nothing was
        // added or the final model could not be simulated).
        let floor = match (outcome.after_steps.last(), &after) {
            (Some((state, base)), Some(r)) => {
                machine_floor(machine, prep, state, base.as_ref(), r)?
            }
            _ if gap_before.is_some() => machine_floor(machine, prep, first, None, &before)?,
            // Nothing simulated: no gap to judge, no floor.
            _ => 0.0,
        };
        let foundation = (outcome.after_steps.last()).is_some_and(|(_, b)| b.is_some());
        // A model that fails the check (or that the check cannot judge) is
        // asked for a unit mistake anywhere; one that passes, at the
        // bearings of its scale-like effects (`unit_scale::find`).
        let final_gap = match (outcome.after_steps.is_empty(), &after) {
            (true, _) => gap_before,
            (false, Some(_)) => gaps_after.last().copied().flatten(),
            (false, None) => None,
        };
        let fails = final_gap.is_some_and(|g| {
            crate::diagnose::trust::MachineCheck::of(g, floor)
                != crate::diagnose::trust::MachineCheck::Agrees
        });
        let named = scale_like_effects(outcome);
        let support = crate::diagnose::trust::base_model_findings(prep);
        // The bearings whose base model identify's tests find poor: one
        // channel in the wrong unit does that (`unit_scale::channel`).
        let poor: Vec<usize> = support
            .iter()
            .filter_map(|(b, _, _)| prep.bearing_index(b))
            .collect();
        // A final model the simulator cannot hold is judged by nothing:
        // every reading is asked, as when it fails.
        let unjudged = !outcome.after_steps.is_empty() && after.is_none();
        let unit_scale = if fails || unjudged || !named.is_empty() || !poor.is_empty() {
            // The final model's gap when the check does not find it
            // failing (it agrees, or cannot judge it): a physical reading
            // a channel competes with only where the data tell them
            // apart. A final model the simulator cannot hold is no such
            // reading (`unit_scale::channel::a_unit_mistake`).
            let disagrees = final_gap.is_some_and(|g| {
                matches!(
                    crate::diagnose::trust::MachineCheck::of(g, floor),
                    crate::diagnose::trust::MachineCheck::Disagrees { .. }
                )
            });
            let rival = final_gap.filter(|_| !(unjudged || disagrees));
            let fails = fails || unjudged;
            super::unit_scale::find(machine, prep, first, fails, rival, &named, &poor)
        } else {
            None
        };
        // The base model's gap and readings as simulated above (none: the
        // simulator could not hold it, nothing to walk).
        let blind = match gap_before {
            Some(gap) if !fails && unit_scale.is_none() => {
                super::unit_scale::blind::blind(machine, prep, first, gap, &before)
            }
            _ => Vec::new(),
        };
        Ok(Self {
            unit_scale,
            blind,
            replaced: replaced_bases(machine, &prep.bearings, foundation),
            support: support
                .into_iter()
                .map(|(bearing, why, _)| (bearing, why))
                .collect(),
            gap_before,
            gap_refitted,
            gaps_after,
            change_sds,
            floor,
            before,
            after,
            warnings,
        })
    }

    /// The final model's gap: the last step's, or the base model's when
    /// nothing was added (`None`: the final model could not be simulated).
    pub fn gap_after(&self) -> Option<f64> {
        match self.gaps_after.last() {
            Some(g) => *g,
            None => self.gap_before,
        }
    }

    /// Writes the gaps into `d` (per step and overall) and judges the final
    /// one ([`crate::diagnose::trust::judge_machine`]).
    pub fn apply(&self, d: &mut crate::diagnose::report::Diagnosis) {
        d.machine_gap_before = self.gap_before;
        d.machine_gap_after = self.gap_after();
        d.machine_gap_floor = Some(self.floor);
        let mut before = self.gap_refitted;
        for ((s, after), sd) in d
            .steps
            .iter_mut()
            .zip(&self.gaps_after)
            .zip(&self.change_sds)
        {
            s.machine_gap_before = before;
            s.machine_gap_after = *after;
            s.machine_gap_change_sd = *sd;
            before = *after;
        }
        crate::diagnose::trust::judge_steps(d, &self.support);
        crate::diagnose::trust::judge_machine(
            d,
            self.gap_after(),
            self.floor,
            self.unit_scale.as_ref(),
        );
        d.locate_unexplained();
        if let Some(note) = super::unit_scale::blind::sentence(&self.blind) {
            d.verdict += &format!(" Note: {note}.");
            d.unit_scale_blind.clone_from(&self.blind);
        }
        if let Some(note) = &self.replaced {
            d.verdict += &format!(" Note: {note}.");
        }
    }
}

/// The effects the final model of `outcome` carries that a scale on one
/// bearing's transducers also explains at the pedestal level (a table
/// scale, a sub-base, a base: [`super::unit_scale`]), each as its words
/// and its bearings' indices.
fn scale_like_effects(outcome: &crate::diagnose::Outcome) -> Vec<(String, Vec<usize>)> {
    let prep = &outcome.prep;
    let mut out = Vec::new();
    for st in outcome
        .diagnosis
        .steps
        .iter()
        .filter(|s| s.dropped.is_none())
    {
        let bearings: Vec<usize> = match st.effect.as_str() {
            "bearing_coefficients" | "pedestal_sub_base" => {
                prep.bearing_index(&st.bearing).into_iter().collect()
            }
            "foundation_coupling" => (0..prep.bearings.len()).collect(),
            _ => continue,
        };
        let words = if st.effect == "foundation_coupling" {
            "`foundation_coupling`".to_string()
        } else {
            format!("`{}` at {}", st.effect, st.bearing)
        };
        out.push((words, bearings));
    }
    out
}

/// Per step, the standard deviation of its machine-level gap change
/// ([`super::change::change_sd`]) where the gap did not fall; `refitted`
/// is step 1's "before" model with its re-simulated readings and gap [-],
/// `readings_after` and `gaps_after` the steps' [-]. A step on or after an
/// identified base gets none (the base's covariance is not the state's):
/// the sign rule judges it.
fn change_sds(
    machine: &Machine,
    prep: &Prepared,
    outcome: &crate::diagnose::Outcome,
    refitted: Option<(&State, &Readings, f64)>,
    readings_after: &[Option<Readings>],
    gaps_after: &[Option<f64>],
) -> Vec<Option<f64>> {
    let mut out = Vec::with_capacity(gaps_after.len());
    // The previous model, its readings and gap, and whether it is on a base.
    let mut before = refitted.map(|(s, r, g)| (s, Some(r), Some(g), false));
    for (((state, base), readings), gap) in outcome
        .after_steps
        .iter()
        .zip(readings_after)
        .zip(gaps_after)
    {
        let sd = match (before, readings, *gap) {
            (Some((b, Some(rb), Some(g0), false)), Some(ra), Some(g1))
                if base.is_none() && g1 >= g0 =>
            {
                super::change::change_sd(machine, prep, (b, rb, g0), (state, ra, g1))
                    .ok()
                    .flatten()
            }
            _ => None,
        };
        out.push(sd);
        before = Some((state, readings.as_ref(), *gap, base.is_some()));
    }
    out
}

#[cfg(test)]
mod tests;
