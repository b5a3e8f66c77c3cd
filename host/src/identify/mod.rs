//! Batch identification of pedestals (Feng & Hahn eq. 4), in f64: by
//! maximum likelihood with noise in every measured phasor (the default,
//! [`estimator`] over [`crate::estimate`]) or by the paper's least squares.
//!
//! Per pedestal (one per bearing), every measured speed gives the force the
//! bearing transmits, F = (K_b + iΩ·C_b)·rel (eq. 2, with the known bearing
//! coefficients interpolated to that speed), and eq. 3,
//! (k − Ω²m + iΩc)·ped = F per direction, gives up to four real equations
//! linear in θ = (k_y, k_z, m, c_y, c_z). They are stacked over speeds and
//! solved by column-scaled least squares ([`lsq`]), the paper's OLS and the
//! maximum-likelihood fit's start; the fit reports standard
//! errors, the residual and the condition number, and warns ([`Warning`])
//! whenever the data cannot support what it returns.
//!
//! Library entry points: [`identify_run`] (a whole [`RunDir`]),
//! [`pedestal_points`] + [`fit_pedestal`] (one pedestal from data in memory).

pub mod base;
mod checks;
pub mod cli;
pub mod conditional;
pub mod convention;
pub mod data;
pub mod delay_unknown;
pub mod estimator;
pub mod flips;
pub mod lsq;
pub mod misfit;
pub mod model;
pub mod on_base;
pub mod physical;
pub mod plausibility;
pub mod sensor_gain;
pub mod speed_lag;
pub mod synthetic;
pub mod trust;

pub use checks::std_err_withheld;
pub use estimator::{Estimator, NoiseReport, OlsComparison};
pub use model::{mode_label, mode_name, parse_mode, Model, ModelError};
pub use plinth_shared::regression::{EquationMode, Parameter};

use crate::estimate::noise::{BearingNoise, Quantisation, RunNoise};
use crate::estimate::params::{null_is_infinite, null_is_nan};
use crate::estimate::{complex_stiffness, Observation, Pedestal};
use crate::rundir::{BearingSchedule, Measurement, OutOfRange, RunDir, RunDirError};
use nalgebra::{DMatrix, DVector};
use plinth_shared::phasor::omega_from_hz;
use plinth_shared::regression::{equations_for_mode, PARAMETERS};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// How to identify: which equations and which parameters, and when to stop
/// trusting a fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// How the real and imaginary parts of eq. 3 are used (Table 2).
    pub mode: EquationMode,
    /// The parameters to estimate; `None` = [`Model::default_for`] the mode.
    pub model: Option<Model>,
    /// Condition number (of the column-scaled regression matrix) above which
    /// a fit is not trusted [-].
    pub max_condition_number: f64,
    /// Fewest distinct speeds for a trusted fit.
    pub min_speeds: usize,
    /// The estimator; ML applies to R&I only (the paper's other equation
    /// variants are least-squares variants and always use OLS).
    pub estimator: Estimator,
    /// How the digits of the numbers were reduced (the noise model's
    /// `digits` source).
    pub quantisation: Quantisation,
    /// With ML: also report OLS and its efficiency against the bound.
    pub compare_ols: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            mode: EquationMode::RealAndImag,
            model: None,
            max_condition_number: DEFAULT_MAX_CONDITION_NUMBER,
            min_speeds: DEFAULT_MIN_SPEEDS,
            estimator: Estimator::default(),
            quantisation: Quantisation::default(),
            compare_ols: false,
        }
    }
}

/// Default [`Options::max_condition_number`]: with unit-norm columns, data
/// accurate to a relative ε can give parameters wrong by up to about κ·ε, so
/// beyond 1e3 even 3-digit data may lose every digit. Well-spread run-downs
/// through the pedestal resonances give κ of order 1-10.
pub const DEFAULT_MAX_CONDITION_NUMBER: f64 = 1.0e3;

