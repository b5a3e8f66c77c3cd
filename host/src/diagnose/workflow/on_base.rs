//! A round of the search once a base is chosen: the corrections among the
//! candidates (probe runout, sensor delays, a table's clearance, pedestal
//! cross-coupling), each applied to the data and tested by the drop of the
//! refitted base's χ², then the backward check on the base
//! ([`crate::diagnose::bases::correction_on_base`]).

use super::search::{Round, Search};
use crate::diagnose::backward::Chosen;
use crate::diagnose::bases::{correction_on_base, lr_test, weakest_on_base, BaseOn};
use crate::diagnose::correct::corrections_only;
use crate::diagnose::forward::StepOutcome;
use crate::diagnose::report::Step;
use crate::diagnose::summaries::{effect_estimates, held_dampings, summary};
use anyhow::Result;

impl Search<'_> {
    /// One round on the chosen base `current` with the candidates of
    /// `outcome`: adds the best significant correction or stops.
    pub(super) fn round_on_base(
        &mut self,
        current: BaseOn,
        outcome: &StepOutcome,
    ) -> Result<Round> {
        let prep = self.prep;
        let opts = self.opts;
        let (tried, best, null) = correction_on_base(prep, &self.state, &current, outcome, opts);
        // The current model settled once more is the reference (and where
        // the search goes on from).
        let settled = null.is_some();
        let base = match null {
            Some((s, on)) => {
                self.state = s;
                self.on_base = Some(on.clone());
                on
            }
            None => current,
        };
        let Some((i, next, on, evidence)) = best else {
            if settled {
                self.settle_last_step(&base);
            }
            self.best_rejected = outcome
                .ranked
                .iter()
                .find(|e| corrections_only(&e.candidate.model))
                .map(|e| summary(prep, e, outcome.tried));
            return Ok(Round::Stop);
        };
        let win = &outcome.ranked[i];
        self.steps.push(Step {
            effect: win.candidate.effect.name().to_string(),
            bearing: prep.bearings[win.candidate.bearing].clone(),
            gap_before: base.fit.gap.gap,
            gap_after: on.fit.gap.gap,
            gap_floor_after: on.fit.gap.floor,
            machine_gap_before: None,
            machine_gap_after: None,
            machine_gap_change_sd: None,
            channels: win.candidate.variant.clone(),
            parameters: effect_estimates(prep, &next, &win.candidate)?,
            test: lr_test(tried),
            foundation: None,
            evidence,
            runner_up: None,
            passed_over: Vec::new(),
            candidates_tried: tried,
            candidates_failed: outcome.failed.len(),
            dropped: None,
            held: held_dampings(&self.state, &next, &win.candidate),
        });
        self.chosen
            .push(Chosen::of(&win.candidate, self.steps.len() - 1));
        self.state = next;
        self.on_base = Some(on);
        if self.chosen.len() > 1 {
            self.backward_on_base();
        }
        self.states.push(self.state.clone());
        self.after_steps.push((
            self.state.clone(),
            self.on_base.as_ref().map(|b| b.fit.clone()),
        ));
        Ok(Round::Added)
    }

    /// The last step's model is the one settled further on `base`: its gap
    /// and the model after it are those of the settled fit.
    fn settle_last_step(&mut self, base: &BaseOn) {
        if let (Some(s), Some(a)) = (self.steps.last_mut(), self.after_steps.last_mut()) {
            s.gap_after = base.fit.gap.gap;
            s.gap_floor_after = base.fit.gap.floor;
            *a = (self.state.clone(), Some(base.fit.clone()));
        }
        // (`states` holds no entry for the base's own step.)
        let correction_last = self.steps.last().is_some_and(|s| s.foundation.is_none());
        if correction_last && self.states.len() > 1 {
            if let Some(last) = self.states.last_mut() {
                *last = self.state.clone();
            }
        }
    }

    /// Backward check on the base: the weakest earlier correction that is
    /// no longer significant is removed and the base refitted without it.
    fn backward_on_base(&mut self) {
        let Some(base) = &self.on_base else {
            return;
        };
        let Some((i, ev, without, on)) =
            weakest_on_base(self.prep, &self.state, base, &self.chosen, self.opts)
        else {
            return;
        };
        let c = self.chosen.remove(i);
        self.steps[c.step].dropped = Some(format!(
            "not significant on the base after step {} (ΔBIC {:.1}, adjusted p {:.2e})",
            self.steps.len(),
            ev.delta_bic,
            ev.p_adjusted
        ));
        self.state = without;
        self.on_base = Some(on);
    }
}
