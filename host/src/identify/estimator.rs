//! Which estimator `identify` uses, and the maximum-likelihood path: the
//! noise model of [`crate::estimate::noise`] and the errors-in-variables fit
//! of [`crate::estimate::ml`] started from the paper's OLS, with the χ² check
//! of the noise scale and, on request, OLS's efficiency against the
//! Cramér–Rao bound.

use super::checks::{self, STD_ERR_WITHHELD};
use super::{ols_solution, Options, PedestalFit, Warning, WarningKind};
use crate::estimate::lack_of_fit;
use crate::estimate::ml::{self, MlFit};
use crate::estimate::noise::{columns, variance, BearingNoise, NoiseSource};
use crate::estimate::pedestal::{fit_under_noise, noise_level, NoiseLevel};
use crate::estimate::robust;
use crate::estimate::Observation;
use crate::identify::IdentifyError;
use plinth_shared::regression::{Parameter, PARAMETERS};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The estimator of the pedestal parameters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Estimator {
    /// Maximum likelihood, errors in variables (noise in rel and ped), from
    /// the noise model; standard errors from the Fisher information (the
    /// Cramér–Rao bound at the estimate). R&I equations only.
    #[default]
    Ml,
    /// The paper's ordinary least squares on eq. 4 (every equation weighted
    /// alike, noise in the regressors ignored).
    Ols,
}

impl Estimator {
    /// `ml` or `ols`.
    pub fn name(self) -> &'static str {
        match self {
            Estimator::Ml => "ml",
            Estimator::Ols => "ols",
        }
    }
}

pub use crate::estimate::pedestal::{CHI2_P_THRESHOLD, SCATTER_LEVEL_TOLERANCE};

mod noise_report;
pub(crate) use noise_report::report;
pub use noise_report::{ols_noise_report, NoiseReport, VarianceLaw};

/// The paper's OLS next to the ML estimate (`identify --compare-ols`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OlsComparison {
    /// OLS estimate per estimated parameter (θ units).
    pub estimate: BTreeMap<String, f64>,
    /// The standard error OLS itself reports (equal, independent equation
    /// errors assumed).
    pub std_err: BTreeMap<String, f64>,
    /// OLS's actual standard deviation under the noise model (sandwich).
    pub sd_under_noise: BTreeMap<String, f64>,
    /// Efficiency of OLS: Cramér–Rao variance / OLS variance, in (0, 1].
    pub efficiency: BTreeMap<String, f64>,
}

/// The ML fit of one pedestal from its observations (any order; non-finite
/// ones are left out with a warning): the OLS start, the ML estimate, its
/// standard errors, warnings and the noise report. `noise` is the model the
/// observations' variances came from, row for row (`noise.var[i]` belongs
/// to `observations[i]`); when the digits do not explain the fit's χ² it
/// switches to the scatter and the fit is redone, and an estimated level is
/// rescaled by χ²/dof.
pub fn fit_ml(
    bearing: &str,
    observations: &[Observation],
    noise: &mut BearingNoise,
    options: &Options,
) -> Result<(PedestalFit, NoiseReport), IdentifyError> {
    fit_ml_checked(bearing, observations, noise, options, Checks::All)
}

/// What [`fit_ml_checked`] judges beyond the estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Checks {
    /// Everything [`fit_ml`] reports.
    All,
    /// The estimate, its standard errors and the warnings that decide its
    /// plausibility ([`super::physical::is_plausible`] reads the parameters,
    /// standard errors, fixed parameters and speed range only); not the
    /// checks whose verdicts only the report and the warnings carry: the
    /// bad-speed check ([`super::trust::bad_speeds`]), the lack-of-fit
    /// evidence ([`lack_of_fit::assess`]) and `--compare-ols`. What the
    /// convention check's refits need: it reads their parameters, standard
    /// errors and plausibility, never their warnings or noise reports.
    Estimate,
}

