//! The diagnosis as data (serialised by `--json`, formats.md keys first);
//! as the text report an engineer reads in [`text`].

use super::criterion::Evidence;
use super::locate::Location;
use serde::Serialize;
use std::collections::BTreeMap;

mod text;

/// What the report's overall machine-level "before" (`machine_gap_before`)
/// is: the base model as `plinth identify` fits it (maximum likelihood,
/// `State::base`).
pub const BASE_AS_IDENTIFY: &str = "base model as identify fits it";

/// What step 1's machine-level "before" is: the base model refitted as the
/// steps' joint refits fit it (`crate::diagnose::machine::refitted_base`),
/// the model step 1 extends.
pub const BASE_AS_STEPS: &str = "base model refitted as the steps fit it";

/// A parameter estimate with its standard error (SI units of the parameter).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Estimate {
    /// Parameter name (`k_yz`, `tau`, ...).
    pub name: String,
    /// Value [SI].
    pub value: f64,
    /// Standard error [SI] (the larger of noise-floor and robust values).
    pub std_err: f64,
}

/// A candidate effect with its evidence.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CandidateSummary {
    /// Effect name (formats.md).
    pub effect: String,
    /// Bearing it acts on.
    pub bearing: String,
    /// Delayed channels of a sensor delay (`ped`, `ped_y`, `rel`, ...).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub channels: Option<String>,
    /// The test that decided it ([`Evidence`]'s statistic): `"Wald, χ² with
    /// Bonferroni over N candidates"` or `"likelihood-ratio, parametric
    /// bootstrap (N)"`.
    pub test: String,
    /// The evidence for it.
    pub evidence: Evidence,
    /// Its own parameters as fitted.
    pub parameters: Vec<Estimate>,
}

/// One step of the greedy search: an effect added.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Step {
    /// Effect name (formats.md).
    pub effect: String,
    /// Bearing it acts on (the first bearing of the first base group for
    /// `foundation_coupling`: every bearing on a base is in `foundation`).
    pub bearing: String,
    /// Pedestal-level gap before adding it [-].
    pub gap_before: f64,
    /// Pedestal-level gap after adding it and refitting [-].
    pub gap_after: f64,
    /// Noise floor of the gap after the step [-].
    pub gap_floor_after: f64,
    /// Machine-level gaps (re-simulated machine), with `--machine`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub machine_gap_before: Option<f64>,
    /// Machine-level gap after the step, with `--machine`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub machine_gap_after: Option<f64>,
    /// Standard deviation of the step's machine-level gap change from one
    /// noise draw to the next (`machine::change`), with `--machine` where
    /// the gap did not fall [-].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub machine_gap_change_sd: Option<f64>,
    /// Delayed channels of a sensor delay.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub channels: Option<String>,
    /// The effect's own parameters after the refit.
    pub parameters: Vec<Estimate>,
    /// The test that decided it (as in [`CandidateSummary::test`]).
    pub test: String,
    /// For `foundation_coupling`: the bases and the bootstrap test.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub foundation: Option<FoundationReport>,
    /// Evidence for the effect.
    pub evidence: Evidence,
    /// The next-best candidate of the step.
    pub runner_up: Option<CandidateSummary>,
    /// Significant candidates ranked above this effect whose joint refit
    /// was rejected, each with why: the reason a runner-up can show a
    /// larger ΔBIC than the effect chosen.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub passed_over: Vec<PassedOver>,
    /// Candidates tried in the step (the Bonferroni count).
    pub candidates_tried: usize,
    /// Candidates that could not be fitted (not identifiable from these data).
    pub candidates_failed: usize,
    /// Set when a later step's joint refit left this effect insignificant
    /// (the backward check): the effect was removed again, with the reason.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dropped: Option<String>,
    /// Pedestal dampings at its bearing the effect was fitted with held at
    /// zero (free, they came out impossible), and what that means for a
    /// delay.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub held: Option<super::summaries::HeldDamping>,
}

/// A significant candidate ranked above a step's effect and not chosen.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PassedOver {
    /// Effect name (formats.md).
    pub effect: String,
    /// Bearing it acts on.
    pub bearing: String,
    /// Why its joint refit was rejected.
    pub reason: String,
}

