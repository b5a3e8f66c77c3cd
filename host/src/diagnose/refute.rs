//! Steps the machine-level check refutes are dropped (`--machine`).
//!
//! The search chooses each effect on the pedestal level (its test against
//! the noise of the pedestal equations); the machine-level check
//! ([`super::machine::MachineCheck`]) re-simulates the whole machine after
//! each step and refutes a step whose gap did not fall
//! ([`super::trust::refutation`]: a rise above its own noise, or any rise
//! where that noise is not known). Such a step fits something in the
//! pedestal equations the machine does not show: until session 50 it stayed
//! named (and the diagnosis untrusted), and every later step was chosen on
//! top of it (unseen-nine `runout-drift`: `probe_runout` at B2, right, then
//! `pedestal_sub_base` and `sensor_delay` at B2, the delay raising the
//! machine-level gap 0.0636 → 0.0940).
//!
//! Here the search stops where the check first refutes it: it is run
//! again with as many rounds as came before the first refuted step
//! ([`super::Options::max_steps`]; the search is deterministic, so it
//! reproduces that step's model exactly), and that step and every step
//! chosen after it are dropped and listed. Not a search again without the
//! refuted (effect, bearing): measured on a cut `runout-drift` run (every
//! third speed, seed 9201), such a search chose two other effects in the
//! delay's place (`pedestal_sub_base`, `pedestal_mass_anisotropy`, the
//! latter refuted again): what a refuted step was chosen on is not a
//! library effect, and the next surrogate fits it as well. Not a backward
//! elimination of the refuted steps alone either: the steps after one were
//! chosen on top of it, their tests conditional on it.
//!
//! The family-wise rate is the search's as stated (`--alpha` per step,
//! Bonferroni over the candidates): every name kept was chosen by the first
//! search's own tests, and the second search adds none (one search again at
//! most: [`SEARCHES_AGAIN`]). A right effect chosen after a refuted step is
//! dropped with it (said, `refuted: false`); the diagnosis was untrusted
//! there before and stays so: every dropped step is a trust reason, the
//! pedestal-level evidence it was chosen on explained by nothing the
//! library holds.

use super::machine::MachineCheck;
use super::report::{Diagnosis, Step};
use super::trust::{refutation, Refutation};
use super::workflow::{diagnose, Options, Outcome};
use crate::rundir::RunDir;
use crate::sim::Machine;
use anyhow::Result;
use serde::Serialize;

/// How many times the search is run again: 1, with the rounds before the
/// first refuted step (module docs); its steps are the first search's up to
/// there, with the same machine-level gaps, so the check refutes none of
/// them and no further search is needed. It costs the rounds before that
/// step: less than the first search.
pub const SEARCHES_AGAIN: usize = 1;

/// A step the first search chose that was dropped because the machine-level
/// check refuted it or a step before it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RefutedStep {
    /// Effect name (formats.md).
    pub effect: String,
    /// Bearing it acted on (as `Step::bearing`).
    pub bearing: String,
    /// Delayed channels of a sensor delay.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub channels: Option<String>,
    /// Its step number in the first search (1-based) [-].
    pub step: usize,
    /// The test that chose it (as `Step::test`).
    pub test: String,
    /// Its ΔBIC in that test [-].
    pub delta_bic: f64,
    /// True when the check refuted this step itself; false for a step
    /// chosen after a refuted one (its test conditional on it).
    pub refuted: bool,
    /// Machine-level gap of the model before the step [-].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub machine_gap_before: Option<f64>,
    /// Machine-level gap of the model after it [-].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub machine_gap_after: Option<f64>,
    /// Standard deviation of the change, where known [-].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub machine_gap_change_sd: Option<f64>,
}

impl RefutedStep {
    /// Step `s` (number `step`, 1-based) of the first search, with its
    /// refutation if the check refuted it.
    fn of(s: &Step, step: usize, refutation: Option<Refutation>) -> Self {
        Self {
            effect: s.effect.clone(),
            bearing: s.bearing.clone(),
            channels: s.channels.clone(),
            step,
            test: s.test.clone(),
            delta_bic: s.evidence.delta_bic,
            refuted: refutation.is_some(),
            machine_gap_before: s.machine_gap_before,
            machine_gap_after: s.machine_gap_after,
            machine_gap_change_sd: refutation.and_then(|r| r.machine_gap_change_sd),
        }
    }

