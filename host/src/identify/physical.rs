//! Physical plausibility of an identified pedestal, and the finiteness of
//! every number a fit reports.
//!
//! A pedestal is passive: its mass, stiffnesses and dampings cannot be
//! negative. An estimate is the true value plus noise, so the rule is a
//! joint one-sided test over every mass, stiffness and damping estimated in
//! the run (its "sign-constrained estimates", [`constrained_estimates`])
//! with a stated family-wise false-alarm rate ([`FAMILY_FALSE_ALARM`],
//! Bonferroni: each of n estimates is tested at FAMILY_FALSE_ALARM/n,
//! [`sigmas_below_zero`]); a fit on its own is its own family
//! ([`violations`]), a whole run is re-judged as one ([`recheck_run`]).
//! Below zero by more than that many standard errors is physically
//! impossible ([`WarningKind::PhysicallyImpossible`]: untrusted, exit 2; the
//! usual cause is a convention mistake in the data, [`super::convention`]).
//! A mass or stiffness below zero within its noise is not impossible but
//! not determined: the data are consistent with a value at or near zero,
//! and the pedestal is untrusted as [`WarningKind::Undetermined`] (never
//! printed `ok` with a negative mass or stiffness, never exit 2). So is any
//! value below zero, beyond its ± or not, on a fit that leaves more than
//! [`MAX_RELATIVE_RESIDUAL`] of its bearing forces unexplained: a stiff
//! pedestal over a narrow band, whose forces are mostly the probes' noise.
//! There the fit's ± is many times too short (clean ROSS recordings of
//! unseen-flex/-train B1: rms (estimate − truth)/± of 3-67 for k and m,
//! against 0.7-1.0 at the pedestals whose forces are measured;
//! docs/trust.md, Session 42 (impossible17)), and values like m = −4.6e4 ± 1.7e3 kg
//! on clean data would otherwise exit 2.
//!
//! A truly undamped pedestal (the paper's first machine) gives dampings
//! that are zero plus noise, half of them negative. In a run the standard
//! error an estimate is judged with is the largest of the fit's, the one
//! measured from its residuals for a damping (the sandwich of
//! [`crate::estimate::robust::sandwich_std_errs`]) and, when the noise level
//! was estimated from the scatter, the fit's before the χ²/dof < 1 rescaling
//! shrank it ([`judged_std_errs`]): the fit's assumes the noise model's
//! pattern over speed, which for noise proportional to each phasor
//! (heteroscedastic) estimated from the scatter is only approximate; it made
//! the fit's ± of a zero damping 24 % too small and 2/20 runs of the
//! undamped paper machine exit 2 (measured with scripts/bench-trust.sh,
//! docs/trust.md). With digits alone (rounding errors, correlated between
//! neighbouring speeds) the fit's ± is right: over 2 000 speed grids of the
//! undamped paper machine at 3 (2) digits z = c/σ had sd 1.008 (1.003),
//! tails lighter than normal, and 1.05 % (0.85 %) of runs exited 2, the
//! nominal rate with the dampings alone as the family. A damping whose loss
//! factor is below [`NEGLIGIBLE_LOSS_FACTOR`] is numerically zero.
//!
//! A result that is not a finite number (an overflow in the arithmetic, e.g.
//! data in the wrong unit by many decades) is an error, not a row of a table;
//! the only non-finite figures a fit may carry are the documented "not
//! estimable" ones: infinite standard errors and condition number of a fit
//! already untrusted because the data do not determine it.

use super::{PedestalFit, Warning, WarningKind};
use plinth_shared::regression::{Parameter, PARAMETERS};

/// Family-wise false-alarm rate of the sign rule per run [-]: the chance
/// that a run of passive pedestals (undamped ones and barely determined
/// masses included) has some mass, stiffness or damping called
/// significantly negative. Measured by `scripts/bench-trust.sh` and on
/// clean recordings (docs/trust.md, Session 42 (impossible17)).
pub const FAMILY_FALSE_ALARM: f64 = 0.01;

