//! One scale on the transducers of one kind, every bearing's or one
//! bearing's (a unit mistake of an import: µm read as mm, mil as µm, 0-pk as
//! pp, rms as pk), as the machine-level check sees it.
//!
//! The pedestal equation Z·ped = K*·(rel − r) (Z = k − Ω²m + iΩc) is
//! homogeneous: every `rel` reading s times its true value identifies
//! Z and r s times theirs, every `ped` reading s times its true value
//! identifies Z 1/s times its own. The pedestal-level fit is as good either
//! way, so `plinth identify` cannot tell (docs/robustness-hostile.md). The
//! machine file can: its rotor and unbalance fix the absolute response, and
//! the rotor's absolute motion is rel + ped, so a scale on one kind alone is
//! not a scale of the model. Hypothesis s on `rel`: the true readings are
//! rel/s and ped, the true pedestals Z/s and runouts r/s; on `ped`: rel and
//! ped/s, pedestals s·Z. Each is re-simulated for s over a wide range and
//! judged as the machine-level check judges a model
//! ([`crate::diagnose::trust::MachineCheck`]: gap against 3× its floor).
//!
//! The same holds for one bearing's transducers (session 40,
//! docs/robustness-hostile.md "Session 40 (partialunit17)"): one bearing's `rel` s times their true
//! value identify that pedestal (and its runouts) s times its own, exactly
//! what a bearing table s times too stiff and too damped at that bearing
//! gives, so the pedestal level cannot tell the two apart and `diagnose`
//! may name `bearing_coefficients`, a sub-base or a base there. The machine
//! file can tell them apart where the rotor's response depends on that
//! bearing: a table scale changes the rotor's motion, a unit mistake only
//! the readings. Each reading is re-simulated and judged by the check; the
//! one that passes is named, and where both the named effect and the unit
//! mistake pass, both are said and neither is trusted ([`Reading`]).
//!
//! A scale that passes is named only when it is a unit mistake a person
//! can act on ([`evidence`], session 42): told from 1 by its own ± (ln ŝ's
//! standard deviation from the machine-level fit) and beyond a
//! transducer's calibration tolerance (×/÷ 1.1).

use super::{machine_floor, machine_gap, resimulate, Readings};
use crate::diagnose::data::Prepared;
use crate::diagnose::fit::Weights;
use crate::diagnose::model::Term;
use crate::diagnose::state::State;
use crate::diagnose::trust::MachineCheck;
use crate::sim::Machine;
use serde::Serialize;

pub mod blind;
pub mod channel;
pub mod evidence;
mod factors;
mod reason;
mod table;
pub use blind::Blind;
use factors::{minimise, refine, COMMON, LOG_RANGE, LOG_RANGE_ONE};
pub use factors::{nearest_common, nearest_listed};
pub use reason::reason;
pub use table::TableScale;

/// The transducers a scale is put on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// The rotor-relative probes (`rel_*` columns).
    Rel,
    /// The pedestal pick-ups (`ped_*` columns).
    Ped,
}

impl Kind {
    /// The column prefix of the kind.
    pub fn columns(self) -> &'static str {
        match self {
            Kind::Rel => "rel",
            Kind::Ped => "ped",
        }
    }
}