/// The likelihood-ratio test of `foundation_coupling` (module docs of
/// `super::foundation`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FoundationTest {
    /// `"likelihood-ratio, parametric bootstrap (N)"`.
    pub test: String,
    /// J_rigid − J_base of the favoured grouping [-].
    pub likelihood_ratio: f64,
    /// The statistic: likelihood ratio − q·ln N [-].
    pub statistic: f64,
    /// Bootstrap replicates under the null (rigid ground).
    pub replicates: usize,
    /// Replicates whose statistic reached the observed one.
    pub exceedances: usize,
    /// 95 % point of the replicates (the critical value at 5 %) [-].
    pub critical_value_95: f64,
    /// (1 + exceedances)/(replicates + 1).
    pub p_empirical: f64,
    /// Beyond every replicate, the tail of a scaled χ² matched to the
    /// replicates; otherwise `p_empirical`.
    pub p_value: f64,
    /// Groupings of pedestals into bases searched (the Bonferroni factor).
    pub groupings: usize,
    /// The p-value the decision uses: `p_value` × `groupings`, at most 1.
    pub p_calibrated: f64,
}

/// One identified base and the pedestals on it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BaseGroupReport {
    /// Bearings whose pedestals stand on it.
    pub bearings: Vec<String>,
    /// What the data determine in y and z (`full`, `quasi_static` with the
    /// compliance 1/K_B [m/N], `mass_line` with M_B [kg], `not_detected`).
    pub identifiability: [crate::estimate::base::BaseIdentifiability; 2],
    /// Its parameters (k [N/m], c [N·s/m], m [kg] per direction; meaningful
    /// as far as `identifiability` says; null = not determined).
    pub base: crate::estimate::base::BaseParams,
    /// Their standard errors.
    pub base_std_err: crate::estimate::base::BaseParams,
    /// Base natural frequency sqrt(K_B/M_B)/2π (y, z) [Hz].
    pub base_frequency_hz: [f64; 2],
    /// Whether the joint fit converged.
    pub converged: bool,
    /// What the data determine, as named estimates (`base_k_y`, ...,
    /// `base_compliance_y` [m/N] when only that is determined).
    pub parameters: Vec<Estimate>,
}

/// The bases `foundation_coupling` identified, with its test.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FoundationReport {
    /// The bases.
    pub groups: Vec<BaseGroupReport>,
    /// The test that decided it.
    pub test: FoundationTest,
}

/// Identified parameters of one pedestal.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Pedestal {
    /// Bearing name.
    pub bearing: String,
    /// Parameter values by name [SI].
    #[serde(flatten)]
    pub values: BTreeMap<String, f64>,
    /// Standard errors by name [SI].
    pub std_err: BTreeMap<String, f64>,
}

/// The measurement noise the criterion used.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NoiseSummary {
    /// Significant digits of each `measurements.csv` column (by column name).
    pub digits: BTreeMap<String, u32>,
    /// Per bearing: the noise source, sd per channel and the scatter law.
    pub bearings: BTreeMap<String, super::noise::BearingNoiseSummary>,
    /// Noise floor of the pedestal-level gap with the base model [-].
    pub gap_floor_before: f64,
    /// Noise floor of the pedestal-level gap with the final model [-].
    pub gap_floor_after: f64,
}