    /// "effect (channels) at bearing".
    fn what(&self) -> String {
        let channels = self
            .channels
            .as_ref()
            .map_or(String::new(), |c| format!(" ({c})"));
        format!("{}{channels} at {}", self.effect, self.bearing)
    }

    /// The machine-level gaps: the refutation's words, or the gaps as they
    /// were.
    fn gaps(&self) -> String {
        let (Some(before), Some(after)) = (self.machine_gap_before, self.machine_gap_after) else {
            return "not simulated".to_string();
        };
        if self.refuted {
            Refutation {
                machine_gap_before: before,
                machine_gap_after: after,
                machine_gap_change_sd: self.machine_gap_change_sd,
            }
            .words()
        } else {
            format!("{before:.4} → {after:.4}")
        }
    }

    /// One line under the text report's steps.
    pub fn line(&self) -> String {
        format!(
            "{} (step {}, ΔBIC {:.1}): machine-level gap {}{}",
            self.what(),
            self.step,
            self.delta_bic,
            self.gaps(),
            if self.refuted {
                ", refuted"
            } else {
                ", chosen after a refuted step"
            }
        )
    }

    /// The trust reason.
    pub fn reason(&self) -> String {
        let test = self.test.split(',').next().unwrap_or(&self.test);
        let why = if self.refuted {
            format!("did not lower the machine-level gap ({})", self.gaps())
        } else {
            "was chosen after a step the machine-level check refuted, its test conditional on that step".to_string()
        };
        format!(
            "{} was chosen by the {test} (step {} of the search, ΔBIC {:.1}) but {why}: dropped, the search ended before the first refuted step; what it was chosen on at the pedestal level is explained by no effect of the library",
            self.what(),
            self.step,
            self.delta_bic,
        )
    }
}

/// The steps of `outcome` the check `check` drops: the first it refutes
/// and every kept step after it, in order.
fn dropped_by(outcome: &Outcome, check: &MachineCheck) -> (Option<usize>, Vec<RefutedStep>) {
    // The check's gaps written into a copy of the steps.
    let mut d: Diagnosis = outcome.diagnosis.clone();
    check.apply(&mut d);
    let Some(first) = d.steps.iter().position(|s| refutation(s).is_some()) else {
        return (None, Vec::new());
    };
    let dropped = d.steps[first..]
        .iter()
        .enumerate()
        .filter(|(_, s)| s.dropped.is_none())
        .map(|(k, s)| RefutedStep::of(s, first + k + 1, refutation(s)))
        .collect();
    (Some(first), dropped)
}

/// `plinth diagnose RUN --machine FILE`: the search ([`diagnose`]) and the
/// machine-level check of `machine`; where the check refutes a step, the
/// search again with the rounds before the first refuted step and the check
/// again (module docs). Returns the last search (its
/// `diagnosis.refuted_steps` the steps dropped) and its check, not yet
/// applied to it (`MachineCheck::apply`, which says the dropped steps).
pub fn diagnose_checked(
    run: &RunDir,
    opts: &Options,
    machine: &Machine,
) -> Result<(Outcome, MachineCheck)> {
    let mut opts = opts.clone();
    let mut outcome = diagnose(run, &opts)?;
    let mut check = MachineCheck::of(machine, &outcome)?;
    let mut dropped: Vec<RefutedStep> = Vec::new();
    for _ in 0..SEARCHES_AGAIN {
        let (Some(first), now) = dropped_by(&outcome, &check) else {
            break;
        };
        // Each round adds one step: `first` rounds end before it.
        opts.max_steps = first;
        dropped.extend(now);
        outcome = diagnose(run, &opts)?;
        check = MachineCheck::of(machine, &outcome)?;
    }
    outcome.diagnosis.refuted_steps = dropped;
    Ok((outcome, check))
}