/// Default [`Options::min_speeds`].
pub const DEFAULT_MIN_SPEEDS: usize = 3;

impl Options {
    /// Options for an equation mode with its default model.
    pub fn with_mode(mode: EquationMode) -> Self {
        Self {
            mode,
            ..Self::default()
        }
    }

    /// The model in effect: the explicit one or the mode's default.
    pub fn model(&self) -> Model {
        self.model.unwrap_or_else(|| Model::default_for(self.mode))
    }

    /// The paper's OLS with these options (what `plinth paper` reports).
    pub fn ols(mut self) -> Self {
        self.estimator = Estimator::Ols;
        self
    }

    /// The estimator in effect: ML only with the R&I equations.
    pub fn effective_estimator(&self) -> Estimator {
        if self.mode == EquationMode::RealAndImag {
            self.estimator
        } else {
            Estimator::Ols
        }
    }
}

/// What a warning is about. Serialised in snake_case.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WarningKind {
    /// Fewer distinct speeds than [`Options::min_speeds`], or no more
    /// equations than parameters (no variance estimate). Fit not trusted.
    TooFewSpeeds,
    /// Some parameters are not determined at all (linearly dependent columns,
    /// e.g. a dead sensor). Fit not trusted.
    RankDeficient,
    /// Condition number above [`Options::max_condition_number`]: the data
    /// barely separate some parameters. Fit not trusted.
    IllConditioned,
    /// A stiffness or mass whose standard error exceeds its value. Fit not trusted.
    Undetermined,
    /// A damping within two standard errors of zero: the data do not
    /// resolve the damping (it is consistent with zero at 2σ). Informative.
    DampingNotResolved,
    /// k − Ω²m keeps its sign over the measured speeds in both directions:
    /// no pedestal resonance in range, so m rests on the curvature alone.
    NoResonance,
    /// Some speeds had non-finite numbers and were left out.
    NonFiniteInput,
    /// The fit's χ² does not fit the noise model's absolute scale (the data
    /// scatter more, or less, than the known noise). Informative.
    NoiseScaleMismatch,
    /// The maximum-likelihood fit failed or did not converge (the OLS
    /// estimate is reported when it failed). Informative.
    MlFailed,
    /// A negative mass or stiffness, or a damping significantly below zero:
    /// no passive pedestal ([`physical`]). Fit not trusted.
    PhysicallyImpossible,
    /// The data fit a passive pedestal to the noise floor only with a
    /// convention mistake undone ([`convention`]). Fit not trusted.
    SuspectedConventionError,
    /// The residuals hold model error, not noise ([`trust`]): structured
    /// across speed or far above the noise measured without the model.
    /// Fit not trusted.
    LackOfFit,
    /// Numbers no pedestal has, or a unit mismatch between the channels
    /// ([`plausibility`]). Fit not trusted.
    Implausible,
    /// Speeds whose residuals the noise cannot explain were left out of the
    /// fit ([`crate::estimate::robust`]). Informative.
    OutlierSpeeds,
    /// Every channel of the bearing looks flipped by 180° at some speeds: a
    /// likely keyphasor fault ([`crate::estimate::robust`]). Informative.
    KeyphasorFlip,
    /// The data do not exclude a sensor delay on the bearing's `rel` probes,
    /// which reads as a damping: the ± count it as unknown
    /// ([`delay_unknown`]). Informative.
    DelayNotExcluded,
    /// The data do not exclude an offset of the speed column (the speed
    /// of the vectors' revolutions read late or early) that moves the
    /// values by more than their ±: the ± count it as unknown
    /// ([`speed_lag`]). Informative.
    SpeedLagNotExcluded,
    /// One channel's sensitivity reads off against its partner's in the
    /// other direction (rel_y against rel_z, ped_y against ped_z) beyond
    /// what the noise gives ([`sensor_gain`]). Fit not trusted.
    SensorGain,
    /// The data favour and do not exclude a sensitivity ratio between the
    /// y and z channels: the ± count it as unknown ([`sensor_gain`]).
    /// Informative.
    SensorGainNotExcluded,
}

