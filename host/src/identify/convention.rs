//! Convention-mistake diagnosis: for every pedestal, try the usual ways field
//! data get their conventions wrong, undo each on the raw run, refit, and
//! name the one under which the data become a passive pedestal that fits to
//! the noise floor, clearly better than every other reading (the data as
//! found included). A physically impossible fit is the usual symptom; a fit
//! far worse than the noise floor is the other (a y-z swap of a pedestal with
//! similar stiffnesses can stay passive). Trying costs eight refits, a few
//! milliseconds, so it is always done.
//!
//! The mistakes ([`Convention`]) and what undoing each does to the run:
//! - `conjugated`: every phasor conjugated (phase lag read as lead, or
//!   e^{−iΩt} for e^{+iΩt}): conjugate every `rel` and `ped` phasor. With
//!   undamped bearings this only flips the sign of the pedestal damping; with
//!   the bearing's own damping the data fit no passive pedestal.
//! - `swapped_yz`: the y and z readings exchanged at the sensors (the bearing
//!   coefficients still in formats.md's axes): exchange y and z of `rel`,
//!   `ped` (and their noise columns).
//! - `rel_negated`: `rel` written as pedestal minus rotor: negate `rel`; the
//!   mistake negates every bearing force, hence k, m and c alike.
//! - `bearing_transposed`: K_b and C_b given transposed (kyz for kzy): swap the
//!   off-diagonal terms of every row of `bearings.csv`; invisible (and never
//!   named) for symmetric bearing matrices.
//! - `cross_coupling_sign`: the cross terms kyz, kzy, cyz, czy with the wrong
//!   sign (the rotation sense or an axis taken the other way): negate them.
//! - `ped_conjugated`: only the pedestal phasors conjugated (pick-ups read
//!   with phase lead, probes with lag): conjugate every `ped` phasor. Mixed
//!   conventions can leave some pedestals passive at the wrong stiffness.
//! - `ped_velocity`: pedestal velocity written as displacement (a velocity
//!   pick-up not integrated): divide every `ped` phasor (and its noise
//!   column) by iΩ.
//! - `speed_in_rpm`: speeds written in rpm where formats.md wants Hz: divide
//!   the measurement speeds by 60, and the bearing table's speeds too when the
//!   table is in the same unit (it covers the measured speeds as written).
//!
//! Two figures judge a reading. For a pedestal estimate θ the residual of
//! eq. 3 at each speed is e = Z(θ)·ped − (K_b + iΩC_b)·rel (complex, y and z).
//! - Against the noise floor: e has the covariance S = Z·Σ_ped·Z^H +
//!   B·Σ_rel·B^H from the noise of both readings, and χ² = Σ e^H S⁻¹ e has
//!   ν = 4·speeds − parameters degrees of freedom when model and conventions
//!   are right. The noise comes from one function ([`noise_floor`]): the
//!   measurement's noise columns when present, else the digits/scatter
//!   estimate of `diagnose::noise`. A reading "fits to the noise floor" when
//!   χ²/ν ≤ [`FLOOR_CHI2_PER_DOF`].
//! - Between readings: a likelihood ratio with the noise scale profiled out,
//!   ν·ln(r_b/r_a), r = Σ|e|²/Σ|F|² the residual relative to the bearing
//!   forces (all readings have the same parameters). It does not depend on
//!   the noise floor's shape, which the digits/scatter estimate can get badly
//!   wrong (on sharp resonances with 1-3 % noise it can take σ for 30 % of
//!   each phasor, and every χ² then looks alike). But it is a likelihood
//!   ratio only when every speed's error has the same variance: with
//!   proportional noise a few resonance speeds dominate r, and a reading
//!   can have a clearly smaller r and a worse χ² (clean data named
//!   `speed_in_rpm`, docs/unseen-train.md "third machine"). So the named reading
//!   must also have the smallest χ²: a weighted ratio ν·ln(χ²_b/χ²_a) ≥ 0.
//!   (Asking it to be decisive as well loses a y-z swap on a simulated
//!   machine with estimated noise, tests/tests/identify_conventions.rs.)
//!   Only where the bearing's residuals leave the floor's law standing: a
//!   law they reject weighs no likelihood ([`decide::decide`]).
//!
//! A reading is named only when it is passive, fits to the noise floor, has
//! the smallest r of the passive readings, beats every other passive
//! reading (the data as found included) by [`DECISIVE_DELTA_CHI2`] in r,
//! and has a χ² no larger than that of every other passive reading and of
//! the data as found (passive or not); otherwise nothing is named. The data
//! as found are the reading the user stated, overturned only by evidence
//! ([`decide::decide`]): the named reading must explain the bearing
//! forces (relative residual at most [`decide::MAX_RELATIVE_RESIDUAL`],
//! 0.25: a fit leaving more is fitted to forces that are mostly noise), the
//! data as found must not fit decisively better in r, and where their fit
//! is passive, or not passive only within its standard errors (a mass of
//! −1000 ± 1400 kg on a stiff pedestal the band does not determine), the
//! named reading must beat them decisively in r and, where the floor's law
//! holds, in χ² as well. A mistake the data cannot tell from the stated
//! convention is then not named (docs/field-data.md "Session 41 (recflex17)": clean
//! narrow-band recordings of unseen-flex named a mistake at its stiff B1
//! in 25 of 39).
//! "Passive" here is also "plausible": a reading whose pedestal has values
//! no pedestal has ([`super::plausibility`]: a mass of 1e-4 kg, a support
//! sagging more than a quarter metre under its own weight) is not a
//! candidate. A mistake made for the whole run ([`Convention::run_wide`]:
//! the speeds' unit) must also be preferred by the whole run, the same
//! rule on the log-likelihood ratio summed over the pedestals
//! ([`decide::run_prefers`]): speeds in rpm only rescale a pedestal whose
//! bearing force is almost all stiffness (m·3600, c·60), so that pedestal
//! alone cannot tell the units apart, while the bearings with damping can
//! (docs/unseen-train.md, third machine, item 3).
//!
//! Every reading is first fitted by the paper's OLS, whose relative residual
//! bounds that of any estimate from below; only the readings that bound
//! leaves in contention are refitted with the estimator in use
//! ([`diagnose`]), so that a clean run costs about two fits, not nine.
//! A first pass refits only the readings that could beat the data as
//! found; when the data as found stay the best passive reading of every
//! pedestal nothing is named, whatever the other readings, and the pass's
//! answer is the full rule's (`decide`'s premise, tested in
//! `nothing_is_named_while_the_data_as_found_stay_best`); otherwise the
//! full rule runs from the start with the fits made. With OLS a reading
//! whose screen leaves no pedestal passive is skipped on the same ground
//! (its misfit, and `ped_velocity`'s noise estimated anew).

