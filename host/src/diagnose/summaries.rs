//! Chosen and tried effects as report entries: the library test's name,
//! a candidate's summary and an effect's estimates as reported.

use super::candidates::Candidate;
use super::data::Prepared;
use super::forward::Evaluated;
use super::model::Model;
use super::report::{CandidateSummary, Estimate, Pedestal};
use super::state::State;
use crate::effects::EffectKind;
use anyhow::Result;

/// The name of the library's test of `e`, with the Bonferroni count: the
/// likelihood ratio for a candidate that adds a profiled scalar, else Wald
/// (`super::criterion`, "Profiled scalars").
pub(super) fn library_test(e: &Evaluated, tried: usize) -> String {
    if e.candidate.new_nonlinear.is_some() {
        format!(
            "likelihood ratio of the profiled scalar, χ² with Bonferroni over {tried} candidates"
        )
    } else {
        format!("Wald, χ² with Bonferroni over {tried} candidates")
    }
}

/// The candidate as a report entry (`tried`: candidates of its step).
pub(super) fn summary(prep: &Prepared, e: &Evaluated, tried: usize) -> CandidateSummary {
    CandidateSummary {
        effect: e.candidate.effect.name().to_string(),
        bearing: prep.bearings[e.candidate.bearing].clone(),
        channels: e.candidate.variant.clone(),
        test: library_test(e, tried),
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

/// An effect's estimates as reported: the clearance scalar δ of
/// `bearing_coefficients` as `clearance_ratio` = 1 + δ, with the written
/// and the true clearance [m]; its stiffness-ratio scalar δ as `k_scale` =
/// 1 + δ (the table's stiffness relative to its damping, `c_scale` held at
/// 1: `super::bearing_table`).
pub(super) fn as_reported(
    model: &Model,
    bearing: usize,
    effect: EffectKind,
    raw: Vec<Estimate>,
) -> Vec<Estimate> {
    if effect.name() != super::candidates::BEARING_COEFFICIENTS {
        return raw;
    }
    let table = model.tables.get(bearing).copied().flatten();
    let mut out = Vec::new();
    for e in raw {
        if e.name == "k_scale" {
            out.push(Estimate {
                name: e.name,
                value: 1.0 + e.value,
                std_err: e.std_err,
            });
        } else if let (Some(table), "clearance_ratio") = (table, e.name.as_str()) {
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
pub(super) fn effect_estimates(
    prep: &Prepared,
    state: &State,
    cand: &Candidate,
) -> Result<Vec<Estimate>> {
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

/// A step's pedestal dampings held at zero (`super::forward`'s
/// held-at-zero variant of its candidate), and what holding them means for
/// a delay.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct HeldDamping {
    /// The held directions (`"c_y"`, `"c_z"`).
    pub dampings: Vec<String>,
    /// For a `sensor_delay` on the `rel` probes: per held direction, the
    /// delay [s] each 1 % of pedestal damping ratio ζ would add to the
    /// fitted τ. A delay τ reads as a damping −τ·k, so a true damping c
    /// adds c/k = 2ζ/ω_n to it: with the damping held at zero, τ is a lower
    /// bound (ω_n = √(k/m) [rad/s] from the step's refit).
    pub delay_per_percent_damping: Vec<(String, f64)>,
    /// For a delay refitted at the end (`super::ml_final::held_delay`): its
    /// ± [s] were the held dampings exactly zero. The step's τ ± counts
    /// them as unknown (the fit with them free, linearised at the held
    /// values), so it covers the delay a true damping adds.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tau_std_err_damping_zero: Option<f64>,
}

/// What `cand` (the step's winner, refitted as `after`) holds at zero:
/// dampings at its bearing that `before` estimated and its model lacks;
/// `None` when it holds none.
pub(super) fn held_dampings(
    before: &State,
    after: &State,
    cand: &Candidate,
) -> Option<HeldDamping> {
    use super::model::Term;
    let b = cand.bearing;
    let dirs: Vec<usize> = super::forward::held_terms(&before.model, &after.model, b)
        .iter()
        .filter_map(|t| match *t {
            Term::Damping { dir, .. } => Some(dir),
            _ => None,
        })
        .collect();
    if dirs.is_empty() {
        return None;
    }
    let name = |dir: usize| format!("c_{}", ["y", "z"][dir]);
    let value = |t: Term| {
        let i = after.model.terms.iter().position(|u| *u == t)?;
        after.params.beta.get(i).copied()
    };
    let rel_delay = cand.effect == EffectKind::SensorDelay
        && cand
            .variant
            .as_deref()
            .is_some_and(|v| v.starts_with("rel"));
    let delay_per_percent_damping = if rel_delay {
        dirs.iter()
            .filter_map(|&dir| {
                let k = value(Term::Stiffness { bearing: b, dir })?;
                let m = value(Term::Mass {
                    bearing: b,
                    dir: Some(dir),
                })
                .or_else(|| {
                    value(Term::Mass {
                        bearing: b,
                        dir: None,
                    })
                })?;
                let omega_n = (k / m).sqrt();
                (omega_n.is_finite() && omega_n > 0.0).then(|| (name(dir), 2.0 * 0.01 / omega_n))
            })
            .collect()
    } else {
        Vec::new()
    };
    Some(HeldDamping {
        dampings: dirs.into_iter().map(name).collect(),
        delay_per_percent_damping,
        tau_std_err_damping_zero: None,
    })
}

impl HeldDamping {
    /// The report's lines under the step (`bearing`: its name).
    pub fn write_text(&self, s: &mut String, bearing: &str) {
        use std::fmt::Write;
        let _ = writeln!(
            s,
            "     {} at {bearing} held at 0 (free, impossible: a passive pedestal's bound)",
            self.dampings.join(", ")
        );
        if !self.delay_per_percent_damping.is_empty() {
            let per: Vec<String> = self
                .delay_per_percent_damping
                .iter()
                .map(|(d, t)| format!("{:.2e} s per 1 % of ζ in {d}", t))
                .collect();
            let _ = writeln!(
                s,
                "     tau is a lower bound: a delay reads as a damping −tau·k, so a true pedestal damping adds c/k = 2ζ/ω_n to it ({})",
                per.join(", ")
            );
        }
        if let Some(se) = self.tau_std_err_damping_zero {
            let _ = writeln!(
                s,
                "     tau's ± counts the held damping as unknown (the fit with it free); with it exactly 0 the ± would be {se:.1e} s"
            );
        }
    }
}

/// Every reported standard error of the pedestals in `pedestals` whose
/// base-model fit by `plinth identify` ([`Prepared::base_fits`]) had its
/// standard errors withheld by the errors-in-variables rule
/// ([`crate::identify::std_err_withheld`]) made infinite (`± ∞` in text,
/// `null` in JSON): such a pedestal is read so near the noise of its phasors
/// that the asymptotic ± of any fit of it is short, and no ± is known.
/// Returns a sentence for the verdict naming those pedestals (empty when
/// none).
pub(super) fn withhold_std_errs(prep: &Prepared, pedestals: &mut [Pedestal]) -> String {
    let withheld: Vec<&str> = prep
        .base_fits
        .iter()
        .filter(|f| crate::identify::std_err_withheld(f))
        .map(|f| f.bearing.as_str())
        .collect();
    let mut named = Vec::new();
    for p in pedestals
        .iter_mut()
        .filter(|p| withheld.contains(&p.bearing.as_str()))
    {
        for se in p.std_err.values_mut() {
            *se = f64::INFINITY;
        }
        if !named.contains(&p.bearing) {
            named.push(p.bearing.clone());
        }
    }
    if named.is_empty() {
        return String::new();
    }
    format!(
        " At {}: the pedestal is read near or below the noise of its phasors (errors in variables, as `plinth identify` finds), so its standard errors are not known and none is given (± ∞, `null` in JSON).",
        named.join(", ")
    )
}