/// What the machine-level check finds of a scale on one kind of transducer.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct UnitScale {
    /// The transducers whose readings look scaled.
    pub kind: Kind,
    /// The bearing whose transducers of `kind` look scaled; absent: every
    /// bearing's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bearing: Option<String>,
    /// The one channel of `bearing` that looks scaled, by the data
    /// contract's column name (`rel_y`, `rel_z`, `ped_y`, `ped_z`:
    /// [`channel`]); absent: both directions of `kind`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub channel: Option<String>,
    /// The factor s the readings look to carry: measured = s × true [-].
    pub factor: f64,
    /// Standard deviation of ln `factor` from the machine-level fit
    /// (measurement noise and the identified parameters' own ±,
    /// [`evidence::log_sd`]) [-].
    pub log_sd: f64,
    /// Machine-level gap of the base model with those readings divided by
    /// s (and its pedestals as that implies) [-].
    pub gap: f64,
    /// That model's machine-level noise floor [-].
    pub floor: f64,
    /// The common unit factor nearest `factor` (within 10 %), with the
    /// mistake it stands for, when one is.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub nearest: Option<String>,
    /// The factors whose hypothesis stays within the check's limit (the
    /// profile of the gap over s, with the floor of `factor`): every s the
    /// machine file cannot tell from `factor` [-]. Not a standard error.
    pub factor_interval: [f64; 2],
    /// The other readings of the run that pass the machine-level check as
    /// well (the named effects, other scales), when any: then the check
    /// cannot tell them apart and none is trusted.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub also_fits: Vec<String>,
    /// The bearing table at the same bearing(s) scaled instead, its
    /// pedestal with it (the unit mistake's twin at the pedestal level,
    /// [`table`]), when the final model fails the check: when it passes
    /// too, the check cannot tell a unit mistake from a table scale there
    /// and neither is trusted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub table: Option<TableScale>,
}

/// Where the scale of a hypothesis is put: every bearing's transducers of
/// one kind, or one bearing's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Reading {
    /// The transducers.
    pub kind: Kind,
    /// The bearing (index into the run's bearings); `None`: every bearing.
    pub bearing: Option<usize>,
    /// One direction of `bearing` only (0: y, 1: z; [`channel`]); `None`:
    /// both. Only with a bearing.
    pub dir: Option<usize>,
}

impl Reading {
    /// Every bearing's transducers of `kind`.
    pub fn every(kind: Kind) -> Self {
        Self {
            kind,
            bearing: None,
            dir: None,
        }
    }

    /// Bearing `b`'s transducers of `kind`.
    pub fn bearing(kind: Kind, b: usize) -> Self {
        Self {
            kind,
            bearing: Some(b),
            dir: None,
        }
    }

    /// Bearing `b`'s channel `dir` (0: y, 1: z) of `kind`.
    pub fn channel(kind: Kind, b: usize, dir: usize) -> Self {
        Self {
            kind,
            bearing: Some(b),
            dir: Some(dir),
        }
    }

    /// Every reading of a run of `nb` bearings: every bearing's `rel` and
    /// `ped`, then (more than one bearing) each bearing's, then each
    /// bearing's four channels.
    pub fn all(nb: usize) -> Vec<Self> {
        let kinds = [Kind::Rel, Kind::Ped];
        let mut out: Vec<Self> = kinds.map(Self::every).to_vec();
        if nb > 1 {
            for b in 0..nb {
                out.extend(kinds.map(|k| Self::bearing(k, b)));
            }
        }
        out.extend((0..nb).flat_map(Self::channels));
        out
    }

    /// Bearing `b`'s four channels (`rel_y`, `rel_z`, `ped_y`, `ped_z`).
    pub fn channels(b: usize) -> [Self; 4] {
        [
            Self::channel(Kind::Rel, b, 0),
            Self::channel(Kind::Rel, b, 1),
            Self::channel(Kind::Ped, b, 0),
            Self::channel(Kind::Ped, b, 1),
        ]
    }
}

/// Step of log10 s of the factor's interval walk [-] (0.46 % in s).
const INTERVAL_STEP: f64 = 0.002;

