//! The warnings of a pedestal fit: every reason not to believe its numbers.

use super::lsq::LeastSquares;
use super::{Options, PedestalFit, Warning, WarningKind};
use crate::estimate::Observation;
use plinth_shared::phasor::Complex;
use plinth_shared::regression::Parameter;

/// The words of the [`WarningKind::Undetermined`] warning of a fit whose
/// standard errors the errors-in-variables rule withheld
/// ([`crate::estimate::ml::MIN_INFORMATION_SIGMAS`], `super::estimator`):
/// they are then infinite (`null` in JSON) and the fit has no covariance.
pub(crate) const STD_ERR_WITHHELD: &str =
    "so their standard errors are not known and none is given";

/// Whether the errors-in-variables rule withheld `fit`'s standard errors
/// (its [`WarningKind::Undetermined`] warning says [`STD_ERR_WITHHELD`]):
/// the pedestal is read so near its noise that no ± is known. The one test
/// of it, for identify and for every other report of the same pedestal
/// (`plinth diagnose`).
pub fn std_err_withheld(fit: &PedestalFit) -> bool {
    fit.warnings
        .iter()
        .any(|w| w.kind == WarningKind::Undetermined && w.message.contains(STD_ERR_WITHHELD))
}

/// All warnings for `fit`, made from the points it used (sorted by speed),
/// the number of non-finite points left out and the least-squares solution
/// over `columns` (the estimated parameters, in θ order).
pub(super) fn warnings(
    fit: &PedestalFit,
    used: &[Observation],
    skipped: usize,
    solution: &LeastSquares,
    columns: &[Parameter],
    options: &Options,
) -> Vec<Warning> {
    let mut out = Vec::new();
    let mut warn = |kind, message: String| out.push(Warning { kind, message });
    let p = columns.len();
    let [lo, hi] = fit.speed_range_hz;

    if skipped > 0 {
        warn(
            WarningKind::NonFiniteInput,
            format!("{skipped} speed(s) with non-finite numbers were left out"),
        );
    }

    let too_few = fit.speeds < options.min_speeds || fit.equations <= p;
    if too_few {
        warn(
            WarningKind::TooFewSpeeds,
            format!(
                "only {} distinct speed(s) ({} equations) for {} parameters: at least {} speeds and more equations than parameters are needed",
                fit.speeds, fit.equations, p, options.min_speeds
            ),
        );
    }

    let names_of = |direction: &[f64]| -> String {
        let mut names: Vec<&str> = columns
            .iter()
            .zip(direction)
            .filter(|(_, v)| v.abs() >= 0.3)
            .map(|(c, _)| c.name())
            .collect();
        if names.is_empty() {
            names = columns.iter().map(|c| c.name()).collect();
        }
        names.join(", ")
    };

    let rank_deficient = solution.rank < p;
    if rank_deficient {
        if fit.equations >= p {
            warn(
                WarningKind::RankDeficient,
                format!(
                    "the data do not determine {} (rank {} of {}): collinear or missing response",
                    names_of(
                        &solution
                            .undetermined
                            .iter()
                            .map(|u| u.sqrt())
                            .collect::<Vec<_>>()
                    ),
                    solution.rank,
                    p
                ),
            );
        }
    } else if solution.condition_number > options.max_condition_number {
        warn(
            WarningKind::IllConditioned,
            format!(
                "condition number {:.2e} exceeds {:.0e}: the data barely separate {}",
                solution.condition_number,
                options.max_condition_number,
                names_of(&solution.weakest_direction)
            ),
        );
    }

    if !rank_deficient && !too_few {
        for (&c, (&value, &se)) in columns
            .iter()
            .zip(solution.theta.iter().zip(&solution.std_err))
        {
            // No standard error known (estimator.rs: the errors-in-variables
            // rule withheld it): that fit's own warning says so, once.
            if se.is_infinite() {
                continue;
            }
            let damping = matches!(c, Parameter::Cy | Parameter::Cz);
            // A damping is resolved when it differs from zero by 2σ; a
            // stiffness or mass is determined when its σ is below its value.
            let reach = if damping { 2.0 * se } else { se };
            if se.is_nan() || reach > value.abs() {
                let (kind, note) = if damping {
                    (
                        WarningKind::DampingNotResolved,
                        "consistent with zero at 2σ: the data do not resolve this damping",
                    )
                } else {
                    (
                        WarningKind::Undetermined,
                        "its standard error exceeds its value: not determined",
                    )
                };
                warn(
                    kind,
                    format!("{} = {:.4e} ± {:.2e}: {note}", c.name(), value, se),
                );
            }
        }
    }

    // Resonance: the in-phase dynamic stiffness Re(F·conj X)/|X|² = k − Ω²m
    // (exact for eq. 3 data) changes sign across a pedestal resonance.
    let mut crossings = Vec::new();
    for (d, axis) in ["y", "z"].iter().enumerate() {
        let s: Vec<f64> = used
            .iter()
            .filter(|p| p.ped[d].norm_sqr() > 0.0)
            .map(|p| in_phase_stiffness(p.force()[d], p.ped[d]))
            .collect();
        if s.is_empty() {
            continue;
        }
        let k = (s.len() / 4).clamp(1, 3);
        let low = median(&s[..k]);
        let high = median(&s[s.len() - k..]);
        crossings.push((*axis, low, high, (low > 0.0) != (high > 0.0)));
    }
    if !crossings.is_empty() && crossings.iter().all(|c| !c.3) {
        let detail: Vec<String> = crossings
            .iter()
            .map(|(axis, low, high, _)| {
                format!("Re(F/X) in {axis} goes from {low:.3e} to {high:.3e} N/m")
            })
            .collect();
        warn(
            WarningKind::NoResonance,
            format!(
                "no pedestal resonance between {lo} and {hi} Hz (k − Ω²m keeps its sign: {}): m is weakly determined",
                detail.join(", ")
            ),
        );
    }
    out
}

/// Re(F·conj X)/|X|² [N/m]: the part of the dynamic stiffness in phase with
/// the pedestal response, k − Ω²m under eq. 3.
fn in_phase_stiffness(force: Complex<f64>, x: Complex<f64>) -> f64 {
    (force * x.conj()).re / x.norm_sqr()
}

fn median(v: &[f64]) -> f64 {
    crate::estimate::noise::median(&mut v.to_vec())
}