/// [`fit_ml`] with only the `checks` asked for; with [`Checks::All`] it is
/// [`fit_ml`], and with [`Checks::Estimate`] the parameters, standard errors,
/// covariance, speed range and physical violations are the same bit for
/// bit (the checks left out read the fit, they never change it).
pub(crate) fn fit_ml_checked(
    bearing: &str,
    observations: &[Observation],
    noise: &mut BearingNoise,
    options: &Options,
    checks: Checks,
) -> Result<(PedestalFit, NoiseReport), IdentifyError> {
    let (ols_fit, solution, used, skipped) = ols_solution(bearing, observations, options)?;
    let columns = options.model().parameters();
    let with_noise = |noise: &BearingNoise| -> Vec<Observation> {
        let mut obs: Vec<Observation> = observations
            .iter()
            .zip(&noise.var)
            .map(|(o, var)| Observation { var: *var, ..*o })
            .filter(Observation::is_finite)
            .collect();
        obs.sort_by(|a, b| a.speed_hz.total_cmp(&b.speed_hz));
        obs
    };
    let start = ols_fit.pedestal.theta();
    // Each observation's digits' variances by speed: the floor of the
    // variance function's variances (variance::variances).
    let mut digits: Vec<(f64, [f64; 8])> = observations
        .iter()
        .zip(&noise.digits_var)
        .map(|(o, d)| (o.speed_hz, *d))
        .collect();
    digits.sort_by(|a, b| a.0.total_cmp(&b.0));
    let floor = |o: &Observation| {
        digits
            .binary_search_by(|d| d.0.total_cmp(&o.speed_hz))
            .map_or([0.0; 8], |i| digits[i].1)
    };
    let mut obs = Vec::new();
    // The source (columns, digits or scatter): the one noise policy.
    let mut attempt = fit_under_noise(
        std::slice::from_mut(noise),
        true,
        |noises, first: Option<&MlFit>| {
            obs = with_noise(&noises[0]);
            ml::fit(&obs, &columns, first.map_or(&start, |f| &f.theta))
        },
        |f| (f.chi2, f.dof),
    );
    let mut outlier_speeds_hz = Vec::new();
    // The variance function of the fit's residuals when they reject the
    // scatter's law (see below), computed once: the outlier test reads it
    // too. The scatter's law is measured where the local fits follow the
    // response; at a resonance the speed steps do not resolve it is carried
    // from elsewhere and may be far below the noise there, where the
    // physical model's residuals (which follow the resonance) show it
    // (docs/trust-noise-law.md "Session 26").
    let mut function = None;
    if let Ok(f) = &attempt {
        if noise.source.pattern_on_trial() && f.chi2_per_dof() <= SCATTER_LEVEL_TOLERANCE {
            function = columns::refit(noise, &obs, floor, &columns, f);
        }
        let (test_obs, test_fit) = match &function {
            Some(r) => (r.obs.as_slice(), &r.fit),
            None => (obs.as_slice(), f),
        };
        // Speeds are outliers only when the rest of the data fit the model:
        // when the fit without them still leaves more than the noise allows,
        // their residuals are model error (e.g. a base's resonance) and the
        // lack-of-fit test, not the outlier list, reports it.
        if let Some(r) = robust::outlier_refit(test_obs, test_fit, &columns)
            .filter(|r| r.fit.chi2_per_dof() <= SCATTER_LEVEL_TOLERANCE)
        {
            // Confirmed outlier speeds are left out of everything that
            // follows, under the noise the fit goes on with.
            if function.is_some() {
                let kept: Vec<Observation> = obs
                    .iter()
                    .filter(|o| !r.outlier_speeds_hz.contains(&o.speed_hz))
                    .copied()
                    .collect();
                if let Ok(fit) = ml::fit(&kept, &columns, &r.fit.theta) {
                    obs = kept;
                    outlier_speeds_hz = r.outlier_speeds_hz;
                    attempt = Ok(fit);
                    function = None;
                }
            } else {
                obs = r.kept;
                outlier_speeds_hz = r.outlier_speeds_hz;
                attempt = Ok(r.fit);
            }
        }
    }
    let fresh = !outlier_speeds_hz.is_empty();
    let ml_fit = match attempt {
        Ok(f) if f.theta.iter().all(|v| v.is_finite()) => f,
        other => {
            let why = match other {
                Err(e) => e.to_string(),
                Ok(_) => "a non-finite estimate".to_string(),
            };
            let mut fit = ols_fit;
            fit.warnings.push(Warning {
                kind: WarningKind::MlFailed,
                message: format!("the maximum-likelihood fit failed ({why}); this is the OLS fit"),
            });
            let report = report(noise, f64::NAN, 0, 1.0, 0.0);
            return Ok((fit, report));
        }
    };
    let mut ml_fit = ml_fit;
    // An estimated noise law the residuals reject: the fit, its standard
    // errors and the level are those under the variance function of the
    // residuals (estimate::noise::variance); the lack-of-fit tests keep the
    // scatter's law and its fit (their floor is model-free).
    let mut law = None;
    let mut lack_of_fit_input = None;
    // Either scatter law can be wrong: the proportional one leaves readings
    // of small amplitude nearly exact, one sd per channel over-weights them
    // when the noise grows with the signal (a fraction plus a floor). The
    // score test reads the residuals the fit already has (bounded cost).
    // Residuals are noise samples only when the model fits: a misfit far
    // beyond the scatter's level (e.g. a pedestal on a base fitted on rigid
    // ground) is model error, which no variance function describes, and this
    // fit is then the start of the base fit that follows.
    let model_fits = ml_fit.chi2_per_dof() <= SCATTER_LEVEL_TOLERANCE;
    let mut columns_rejected = None;
    if noise.source.pattern_on_trial() && model_fits {
        // Computed above on these observations and this fit unless speeds
        // were left out since.
        let refit = if fresh {
            columns::refit(noise, &obs, floor, &columns, &ml_fit)
        } else {
            function
        };
        if let Some(r) = refit {
            for ((v, o), d) in noise
                .var
                .iter_mut()
                .zip(observations)
                .zip(&noise.digits_var)
            {
                let w = variance::variances(o, &r.law, d);
                if w.iter().all(|x| *x > 0.0 && x.is_finite()) {
                    *v = w;
                }
            }
            if noise.source == NoiseSource::Columns {
                columns_rejected = Some(columns::rejected(r.p_value, ml_fit.chi2_per_dof()));
            }
            let scatter_obs = std::mem::replace(&mut obs, r.obs);
            let scatter_fit = std::mem::replace(&mut ml_fit, r.fit);
            lack_of_fit_input = Some((scatter_obs, scatter_fit));
            law = Some((r.law, r.p_value));
        }
    }
    let chi2 = ml_fit.chi2;
    let dof = ml_fit.dof;
    let p_value = ml::chi2_two_sided_p(chi2, dof);
    let mut extra: Vec<Warning> = columns_rejected
        .into_iter()
        .map(|message| Warning {
            kind: WarningKind::NoiseScaleMismatch,
            message,
        })
        .collect();
    // The level: the one noise policy's verdict on χ².
    let level = noise_level(chi2, dof, noise.source.scale_estimated());
    let variance_scale = match level {
        // A measured noise level (columns, digits, or the scatter's own
        // level from its local fits) that the residuals exceed by far: the
        // model error, not the noise, may dominate, and is then modelled as
        // the paper's equation error on top of the noise (estimate::ml,
        // "Equation error").
        NoiseLevel::Exceeded(ratio) => {
            // Two explanations of the excess, each with one free level: the
            // noise larger by χ²/dof everywhere, or an equation error on top of
            // it; the one under which the residuals are the more likely wins.
            let n = obs.len() as f64;
            let rescaled = ml::log_det(&obs, &ml_fit.theta, 0.0)
                .map(|d| d + 4.0 * n * ratio.ln() + dof as f64);
            let combined = ml::fit_with_equation_error(&obs, &columns, &ml_fit.theta).and_then(
                |(f, settled)| {
                    let d = ml::log_det(&obs, &f.theta, f.equation_var)? + f.chi2;
                    Ok((f, settled, d))
                },
            );
            match (combined, rescaled) {
                (Ok((f, settled, d)), Ok(d_rescaled))
                    if f.theta.iter().all(|v| v.is_finite()) && d < d_rescaled =>
                {
                    ml_fit = f;
                    extra.push(Warning {
                    kind: WarningKind::NoiseScaleMismatch,
                    message: format!(
                        "χ²/dof = {ratio:.3} (p = {p_value:.1e}): the data scatter more than the noise of their {} allows, and not in its pattern (a model discrepancy); the excess is modelled as an equation error of {:.3e} N on every real equation (the paper's OLS error model) added to the noise, and the fit and its standard errors are those of the combined model{}",
                        noise.source.name(),
                        ml_fit.equation_var.sqrt(),
                        if settled {
                            ""
                        } else {
                            " (its level did not settle)"
                        }
                    ),
                });
                    1.0
                }
                _ if noise.source.scale_estimated() => ratio,
                _ => {
                    extra.push(Warning {
                    kind: WarningKind::NoiseScaleMismatch,
                    message: format!(
                        "χ²/dof = {ratio:.3} (p = {p_value:.1e}): the data scatter more than the noise of their {} allows (a larger noise); standard errors are scaled by {:.3}",
                        noise.source.name(),
                        ratio.sqrt()
                    ),
                });
                    ratio
                }
            }
        }
        NoiseLevel::Estimated(ratio) => ratio,
        NoiseLevel::Below(ratio) => {
            extra.push(Warning {
                kind: WarningKind::NoiseScaleMismatch,
                message: format!(
                    "χ²/dof = {ratio:.3} (p = {p_value:.1e}): the data scatter less than the noise of their {} says (an upper bound); standard errors are scaled to the residuals by {:.3}",
                    noise.source.name(),
                    level.reported_scale().sqrt()
                ),
            });
            level.reported_scale()
        }
        NoiseLevel::Known => 1.0,
    };
    if noise.source.scale_estimated() {
        noise.rescale(variance_scale);
    }
    // The covariance with the regressors' noise (estimate::ml::eiv): F⁻¹ of
    // the measured phasors counts their noise as information, which matters
    // where a pedestal is read near or below its noise.
    // Where it is withheld (the remaining information too close to its own
    // noise) no ± is known: the fit's F⁻¹ is short there (docs/estimation.md
    // "Session 43 (eivpm17)"), so none is shown (infinite, `null` in JSON,
    // no covariance) rather than one that does not mean what it says.
    let mut withheld = false;
    if let Some(e) = ml::eiv_covariance(&obs, &columns, &ml_fit.theta, ml_fit.equation_var) {
        match e.excess {
            // Added to the fit's covariance: a widening it already carries
            // (the variance function's error) is kept.
            Some(x) => {
                for (row, add) in ml_fit.covariance.iter_mut().zip(&x) {
                    for (v, a) in row.iter_mut().zip(add) {
                        *v += a;
                    }
                }
            }
            None => {
                withheld = true;
                extra.push(Warning {
                    kind: WarningKind::Undetermined,
                    message: format!(
                        "the pedestal is read near or below its noise: the noise of its phasors carries {:.0} % of the fit's information on some combination of the parameters (errors in variables), and what remains is {:.1} standard deviations of its own noise (below {}), {STD_ERR_WITHHELD} (± ∞, `null` in JSON): the asymptotic ones are too short here",
                        100.0 * e.noise_share,
                        e.information_sigmas.max(0.0),
                        ml::MIN_INFORMATION_SIGMAS
                    ),
                })
            }
        }
    }
    // Noise correlated along the run (estimate::serial): the ± widened for it.
    let serial =
        crate::estimate::serial::assess(&obs, &ml_fit.theta, &columns, ml_fit.equation_var);
    if let Some(s) = &serial {
        s.widen(&mut ml_fit.covariance);
        extra.push(Warning {
            kind: WarningKind::NoiseScaleMismatch,
            message: s.message(),
        });
    }
    let mut se = ml_fit.std_err(variance_scale);
    if withheld {
        for &c in &columns {
            se[c as usize] = f64::INFINITY;
        }
    }
    let mut fit = ols_fit.clone();
    fit.pedestal = crate::estimate::Pedestal::from_theta(ml_fit.theta);
    fit.std_err = crate::estimate::Pedestal::from_theta(se);
    fit.residual_rms = ml_fit.residual_rms;
    fit.condition_number = ml_fit.condition_number;
    fit.covariance = if withheld {
        None
    } else {
        scaled_covariance(&ml_fit.covariance, variance_scale)
    };
    let mut view = solution.clone();
    for (k, &c) in columns.iter().enumerate() {
        view.theta[k] = ml_fit.theta[c as usize];
        view.std_err[k] = se[c as usize];
    }
    view.condition_number = ml_fit.condition_number;
    fit.warnings = checks::warnings(&fit, &used, skipped, &view, &columns, options);
    if !ml_fit.converged {
        fit.warnings.push(Warning {
            kind: WarningKind::MlFailed,
            message: format!(
                "the maximum-likelihood iteration stopped after {} steps without meeting its convergence test",
                ml_fit.iterations
            ),
        });
    }
    fit.warnings.extend(extra);
    let mut flip_search = None;
    if checks == Checks::All {
        let (warnings, search) = super::trust::bad_speeds(observations, &mut outlier_speeds_hz);
        fit.warnings.extend(warnings);
        flip_search = Some(search);
    }
    super::physical::check_finite(&fit)?;
    fit.warnings.extend(super::physical::violations(&fit));
    fit.trusted = !fit.warnings.iter().any(|w| w.kind.makes_untrusted());
    if checks == Checks::Estimate {
        return Ok((
            fit,
            report(noise, chi2, dof, variance_scale, ml_fit.equation_var.sqrt()),
        ));
    }
    if options.compare_ols {
        fit.ols = Some(compare(&ols_fit, &ml_fit, &obs, &columns, variance_scale));
    }
    let mut report = report(noise, chi2, dof, variance_scale, ml_fit.equation_var.sqrt());
    report.outlier_speeds_hz = outlier_speeds_hz;
    report.flip_search = flip_search;
    report.serial_correlation = serial;
    report.variance_function = law.map(|(p, p_value)| VarianceLaw::of(&p, variance_scale, p_value));
    // The lack-of-fit tests see the fit under the scatter's law: its
    // residuals, χ² and dof (before any equation error), as without a
    // variance function.
    let (lof_obs, lof_theta, lof_chi2, lof_dof) = match &lack_of_fit_input {
        Some((o, f)) => (o, &f.theta, f.chi2, f.dof),
        None => (&obs, &ml_fit.theta, chi2, dof),
    };
    report.lack_of_fit = lack_of_fit::assess(
        lof_obs,
        lof_theta,
        &columns,
        noise.source,
        lof_chi2,
        lof_dof,
        CHI2_P_THRESHOLD,
    );
    Ok((fit, report))
}