/// Standard errors below zero beyond which one of `family` sign-constrained
/// estimates tested together is significantly negative: the one-sided
/// normal quantile at FAMILY_FALSE_ALARM/family (Bonferroni, valid whatever
/// the correlation of the estimates): 2.33 for one estimate, 2.58 for two,
/// 2.81 for four, 2.88 for five (one pedestal), 3.09 for ten (two).
pub fn sigmas_below_zero(family: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    let alpha = FAMILY_FALSE_ALARM / family.max(1) as f64;
    Normal::standard().inverse_cdf(1.0 - alpha)
}

/// Number of sign-constrained parameters `fit` estimates (its masses,
/// stiffnesses and dampings not fixed by its model): its share of the
/// run's family ([`sigmas_below_zero`]).
pub fn constrained_estimates(fit: &PedestalFit) -> usize {
    Parameter::ALL
        .iter()
        .filter(|p| !fit.fixed.iter().any(|f| f == p.name()))
        .count()
}

/// Loss factor Ω_max·|c|/k [-] below which a negative damping is numerically
/// zero, whatever its standard error: exact (12-digit) data leave dampings of
/// order 1e-12 N·s/m whose least-squares standard errors understate the
/// round-off. Real structures have loss factors of 1e-4 and more.
pub const NEGLIGIBLE_LOSS_FACTOR: f64 = 1e-6;

/// Whether a pedestal damping `c` ± `se` [N·s/m] is one no passive pedestal
/// has: below zero by more than `sigmas` standard errors
/// ([`sigmas_below_zero`] of its family) and material, its loss factor
/// `omega_max`·|c|/`k` (`omega_max` [rad/s], `k` [N/m] the same direction's
/// stiffness) above [`NEGLIGIBLE_LOSS_FACTOR`]. The one rule identify's
/// warning and diagnose's held-at-zero candidates use.
pub fn damping_impossible(c: f64, se: f64, k: f64, omega_max: f64, sigmas: f64) -> bool {
    let material = omega_max * c.abs() > NEGLIGIBLE_LOSS_FACTOR * k.abs();
    se.is_finite() && c < -sigmas * se && material
}

/// Marks the sign rule's notes that a value is not determined
/// ([`WarningKind::Undetermined`], module docs), so that a re-judgement
/// ([`recheck_run`]) replaces them.
pub const NOT_DETERMINED: &str = "not determined by these data";

/// Largest relative residual Σ|e|²/Σ|F|² [-] ([`super::misfit::Misfit`]) of
/// a fit whose standard errors the sign rule trusts to call a value
/// impossible: the convention check's bound on a reading that explains its
/// forces (one definition). A fit that leaves more is fitted to bearing
/// forces that are mostly the probes' noise, where the linearised ± is far
/// too short (module docs).
pub use super::convention::MAX_RELATIVE_RESIDUAL;

/// The sign rule's findings on `fit` (module docs): one
/// [`WarningKind::PhysicallyImpossible`] warning per parameter below zero
/// beyond the noise, one [`WarningKind::Undetermined`] note per mass or
/// stiffness below zero within it; empty when every value is non-negative
/// ([`recheck_run`] leaves out a note the fit's own check already makes). Parameters
/// fixed by the model are 0 and pass. Its estimates are tested as a family
/// of their own (see [`violations_in_family`]).
pub fn violations(fit: &PedestalFit) -> Vec<Warning> {
    violations_in_family(fit, constrained_estimates(fit), None, None)
}