#[cfg(test)]
use super::misfit::noise_floor;
use super::physical::is_plausible;
use super::{Identification, Options, PedestalFit, Warning, WarningKind};
#[cfg(test)]
use crate::estimate::noise::Quantisation;
use crate::estimate::noise::RunNoise;
use crate::rundir::RunDir;
use plinth_shared::bearing::BearingCoefficients;
use plinth_shared::phasor::Phasor2;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::fmt;

/// Largest χ²/ν of a reading that "fits to the noise floor". The noise
/// floor of `diagnose::noise` is uncertain by a factor of about three in σ
/// (its scatter law can read resonance curvature as noise, or pick the
/// relative law for absolute noise), so a reading within an order of
/// magnitude of it in variance counts; the comparison between readings is
/// what decides.
pub const FLOOR_CHI2_PER_DOF: f64 = 10.0;

/// Least −2·ln(likelihood ratio) by which the named reading must beat every
/// other passive one: 2·ln(1000), a likelihood ratio of 1000 ("decisive"),
/// as all readings have the same parameters.
pub const DECISIVE_DELTA_CHI2: f64 = 13.815_510_557_964_274;

/// How well one reading of the data fits one pedestal.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Reading {
    /// The mistake undone, or `None` for the data as found.
    pub convention: Option<Convention>,
    /// Noise-whitened residual sum of squares χ² [-] at the fit's estimate.
    pub chi2: f64,
    /// Degrees of freedom ν = 4·speeds − parameters.
    pub dof: usize,
    /// Σ|e|²/Σ|F|² [-] ([`super::misfit::Misfit::relative_residual`]).
    pub relative_residual: f64,
    /// Whether the estimate is a passive pedestal ([`is_plausible`]) with
    /// values a pedestal can have ([`super::plausibility::findings`]).
    pub plausible: bool,
}

impl Reading {
    /// χ²/ν [-]; 1 on average when model, conventions and noise are right.
    pub fn chi2_per_dof(&self) -> f64 {
        self.chi2 / self.dof.max(1) as f64
    }

    fn label(&self) -> String {
        self.convention
            .map_or("as found".to_string(), |c| c.to_string())
    }
}