/// `covariance` × `scale` when every entry is finite (the covariance a
/// fit reports), else `None`.
pub(crate) fn scaled_covariance(
    covariance: &[[f64; PARAMETERS]; PARAMETERS],
    scale: f64,
) -> Option<[[f64; PARAMETERS]; PARAMETERS]> {
    let c: [[f64; PARAMETERS]; PARAMETERS] =
        std::array::from_fn(|i| std::array::from_fn(|j| scale * covariance[i][j]));
    c.iter().flatten().all(|v| v.is_finite()).then_some(c)
}

fn compare(
    ols: &PedestalFit,
    ml_fit: &MlFit,
    obs: &[Observation],
    columns: &[Parameter],
    variance_scale: f64,
) -> OlsComparison {
    let sandwich = ml::ols_covariance_with(obs, columns, &ml_fit.theta, ml_fit.equation_var);
    let named = |f: &dyn Fn(usize) -> f64| -> BTreeMap<String, f64> {
        columns
            .iter()
            .map(|&c| (c.name().to_string(), f(c as usize)))
            .collect()
    };
    OlsComparison {
        estimate: named(&|i| ols.pedestal.theta()[i]),
        std_err: named(&|i| ols.std_err.theta()[i]),
        sd_under_noise: named(&|i| (variance_scale * sandwich[i][i]).sqrt()),
        efficiency: named(&|i| ml_fit.covariance[i][i] / sandwich[i][i]),
    }
}