impl WarningKind {
    /// True when a warning of this kind means the fit must not be trusted.
    pub fn makes_untrusted(self) -> bool {
        matches!(
            self,
            WarningKind::TooFewSpeeds
                | WarningKind::RankDeficient
                | WarningKind::IllConditioned
                | WarningKind::Undetermined
                | WarningKind::PhysicallyImpossible
                | WarningKind::SuspectedConventionError
                | WarningKind::LackOfFit
                | WarningKind::Implausible
                | WarningKind::SensorGain
        )
    }
}

/// Something the user must know about a fit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Warning {
    /// What it is about.
    pub kind: WarningKind,
    /// A sentence for people, naming parameters, speeds and figures.
    pub message: String,
}

/// The identified pedestal at one bearing, serialised exactly as an element
/// of formats.md's `"pedestals"` (plus the extra keys `fixed`, `trusted`,
/// `speeds`, `equations`, `speed_range_hz`, `warnings`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PedestalFit {
    /// Bearing name.
    pub bearing: String,
    /// The identified parameters (a damping fixed by the model is 0).
    #[serde(flatten)]
    pub pedestal: Pedestal,
    /// Their standard errors, in their units: 0 for parameters fixed by
    /// the model, infinite (`null` in JSON) when not estimable.
    #[serde(deserialize_with = "crate::estimate::params::std_err")]
    pub std_err: Pedestal,
    /// RMS of the equation residuals [N].
    #[serde(deserialize_with = "null_is_nan")]
    pub residual_rms: f64,
    /// Condition number of the column-scaled regression matrix [-]
    /// (infinite, `null` in JSON, when rank deficient).
    #[serde(deserialize_with = "null_is_infinite")]
    pub condition_number: f64,
    /// Parameters the model fixed at zero (not estimated).
    pub fixed: Vec<String>,
    /// False when a warning says the numbers cannot be relied on.
    pub trusted: bool,
    /// Number of distinct speeds used.
    pub speeds: usize,
    /// Number of real equations in the regression.
    pub equations: usize,
    /// Lowest and highest speed used [Hz].
    pub speed_range_hz: [f64; 2],
    /// Everything the user must know about this fit.
    pub warnings: Vec<Warning>,
    /// With `--compare-ols`: the paper's OLS next to this ML fit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ols: Option<OlsComparison>,
    /// The convention mistake the data most likely carry ([`convention`]),
    /// when undoing one makes the data a passive pedestal at the noise floor.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub suspected_convention_error: Option<convention::Convention>,
    /// The base this pedestal was identified on (`base.csv`'s name, or
    /// `groupN` of `--unmeasured-base`); absent: rigid ground.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base: Option<String>,
    /// True when that base's motion was measured (`base.csv`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base_measured: Option<bool>,
    /// Covariance of θ = (k_y, k_z, m, c_y, c_z) in θ units (zero rows for
    /// fixed parameters); absent when the fit cannot give one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub covariance: Option<crate::present::modal::Covariance>,
    /// Natural frequency and damping ratio per direction with ±
    /// ([`crate::present::modal`], formats.md `modal`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub modal: Option<crate::present::modal::PedestalModal>,
}

impl PedestalFit {
    /// True when some warning is of `kind`.
    pub fn has_warning(&self, kind: WarningKind) -> bool {
        self.warnings.iter().any(|w| w.kind == kind)
    }