/// [`violations`] with the estimates tested as `family` of a larger family
/// (every sign-constrained estimate of the run), each at
/// [`sigmas_below_zero`]`(family)` standard errors, each the larger of the
/// fit's and `floor` (θ units: N/m, N/m, kg, N·s/m, N·s/m;
/// [`judged_std_errs`]; module docs). With the fit's `relative_residual`
/// (Σ|e|²/Σ|F|² [-] on its bearing's data) above [`MAX_RELATIVE_RESIDUAL`]
/// a value below zero beyond its noise is not determined either, not
/// impossible (its ± is not to be trusted there).
pub fn violations_in_family(
    fit: &PedestalFit,
    family: usize,
    floor: Option<[f64; PARAMETERS]>,
    relative_residual: Option<f64>,
) -> Vec<Warning> {
    let sigmas = sigmas_below_zero(family);
    let mut out = Vec::new();
    let mut se = fit.std_err.theta();
    if let Some(floor) = floor {
        for (s, f) in se.iter_mut().zip(floor) {
            if f.is_finite() && f > *s {
                *s = f;
            }
        }
    }
    let allowance = format!(
        "the {sigmas:.2} that keep the run's {family} mass, stiffness and damping estimate(s) at a {:.0} % family-wise false-alarm rate",
        100.0 * FAMILY_FALSE_ALARM
    );
    for p in Parameter::ALL {
        let value = fit.pedestal.get(p);
        let sigma = se[p as usize];
        if value >= 0.0 || fit.fixed.iter().any(|f| f == p.name()) {
            continue;
        }
        let (unit, what) = match p {
            Parameter::Ky | Parameter::Kz => ("N/m", "stiffness"),
            Parameter::M => ("kg", "mass"),
            Parameter::Cy | Parameter::Cz => ("N·s/m", "damping"),
        };
        let beyond = match p {
            Parameter::Cy | Parameter::Cz => {
                let k = if p == Parameter::Cy {
                    fit.pedestal.k_y
                } else {
                    fit.pedestal.k_z
                };
                let omega_max = 2.0 * std::f64::consts::PI * fit.speed_range_hz[1];
                damping_impossible(value, sigma, k, omega_max, sigmas)
            }
            _ => negative_beyond_noise(value, sigma, sigmas),
        };
        let name = p.name();
        let noise_forces = relative_residual.filter(|r| r.is_nan() || *r > MAX_RELATIVE_RESIDUAL);
        if let (true, Some(r)) = (beyond, noise_forces) {
            out.push(Warning {
                kind: WarningKind::Undetermined,
                message: format!(
                    "{name} = {value:.4e} ± {sigma:.2e} {unit} is negative by {:.1} standard errors, but the fit leaves {:.0} % of the bearing forces unexplained (more than the {:.0} % within which its ± is trusted to call a value impossible): the forces are mostly noise, the ± too short to judge by, and the {what} {NOT_DETERMINED}",
                    -value / sigma,
                    100.0 * r,
                    100.0 * MAX_RELATIVE_RESIDUAL
                ),
            });
        } else if beyond {
            out.push(Warning {
                kind: WarningKind::PhysicallyImpossible,
                message: format!(
                    "{name} = {value:.4e} ± {sigma:.2e} {unit} is negative by {:.1} standard errors (more than {allowance}): a passive pedestal cannot have a negative {what}",
                    -value / sigma
                ),
            });
        } else if what != "damping" && !sigma.is_finite() {
            out.push(Warning {
                kind: WarningKind::Undetermined,
                message: format!(
                    "{name} = {value:.4e} {unit} is negative and no standard error is known: the {what} {NOT_DETERMINED}"
                ),
            });
        } else if what != "damping" {
            out.push(Warning {
                kind: WarningKind::Undetermined,
                message: format!(
                    "{name} = {value:.4e} ± {sigma:.2e} {unit} is negative within its noise ({:.1} standard errors, within {allowance}): consistent with zero, the {what} {NOT_DETERMINED}",
                    -value / sigma
                ),
            });
        }
    }
    out
}

/// Whether a mass or stiffness `value` ± `se` (θ units) is below zero by
/// more than `sigmas` standard errors ([`sigmas_below_zero`] of its
/// family); an estimate with no finite standard error is not determined,
/// not judged.
pub fn negative_beyond_noise(value: f64, se: f64, sigmas: f64) -> bool {
    se.is_finite() && value < -sigmas * se
}

/// Whether the sign rule's note `w` repeats what `fit` already says: the
/// same value not determined by the fit's own check (its standard error
/// exceeds its value).
fn repeats(fit: &PedestalFit, w: &Warning) -> bool {
    let Some((name, _)) = w.message.split_once(" = ") else {
        return false;
    };
    w.kind == WarningKind::Undetermined
        && fit.warnings.iter().any(|v| {
            v.kind == WarningKind::Undetermined
                && v.message.split_once(" = ").is_some_and(|(n, _)| n == name)
                && !v.message.contains(NOT_DETERMINED)
        })
}