/// A convention mistake named for one pedestal.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Finding {
    /// Bearing name.
    pub bearing: String,
    /// The mistake the data most likely carry.
    pub convention: Convention,
    /// The reading with the mistake undone.
    pub corrected: Reading,
    /// The data as found.
    pub as_found: Reading,
    /// The next-best reading (the data as found or another mistake).
    pub runner_up: Reading,
    /// The pedestal identified with the mistake undone.
    pub corrected_fit: PedestalFit,
}

impl Finding {
    /// One sentence for people: the mistake, the evidence and the corrected
    /// estimate.
    pub fn message(&self) -> String {
        let f = &self.corrected_fit;
        let passive = |r: &Reading| {
            if r.plausible {
                "passive"
            } else {
                "not passive"
            }
        };
        format!(
            "suspected convention error `{}`: {}. With it undone the pedestal is passive and fits to the noise floor (χ²/ν {:.3}) with a residual of {:.2e} of the bearing forces, against {:.2e} as found ({}) and {:.2e} for the best other reading, {} ({}); it gives k_y = {:.4e} N/m, k_z = {:.4e} N/m, m = {:.4e} kg, c_y = {:.4e} N·s/m, c_z = {:.4e} N·s/m: fix the data and run again",
            self.convention,
            self.convention.describe(),
            self.corrected.chi2_per_dof(),
            self.corrected.relative_residual.sqrt(),
            self.as_found.relative_residual.sqrt(),
            passive(&self.as_found),
            self.runner_up.relative_residual.sqrt(),
            self.runner_up.label(),
            passive(&self.runner_up),
            f.pedestal.k_y,
            f.pedestal.k_z,
            f.pedestal.m,
            f.pedestal.c_y,
            f.pedestal.c_z
        )
    }
}

/// The named mistakes of every pedestal of `identification` (fitted with
/// `options` on `run`, whose noise is `noise`). Every pedestal is examined,
/// passive or not: a mistake can leave a passive pedestal that fits far
/// worse than the data allow (a swap of y and z with similar stiffnesses).
/// Readings whose refit fails (e.g. speeds outside the bearing table) are
/// left out.
///
/// Every correction is first fitted by OLS ([`screen`], from the normal
/// equations; the named reading's fit is the full one): OLS minimises
/// Σ|e|² itself, so its relative residual is a lower bound on that of any
/// other estimate of the same reading. A correction is refitted with the
/// estimator of `options` only when that bound leaves it a chance to be
/// named, to spoil the named one's decisiveness or to be the runner-up; the
/// others cannot change what is named (with OLS the screen is the fit). The
/// noise is estimated once and transformed as each correction transforms
/// the data ([`corrected_noise`]).
pub fn diagnose(
    run: &RunDir,
    identification: &Identification,
    noise: &RunNoise,
    options: &Options,
) -> Vec<Finding> {
    let judge = Judge::new(run, identification, noise, options);
    let mut candidates = judge.candidates();
    // With OLS the screens are the fits: nothing is refitted.
    if !judge.ols {
        refit::refit(&judge, &mut candidates);
    }
    named(&judge, identification, &mut candidates)
}

