//! `pedestal_sub_base` above the speed range named where the support-mode
//! test found it (session 31).
//!
//! **Why.** The support-mode test (`plinth identify`'s,
//! [`crate::estimate::lack_of_fit::support_mode`]) asks one bearing's
//! base-model fit for the Ω⁴ term a support below its second mode adds,
//! one-sided (q ≥ 0, what physics allows), at its family-wise rate
//! [`SUPPORT_FALSE_ALARM`] shared among the bearings tested. Diagnose's
//! library offers the same term as the candidate `pedestal_sub_base`
//! ([`ABOVE_RANGE`]) and judges it like every other candidate: two-sided
//! Wald χ²(2) (the smaller of the floor and the robust statistic),
//! Bonferroni over every candidate of the step (36 on three bearings), and
//! ΔBIC = W − 2 ln N > 0. Where the term is a few standard errors (the
//! third unseen machine's B2 on a 150 kg, 200/120 MN/m sub-base: Ω⁴Q 1-4 %
//! of the stiffness at the top speed, the support test's T̄ 15-19 on
//! seeds 2, 4 and 5), the support test flags the bearing and the library's
//! criterion (W > 21 and W > 14.8 for two parameters; the candidate's own
//! W 9.6-14.8) does not: the diagnosis then says the support falls as Ω⁴
//! "as a sub-base or a frame makes it" and names nothing.
//!
//! **The rule.** When no library candidate of a step is significant, a
//! bearing whose base model fails the support-mode test at its rate, at
//! which no kept step acts, is given the above-range candidate fitted at
//! it in that step (when its fit was physical: q not below zero,
//! `forward::softens`) as the step's effect, decided by the support test:
//! the hypothesis is the one that test made, per bearing, with its own
//! multiplicity. A bearing whose Ω⁴ term another effect of the search
//! explains has a step acting at it and is not given it; a shared base is
//! still tried against it in that round.
//!
//! **What it costs.** Nothing on clean data: a run where this names the
//! sub-base is one the same test already made untrusted (the reason of
//! [`crate::diagnose::trust::support_reasons`]); the diagnosis stays
//! untrusted (`trust::above_range_reason`: the pedestal and the sub-base
//! are not separable over the range), with the Ω⁴ coefficients and their ±
//! given. No threshold is added.

use crate::diagnose::candidates::{ABOVE_RANGE, PEDESTAL_SUB_BASE};
use crate::diagnose::criterion::Evidence;
use crate::diagnose::data::Prepared;
use crate::diagnose::forward::StepOutcome;
use crate::diagnose::report::Step;
use crate::diagnose::trust::acts_at;
use crate::identify::trust::{support_limit, SUPPORT_FALSE_ALARM};

/// The above-range candidate of a step the support-mode test decides.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedBySupport {
    /// Its index in the step's `ranked` candidates.
    pub index: usize,
    /// Its evidence: the fit's own Wald statistics and ΔBIC, with the
    /// support-mode test's p-value (`p_value`) and that p times the
    /// bearings tested (`p_adjusted`, capped at 1) [-].
    pub evidence: Evidence,
    /// The test that decided it, for the report.
    pub test: String,
}

/// The above-range `pedestal_sub_base` candidate of `outcome` (a step on
/// the state whose kept steps are `steps`) at the bearing of `prep` with
/// the smallest support-mode p-value among those that fail the test at its
/// family-wise rate and at which no kept step acts; `None` when there is
/// none, or its fit was refused (it is then not among the ranked).
pub fn named_by_support(
    prep: &Prepared,
    steps: &[Step],
    outcome: &StepOutcome,
) -> Option<NamedBySupport> {
    let tested = prep.support_modes.iter().flatten().count();
    let alpha = support_limit(tested);
    let mut flagged: Vec<(usize, f64, f64)> = prep
        .support_modes
        .iter()
        .enumerate()
        .filter_map(|(b, t)| {
            let t = t.as_ref()?;
            let name = prep.bearings.get(b)?;
            let acted = steps
                .iter()
                .any(|s| s.dropped.is_none() && acts_at(s, name));
            (t.p_value < alpha && !acted).then_some((b, t.p_value, t.statistic))
        })
        .collect();
    flagged.sort_by(|a, b| a.1.total_cmp(&b.1));
    flagged.into_iter().find_map(|(b, p, statistic)| {
        let index = outcome.ranked.iter().position(|e| {
            e.candidate.bearing == b
                && e.candidate.effect.name() == PEDESTAL_SUB_BASE
                && e.candidate.variant.as_deref() == Some(ABOVE_RANGE)
        })?;
        let own = outcome.ranked[index].evidence;
        let evidence = Evidence {
            p_value: p,
            p_adjusted: (p * tested.max(1) as f64).min(1.0),
            ..own
        };
        let test = format!(
            "support-mode test of the base model (one-sided Ω⁴ score, chi-bar², T̄ = {statistic:.1}), family-wise {SUPPORT_FALSE_ALARM} over {tested} bearing(s) tested; no library candidate was significant (this candidate's Wald χ² {:.1} on 2, adjusted p {:.2e} over {} candidates, ΔBIC {:.1})",
            own.wald, own.p_adjusted, outcome.tried, own.delta_bic
        );
        Some(NamedBySupport {
            index,
            evidence,
            test,
        })
    })
}