/// Re-judges the sign rule on every pedestal of a run with its
/// sign-constrained estimates tested as one family (all the run's
/// estimated masses, stiffnesses and dampings), so that the run's
/// false-alarm rate is [`FAMILY_FALSE_ALARM`] however many pedestals it
/// has, each estimate with the larger of its fit's standard error and the
/// floor of [`judged_std_errs`] and the fit's relative residual on its
/// bearing's data from `relative_residuals` (by bearing name;
/// [`violations_in_family`]), and updates `trusted`.
pub fn recheck_run(
    identification: &mut super::Identification,
    relative_residuals: &std::collections::BTreeMap<String, f64>,
) {
    let family: usize = identification
        .pedestals
        .iter()
        .map(constrained_estimates)
        .sum();
    let noise = &identification.noise;
    for p in &mut identification.pedestals {
        p.warnings.retain(|w| {
            w.kind != WarningKind::PhysicallyImpossible
                && !(w.kind == WarningKind::Undetermined && w.message.contains(NOT_DETERMINED))
        });
        let floor = noise.get(&p.bearing).map(|n| judged_std_errs(p, n));
        let r = relative_residuals.get(&p.bearing).copied();
        let found: Vec<Warning> = violations_in_family(p, family, floor, r)
            .into_iter()
            .filter(|w| !repeats(p, w))
            .collect();
        p.warnings.extend(found);
        p.trusted = !p.warnings.iter().any(|w| w.kind.makes_untrusted());
    }
}

/// Standard errors (θ units: N/m, N/m, kg, N·s/m, N·s/m) the run's sign
/// rule judges `fit` with, besides the fit's own (module docs): for a noise
/// level estimated from the scatter (an upper bound of the noise, measured
/// without the model) that the fit's χ²/dof < 1 scaled down, the fit's own
/// before that scaling; for c_y and c_z also the one from the residuals
/// (`noise.lack_of_fit.damping_std_err_from_residuals`) when larger.
pub fn judged_std_errs(
    fit: &PedestalFit,
    noise: &super::estimator::NoiseReport,
) -> [f64; PARAMETERS] {
    let own = fit.std_err.theta();
    let unshrunk = if noise.scale_estimated && noise.variance_scale > 0.0 {
        own.map(|s| s / noise.variance_scale.min(1.0).sqrt())
    } else {
        own
    };
    let residuals = noise
        .lack_of_fit
        .and_then(|l| l.damping_std_err_from_residuals)
        .unwrap_or([0.0; 2]);
    let mut out = unshrunk;
    for (p, r) in [(Parameter::Cy, residuals[0]), (Parameter::Cz, residuals[1])] {
        if r.is_finite() && r > out[p as usize] {
            out[p as usize] = r;
        }
    }
    out
}

/// True when every value of `fit` is one a passive pedestal can have: no
/// mass or stiffness below zero, even within its noise, and no damping
/// below zero beyond it ([`violations`]).
pub fn is_plausible(fit: &PedestalFit) -> bool {
    let non_negative = [Parameter::Ky, Parameter::Kz, Parameter::M]
        .iter()
        .all(|&p| fit.pedestal.get(p) >= 0.0 || fit.fixed.iter().any(|f| f == p.name()));
    non_negative
        && !violations(fit)
            .iter()
            .any(|w| w.kind == WarningKind::PhysicallyImpossible)
}

/// A number of a fit that is not finite where it must be.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("pedestal `{bearing}`: the fit's {quantity} is {value} (an overflow in the arithmetic: are the numbers of measurements.csv and bearings.csv in SI units, m, N/m, N·s/m?)")]
pub struct NonFiniteResult {
    /// Bearing name.
    pub bearing: String,
    /// Which figure, e.g. `k_y`, `std_err.m`, `residual_rms`.
    pub quantity: String,
    /// Its value (inf, -inf or NaN).
    pub value: f64,
}

