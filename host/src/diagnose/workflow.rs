//! The discrepancy workflow: fit the base model, measure the gap, then add
//! the best-supported missing effect, one at a time (forward selection over
//! the whole library, the bases included), while the evidence is
//! significant relative to the noise floor. After each effect added the
//! whole model is refitted jointly, and every earlier effect must still be
//! significant in that joint fit (backward check, Bonferroni over the
//! effects checked); one that is not is removed again. The bases
//! (`foundation_coupling`, `pedestal_sub_base`) are tried in every round on
//! the data the chosen sensor and table effects correct.

mod finish;
mod on_base;
mod on_ground;
mod search;

use super::bearing_table::WrittenTable;
pub use super::correct::corrected;
use super::data::Prepared;
pub use super::forward::{evaluate, step, Evaluated, StepOutcome};
use super::foundation::{self, FoundationFit};
use super::report::Diagnosis;
pub use super::state::{base_model, pedestals, GroupInference, State};
use crate::rundir::RunDir;
use crate::sim::oil_film::OilFilmBearing;
use anyhow::{Context, Result};
use plinth_shared::regression::Parameter;
use search::search;
use std::collections::BTreeMap;

/// Settings of the workflow.
#[derive(Clone, Debug)]
pub struct Options {
    /// Parameters of the base pedestal model (default: the paper's five).
    pub base: Vec<Parameter>,
    /// Family-wise significance level per step (Bonferroni over candidates).
    pub alpha: f64,
    /// Most effects to add.
    pub max_steps: usize,
    /// A progress line on stderr (only on a terminal, after a second).
    pub progress: bool,
    /// Bootstrap replicates of the `foundation_coupling` test (0: the
    /// candidate is not tried).
    pub foundation_replicates: usize,
    /// Seed of that bootstrap.
    pub foundation_seed: u64,
    /// Oil-film geometry of bearings (by name) from the machine file: the
    /// `bearing_coefficients` candidate of those bearings
    /// ([`super::bearing_table`]).
    pub oil_films: Vec<(String, OilFilmBearing)>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            base: Parameter::ALL.to_vec(),
            alpha: 1e-3,
            max_steps: 8,
            progress: false,
            foundation_replicates: foundation::REPLICATES,
            foundation_seed: foundation::SEED,
            oil_films: Vec::new(),
        }
    }
}

/// Everything a diagnosis computed: the report and the fitted states (base
/// model first, then after each step) for plots.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The report.
    pub diagnosis: Diagnosis,
    /// The arranged measurements.
    pub prep: Prepared,
    /// The base model's fit, then the fit after each step.
    pub states: Vec<State>,
    /// `foundation_coupling` when chosen: the bases and pedestals on them
    /// (the last state keeps the rigid fit of the bearings on no base).
    pub foundation: Option<FoundationFit>,
    /// The whole model after each step (aligned with `diagnosis.steps`):
    /// the state and the base it stands on, if any (`--machine`).
    pub after_steps: Vec<(State, Option<FoundationFit>)>,
}

/// Runs the whole workflow on a run directory at the pedestal level.
///
/// `foundation_coupling` (pedestals on a shared, unmeasured base,
/// [`super::foundation`]) is tried on the base model in the first round,
/// next to the library; it wins when its bootstrap test is significant, it
/// brings the gap down, and further down than the best significant library
/// candidate does. The search then goes on with the corrections (probe
/// runout, sensor delays, a table's clearance, pedestal cross-coupling) on
/// top of the base: each applied to the data, the base refitted, tested by
/// the drop of the base's χ², with the backward check on the base
/// ([`super::bases::correction_on_base`]).
///
/// The speeds the base model's robust fit lists as outliers are left out of
/// the search and tested again under the model it chose
/// ([`super::outliers`]): those the chosen effects explain are put back and
/// the search run again with them, the others listed
/// (`Diagnosis::outlier_speeds_hz`).
pub fn diagnose(run: &RunDir, opts: &Options) -> Result<Outcome> {
    let all = Prepared::from_run(run)?;
    let listed = all.outlier_speeds_hz.clone();
    if listed.iter().all(Vec::is_empty) {
        return search(run, all, opts);
    }
    let why = "the run without the speeds the base model's robust fit lists as outliers";
    let prep = all.leaving_out(run, &listed).context(why)?;
    let first = search(run, prep, opts)?;
    let explained = super::outliers::explained(&all, &first, opts, &listed);
    let mut out = first;
    let mut left_out = listed.clone();
    if explained.iter().any(|e| !e.is_empty()) {
        let still = super::outliers::still_out(&listed, &explained);
        let prep = all.leaving_out(run, &still).context(why)?;
        let again = search(run, prep, opts)?;
        // Put back only when the search with them still names an effect
        // (the effects that explain them); otherwise they stay out.
        if !again.diagnosis.effects_added.is_empty() {
            out = again;
            left_out = still;
            out.diagnosis.outliers_explained_hz = by_name(&all, &explained);
        }
    }
    out.diagnosis.outlier_speeds_hz = by_name(&all, &left_out);
    Ok(out)
}

/// Per-bearing lists of `prep` by bearing name, only the non-empty ones.
fn by_name(prep: &Prepared, lists: &[Vec<f64>]) -> BTreeMap<String, Vec<f64>> {
    prep.bearings
        .iter()
        .zip(lists)
        .filter(|(_, l)| !l.is_empty())
        .map(|(b, l)| (b.clone(), l.clone()))
        .collect()
}

/// The oil-film table of every bearing of `prep` whose geometry `films`
/// gives and whose table it reproduces ([`WrittenTable::matched`]).
pub fn written_tables(
    prep: &Prepared,
    films: &[(String, OilFilmBearing)],
) -> Vec<Option<WrittenTable>> {
    prep.bearings
        .iter()
        .enumerate()
        .map(|(b, name)| {
            let (_, film) = films.iter().find(|(n, _)| n == name)?;
            let table: Vec<_> = prep.points[b]
                .iter()
                .flatten()
                .map(|p| (p.speed_hz, p.kstar))
                .collect();
            WrittenTable::matched(film, &table)
        })
        .collect()
}