/// `prep` and the base model `state` as hypothesis s on `reading` makes
/// them (module docs): its readings divided by s (variances by s²), its
/// bearings' pedestal terms and runouts scaled as the equation's
/// homogeneity says, the noise weights propagated afresh. One channel
/// ([`Reading::dir`]): the pedestals refitted instead ([`channel`]);
/// `None` where that refit fails.
pub fn hypothesis(
    prep: &Prepared,
    state: &State,
    reading: Reading,
    s: f64,
) -> Option<(Prepared, State)> {
    if let (Some(b), Some(dir)) = (reading.bearing, reading.dir) {
        return channel::hypothesis(prep, state, reading.kind, b, dir, s);
    }
    let mut p = prep.clone();
    let kind = reading.kind;
    let range = match kind {
        Kind::Rel => 0..4,
        Kind::Ped => 4..8,
    };
    let chosen = |b: usize| reading.bearing.is_none_or(|j| j == b);
    for o in p
        .points
        .iter_mut()
        .enumerate()
        .filter(|(b, _)| chosen(*b))
        .flat_map(|(_, row)| row.iter_mut().flatten())
    {
        let x = match kind {
            Kind::Rel => &mut o.rel,
            Kind::Ped => &mut o.ped,
        };
        for z in x.iter_mut() {
            *z /= s;
        }
        for v in &mut o.var[range.clone()] {
            *v /= s * s;
        }
    }
    let mut st = state.clone();
    for (t, v) in st.model.terms.iter().zip(st.params.beta.iter_mut()) {
        if !t.bearings().into_iter().flatten().any(chosen) {
            continue;
        }
        let runout = matches!(t, Term::Runout { .. });
        *v *= match kind {
            Kind::Rel => 1.0 / s,
            Kind::Ped if runout => 1.0,
            Kind::Ped => s,
        };
    }
    st.weights = Weights::propagate(&p, &st.model, &st.params);
    Some((p, st))
}

/// The machine-level gap of hypothesis s on `kind` (`None` where that
/// model cannot be simulated) [-].
fn gap_of(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    reading: Reading,
    s: f64,
) -> Option<f64> {
    let (p, st) = hypothesis(prep, state, reading, s)?;
    let r: Readings = resimulate(machine, &p, &st, None).ok()?;
    Some(machine_gap(&p, &r)).filter(|g| g.is_finite())
}

/// The s of `reading` that minimises the base model's machine-level gap:
/// [`minimise`] over log10 s within ±[`LOG_RANGE`] (one bearing:
/// ±[`LOG_RANGE_ONE`]); one channel: [`channel::best_factor`].
fn best_factor(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    reading: Reading,
) -> Option<(f64, f64)> {
    let g = |l: f64| gap_of(machine, prep, state, reading, 10f64.powf(l));
    if reading.dir.is_some() {
        return channel::best_factor(g, reading);
    }
    let range = if reading.bearing.is_some() {
        LOG_RANGE_ONE
    } else {
        LOG_RANGE
    };
    minimise(g, range)
}

/// The factors around `s` [-] whose hypothesis on `reading` stays within
/// the check's limit for the floor `floor` [-]: log10 s walked outward in
/// steps of [`INTERVAL_STEP`] until the gap leaves it (at most 0.5 either
/// side).
fn interval(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    reading: Reading,
    s: f64,
    floor: f64,
) -> [f64; 2] {
    let passes = |l: f64| {
        gap_of(machine, prep, state, reading, 10f64.powf(l))
            .is_some_and(|g| MachineCheck::of(g, floor) == MachineCheck::Agrees)
    };
    let l0 = s.log10();
    let edge = |dir: f64| {
        let mut l = l0;
        for _ in 0..250 {
            if !passes(l + dir * INTERVAL_STEP) {
                break;
            }
            l += dir * INTERVAL_STEP;
        }
        10f64.powf(l)
    };
    [edge(-1.0), edge(1.0)]
}

/// What the search finds of one reading on a run: its best factor and the
/// three tests a named scale passes ([`passing`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Examined {
    /// The reading.
    pub reading: Reading,
    /// Its best factor s [-].
    pub factor: f64,
    /// The machine-level gap at s [-].
    pub gap: f64,
    /// That model's floor [-].
    pub floor: f64,
    /// Whether s passes the check (its own floor).
    pub passes: bool,
    /// The gap of the hypothesis at s = 1 (the readings as they are; one
    /// channel: the refit of them) [-].
    pub as_read_gap: f64,
    /// Whether that gap fails the yardstick under which s passes (the
    /// evidence that the readings are not right as they are).
    pub as_read_fails: bool,
    /// sd of ln s ([`evidence::log_sd`]); NaN where not computed [-].
    pub log_sd: f64,
    /// Whether s is named: it passes, the readings as read fail, and
    /// [`evidence::named`].
    pub named: bool,
}

