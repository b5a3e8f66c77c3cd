//! The search of [`super::diagnose`] on one arrangement of the data: the
//! base model, then rounds of forward selection, each on rigid ground
//! ([`super::on_ground`]) or, once a base is chosen, on that base
//! ([`super::on_base`]), then the report ([`super::finish`]).

use super::{written_tables, Options, Outcome};
use crate::diagnose::backward::Chosen;
use crate::diagnose::bases::BaseOn;
use crate::diagnose::data::Prepared;
use crate::diagnose::forward::step;
use crate::diagnose::foundation::FoundationFit;
use crate::diagnose::gap::{Gap, Prediction};
use crate::diagnose::locate::{locate, Location};
use crate::diagnose::report::{CandidateSummary, PassedOver, Pedestal, Step};
use crate::diagnose::state::{pedestals, State};
use crate::rundir::RunDir;
use anyhow::Result;
use plinth_shared::regression::Parameter;

/// Where the search stands: the model, the steps taken and what each
/// round needs from the rounds before it.
pub(super) struct Search<'a> {
    /// The arranged measurements searched.
    pub(super) prep: &'a Prepared,
    /// The workflow's settings.
    pub(super) opts: &'a Options,
    /// The model as it stands.
    pub(super) state: State,
    /// The base model's fit, then the fit after each library step.
    pub(super) states: Vec<State>,
    /// The whole model after each step and the base it stands on, if any.
    pub(super) after_steps: Vec<(State, Option<FoundationFit>)>,
    /// The steps taken, a removed one marked `dropped`.
    pub(super) steps: Vec<Step>,
    /// The best candidate of the round that stopped the search.
    pub(super) best_rejected: Option<CandidateSummary>,
    /// The significant candidates of the round that stopped the search
    /// whose joint refit was rejected, with why.
    pub(super) passed_over_at_stop: Vec<PassedOver>,
    /// The shared base as tried on the base model (reported whether chosen
    /// or not); later rounds try it again on the data the chosen sensor
    /// and table effects correct.
    pub(super) foundation_tried: Option<FoundationFit>,
    /// The library effects chosen so far (for the backward check).
    pub(super) chosen: Vec<Chosen>,
    /// The chosen base, refitted on the data the chosen corrections
    /// (sensor, table and cross-coupling effects) correct.
    pub(super) on_base: Option<BaseOn>,
    /// Set when a round brought the model back to one an earlier round had
    /// left ([`Search::came_back`]): the search stopped there, and why.
    pub(super) cycle: Option<String>,
}

/// The model as the search's steps define it: the kept steps' effect,
/// bearing and variant (channels), sorted. Two rounds that end with the
/// same set hold the same model (the joint refit of the same terms).
type Kept = Vec<(String, String, Option<String>)>;

/// What a round decided.
pub(super) enum Round {
    /// An effect or a base was added: search on.
    Added,
    /// Nothing more is supported: the search ends.
    Stop,
}

/// The base model as fitted before any step (what the report compares to).
pub(super) struct Before {
    /// Its prediction of the measurements.
    pub(super) prediction: Prediction,
    /// Its gap and the gap's noise floor.
    pub(super) gap: Gap,
    /// Where in speed and at which bearing it disagrees.
    pub(super) located: Vec<Location>,
    /// Its pedestals.
    pub(super) pedestals: Vec<Pedestal>,
}

impl Search<'_> {
    /// The model the kept steps define ([`Kept`]).
    fn kept(&self) -> Kept {
        let mut k: Kept = self
            .steps
            .iter()
            .filter(|s| s.dropped.is_none())
            .map(|s| (s.effect.clone(), s.bearing.clone(), s.channels.clone()))
            .collect();
        k.sort();
        k
    }

    /// Whether the round just ended brought the model back to one held
    /// after an earlier round (`visited`: each model with the step count it
    /// was reached at; this one is added when new). The forward step and
    /// the backward check are deterministic in the model, so from there
    /// they would add and remove the same effects again (two effects each
    /// significant alone and not beside the other: the data do not choose
    /// between them); the search stops at the model it came back to, and
    /// the statement says so.
    fn came_back(&self, visited: &mut Vec<(Kept, usize)>) -> Option<String> {
        let now = self.kept();
        let n = self.steps.len();
        let Some((_, m)) = visited.iter().find(|(k, _)| *k == now) else {
            visited.push((now, n));
            return None;
        };
        let model = if now.is_empty() {
            "the base model".to_string()
        } else {
            now.iter()
                .map(|(e, b, _)| format!("{e} at {b}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let earlier = if *m == 0 {
            "before step 1".to_string()
        } else {
            format!("after step {m}")
        };
        let between: Vec<String> = self.steps[*m..]
            .iter()
            .map(|s| format!("{} at {}", s.effect, s.bearing))
            .collect();
        Some(format!(
            "the search cycled: after step {n} its model ({model}) is the one it had {earlier}; the forward selection and the backward check would add and remove the same effects again ({}), each significant alone and not beside the others, so the data do not choose between these models; the search stopped at that model, and the values fitted at those effects' bearings depend on that choice",
            between.join(", ")
        ))
    }
}

/// The search of [`super::diagnose`] on the arranged data `prep` of `run`.
pub(super) fn search(run: &RunDir, prep: Prepared, opts: &Options) -> Result<Outcome> {
    let mut state = State::base(&prep, &opts.base)?;
    state.model.tables = written_tables(&prep, &opts.oil_films);
    let (prediction, gap) = state.gap(&prep);
    let before = Before {
        located: locate(&prep, &state.model, &state.params, &prediction),
        pedestals: pedestals(&prep, &state)?,
        prediction,
        gap,
    };
    let mut s = Search {
        prep: &prep,
        opts,
        states: vec![state.clone()],
        state,
        after_steps: Vec::new(),
        steps: Vec::new(),
        best_rejected: None,
        passed_over_at_stop: Vec::new(),
        foundation_tried: None,
        chosen: Vec::new(),
        on_base: None,
        cycle: None,
    };
    let try_bases = opts.base == Parameter::ALL.as_slice() && opts.foundation_replicates > 0;
    let mut ticker = crate::progress::Ticker::new(
        "diagnose: candidate-effect rounds",
        opts.max_steps,
        opts.progress,
    );
    let mut visited: Vec<(Kept, usize)> = vec![(s.kept(), 0)];
    for round in 0..opts.max_steps {
        ticker.tick(round);
        let outcome = step(&prep, &s.state, opts.alpha);
        // With a base chosen the search goes on: the corrections among the
        // candidates, each tested by the drop of the refitted base's χ²,
        // then the backward check on the base.
        let decided = match s.on_base.clone() {
            Some(current) => s.round_on_base(current, &outcome)?,
            None => s.round_on_ground(&outcome, round == 0, try_bases)?,
        };
        if let Round::Stop = decided {
            break;
        }
        if let Some(why) = s.came_back(&mut visited) {
            s.cycle = Some(why);
            break;
        }
    }
    let found = s.finish(run, before)?;
    Ok(Outcome {
        diagnosis: found.diagnosis,
        prep,
        states: found.states,
        foundation: found.foundation,
        after_steps: found.after_steps,
    })
}