/// The whole diagnosis.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Diagnosis {
    /// Parameters of the base pedestal model.
    pub base_model: Vec<String>,
    /// The effects added, in order.
    pub steps: Vec<Step>,
    /// Names of the effects added (empty: no significant missing effect).
    pub effects_added: Vec<String>,
    /// Pedestal-level gap of the base model [-].
    pub gap_before: f64,
    /// Pedestal-level gap of the final model [-].
    pub gap_after: f64,
    /// Machine-level gap of the base model, with `--machine` [-].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub machine_gap_before: Option<f64>,
    /// Machine-level gap of the final model, with `--machine` [-].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub machine_gap_after: Option<f64>,
    /// Noise floor of the machine-level gap, with `--machine` [-].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub machine_gap_floor: Option<f64>,
    /// Whether the machine-level check could judge the final model (its
    /// limit at most `trust::MACHINE_INFORMATIVE_LIMIT`), with `--machine`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub machine_check_informative: Option<bool>,
    /// With `--machine`, when the final model fails the machine-level
    /// check: one scale on every transducer of one kind (rel or ped) that
    /// brings the base model within it, the likely cause
    /// (`machine::unit_scale`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unit_scale: Option<super::machine::unit_scale::UnitScale>,
    /// With `--machine`, when the final model passes: the scales on one
    /// bearing's transducers the check cannot see, where they hold a
    /// common unit mistake (`machine::unit_scale::blind`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub unit_scale_blind: Vec<super::machine::unit_scale::Blind>,
    /// The noise floor.
    pub noise: NoiseSummary,
    /// Where the base model's disagreement lives, largest first.
    pub where_before: Vec<Location>,
    /// Where the final model's disagreement lives, largest first.
    pub where_after: Vec<Location>,
    /// Identified pedestals with the base model.
    pub pedestals_before: Vec<Pedestal>,
    /// Identified pedestals with the final model.
    pub pedestals_after: Vec<Pedestal>,
    /// The best candidate left when the search stopped (not significant,
    /// or significant with its joint refit rejected).
    pub best_rejected: Option<CandidateSummary>,
    /// The significant candidates of the round that stopped the search,
    /// each with why its joint refit was rejected (a pedestal made
    /// negative, or held dampings and a worse fit than the final model).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub passed_over_at_stop: Vec<PassedOver>,
    /// Set when the search stopped because a round brought the model back
    /// to one an earlier round had left (forward and backward steps
    /// cycling): the statement, also a trust reason.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub search_cycle: Option<String>,
    /// `foundation_coupling` as tried on the base model (its bases and
    /// test), whether chosen or not; absent when not tried (one bearing, a
    /// reduced `--base`, or a base model already at the noise floor).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub foundation: Option<FoundationReport>,
    /// Family-wise significance level per step.
    pub significance_level: f64,
    /// One-paragraph conclusion.
    pub verdict: String,
    /// False when the identified parameters are not to be trusted: the
    /// final model leaves a gap well above its noise floor (the data hold
    /// something no effect of the library explains), the gap rose, or a
    /// pedestal is physically impossible; `trust_reasons` says which.
    pub trusted: bool,
    /// Why the parameters are not to be trusted (empty when trusted).
    pub trust_reasons: Vec<String>,
    /// When the final model leaves a disagreement above the floor, or a
    /// bearing is untrusted for a model error there: the pedestal channels
    /// and speed bands that hold it (where to look;
    /// [`Diagnosis::locate_unexplained`]).
    pub unexplained: Vec<super::locate::Unexplained>,
    /// Convention mistakes the data most likely carry, per pedestal
    /// (`identify::convention`): with one, every other finding is suspect.
    pub suspected_convention_errors: Vec<crate::identify::convention::ConventionFinding>,
    /// Per bearing, the speeds [Hz] whose channels look flipped by 180° (a
    /// keyphasor fault; the tests of `plinth identify`,
    /// `identify::flips::flipped_speeds`), ascending: those readings are
    /// left out of the noise, every fit and every gap above. Only bearings
    /// with such speeds.
    pub flipped_speeds_hz: BTreeMap<String, Vec<f64>>,
    /// Per bearing, the speeds [Hz] the robust fit of the base model lists
    /// as outliers (`plinth identify`'s `outlier_speeds_hz`) that the final
    /// model does not explain either, ascending: left out of the noise,
    /// every fit and every gap above (`diagnose::outliers`). Only bearings
    /// with such speeds.
    pub outlier_speeds_hz: BTreeMap<String, Vec<f64>>,
    /// Per bearing, the speeds [Hz] the robust fit of the base model lists
    /// as outliers that the effects chosen without them explain: put back
    /// into the data, the search run again with them. Only bearings with
    /// such speeds.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub outliers_explained_hz: BTreeMap<String, Vec<f64>>,
    /// With `--machine`: the steps the first search chose from the first
    /// one the machine-level check refuted on, dropped (`super::refute`);
    /// each keeps the diagnosis untrusted.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub refuted_steps: Vec<super::refute::RefutedStep>,
}

/// The modal view of the pedestals by bearing, of the base and the final
/// model (`diagnose::cli::modal_views`), shown under their tables.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ModalViews {
    /// Base model.
    pub before: BTreeMap<String, crate::present::modal::PedestalModal>,
    /// Final model.
    pub after: BTreeMap<String, crate::present::modal::PedestalModal>,
}

impl Diagnosis {
    /// Sets `unexplained` from the verdict as it stands: the pedestal
    /// channels above [`super::trust::AT_THE_FLOOR`] times their floor when
    /// the verdict says the disagreement is unexplained, and the channels
    /// of every bearing a trust reason untrusts for a model error there
    /// ([`super::locate::untrusted_bearings`]), whatever else was named.
    /// Called once the verdict is concluded and again after the
    /// machine-level check has added its reasons.
    pub fn locate_unexplained(&mut self) {
        let mut names: Vec<String> = Vec::new();
        for l in &self.where_after {
            if !names.contains(&l.bearing) {
                names.push(l.bearing.clone());
            }
        }
        let flagged = super::locate::untrusted_bearings(&names, &self.trust_reasons);
        self.unexplained =
            if self.verdict.contains(super::trust::UNEXPLAINED) || !flagged.is_empty() {
                super::locate::unexplained(&self.where_after, super::trust::AT_THE_FLOOR, &flagged)
            } else {
                Vec::new()
            };
    }
}
