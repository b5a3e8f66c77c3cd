//! Physical plausibility of an identified pedestal, and the finiteness of
//! every number a fit reports.
//!
//! A pedestal is passive: its mass and stiffnesses cannot be negative (a
//! negative estimate is physically impossible, whatever its standard error),
//! and its damping cannot be below zero by more than the noise allows. A
//! truly undamped pedestal (the paper's first machine) gives dampings that
//! are zero plus noise, half of them negative, so the damping rule is a
//! joint one-sided test over every damping estimated in the run with a
//! stated family-wise false-alarm rate ([`FAMILY_FALSE_ALARM`], Bonferroni:
//! each of n dampings is tested at FAMILY_FALSE_ALARM/n, [`damping_sigmas`]);
//! a fit on its own is its own family ([`violations`]), a whole run is
//! re-judged as one ([`recheck_run`]). In a run the standard error a
//! damping is judged with is the largest of the fit's, the one measured
//! from its residuals (the sandwich of
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
//! nominal rate. A damping whose loss factor is below
//! [`NEGLIGIBLE_LOSS_FACTOR`] is numerically zero. A fit that breaks either
//! rule is not trusted, and the warning says which value and why; the usual
//! cause is a convention mistake in the data ([`super::convention`]).
//!
//! A result that is not a finite number (an overflow in the arithmetic, e.g.
//! data in the wrong unit by many decades) is an error, not a row of a table;
//! the only non-finite figures a fit may carry are the documented "not
//! estimable" ones: infinite standard errors and condition number of a fit
//! already untrusted because the data do not determine it.

use super::{PedestalFit, Warning, WarningKind};
use plinth_shared::regression::Parameter;

/// Family-wise false-alarm rate of the negative-damping rule per run [-]:
/// the chance that a run of passive pedestals (undamped ones included) has
/// some damping called significantly negative. Measured by
/// `scripts/bench-trust.sh`.
pub const FAMILY_FALSE_ALARM: f64 = 0.01;

/// Standard errors below zero beyond which one of `family` damping
/// estimates tested together is significantly negative: the one-sided
/// normal quantile at FAMILY_FALSE_ALARM/family (Bonferroni, valid whatever
/// the correlation of the estimates): 2.33 for one damping, 2.58 for two,
/// 2.81 for four, 2.94 for six.
pub fn damping_sigmas(family: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    let alpha = FAMILY_FALSE_ALARM / family.max(1) as f64;
    Normal::standard().inverse_cdf(1.0 - alpha)
}

/// Number of dampings `fit` estimates (not fixed by its model).
pub fn estimated_dampings(fit: &PedestalFit) -> usize {
    ["c_y", "c_z"]
        .iter()
        .filter(|d| !fit.fixed.iter().any(|f| f == *d))
        .count()
}

/// Loss factor Ω_max·|c|/k [-] below which a negative damping is numerically
/// zero, whatever its standard error: exact (12-digit) data leave dampings of
/// order 1e-12 N·s/m whose least-squares standard errors understate the
/// round-off. Real structures have loss factors of 1e-4 and more.
pub const NEGLIGIBLE_LOSS_FACTOR: f64 = 1e-6;

/// Whether a pedestal damping `c` ± `se` [N·s/m] is one no passive pedestal
/// has: below zero by more than `sigmas` standard errors
/// ([`damping_sigmas`] of its family) and material, its loss factor
/// `omega_max`·|c|/`k` (`omega_max` [rad/s], `k` [N/m] the same direction's
/// stiffness) above [`NEGLIGIBLE_LOSS_FACTOR`]. The one rule identify's
/// warning and diagnose's held-at-zero candidates use.
pub fn damping_impossible(c: f64, se: f64, k: f64, omega_max: f64, sigmas: f64) -> bool {
    let material = omega_max * c.abs() > NEGLIGIBLE_LOSS_FACTOR * k.abs();
    se.is_finite() && c < -sigmas * se && material
}