    /// Multiplies each value's ± by its factor `w` [-] (k_y, k_z, m, c_y,
    /// c_z order), the covariance by w_i·w_j, and recomputes the modal
    /// view from them: how a nuisance the data do not exclude (a sensor
    /// delay, a speed offset, a sensitivity ratio) is counted in the ±.
    pub fn widen_by(&mut self, w: [f64; PARAMETERS]) {
        let se = self.std_err.theta();
        self.std_err = Pedestal::from_theta(std::array::from_fn(|i| se[i] * w[i]));
        if let Some(cov) = &mut self.covariance {
            for (i, row) in cov.iter_mut().enumerate() {
                for (j, v) in row.iter_mut().enumerate() {
                    *v *= w[i] * w[j];
                }
            }
        }
        self.modal = Some(crate::present::modal::pedestal(
            &self.pedestal.theta(),
            self.covariance.as_ref(),
        ));
    }

    /// Adds `add` (k_y, k_z, m, c_y, c_z order, their units squared) to
    /// the covariance and each variance: a stated uncertainty of an input
    /// the fit took as exact, carried in to first order (Σ' = Σ + Σ_k
    /// σ_k²·b_k·b_kᵀ, b_k the values' shift per unit of input k). A value
    /// fixed by the model (± 0) or whose ± is not finite keeps its ±.
    pub fn add_covariance(&mut self, add: &[[f64; PARAMETERS]; PARAMETERS]) {
        let se = self.std_err.theta();
        let kept = |i: usize| se[i] > 0.0 && se[i].is_finite();
        self.std_err = Pedestal::from_theta(std::array::from_fn(|i| {
            if kept(i) {
                (se[i] * se[i] + add[i][i]).sqrt()
            } else {
                se[i]
            }
        }));
        if let Some(cov) = &mut self.covariance {
            for (i, row) in cov.iter_mut().enumerate() {
                for (j, v) in row.iter_mut().enumerate() {
                    if kept(i) && kept(j) {
                        *v += add[i][j];
                    }
                }
            }
        }
    }
}

/// The identification of every pedestal in a run: formats.md's output of
/// `plinth identify --json` (plus the key `equations`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Identification {
    /// Names of the estimated parameters.
    pub model: Vec<String>,
    /// How eq. 4 was used: `r-and-i`, `r-plus-i`, `real` or `imag`.
    pub equations: String,
    /// The estimator used: `ml` or `ols`.
    #[serde(default = "ols_name")]
    pub estimator: String,
    /// One fit per measured bearing, in order of first appearance.
    pub pedestals: Vec<PedestalFit>,
    /// The noise model of each bearing, by bearing name.
    #[serde(default)]
    pub noise: BTreeMap<String, NoiseReport>,
    /// The bases pedestals were identified on ([`on_base`]); empty: rigid ground.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bases: Vec<on_base::BaseReport>,
    /// What the data say of an offset of the speed column shared by every
    /// bearing ([`speed_lag`]); `None` where it was not estimated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed_lag: Option<speed_lag::SpeedLag>,
    /// What each bearing's data say of its channels' sensitivities
    /// ([`sensor_gain`]); empty where not judged.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sensor_gain: Vec<sensor_gain::GainEvidence>,
}

fn ols_name() -> String {
    Estimator::Ols.name().to_string()
}

impl Identification {
    /// The fit of the pedestal at `bearing`.
    pub fn pedestal(&self, bearing: &str) -> Option<&PedestalFit> {
        self.pedestals.iter().find(|p| p.bearing == bearing)
    }

    /// Every warning of `kind`, with its pedestal's bearing, in the
    /// pedestals' order: what the lines under the table say.
    pub fn warnings_of(&self, kind: WarningKind) -> impl Iterator<Item = (&str, &Warning)> {
        self.pedestals.iter().flat_map(move |p| {
            p.warnings
                .iter()
                .filter(move |w| w.kind == kind)
                .map(|w| (p.bearing.as_str(), w))
        })
    }
}

