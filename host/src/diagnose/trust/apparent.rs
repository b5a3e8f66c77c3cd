//! What `plinth diagnose`'s pedestal values are conditional on: the
//! support as a whole, said where the values are printed (text and JSON
//! `conditional_on`), with what the run excludes of a sub-base above it.
//!
//! A pedestal on its own sub-base whose modes lie above the run moves
//! there as one mass on the series stiffness of the two springs, to the
//! small Ω⁴ term the support-mode test looks for
//! ([`crate::identify::conditional::sub_base`]): unseen-seven's B1 (a
//! 400 kg sole plate under an 800 kg pedestal, its modes at 138/97 Hz
//! against a 50 Hz trip) is a single mass-spring-damper over the run to
//! 0.15 % (y) and 2.3 % (z), so the data hold the support as a whole, and
//! diagnose printed B1's k 40 % below the pedestal's own, trusted, its ±
//! 0.4 % (docs/unseen-seven.md, finding 1). The run cannot tell that
//! support from a pedestal that has the printed values (the same fit, the
//! same residuals), so no rule on these data can untrust the one without
//! the other: the verdict stays what the data say of the support, and the
//! report says, per bearing, that the values are the support's and how far
//! the pedestal's own k and m could lie from them (`trusted` is about the
//! support's values; docs/diagnose-sub-base.md, "Session 47 (apparent17)").
//!
//! The same holds of a support whose stiffness drifts over the run (in a
//! run-down time and speed are tied: the drift reads as a mass term, with a
//! fit as good as a constant support's): the condition is `plinth
//! identify`'s ([`crate::identify::conditional::drift`]), stated with its
//! size per bearing whose values are the base model's
//! (docs/diagnose-verdict.md, "Session 50 (refute50)").

use super::acts_at;
use crate::diagnose::data::Prepared;
use crate::diagnose::report::Diagnosis;
use crate::identify::conditional::drift::{self, DriftSensitivity};
use crate::identify::conditional::sub_base::{self, SubBaseBound};
use crate::identify::conditional::APPARENT;
use serde::Serialize;

/// What a diagnosis's pedestal values are conditional on (`conditional_on`
/// in `plinth diagnose --json`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Conditional {
    /// The promise in one paragraph, as the text report prints it.
    pub statement: String,
    /// Per bearing whose final values are its base model's (no kept step
    /// acts there) and whose support-mode test was made, what the run
    /// excludes of a sub-base above it.
    pub sub_base: Vec<SubBaseBound>,
    /// Per bearing whose final values are its base model's (as
    /// `sub_base`), how far a drift of its support's stiffness over the
    /// run would move them ([`drift::of_fit`] of its base model's fit).
    pub support_drift: Vec<DriftSensitivity>,
}

impl Conditional {
    /// The paragraph at the end of the text report.
    pub fn to_text(&self) -> String {
        let mut out = format!("\nConditional on: {}\n", self.statement);
        for b in &self.sub_base {
            out.push_str(&format!("  {}\n", b.message()));
        }
        for d in self.support_drift.iter().filter(|d| d.matters()) {
            out.push_str(&format!("  {}\n", d.message()));
        }
        out
    }
}

/// The final pedestal of `name` in `d`: (k_y, k_z) [N/m] and the mass of
/// each direction [kg] (one mass twice unless it is split).
fn stiffness_and_mass(d: &Diagnosis, name: &str) -> Option<([f64; 2], [f64; 2])> {
    let p = d.pedestals_after.iter().find(|p| p.bearing == name)?;
    let v = |n: &str| p.values.get(n).copied();
    let k = [v("k_y")?, v("k_z")?];
    let m = match v("m") {
        Some(m) => [m, m],
        None => [v("m_y")?, v("m_z")?],
    };
    Some((k, m))
}

/// The bearings of `prep` (index, name) whose final values in `d` are
/// their base model's: no kept step acts there.
fn as_base_model<'a>(
    prep: &'a Prepared,
    d: &'a Diagnosis,
) -> impl Iterator<Item = (usize, &'a String)> + 'a {
    prep.bearings.iter().enumerate().filter(|(_, name)| {
        !d.steps
            .iter()
            .any(|s| s.dropped.is_none() && acts_at(s, name))
    })
}

/// What diagnosis `d` of `prep` is conditional on.
pub fn of(prep: &Prepared, d: &Diagnosis) -> Conditional {
    let support_drift = as_base_model(prep, d)
        .filter_map(|(b, name)| {
            let fit = prep.base_fits.iter().find(|f| f.bearing == *name)?;
            let obs: Vec<_> = prep.points.get(b)?.iter().flatten().cloned().collect();
            drift::of_fit(fit, &obs)
        })
        .collect();
    let sub_base = as_base_model(prep, d)
        .filter_map(|(b, name)| {
            let t = prep.support_modes.get(b).copied().flatten()?;
            let (k, m) = stiffness_and_mass(d, name)?;
            let top = prep
                .points
                .get(b)?
                .iter()
                .flatten()
                .map(|q| q.speed_hz)
                .fold(0.0, f64::max);
            sub_base::bound(name, k, m, top, &t)
        })
        .collect();
    Conditional {
        statement: format!(
            "{APPARENT} `trusted` judges the values as the support's: the run cannot tell such a support from a pedestal that has the printed values. At a bearing where an effect was named the values are the model's with that effect. {}",
            drift::STATEMENT
        ),
        sub_base,
        support_drift,
    }
}
