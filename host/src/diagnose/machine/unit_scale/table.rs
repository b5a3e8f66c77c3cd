//! The twin of a unit mistake at a bearing: that bearing's table scaled.
//!
//! At the pedestal level a bearing table t times the file's (stiffness and
//! damping, K*·t) at bearing j identifies that pedestal t times what the
//! file's table gives: Z·t·ped = t·K*·(rel − r). That is exactly what j's
//! `rel` readings 1/t times their true value give (Z/s, s = 1/t), or its
//! `ped` readings t times theirs (s·Z). `plinth identify` cannot tell the
//! three apart. The machine file can only where the rotor's response
//! depends on that table: a table scale changes the rotor's motion, a unit
//! mistake only the readings. So the reading "table × t at j, its pedestal
//! × t, the readings as they are" is re-simulated over t and judged by the
//! same check as the unit reading ([`crate::diagnose::trust::MachineCheck`]);
//! which of the two passes is decided by the check's misfit of each, never
//! by the factor's closeness to a unit factor.

use super::super::{machine_floor, machine_gap, resimulate};
use super::minimise;
use crate::diagnose::data::Prepared;
use crate::diagnose::fit::Weights;
use crate::diagnose::model::Term;
use crate::diagnose::state::State;
use crate::diagnose::trust::MachineCheck;
use crate::sim::{BearingModel, Machine};
use plinth_shared::bearing::BearingCoefficients;
use serde::Serialize;

/// The bearing table of a unit reading's bearing(s) scaled instead (its
/// twin at the pedestal level), as the machine-level check sees it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TableScale {
    /// The factor t on the table (stiffness and damping) and on the
    /// pedestal at the same bearing(s) that minimises the gap [-].
    pub factor: f64,
    /// Machine-level gap of the base model with that table and pedestal [-].
    pub gap: f64,
    /// That model's machine-level noise floor [-].
    pub floor: f64,
    /// Whether that model passes the check (its gap within the limit of its
    /// own floor, and the limit can tell).
    pub passes: bool,
}

/// Search range of log10 t [-]: a table off by up to 10× either way.
const LOG_RANGE_TABLE: f64 = 1.0;

/// `machine` with the table of `bearing` (every measured bearing: `None`)
/// t times the one the data were fitted with (`bearings.csv` at the
/// measured speeds, stiffness and damping), and `state` with that
/// bearing's pedestal terms (not its runouts) × t.
pub fn hypothesis(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    bearing: Option<usize>,
    t: f64,
) -> Option<(Machine, State)> {
    let chosen = |b: usize| bearing.is_none_or(|j| j == b);
    let mut m = machine.clone();
    for (b, name) in prep.bearings.iter().enumerate().filter(|(b, _)| chosen(*b)) {
        let rows: Vec<(f64, BearingCoefficients<f64>)> = prep
            .points
            .get(b)?
            .iter()
            .flatten()
            .map(|o| {
                let w = o.omega();
                let coefficients = BearingCoefficients {
                    k: std::array::from_fn(|r| std::array::from_fn(|c| t * o.kstar[r][c].re)),
                    c: std::array::from_fn(|r| std::array::from_fn(|c| t * o.kstar[r][c].im / w)),
                };
                (o.speed_hz, coefficients)
            })
            .collect();
        let i = m.bearing_index(name).ok()?;
        m.bearings[i].model = BearingModel::Table(rows);
    }
    let mut st = state.clone();
    for (term, v) in st.model.terms.iter().zip(st.params.beta.iter_mut()) {
        if matches!(term, Term::Runout { .. }) || !term.bearings().into_iter().flatten().any(chosen)
        {
            continue;
        }
        *v *= t;
    }
    st.weights = Weights::propagate(prep, &st.model, &st.params);
    Some((m, st))
}

/// The machine-level gap of the table reading at `bearing` with factor t
/// (`None` where that model cannot be simulated) [-].
fn gap_of(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    bearing: Option<usize>,
    t: f64,
) -> Option<f64> {
    let (m, st) = hypothesis(machine, prep, state, bearing, t)?;
    let r = resimulate(&m, prep, &st, None).ok()?;
    Some(machine_gap(prep, &r)).filter(|g| g.is_finite())
}

/// The table reading at `bearing` at its best t (log10 t within
/// ±[`LOG_RANGE_TABLE`]), with its gap, floor and whether it passes.
pub fn best(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    bearing: Option<usize>,
) -> Option<TableScale> {
    let (t, gap) = minimise(
        |l| gap_of(machine, prep, state, bearing, 10f64.powf(l)),
        LOG_RANGE_TABLE,
    )?;
    let (m, st) = hypothesis(machine, prep, state, bearing, t)?;
    let r = resimulate(&m, prep, &st, None).ok()?;
    let floor = machine_floor(&m, prep, &st, None, &r).ok()?;
    Some(TableScale {
        factor: t,
        gap,
        floor,
        passes: MachineCheck::of(gap, floor) == MachineCheck::Agrees,
    })
}