/// Why an identification could not run at all (as opposed to a fit that ran
/// but cannot be trusted, which carries [`Warning`]s).
#[derive(Debug, thiserror::Error)]
pub enum IdentifyError {
    /// The run has no measurements.
    #[error("the run has no measurements")]
    NoMeasurements,
    /// No finite data for a pedestal.
    #[error("pedestal `{bearing}`: no usable (finite) data")]
    NoData {
        /// Bearing name.
        bearing: String,
    },
    /// A measured bearing with no coefficients.
    #[error("bearing `{bearing}` has no coefficients (no rows in bearings.csv)")]
    UnknownBearing {
        /// Bearing name.
        bearing: String,
    },
    /// A measurement speed outside the bearing's coefficient table.
    #[error("bearing `{bearing}`: {source}")]
    BearingRange {
        /// Bearing name.
        bearing: String,
        /// The speed and the table's range.
        #[source]
        source: OutOfRange,
    },
    /// The run directory could not be read.
    #[error(transparent)]
    RunDir(#[from] RunDirError),
    /// A problem with the bases pedestals stand on (`base.csv`,
    /// `--unmeasured-base`), said in full.
    #[error("{0}")]
    Base(String),
    /// A fit's result is not a finite number (an overflow).
    #[error(transparent)]
    NonFinite(#[from] physical::NonFiniteResult),
    /// Fewer measured speeds than [`MIN_SPEEDS`] for a pedestal.
    #[error("bearing `{bearing}`: only {speeds} speed(s) measured; the pedestal model needs at least {MIN_SPEEDS}")]
    TooFewSpeeds {
        /// Bearing name.
        bearing: String,
        /// Speeds measured.
        speeds: usize,
    },
}

/// The fewest measured speeds a pedestal is fitted from at all: one speed's
/// four real equations cannot determine the model's five parameters (from
/// two speeds up to [`DEFAULT_MIN_SPEEDS`] the fit is made and marked
/// UNTRUSTED with a `TooFewSpeeds` warning).
pub const MIN_SPEEDS: usize = 2;

/// The per-speed data of one pedestal without their noise
/// ([`Observation::without_noise`]): the measured phasors and the complex
/// bearing stiffness with the coefficients interpolated from `schedule` at
/// each speed (formats.md; no extrapolation).
pub fn pedestal_points<'a>(
    measurements: impl IntoIterator<Item = &'a Measurement>,
    schedule: &BearingSchedule,
) -> Result<Vec<Observation>, OutOfRange> {
    measurements
        .into_iter()
        .map(|m| {
            let coefficients = schedule.at(m.speed_hz)?;
            Ok(Observation::without_noise(
                m.speed_hz,
                m.rel,
                m.ped,
                &coefficients,
            ))
        })
        .collect()
}

/// Identifies one pedestal from its per-speed data by least squares on
/// eq. 4 (rows from [`plinth_shared::regression`]): the paper's OLS, whatever
/// [`Options::estimator`] says (the ML fit needs the rotor-relative phasors
/// and the noise: [`identify_run`] or [`estimator::fit_ml`]). Never fails on
/// poor data: the fit carries warnings and `trusted = false` instead. Fails
/// only when no point is finite.
pub fn fit_pedestal(
    bearing: &str,
    points: &[Observation],
    options: &Options,
) -> Result<PedestalFit, IdentifyError> {
    Ok(ols_solution(bearing, points, options)?.0)
}

/// The OLS fit of [`fit_pedestal`] with the least-squares solution, the
/// finite points used (sorted by speed) and the number left out.
pub(crate) fn ols_solution(
    bearing: &str,
    points: &[Observation],
    options: &Options,
) -> Result<(PedestalFit, lsq::LeastSquares, Vec<Observation>, usize), IdentifyError> {
    let model = options.model();
    let columns = model.parameters();
    let mut used: Vec<Observation> = points
        .iter()
        .filter(|p| p.equation_is_finite())
        .copied()
        .collect();
    let skipped = points.len() - used.len();
    if used.is_empty() {
        return Err(IdentifyError::NoData {
            bearing: bearing.to_string(),
        });
    }
    used.sort_by(|a, b| a.speed_hz.total_cmp(&b.speed_hz));

    let mut rows: Vec<f64> = Vec::with_capacity(4 * used.len() * columns.len());
    let mut rhs: Vec<f64> = Vec::with_capacity(4 * used.len());
    for p in &used {
        let (eqs, n) =
            equations_for_mode(options.mode, omega_from_hz(p.speed_hz), &p.ped, &p.force());
        for eq in &eqs[..n] {
            rows.extend(columns.iter().map(|&c| eq.row[c as usize]));
            rhs.push(eq.rhs);
        }
    }
    let a = DMatrix::from_row_slice(rhs.len(), columns.len(), &rows);
    let b = DVector::from_vec(rhs);
    let solution = lsq::solve(&a, &b);

    let mut theta = [0.0; PARAMETERS];
    let mut se = [0.0; PARAMETERS];
    for (k, &c) in columns.iter().enumerate() {
        theta[c as usize] = solution.theta[k];
        se[c as usize] = solution.std_err[k];
    }
    let mut speeds: Vec<f64> = used.iter().map(|p| p.speed_hz).collect();
    speeds.dedup();

    let mut fit = PedestalFit {
        bearing: bearing.to_string(),
        pedestal: Pedestal::from_theta(theta),
        std_err: Pedestal::from_theta(se),
        residual_rms: solution.residual_rms(),
        condition_number: solution.condition_number,
        fixed: model.fixed().iter().map(|p| p.name().to_string()).collect(),
        trusted: true,
        speeds: speeds.len(),
        equations: solution.equations,
        speed_range_hz: [used[0].speed_hz, used[used.len() - 1].speed_hz],
        warnings: Vec::new(),
        ols: None,
        suspected_convention_error: None,
        base: None,
        base_measured: None,
        covariance: solution.covariance_of(&columns),
        modal: None,
    };
    fit.warnings = checks::warnings(&fit, &used, skipped, &solution, &columns, options);
    physical::check_finite(&fit)?;
    fit.warnings.extend(physical::violations(&fit));
    fit.trusted = !fit.warnings.iter().any(|w| w.kind.makes_untrusted());
    Ok((fit, solution, used, skipped))
}

/// The observations of one bearing's rows: phasors, the complex bearing
/// stiffness interpolated from `schedule` at each speed (formats.md; no
/// extrapolation) and the noise variances of `noise` (made from the same
/// rows, in the same order).
pub fn observations(
    rows: &[&Measurement],
    schedule: &BearingSchedule,
    noise: &BearingNoise,
) -> Result<Vec<Observation>, OutOfRange> {
    rows.iter()
        .zip(&noise.var)
        .map(|(m, var)| {
            let coefficients = schedule.at(m.speed_hz)?;
            Ok(Observation {
                speed_hz: m.speed_hz,
                rel: m.rel,
                ped: m.ped,
                kstar: complex_stiffness(&coefficients, omega_from_hz(m.speed_hz)),
                var: *var,
            })
        })
        .collect()
}

/// Identifies every measured pedestal of a run, in the order the bearings
/// first appear in `measurements.csv`, with the estimator of `options`
/// (default: maximum likelihood with the noise model of
/// [`crate::estimate::noise`]); every pedestal is checked for the usual
/// convention mistakes ([`convention`]: eight refits of the run), the run's
/// dampings judged as one family ([`physical::recheck_run`]), keyphasor
/// flips judged against the other bearings ([`flips`]), each bearing's
/// lack of fit judged ([`trust`]) and the values checked for plausibility
/// ([`plausibility`]).
pub fn identify_run(run: &RunDir, options: &Options) -> Result<Identification, IdentifyError> {
    identify_prepared(
        run,
        &data::Prepared::new(run, None, options.quantisation),
        options,
    )
}

/// [`identify_run`] of `run` made ready for fitting beforehand
/// ([`data::Prepared`]: its noise and observations, what the refits on a
/// base read afterwards).
pub fn identify_prepared(
    run: &RunDir,
    prepared: &data::Prepared,
    options: &Options,
) -> Result<Identification, IdentifyError> {
    let noise = &prepared.noise;
    let mut identification =
        fit_observed(&prepared.bearings, noise, options, estimator::Checks::All)?;
    flips::mark_cross_bearing_flips(&prepared.bearings, &mut identification);
    let findings = convention::diagnose(run, &identification, noise, options);
    convention::mark(&mut identification, &findings);
    crate::present::modal::attach(&mut identification);
    let relative_residuals = misfit::relative_residuals(run, noise, &identification.pedestals);
    physical::recheck_run(&mut identification, &relative_residuals);
    trust::mark_lack_of_fit(&mut identification);
    plausibility::mark(run, &mut identification);
    delay_unknown::mark(&mut identification);
    speed_lag::mark(run, &prepared.bearings, &mut identification);
    sensor_gain::mark(run, prepared, &mut identification);
    Ok(identification)
}

/// Fits every measured pedestal of a run ([`fit_pedestal`]), nothing more.
pub fn fit_run(run: &RunDir, options: &Options) -> Result<Identification, IdentifyError> {
    fit_run_with(run, &RunNoise::estimate(run, options.quantisation), options)
}

/// [`fit_run`] with the run's noise estimated beforehand ([`RunNoise`]).
pub fn fit_run_with(
    run: &RunDir,
    run_noise: &RunNoise,
    options: &Options,
) -> Result<Identification, IdentifyError> {
    fit_run_checked(run, run_noise, options, estimator::Checks::All)
}

/// [`fit_run_with`] with only the ML fit's `checks` asked for
/// ([`estimator::fit_ml_checked`]; the OLS fit is the same either way).
pub(crate) fn fit_run_checked(
    run: &RunDir,
    run_noise: &RunNoise,
    options: &Options,
    checks: estimator::Checks,
) -> Result<Identification, IdentifyError> {
    fit_observed(&data::observe(run, run_noise), run_noise, options, checks)
}

/// Fits every measured bearing of `bearings` ([`data::observe`] of a run
/// whose noise is `run_noise`), in their order, each on its own copy of
/// its noise.
fn fit_observed(
    bearings: &[data::BearingObservations],
    run_noise: &RunNoise,
    options: &Options,
    checks: estimator::Checks,
) -> Result<Identification, IdentifyError> {
    if bearings.is_empty() {
        return Err(IdentifyError::NoMeasurements);
    }
    let estimator = options.effective_estimator();
    let mut pedestals = Vec::with_capacity(bearings.len());
    let mut noise_reports = BTreeMap::new();
    for b in bearings {
        let bearing = b.bearing.as_str();
        let obs = b.observations.as_deref().map_err(|e| e.of(bearing))?;
        let (_, noise) = run_noise
            .bearing(bearing)
            .ok_or(IdentifyError::NoMeasurements)?;
        let mut noise = noise.clone();
        let (fit, report) = match estimator {
            Estimator::Ml => estimator::fit_ml_checked(bearing, obs, &mut noise, options, checks)?,
            Estimator::Ols => {
                let fit = fit_pedestal(bearing, obs, options)?;
                let report = estimator::ols_noise_report(&fit, obs, &noise);
                (fit, report)
            }
        };
        noise_reports.insert(bearing.to_string(), report);
        pedestals.push(fit);
    }
    Ok(Identification {
        model: options.model().names(),
        equations: mode_name(options.mode).to_string(),
        estimator: estimator.name().to_string(),
        pedestals,
        noise: noise_reports,
        bases: Vec::new(),
        speed_lag: None,
        sensor_gain: Vec::new(),
    })
}

/// Reads the run directory `dir` and identifies every pedestal in it.
pub fn identify_dir(
    dir: impl AsRef<Path>,
    options: &Options,
) -> Result<Identification, IdentifyError> {
    let run = RunDir::read(dir)?;
    identify_run(&run, options)
}
