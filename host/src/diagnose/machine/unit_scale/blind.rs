//! What the machine-level check cannot see: the scales on one bearing's
//! transducers that pass it as well as the readings as they are.
//!
//! Where a pedestal is much stiffer than its bearing, or its readings are
//! small in the gap's sum, the rotor barely sees that pedestal and the
//! check passes a unit mistake on its transducers as recorded (session 40:
//! unseen-train's B1 with `rel` × √2, `ped` × 2 or × √2 trusted, the
//! pedestal off by that factor). Nothing in the run can then name the
//! mistake without naming it on clean runs too, so the verdict says what
//! the check cannot see instead: per bearing and kind, the factors s
//! around 1 whose hypothesis ([`super::hypothesis`]) passes the check with
//! the floor of the readings as they are, when that range holds a common
//! unit mistake ([`super::COMMON`]). A pedestal there is right only if its
//! transducers' units are.

use super::super::{machine_floor, Readings};
use super::{gap_of, Kind, Reading, COMMON};
use crate::diagnose::data::Prepared;
use crate::diagnose::state::State;
use crate::diagnose::trust::MachineCheck;
use crate::sim::Machine;
use serde::Serialize;

/// Scales of one bearing's transducers of one kind that the machine-level
/// check cannot tell from the readings as they are.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Blind {
    /// The transducers.
    pub kind: Kind,
    /// Their bearing.
    pub bearing: String,
    /// The factors s (measured = s × true) around 1 whose hypothesis
    /// passes the check [-] (walked in steps of [`STEP`] in log10 s, at
    /// most [`RANGE`] either side: an edge there is a bound, not the end).
    pub factor_interval: [f64; 2],
    /// The common unit mistakes within it (`×√2 (rms against peak)`, …).
    pub unseen: Vec<String>,
    /// The common unit mistakes beyond an edge the walk stopped at (its
    /// [`RANGE`]) that pass the check too, each tried on its own: the
    /// range may not hold every factor between.
    pub beyond: Vec<String>,
}

/// Step of log10 s of the walk [-] (2.3 % in s).
const STEP: f64 = 0.01;

/// How far the walk goes either side, in log10 s [-] (× 5: beyond 2√2).
const RANGE: f64 = 0.7;

/// The common unit factors (each also as its inverse) s with
/// `within(s)`, named.
fn common_where(within: impl Fn(f64) -> bool) -> Vec<String> {
    let mut out = Vec::new();
    for &(f, _) in COMMON.iter() {
        for s in [f, 1.0 / f] {
            if within(s) {
                if let Some(n) = super::nearest_common(s) {
                    out.push(n);
                }
            }
        }
    }
    out
}

/// Per bearing and kind, the scales the check cannot see on the base model
/// `state` (module docs), when the readings as they are pass it (`gap`
/// [-]: its machine-level gap; `readings`: its re-simulated readings, the
/// check's own); only those whose range holds a common unit mistake.
pub fn blind(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    gap: f64,
    readings: &Readings,
) -> Vec<Blind> {
    let Ok(floor) = machine_floor(machine, prep, state, None, readings) else {
        return Vec::new();
    };
    if MachineCheck::of(gap, floor) != MachineCheck::Agrees {
        return Vec::new();
    }
    let mut out = Vec::new();
    for (b, name) in prep.bearings.iter().enumerate() {
        for kind in [Kind::Rel, Kind::Ped] {
            let reading = Reading::bearing(kind, b);
            let passes = |l: f64| {
                gap_of(machine, prep, state, reading, 10f64.powf(l))
                    .is_some_and(|g| MachineCheck::of(g, floor) == MachineCheck::Agrees)
            };
            let edge = |dir: f64| {
                let mut l = 0.0;
                while l < RANGE && passes(dir * (l + STEP)) {
                    l += STEP;
                }
                10f64.powf(dir * l)
            };
            let (lo, hi) = (edge(-1.0), edge(1.0));
            let unseen = common_where(|s| (lo..=hi).contains(&s));
            // Where the walk stopped at its end, the common factors beyond
            // it are tried one by one (flex B1's `ped` × 1/25.4 passed,
            // trusted, with a note that stopped at × 0.2: session 41).
            let end = 10f64.powf(RANGE - 0.5 * STEP);
            let beyond = common_where(|s| {
                ((hi > end && s > hi) || (lo < 1.0 / end && s < lo)) && passes(s.log10())
            });
            if !unseen.is_empty() || !beyond.is_empty() {
                out.push(Blind {
                    kind,
                    bearing: name.clone(),
                    factor_interval: [lo, hi],
                    unseen,
                    beyond,
                });
            }
        }
    }
    out
}

/// The verdict's sentence on what the check cannot see [text].
pub fn sentence(blind: &[Blind]) -> Option<String> {
    if blind.is_empty() {
        return None;
    }
    let parts: Vec<String> = blind
        .iter()
        .map(|b| {
            let [lo, hi] = b.factor_interval;
            // An edge at the walk's end is a bound: the range goes on.
            let end = 10f64.powf(RANGE - 0.5 * STEP);
            let lo = if lo < 1.0 / end {
                "below × 0.2".to_string()
            } else {
                format!("× {lo:.3}")
            };
            let hi = if hi > end {
                "beyond × 5".to_string()
            } else {
                format!("× {hi:.3}")
            };
            let holds = if b.unseen.is_empty() {
                String::new()
            } else {
                format!(" (it holds {})", b.unseen.join(", "))
            };
            let beyond = if b.beyond.is_empty() {
                String::new()
            } else {
                format!(
                    "; beyond the walk, {} pass{} too",
                    b.beyond.join(", "),
                    if b.beyond.len() == 1 { "es" } else { "" }
                )
            };
            format!(
                "{}'s `{}` readings {lo} to {hi}{holds}{beyond}",
                b.bearing,
                b.kind.columns()
            )
        })
        .collect();
    Some(format!(
        "the machine-level check cannot see a unit or scale mistake of these sizes: {}; a pedestal there is right only if its transducers' units are (check them)",
        parts.join("; ")
    ))
}