/// [`Examined`] of `reading` on the base model `state`. `stop`: leave off
/// at the first test it fails (the search's way: `log_sd` NaN, `as_read`
/// NaN where not reached); otherwise every number is computed (the
/// false-alarm measurement's, docs/robustness-hostile.md, Session 43 (unitfa17)).
pub fn examine(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    reading: Reading,
    stop: bool,
) -> Option<Examined> {
    let (s, g) = best_factor(machine, prep, state, reading)?;
    let (p, st) = hypothesis(prep, state, reading, s)?;
    let r = resimulate(machine, &p, &st, None).ok()?;
    let f = machine_floor(machine, &p, &st, None, &r).ok()?;
    let mut e = Examined {
        reading,
        factor: s,
        gap: g,
        floor: f,
        passes: MachineCheck::of(g, f) == MachineCheck::Agrees,
        as_read_gap: f64::NAN,
        as_read_fails: false,
        log_sd: f64::NAN,
        named: false,
    };
    if stop && !e.passes {
        return Some(e);
    }
    // The evidence: the readings as they are (s = 1) fail the yardstick
    // under which s passes. A wide limit of the model as read (the check
    // cannot judge it) is no evidence for a scale that merely narrows it.
    // One channel: the refit of the readings as read; where the simulator
    // cannot hold it, the base model itself (the readings as read too).
    e.as_read_gap = gap_of(machine, prep, state, reading, 1.0).or_else(|| {
        let r = resimulate(machine, prep, state, None).ok()?;
        Some(machine_gap(prep, &r)).filter(|g| g.is_finite())
    })?;
    e.as_read_fails = MachineCheck::of(e.as_read_gap, f) != MachineCheck::Agrees;
    if stop && !e.as_read_fails {
        return Some(e);
    }
    // A scale within its own ± of 1, or within a transducer's calibration
    // tolerance, is no unit mistake ([`evidence`]).
    e.log_sd = evidence::log_sd(machine, prep, state, reading, s).unwrap_or(f64::NAN);
    e.named = e.passes && e.as_read_fails && evidence::named(s, e.log_sd);
    Some(e)
}

/// The hypothesis `reading` at its best s, when it brings the base model
/// `state` within the machine-level check's limit ([`MachineCheck::of`]
/// agrees, its own floor) and is named ([`examine`]).
///
/// One channel is named only as a unit mistake
/// ([`channel::a_unit_mistake`]): near a listed factor, and, when the final
/// model is not found failing the check (its gap `rival` [-]: the physical
/// effects it names may explain the run), told apart from it by the data.
fn passing(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    reading: Reading,
    rival: Option<f64>,
) -> Option<UnitScale> {
    let e = examine(machine, prep, state, reading, true)?;
    if !e.named {
        return None;
    }
    let s = e.factor;
    if reading.dir.is_some() && !channel::a_unit_mistake(s, e.log_sd, e.floor, rival) {
        return None;
    }
    Some(UnitScale {
        kind: reading.kind,
        bearing: reading.bearing.and_then(|b| prep.bearings.get(b).cloned()),
        channel: reading.dir.map(|d| channel::column(reading.kind, d)),
        factor: s,
        log_sd: e.log_sd,
        gap: e.gap,
        floor: e.floor,
        nearest: nearest_common(s),
        factor_interval: interval(machine, prep, state, reading, s, e.floor),
        also_fits: Vec::new(),
        table: None,
    })
}

/// The scale in words: `\`rel\` of B2 × 0.0394` [text].
fn short(u: &UnitScale) -> String {
    let at = u
        .bearing
        .as_deref()
        .map_or(" (every bearing)".to_string(), |b| format!(" of {b}"));
    format!("`{}`{at} ÷ {:.4}", u.columns(), u.factor)
}

