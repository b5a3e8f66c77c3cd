//! How the readings of one pedestal (the data as found and each mistake
//! undone) are judged against each other (the module docs of
//! [`super`]): which readings can be what happened, which is decisively
//! best, and, for a mistake made for the whole run, whether the run as a
//! whole prefers it.

use super::{is_plausible, PedestalFit, Reading, DECISIVE_DELTA_CHI2, FLOOR_CHI2_PER_DOF};

/// Whether `fit` can be what happened: a passive pedestal
/// ([`is_plausible`]) with values a pedestal can have
/// ([`crate::identify::plausibility::findings`], `bearing_stiffness` its bearing's
/// [N/m]): a reading that needs a pedestal sagging a quarter metre under its
/// own weight is no more a candidate than one with a negative mass.
pub(super) fn plausible(fit: &PedestalFit, bearing_stiffness: Option<f64>) -> bool {
    is_plausible(fit) && crate::identify::plausibility::findings(fit, bearing_stiffness).is_empty()
}

/// The relative residual [-] below which a reading not yet fitted could
/// still change what [`decide`] makes of `readings`: be the best passive
/// reading, come within the decisive margin of it, or be the runner-up;
/// infinite while no reading is passive.
pub(super) fn relevance_limit(readings: &[(Reading, PedestalFit)]) -> f64 {
    let Some(best) = best_passive(readings) else {
        return f64::INFINITY;
    };
    let decisive = best.relative_residual
        * (DECISIVE_DELTA_CHI2 / best.dof.max(1) as f64).exp()
        * (1.0 + 1e-9);
    // The runner-up is the best other reading, passive or not.
    let runner_up = readings
        .iter()
        .map(|(r, _)| r)
        .filter(|r| *r != best)
        .map(|r| r.relative_residual)
        .fold(f64::INFINITY, f64::min);
    if runner_up.is_finite() {
        decisive.max(runner_up * (1.0 + 1e-9))
    } else {
        decisive
    }
}

/// The reading [`decide`] judges: the passive one with the smallest
/// relative residual (the first of equals, so the data as found, listed
/// first, win a tie); `None` when no reading is passive.
pub(super) fn best_passive<F>(readings: &[(Reading, F)]) -> Option<&Reading> {
    readings
        .iter()
        .map(|(r, _)| r)
        .filter(|r| r.plausible && r.relative_residual.is_finite())
        .min_by(|a, b| a.relative_residual.total_cmp(&b.relative_residual))
}

/// Whether [`decide`] names nothing in `readings` whatever the readings
/// not among them: the best passive reading is the data as found (a
/// reading not yet made that cannot beat it, its relative residual bounded
/// below by the data's, changes nothing: [`decide`] names only a
/// correction that is best) or no reading is passive and none is to come.
pub(super) fn found_is_best<F>(readings: &[(Reading, F)]) -> bool {
    best_passive(readings).is_some_and(|b| b.convention.is_none())
}

/// [`relevance_limit`] for a first pass that asks only what could name a
/// mistake: while the data as found are the best passive reading, only a
/// reading that could beat them (relative residual at most theirs) can
/// change that, and [`decide`] names nothing while they stay best; the
/// runner-up and the decisive margin then do not matter.
pub(super) fn naming_limit(readings: &[(Reading, PedestalFit)]) -> f64 {
    match best_passive(readings) {
        Some(best) if best.convention.is_none() => best.relative_residual,
        _ => relevance_limit(readings),
    }
}