/// The findings of `judge`'s run once `candidates` are read: per pedestal,
/// the reading [`decide`] names, when it is a mistake (and, made for the
/// whole run, the run prefers it), with the corrected fit made in full.
fn named<'a>(
    judge: &Judge<'a>,
    identification: &Identification,
    candidates: &mut [Candidate<'a>],
) -> Vec<Finding> {
    let (run, options, ols, pedestals) = (judge.run, judge.options, judge.ols, judge.pedestals);
    let mut findings = Vec::new();
    for (j, p) in pedestals.iter().enumerate() {
        let Some(readings) = judge.readings_of(j, candidates) else {
            continue;
        };
        let found = readings[0].0;
        let refs: Vec<(Reading, &PedestalFit)> = readings.iter().map(|(r, q)| (*r, q)).collect();
        // Whether the bearing's residuals left the noise floor's law
        // standing ([`decide`]).
        let floor_law_holds = identification
            .noise
            .get(&p.bearing)
            .is_none_or(|n| n.variance_function.is_none());
        if let Some((best, runner_up, q)) = decide(&refs, floor_law_holds) {
            let Some(convention) = best.convention else {
                continue;
            };
            if convention.run_wide() {
                // The run's readings as found and with the mistake undone,
                // pedestal by pedestal.
                let pairs: Vec<(Reading, Reading)> = (0..pedestals.len())
                    .filter_map(|i| {
                        let readings = judge.readings_of(i, candidates)?;
                        let c = readings
                            .iter()
                            .find(|(r, _)| r.convention == Some(convention))?;
                        Some((readings[0].0, c.0))
                    })
                    .collect();
                if !run_prefers(&pairs) {
                    continue;
                }
            }
            let mut corrected = best;
            let mut corrected_fit = q.clone();
            if !ols && convention == Convention::RelNegated {
                // Its readings came from the negated fits as found; the
                // finding carries the refit itself (the same parameters).
                if let Some(k) = candidates.iter_mut().find(|k| k.convention == convention) {
                    let fixed = k.fixed.get_or_insert_with(|| convention.correct(run));
                    let refit = super::fit_run_checked(
                        fixed,
                        &k.noise,
                        options,
                        super::estimator::Checks::Estimate,
                    )
                    .ok()
                    .and_then(|id| id.pedestals.into_iter().find(|q| q.bearing == p.bearing));
                    let rows = judge.rows_of(convention);
                    if let Some((r, q)) = refit.and_then(|q| {
                        Some((judge.reading(&rows, &k.sigma, &q, Some(convention))?, q))
                    }) {
                        corrected = r;
                        corrected_fit = q;
                    }
                }
            }
            if ols {
                // The named reading with the full OLS fit, not its screen.
                if let Some(k) = candidates.iter_mut().find(|k| k.convention == convention) {
                    let rows = judge.rows_of(convention);
                    let exact = rows
                        .iter()
                        .find(|r| r.bearing == p.bearing)
                        .and_then(|r| screen::exact(r.in_range()?, options, &p.bearing));
                    if let Some((r, q)) = exact.and_then(|q| {
                        Some((judge.reading(&rows, &k.sigma, &q, Some(convention))?, q))
                    }) {
                        corrected = r;
                        corrected_fit = q;
                    }
                }
            }
            findings.push(Finding {
                bearing: p.bearing.clone(),
                convention,
                corrected,
                as_found: found,
                runner_up,
                corrected_fit,
            });
        }
    }
    findings
}

/// Every bearing's coefficient schedule ([`RunDir::bearing_schedules`]).
type Schedules = std::collections::BTreeMap<String, crate::rundir::BearingSchedule>;

/// Marks every pedestal of `identification` that a [`Finding`] names: not
/// trusted, `suspected_convention_error` set, and a warning
/// ([`WarningKind::SuspectedConventionError`]) with the evidence.
pub fn mark(identification: &mut Identification, findings: &[Finding]) {
    for f in findings {
        if let Some(p) = identification
            .pedestals
            .iter_mut()
            .find(|p| p.bearing == f.bearing)
        {
            p.suspected_convention_error = Some(f.convention);
            p.trusted = false;
            p.warnings.push(Warning {
                kind: WarningKind::SuspectedConventionError,
                message: f.message(),
            });
        }
    }
}

/// A convention mistake as `plinth diagnose` lists it among its findings.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConventionFinding {
    /// Bearing name.
    pub bearing: String,
    /// The mistake the data most likely carry (`conjugated`, ...).
    pub convention: Convention,
    /// χ²/ν of the data as found [-].
    pub chi2_per_dof_as_found: f64,
    /// χ²/ν with the mistake undone [-].
    pub chi2_per_dof_corrected: f64,
    /// The sentence `plinth identify` prints.
    pub message: String,
}

/// The convention mistakes [`diagnose`] names in `run` when each pedestal is
/// fitted (by the batch fit, R&I) with the parameters `base`; empty when the
/// run cannot be identified at all (the caller reports that itself).
pub fn findings_for_run(
    run: &RunDir,
    base: &[plinth_shared::regression::Parameter],
) -> Vec<ConventionFinding> {
    let Ok(model) = super::Model::from_parameters(base) else {
        return Vec::new();
    };
    let options = super::Options {
        model: Some(model),
        ..super::Options::default()
    };
    let noise = RunNoise::estimate(run, options.quantisation);
    let Ok(identification) = super::fit_run_with(run, &noise, &options) else {
        return Vec::new();
    };
    diagnose(run, &identification, &noise, &options)
        .into_iter()
        .map(|f| ConventionFinding {
            message: f.message(),
            bearing: f.bearing,
            convention: f.convention,
            chi2_per_dof_as_found: f.as_found.chi2_per_dof(),
            chi2_per_dof_corrected: f.corrected.chi2_per_dof(),
        })
        .collect()
}

mod candidate;
mod decide;
mod judge;
mod mistake;
mod refit;
mod rotation;
mod rows;
mod screen;

use candidate::Candidate;
pub use decide::MAX_RELATIVE_RESIDUAL;
use decide::{decide, run_prefers};
use judge::Judge;

pub use mistake::Convention;
pub use rotation::Angle;
#[cfg(test)]
mod tests;