impl UnitScale {
    /// The columns the scale is on: the channel's name, or the kind's
    /// prefix (`rel_y`, `rel`) [text].
    pub fn columns(&self) -> &str {
        self.channel.as_deref().unwrap_or(self.kind.columns())
    }
}

/// A scale on the transducers of one kind (every bearing's, or one
/// bearing's, or one bearing's one channel) that the machine file finds,
/// for the base model `state`.
///
/// `fails`: the final model fails the machine-level check or the check
/// cannot judge it (its limit is too wide) or it cannot be simulated. Then every
/// reading is tried ([`Reading::all`]: every bearing's `rel`, `ped`, then
/// each bearing's, then each bearing's four channels),
/// and the one whose best s brings the base model within the check's limit
/// with the smallest gap is returned, the other passing ones in
/// `also_fits`. `None` when the base model already agrees (s = 1 passes)
/// or when no scale explains the disagreement (another cause: the file's
/// rotor, unbalance or table).
///
/// Otherwise (the final model passes): `named` are the effects the final
/// model carries that a scale at one bearing also explains at the pedestal
/// level (`bearing_coefficients`, `pedestal_sub_base`,
/// `foundation_coupling`), each as (its words, its bearings' indices).
/// Each of their bearings' `rel` and `ped` is tried, and the four
/// channels of those bearings and of the bearings in `poor` (whose base
/// model identify's tests find poor, [`crate::diagnose::trust::base_model_findings`]:
/// one channel in the wrong unit leaves its bearing's fit poor); a passing
/// one is returned with the named effects in `also_fits`: the machine file
/// cannot tell the two readings apart, and neither is to be trusted.
///
/// `rival`: the final model's gap [-] when the check does not find it
/// failing (it agrees or cannot judge), a physical reading of the run that
/// a channel competes with only where the data tell them apart
/// ([`channel::a_unit_mistake`]; session 44, docs/robustness-hostile.md, Session 44 (unit17b));
/// `None`: the check finds it failing, or it cannot be simulated.
pub fn find(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    fails: bool,
    rival: Option<f64>,
    named: &[(String, Vec<usize>)],
    poor: &[usize],
) -> Option<UnitScale> {
    let nb = prep.bearings.len();
    let mut readings: Vec<Reading> = Vec::new();
    let kinds = [Kind::Rel, Kind::Ped];
    if fails {
        let r = resimulate(machine, prep, state, None).ok()?;
        let gap = machine_gap(prep, &r);
        let floor = machine_floor(machine, prep, state, None, &r).ok()?;
        if MachineCheck::of(gap, floor) == MachineCheck::Agrees {
            return None;
        }
        readings = Reading::all(nb);
    } else {
        let mut at: Vec<usize> = named.iter().flat_map(|(_, b)| b.clone()).collect();
        at.sort_unstable();
        at.dedup();
        for &b in at.iter().filter(|&&b| b < nb) {
            readings.extend(kinds.map(|kind| Reading::bearing(kind, b)));
        }
        // One channel in the wrong unit leaves its bearing's pedestal fit
        // poor (identify untrusts it) and may pass the check with another
        // effect named: its channels are tried at those bearings too.
        at.extend(poor);
        at.sort_unstable();
        at.dedup();
        readings.extend(
            at.into_iter()
                .filter(|&b| b < nb)
                .flat_map(Reading::channels),
        );
    }
    let mut found: Vec<(Reading, UnitScale)> = readings
        .into_iter()
        .filter_map(|r| passing(machine, prep, state, r, rival).map(|u| (r, u)))
        .collect();
    found.sort_by(|a, b| a.1.gap.total_cmp(&b.1.gap));
    let (reading, first) = found.first()?;
    let mut first = first.clone();
    if fails {
        // The unit mistake's twin: the table at the same bearing(s).
        first.table = table::best(machine, prep, state, reading.bearing);
    } else {
        first.also_fits.extend(named.iter().map(|(w, _)| w.clone()));
    }
    first.also_fits.extend(
        found
            .iter()
            .skip(1)
            .map(|(_, u)| format!("{} (gap {:.4})", short(u), u.gap)),
    );
    Some(first)
}