/// Checks that every figure of `fit` is a number: the parameters and the
/// residual always; the standard errors and the condition number unless the
/// fit is already untrusted because the data do not determine it (then +∞
/// means "not estimable" and is written as `null`); the standard errors also
/// where the errors-in-variables rule withheld them
/// ([`super::checks::std_err_withheld`]).
pub fn check_finite(fit: &PedestalFit) -> Result<(), NonFiniteResult> {
    let undetermined = fit.has_warning(WarningKind::RankDeficient)
        || fit.has_warning(WarningKind::TooFewSpeeds)
        || super::checks::std_err_withheld(fit);
    let error = |quantity: String, value: f64| NonFiniteResult {
        bearing: fit.bearing.clone(),
        quantity,
        value,
    };
    for p in Parameter::ALL {
        let v = fit.pedestal.get(p);
        if !v.is_finite() {
            return Err(error(p.name().to_string(), v));
        }
        let s = fit.std_err.theta()[p as usize];
        if s.is_nan() || s < 0.0 || (s.is_infinite() && !undetermined) {
            return Err(error(format!("std_err.{}", p.name()), s));
        }
    }
    if !fit.residual_rms.is_finite() {
        return Err(error("residual_rms".into(), fit.residual_rms));
    }
    let c = fit.condition_number;
    if c.is_nan() || (c.is_infinite() && !undetermined) {
        return Err(error("condition_number".into(), c));
    }
    Ok(())
}

/// `plinth identify`'s exit code when it ran and printed everything but some
/// pedestal is physically impossible or carries a suspected convention
/// mistake (1 is an error that stopped it).
pub const EXIT_NOT_PHYSICAL: u8 = 2;

/// The pedestals of an identification that no passive pedestal explains:
/// returned (after printing) by `plinth identify`, which then exits with
/// [`EXIT_NOT_PHYSICAL`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}", .0.join("; "))]
pub struct NotPhysical(pub Vec<String>);

impl NotPhysical {
    /// One line per pedestal that is physically impossible, implausible
    /// ([`super::plausibility`]) or has a suspected convention error; `None`
    /// when every pedestal is passive and plausible.
    pub fn of(identification: &super::Identification) -> Option<Self> {
        let lines: Vec<String> = identification
            .pedestals
            .iter()
            .filter_map(|p| {
                if let Some(c) = p.suspected_convention_error {
                    Some(format!(
                        "pedestal `{}`: suspected convention error `{c}`: {}",
                        p.bearing,
                        c.describe()
                    ))
                } else if let Some(w) = p
                    .warnings
                    .iter()
                    .find(|w| w.kind == WarningKind::Implausible)
                {
                    Some(format!("pedestal `{}`: {}", p.bearing, w.message))
                } else if p.has_warning(WarningKind::PhysicallyImpossible) {
                    Some(format!(
                        "pedestal `{}`: physically impossible (see the warnings; no usual convention mistake explains it: an effect the pedestal model lacks? try `plinth diagnose`)",
                        p.bearing
                    ))
                } else {
                    None
                }
            })
            .collect();
        (!lines.is_empty()).then_some(Self(lines))
    }
}