/// The physical impossibilities of `fit`, one warning
/// ([`WarningKind::PhysicallyImpossible`]) per offending parameter; empty
/// when the pedestal is passive. Parameters fixed by the model are 0 and
/// pass. Its dampings are tested as a family of their own (see
/// [`violations_in_family`]).
pub fn violations(fit: &PedestalFit) -> Vec<Warning> {
    violations_in_family(fit, estimated_dampings(fit), None)
}

/// [`violations`] with the dampings tested as `family` of a larger family
/// (every damping estimated in the run), each at [`damping_sigmas`]`(family)`
/// standard errors, each the larger of the fit's and `floor` (c_y, c_z
/// [N·s/m]: [`judged_std_errs`]; module docs).
pub fn violations_in_family(
    fit: &PedestalFit,
    family: usize,
    floor: Option<[f64; 2]>,
) -> Vec<Warning> {
    let sigmas = damping_sigmas(family);
    let mut out = Vec::new();
    let mut se = fit.std_err.theta();
    if let Some([cy, cz]) = floor {
        for (p, s) in [(Parameter::Cy, cy), (Parameter::Cz, cz)] {
            if s.is_finite() && s > se[p as usize] {
                se[p as usize] = s;
            }
        }
    }
    for p in Parameter::ALL {
        let value = fit.pedestal.get(p);
        let sigma = se[p as usize];
        let (unit, damping) = match p {
            Parameter::Ky | Parameter::Kz => ("N/m", false),
            Parameter::M => ("kg", false),
            Parameter::Cy | Parameter::Cz => ("N·s/m", true),
        };
        let message = if damping {
            let k = if p == Parameter::Cy {
                fit.pedestal.k_y
            } else {
                fit.pedestal.k_z
            };
            let omega_max = 2.0 * std::f64::consts::PI * fit.speed_range_hz[1];
            damping_impossible(value, sigma, k, omega_max, sigmas).then(|| {
                format!(
                    "{} = {value:.4e} ± {sigma:.2e} {unit} is negative by {:.1} standard errors (more than the {sigmas:.2} that keep the run's {family} damping(s) at a {:.0} % family-wise false-alarm rate): a passive pedestal cannot have negative damping",
                    p.name(),
                    -value / sigma,
                    100.0 * FAMILY_FALSE_ALARM
                )
            })
        } else {
            (value < 0.0).then(|| {
                format!(
                    "{} = {value:.4e} ± {sigma:.2e} {unit} is negative: a passive pedestal cannot have a negative {}",
                    p.name(),
                    if p == Parameter::M { "mass" } else { "stiffness" }
                )
            })
        };
        if let Some(message) = message {
            out.push(Warning {
                kind: WarningKind::PhysicallyImpossible,
                message,
            });
        }
    }
    out
}

/// Re-judges the physical impossibilities of every pedestal of a run with
/// its dampings tested as one family (all the run's estimated dampings), so
/// that the run's false-alarm rate is [`FAMILY_FALSE_ALARM`] however many
/// pedestals it has, each damping with the larger of its fit's standard
/// error and the one from its residuals (the bearing's
/// `noise.<b>.lack_of_fit.damping_std_err_from_residuals`), and updates
/// `trusted`.
pub fn recheck_run(identification: &mut super::Identification) {
    let family: usize = identification
        .pedestals
        .iter()
        .map(estimated_dampings)
        .sum();
    let noise = &identification.noise;
    for p in &mut identification.pedestals {
        p.warnings
            .retain(|w| w.kind != WarningKind::PhysicallyImpossible);
        let floor = noise.get(&p.bearing).map(|n| judged_std_errs(p, n));
        let found = violations_in_family(p, family, floor);
        p.warnings.extend(found);
        p.trusted = !p.warnings.iter().any(|w| w.kind.makes_untrusted());
    }
}