/// The decisive reading (module docs) with the runner-up and its fit, or
/// `None` when no reading is passive, at the noise floor and decisively best.
/// Only passive readings compete with it: one that is not passive cannot be
/// what happened, however well it fits (negating `rel` and every parameter
/// leaves every residual unchanged, for one). The runner-up reported is the
/// best other reading, passive or not. The data as found, the stated
/// reading, are overturned only by evidence (the comments in the body,
/// [`explains_forces`], [`passive_within_noise`]): otherwise the data
/// cannot tell the mistake from the stated convention and nothing is named.
///
/// `floor_law_holds`: whether the bearing's residuals leave the noise
/// floor's law standing. Where they reject it (the estimator's score test,
/// p < 1e-3: it then fits under the variance function of its residuals,
/// `noise.<B>.variance_function`), a χ² weighted by that floor is no
/// likelihood and cannot veto the name: the unweighted ratio decides alone,
/// with the floor check. A proportional scatter law on noise that is in
/// fact one sd per channel gives the speeds of small amplitude nearly all
/// the weight; five parameters fit those few speeds about as well under any
/// reading, and a wrong reading can come out a little lower in χ². Seen on
/// the cross-coupled machine of `scripts/convention-sweep.sh` (1 % noise,
/// seed 3, 6 digits): at B1 `bearing_transposed` undone leaves 5.1e-4 of
/// the bearing forces against 5.6e-2 for `cross_coupling_sign` undone (an
/// unweighted ratio ν·ln(r_b/r_a) of 1313), while the rejected proportional
/// floor (score test p 2e-10) gave χ²/ν 0.630 against 0.593 and vetoed the
/// name. The variance function itself is no fairer yardstick there: fitted
/// to the residuals of the data as found, it takes the mistake's misfit for
/// noise (80 % of |rel| at B1).
pub(super) fn decide<'a>(
    readings: &[(Reading, &'a PedestalFit)],
    floor_law_holds: bool,
) -> Option<(Reading, Reading, &'a PedestalFit)> {
    let by_residual = |a: &&(Reading, &PedestalFit), b: &&(Reading, &PedestalFit)| {
        a.0.relative_residual.total_cmp(&b.0.relative_residual)
    };
    let (best, fit) = readings
        .iter()
        .filter(|(r, _)| r.plausible && r.relative_residual.is_finite())
        .min_by(by_residual)?;
    if best.chi2_per_dof().is_nan() || best.chi2_per_dof() > FLOOR_CHI2_PER_DOF {
        return None;
    }
    let others = || readings.iter().filter(|(r, _)| r != best);
    // No worse a fit to the noise floor than `r` (with `rel_negated` the
    // data as found and the correction fit alike, up to rounding).
    let not_worse = |r: &Reading| {
        !floor_law_holds || best.chi2 <= r.chi2 * (1.0 + TIE_TOLERANCE) || r.chi2.is_nan()
    };
    let decisive = others()
        .filter(|(r, _)| r.plausible)
        .all(|(r, _)| log_likelihood_ratio(best, r) >= DECISIVE_DELTA_CHI2 && not_worse(r));
    // The data as found, passive or not, must not fit the noise better
    // than the named reading, nor decisively better in the unweighted
    // ratio (the one comparison with them left where the floor's law is
    // rejected). Where they are a passive pedestal, or one within their
    // standard errors ([`passive_within_noise`]), they are the stated
    // reading and the named one must beat them decisively in both
    // figures: the unweighted ratio and, where the floor's law holds, the
    // χ² itself (−2·ln of the likelihood ratio under that floor). Where
    // the bearing forces are mostly noise (a stiff pedestal over a narrow
    // band: relative residuals 0.8-0.9) the unweighted ratio follows
    // Σ|F|², which a reading changes (y and z exchanged on an anisotropic
    // bearing), and calls readings decisive (ν·ln of 1.13: 97) whose χ²
    // differ by noise (5.6).
    let as_found = readings.iter().find(|(r, _)| r.convention.is_none());
    let better_than_found = as_found.is_none_or(|(r, q)| {
        if r == best {
            return true;
        }
        let not_decisively_better =
            not_worse(r) && log_likelihood_ratio(r, best) < DECISIVE_DELTA_CHI2;
        let stated_stands = r.plausible || passive_within_noise(q);
        let beats_stated = log_likelihood_ratio(best, r) >= DECISIVE_DELTA_CHI2
            && (!floor_law_holds || r.chi2 - best.chi2 >= DECISIVE_DELTA_CHI2);
        not_decisively_better && (!stated_stands || beats_stated)
    });
    let runner_up = others().min_by(by_residual)?.0;
    (explains_forces(best) && decisive && better_than_found).then_some((*best, runner_up, *fit))
}

/// Largest relative residual Σ|e|²/Σ|F|² [-] of a reading that can be named:
/// its residual at most half the bearing forces in rms. A reading at the
/// noise floor (χ²/ν ≈ 1) that leaves more is fitted to forces that are
/// mostly the probes' noise (a stiff pedestal over a narrow band), and
/// every reading of such forces fits about alike: on clean ROSS recordings
/// of unseen-flex and -train the mistakes named at such pedestals (r 0.52-0.94)
/// were as often wrong as right, while ROSS phasor runs of the same band
/// leave 0.003-0.015 (docs/field-data.md "Session 41 (recflex17)"; the bound was chosen
/// between the two after seeing them).
pub const MAX_RELATIVE_RESIDUAL: f64 = 0.25;

/// Whether reading `r` explains the bearing forces well enough to be named:
/// a relative residual at most [`MAX_RELATIVE_RESIDUAL`] (the zero
/// pedestal leaves 1). A fit whose residual is most of the forces it is
/// fitted to says little about the pedestal, and nothing about the
/// conventions of its data.
fn explains_forces(r: &Reading) -> bool {
    r.relative_residual <= MAX_RELATIVE_RESIDUAL
}

/// Whether `fit` is a passive pedestal within its standard errors: no
/// stiffness, mass or damping below zero by more than
/// [`crate::identify::plausibility::SIGMAS`] standard errors (the same
/// margin as the plausibility ranges), and no value outside what a
/// pedestal can be ([`crate::identify::plausibility::findings`], whose
/// ranges are themselves judged at that margin). The data as found are the reading
/// the user stated; where their fit is not passive only by amounts its
/// noise allows (a mass of −1000 ± 1400 kg on a stiff pedestal whose mass
/// the band does not determine), the passivity of another reading is no
/// evidence against them, and only the fit can tell the readings apart.
pub(super) fn passive_within_noise(fit: &PedestalFit) -> bool {
    use crate::identify::plausibility::SIGMAS;
    let se = fit.std_err.theta();
    let within = plinth_shared::regression::Parameter::ALL.iter().all(|&p| {
        let s = se[p as usize];
        let s = if s.is_finite() { s } else { f64::INFINITY };
        fit.pedestal.get(p) >= -SIGMAS * s
    });
    within && crate::identify::plausibility::findings(fit, None).is_empty()
}

/// Relative difference [-] of two χ² taken as a tie: readings that are the
/// same fit up to a sign of every parameter (`rel_negated`) differ by
/// rounding only.
const TIE_TOLERANCE: f64 = 1e-6;

/// −2·ln of the likelihood ratio of reading `b` against `a`, Gaussian
/// equation errors of one common variance profiled out of each (unknown
/// noise scale): ν·ln(r_b/r_a) with r the relative residual. Free of the
/// noise floor's shape, which the digits/scatter estimate can get badly
/// wrong; but a likelihood ratio only where every speed's error has the
/// same variance, which proportional noise breaks (a few resonance speeds
/// then dominate r), hence the χ² check of [`decide`].
pub(super) fn log_likelihood_ratio(a: &Reading, b: &Reading) -> f64 {
    a.dof as f64 * (b.relative_residual / a.relative_residual).ln()
}

/// Whether the whole run prefers mistake `c` (a [`Convention::run_wide`]
/// one) to the data as found, given per pedestal its readings as found and
/// with `c` undone (`(as found, corrected)`, pedestals where either is
/// missing left out). The pedestals' data are independent, so the run's
/// log-likelihood ratio is the sum of theirs; a run-wide mistake has one
/// value for the run, and the rule that names it at one pedestal is applied
/// to that sum: ν·ln(r_found/r_c) summed decisive, and the summed χ² no
/// worse with `c` undone. Where a bearing's force is almost all stiffness
/// (ΩC_b ≪ K_b) the speeds' unit only rescales its pedestal (m·3600, c·60)
/// and that pedestal's readings fit alike, by noise one way or the other;
/// the bearings whose damping force is not negligible decide.
pub(super) fn run_prefers(pairs: &[(Reading, Reading)]) -> bool {
    let ratio: f64 = pairs
        .iter()
        .map(|(found, c)| log_likelihood_ratio(c, found))
        .sum();
    let chi2_found: f64 = pairs.iter().map(|(found, _)| found.chi2).sum();
    let chi2_c: f64 = pairs.iter().map(|(_, c)| c.chi2).sum();
    ratio >= DECISIVE_DELTA_CHI2 && chi2_c <= chi2_found * (1.0 + TIE_TOLERANCE)
}