/// The process exit code for an error a command returned:
/// [`EXIT_NOT_PHYSICAL`] for [`NotPhysical`], 1 for anything else.
pub fn exit_code(error: &anyhow::Error) -> u8 {
    if error.is::<NotPhysical>() {
        EXIT_NOT_PHYSICAL
    } else {
        1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::Pedestal;

    fn fit(theta: [f64; 5], se: [f64; 5]) -> PedestalFit {
        PedestalFit {
            bearing: "left".into(),
            pedestal: Pedestal::from_theta(theta),
            std_err: Pedestal::from_theta(se),
            residual_rms: 1.0,
            condition_number: 3.0,
            fixed: Vec::new(),
            trusted: true,
            speeds: 50,
            equations: 200,
            speed_range_hz: [5.0, 200.0],
            warnings: Vec::new(),
            suspected_convention_error: None,
            base: None,
            base_measured: None,
            covariance: None,
            modal: None,
            ols: None,
        }
    }

    const SE: [f64; 5] = [1e4, 1e4, 0.1, 50.0, 50.0];

    fn offending(f: &PedestalFit) -> Vec<String> {
        violations(f)
            .iter()
            .map(|w| w.message.split(' ').next().unwrap_or("").to_string())
            .collect()
    }

    #[test]
    fn passive_pedestals_pass() {
        let f = fit([1e7, 8e6, 150.0, 100.0, 80.0], SE);
        assert!(is_plausible(&f));
        // Damping consistent with zero, even below it within 2 σ, is fine.
        assert!(is_plausible(&fit([1e7, 8e6, 150.0, -90.0, -10.0], SE)));
        // Round-off damping of exact data: loss factor far below 1e-6.
        assert!(is_plausible(&fit(
            [1e7, 8e6, 150.0, -3e-12, 0.0],
            [1e-6, 1e-6, 1e-12, 1e-13, 1e-13]
        )));
    }

    #[test]
    fn negative_mass_stiffness_and_damping_are_named() {
        assert_eq!(offending(&fit([-1e7, 8e6, 150.0, 0.0, 0.0], SE)), ["k_y"]);
        assert_eq!(offending(&fit([1e7, -8e6, 150.0, 0.0, 0.0], SE)), ["k_z"]);
        assert_eq!(offending(&fit([1e7, 8e6, -0.5, 0.0, 0.0], SE)), ["m"]);
        assert_eq!(
            offending(&fit([1e7, 8e6, 150.0, -150.0, -5000.0], SE)),
            ["c_y", "c_z"]
        );
        // 2.02 σ below zero is chance for a family of five (2.88 σ).
        assert!(is_plausible(&fit([1e7, 8e6, 150.0, -101.0, 0.0], SE)));
        let w = &violations(&fit([1e7, 8e6, -150.0, 0.0, 0.0], SE))[0];
        assert_eq!(w.kind, WarningKind::PhysicallyImpossible);
        assert!(w.message.contains("negative mass"), "{}", w.message);
    }

    #[test]
    fn a_mass_or_stiffness_negative_within_its_noise_is_undetermined() {
        // m = −0.2 ± 0.1 kg: 2 σ below zero, within the 2.88 σ of one
        // pedestal's five estimates: not impossible, not determined.
        let f = fit([1e7, 8e6, -0.2, 0.0, 0.0], SE);
        let w = violations(&f);
        assert_eq!(w.len(), 1);
        assert_eq!(w[0].kind, WarningKind::Undetermined);
        assert!(w[0].message.starts_with("m = "), "{}", w[0].message);
        assert!(w[0].message.contains(NOT_DETERMINED));
        assert!(!is_plausible(&f));
        // −2.9 σ: beyond the allowance of one pedestal (2.88), within that
        // of a two-pedestal run (3.09).
        let f = fit([-2.9e4, 8e6, 150.0, 0.0, 0.0], SE);
        assert_eq!(violations(&f)[0].kind, WarningKind::PhysicallyImpossible);
        assert_eq!(
            violations_in_family(&f, 10, None, None)[0].kind,
            WarningKind::Undetermined
        );
        // Said on its own (diagnose reads it), but not repeated in a run
        // where the fit already says the value is not determined.
        let mut f = fit([1e7, 8e6, -0.05, 0.0, 0.0], SE);
        f.warnings.push(Warning {
            kind: WarningKind::Undetermined,
            message: "m = -5e-2 ± 1e-1: its standard error exceeds its value: not determined"
                .into(),
        });
        assert_eq!(violations(&f).len(), 1);
        assert!(!is_plausible(&f));
        let mut run = crate::identify::Identification {
            model: Vec::new(),
            equations: "r-and-i".into(),
            estimator: "ml".into(),
            pedestals: vec![f],
            noise: Default::default(),
            bases: Vec::new(),
            speed_lag: None,
            sensor_gain: Vec::new(),
        };
        recheck_run(&mut run, &Default::default());
        recheck_run(&mut run, &Default::default());
        assert_eq!(run.pedestals[0].warnings.len(), 1);
        assert!(!run.pedestals[0].trusted);
        // A negative damping within its noise is only unresolved (the
        // fit's own check), not a finding of the sign rule.
        assert!(violations(&fit([1e7, 8e6, 150.0, -101.0, 0.0], SE)).is_empty());
    }

    #[test]
    fn the_threshold_is_bonferroni_at_one_percent() {
        assert!((sigmas_below_zero(1) - 2.3263).abs() < 1e-3);
        assert!((sigmas_below_zero(2) - 2.5758).abs() < 1e-3);
        assert!((sigmas_below_zero(4) - 2.8070).abs() < 1e-3);
        assert!((sigmas_below_zero(10) - 3.0902).abs() < 1e-3);
        let mut f = fit([1e7, 8e6, 150.0, 0.0, 0.0], SE);
        assert_eq!(constrained_estimates(&f), 5);
        f.fixed = vec!["c_y".into(), "c_z".into()];
        assert_eq!(constrained_estimates(&f), 3);
        // A fixed parameter is never judged.
        f.pedestal.c_y = -1e9;
        assert!(violations(&f).is_empty());
    }

    #[test]
    fn a_damping_is_judged_with_the_larger_standard_error() {
        // -3 σ of the fit's own ± is significant for one pedestal's five
        // estimates (2.88); against residuals that spread twice as much it
        // is -1.5 σ. A smaller ± from the residuals never tightens the rule.
        let f = fit([1e7, 8e6, 150.0, -150.0, 0.0], SE);
        let floor = |c: f64| Some([0.0, 0.0, 0.0, c, c]);
        assert_eq!(violations_in_family(&f, 5, None, None).len(), 1);
        assert!(violations_in_family(&f, 5, floor(100.0), None).is_empty());
        assert_eq!(violations_in_family(&f, 5, floor(10.0), None).len(), 1);
        assert_eq!(violations_in_family(&f, 5, floor(f64::NAN), None).len(), 1);
    }

    #[test]
    fn a_run_is_one_family() {
        // -2.95 σ: significant for a pedestal alone (2.88), chance among the
        // ten estimates of a two-pedestal run (3.09).
        let lone = fit([1e7, 8e6, 150.0, -147.5, 0.0], SE);
        assert_eq!(offending(&lone), ["c_y"]);
        let mut lone = lone;
        lone.warnings = violations(&lone);
        lone.trusted = false;
        let mut run = crate::identify::Identification {
            model: Vec::new(),
            equations: "r-and-i".into(),
            estimator: "ml".into(),
            pedestals: vec![lone, fit([6e6, 8e6, 60.0, 10.0, 5.0], SE)],
            noise: Default::default(),
            bases: Vec::new(),
            speed_lag: None,
            sensor_gain: Vec::new(),
        };
        recheck_run(&mut run, &Default::default());
        assert!(run
            .pedestals
            .iter()
            .all(|p| p.trusted && p.warnings.is_empty()));
        run.pedestals[0].pedestal.c_y = -160.0;
        recheck_run(&mut run, &Default::default());
        assert!(!run.pedestals[0].trusted);
        assert!(run.pedestals[0].warnings[0].message.contains("family-wise"));
    }

    #[test]
    fn non_finite_results_are_errors() {
        assert!(check_finite(&fit([1e7, 8e6, 150.0, 1.0, 1.0], SE)).is_ok());
        let e = check_finite(&fit([f64::INFINITY, 8e6, 150.0, 1.0, 1.0], SE)).unwrap_err();
        assert_eq!(e.quantity, "k_y");
        let e = check_finite(&fit([1e7, 8e6, f64::NAN, 1.0, 1.0], SE)).unwrap_err();
        assert_eq!(e.quantity, "m");
        let mut se = SE;
        se[3] = f64::INFINITY;
        let e = check_finite(&fit([1e7, 8e6, 150.0, 1.0, 1.0], se)).unwrap_err();
        assert_eq!(e.quantity, "std_err.c_y");
        // "Not estimable" is allowed where the fit already says so.
        let mut f = fit([1e7, 8e6, 150.0, 1.0, 1.0], se);
        f.condition_number = f64::INFINITY;
        f.warnings.push(Warning {
            kind: WarningKind::RankDeficient,
            message: String::new(),
        });
        assert!(check_finite(&f).is_ok());
    }
}