/// Standard errors of c_y and c_z [N·s/m] a run's damping rule judges
/// `fit` with, besides the fit's own (module docs): the larger of the one
/// from its residuals (`noise.lack_of_fit.damping_std_err_from_residuals`)
/// and, for a noise level estimated from the scatter (an upper bound of the
/// noise, measured without the model) that the fit's χ²/dof < 1 scaled down,
/// the fit's own before that scaling.
pub fn judged_std_errs(fit: &PedestalFit, noise: &super::estimator::NoiseReport) -> [f64; 2] {
    let se = fit.std_err.theta();
    let own = [se[Parameter::Cy as usize], se[Parameter::Cz as usize]];
    let unshrunk = if noise.scale_estimated && noise.variance_scale > 0.0 {
        own.map(|s| s / noise.variance_scale.min(1.0).sqrt())
    } else {
        own
    };
    let residuals = noise
        .lack_of_fit
        .and_then(|l| l.damping_std_err_from_residuals)
        .unwrap_or([0.0; 2]);
    std::array::from_fn(|k| {
        let r = if residuals[k].is_finite() {
            residuals[k]
        } else {
            0.0
        };
        unshrunk[k].max(r)
    })
}

/// True when `fit` describes a passive pedestal ([`violations`] is empty).
pub fn is_plausible(fit: &PedestalFit) -> bool {
    violations(fit).is_empty()
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
/// means "not estimable" and is written as `null`).
pub fn check_finite(fit: &PedestalFit) -> Result<(), NonFiniteResult> {
    let undetermined =
        fit.has_warning(WarningKind::RankDeficient) || fit.has_warning(WarningKind::TooFewSpeeds);
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
        // Negative mass is impossible whatever its standard error.
        assert_eq!(offending(&fit([1e7, 8e6, -0.01, 0.0, 0.0], SE)), ["m"]);
        assert_eq!(
            offending(&fit([1e7, 8e6, 150.0, -130.0, -5000.0], SE)),
            ["c_y", "c_z"]
        );
        // 2.02 σ below zero is chance for a family of two dampings (2.58 σ).
        assert!(is_plausible(&fit([1e7, 8e6, 150.0, -101.0, 0.0], SE)));
        let w = &violations(&fit([1e7, 8e6, -150.0, 0.0, 0.0], SE))[0];
        assert_eq!(w.kind, WarningKind::PhysicallyImpossible);
        assert!(w.message.contains("negative mass"), "{}", w.message);
    }

    #[test]
    fn damping_threshold_is_bonferroni_at_one_percent() {
        assert!((damping_sigmas(1) - 2.3263).abs() < 1e-3);
        assert!((damping_sigmas(2) - 2.5758).abs() < 1e-3);
        assert!((damping_sigmas(4) - 2.8070).abs() < 1e-3);
        let mut f = fit([1e7, 8e6, 150.0, 0.0, 0.0], SE);
        assert_eq!(estimated_dampings(&f), 2);
        f.fixed = vec!["c_y".into(), "c_z".into()];
        assert_eq!(estimated_dampings(&f), 0);
    }

    #[test]
    fn a_damping_is_judged_with_the_larger_standard_error() {
        // -3 σ of the fit's own ± is significant for one pedestal's two
        // dampings (2.58); against residuals that spread twice as much it is
        // -1.5 σ. A smaller ± from the residuals never tightens the rule.
        let f = fit([1e7, 8e6, 150.0, -150.0, 0.0], SE);
        assert_eq!(violations_in_family(&f, 2, None).len(), 1);
        assert!(violations_in_family(&f, 2, Some([100.0, 100.0])).is_empty());
        assert_eq!(violations_in_family(&f, 2, Some([10.0, 10.0])).len(), 1);
        assert_eq!(violations_in_family(&f, 2, Some([f64::NAN, 0.0])).len(), 1);
    }

    #[test]
    fn a_run_is_one_family() {
        // -2.7 σ: significant for a pedestal alone (2.58), chance among the
        // four dampings of a two-pedestal run (2.81).
        let lone = fit([1e7, 8e6, 150.0, -135.0, 0.0], SE);
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
        };
        recheck_run(&mut run);
        assert!(run
            .pedestals
            .iter()
            .all(|p| p.trusted && p.warnings.is_empty()));
        run.pedestals[0].pedestal.c_y = -150.0;
        recheck_run(&mut run);
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
