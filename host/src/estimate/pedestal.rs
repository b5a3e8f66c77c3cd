//! The noise policy of a pedestal's fit: which noise every number of a
//! bearing's data is given, decided here once for `identify` (rigid ground
//! and on a base), `diagnose` and `accuracy`.
//!
//! - **Per number** ([`number_variance`]): a real number written with unit in
//!   the last place ulp has the variance of its reduction (ulp²/12 rounded,
//!   ulp²/3 truncated, [`Quantisation`]); a measured complex noise sd s of its
//!   phasor (formats.md's `*_sd` columns, `base.csv`'s `y_sd,z_sd`, a known
//!   simulated noise) is split equally, s²/2 per real part, never below the
//!   digits' variance.
//! - **Source** ([`fit_under_noise`]): the bearing's [`BearingNoise`] starts
//!   at its best source (columns, else digits); a fit under the digits whose
//!   χ² says the data scatter significantly more than their digits allow is
//!   redone under the scatter between neighbouring speeds (floored by the
//!   digits), and digits that are negligible against that scatter are not
//!   tried at all when the caller screens them.
//! - **Level** ([`noise_level`]): after the fit, χ²/dof against the source:
//!   an estimated level (scatter) is set by χ²/dof; a known level (columns,
//!   digits) is kept unless the data scatter significantly more than it
//!   allows ([`NoiseLevel::Exceeded`]: a larger noise or an equation error,
//!   the caller's model decides) or less ([`NoiseLevel::Below`]: kept, an
//!   upper bound, for the tests; the reported ± follow the residuals,
//!   [`NoiseLevel::reported_scale`]).
//! - **Without a fit** ([`floor_sd`]): the larger of the digits and the
//!   scatter, or the columns: what the convention check compares readings with.
//! - **From the data alone** ([`unscale`], [`data_alone_sd`]): the source
//!   the fit decided, not rescaled by any misfit and never finer than
//!   [`PRECISION`] of its phasor: what `diagnose`'s significance tests use.

use super::ml::chi2_two_sided_p;
use super::noise::{BearingNoise, Quantisation, RunNoise};

/// Two-sided p-value of χ² below which the noise level is said not to fit.
pub const CHI2_P_THRESHOLD: f64 = 1e-3;

/// Factor by which χ²/dof may exceed 1 at the scatter's own level (its
/// local fits' estimate, itself uncertain) before the excess is taken for a
/// model error rather than a level to rescale [-].
pub const SCATTER_LEVEL_TOLERANCE: f64 = 4.0;

/// Relative precision below which no phasor's digits are information: a
/// response computed in double precision (an FE assembly and LU solve, an
/// extraction) keeps about 10 significant digits, so the significance tests
/// never take a number as more accurate than 1e-10 of its phasor's magnitude
/// (it matters only for data written with more than about 10 digits) [-].
pub const PRECISION: f64 = 1e-10;

/// Variance [m²] of one real number written with unit in the last place
/// `ulp` [m] and reduced to its digits by `quantisation`, whose phasor has
/// the measured complex noise sd `sd` [m] when known: max(sd²/2, ulp²·msu)
/// with msu = [`Quantisation::mean_square_ulps`].
pub fn number_variance(quantisation: Quantisation, ulp: f64, sd: Option<f64>) -> f64 {
    let digits = quantisation.mean_square_ulps() * ulp.powi(2);
    sd.map_or(digits, |sd| (0.5 * sd * sd).max(digits))
}

/// True when a fit's `chi2` on `dof` says the data scatter significantly
/// more than the noise they were given (two-sided p below
/// [`CHI2_P_THRESHOLD`] and χ²/dof above 1).
pub fn scatters_more(chi2: f64, dof: usize) -> bool {
    chi2_two_sided_p(chi2, dof) < CHI2_P_THRESHOLD && chi2 / dof.max(1) as f64 > 1.0
}

/// Runs `fit` under the noise of every bearing of `noises` (one, or a
/// group fitted together) and settles the source: with `screen_digits`,
/// digits negligible against the scatter ([`BearingNoise::digits_negligible`])
/// are replaced by the scatter before the first fit; when the fit
/// ([`scatters_more`] of its `chi2_dof`) says the data scatter more than the
/// digits allow, every bearing still on its digits switches to the scatter
/// ([`BearingNoise::use_scatter`]) and `fit` runs again from the first
/// fit's result (its second argument). The fit that counts is returned; a
/// first fit's error is returned as it is.
pub fn fit_under_noise<F, E>(
    noises: &mut [BearingNoise],
    screen_digits: bool,
    mut fit: impl FnMut(&[BearingNoise], Option<&F>) -> Result<F, E>,
    chi2_dof: impl Fn(&F) -> (f64, usize),
) -> Result<F, E> {
    if screen_digits {
        for noise in noises.iter_mut() {
            if noise.digits_negligible() {
                noise.use_scatter();
            }
        }
    }
    let first = fit(noises, None)?;
    let (chi2, dof) = chi2_dof(&first);
    if !scatters_more(chi2, dof) {
        return Ok(first);
    }
    let mut switched = false;
    for noise in noises.iter_mut() {
        // Every bearing switches, not just the first that can.
        switched |= noise.use_scatter();
    }
    if switched {
        fit(noises, Some(&first))
    } else {
        Ok(first)
    }
}

/// What a fit's χ² says of the noise level it was given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NoiseLevel {
    /// A known level (columns, digits) the residuals agree with: kept.
    Known,
    /// An estimated level (scatter): set by χ²/dof, the factor given [-].
    Estimated(f64),
    /// The data scatter significantly more than the level allows (beyond
    /// [`SCATTER_LEVEL_TOLERANCE`] for an estimated one): a larger noise,
    /// by χ²/dof (given) [-], or a model error on top of the noise.
    Exceeded(f64),
    /// The data scatter significantly less than a known level says (χ²/dof
    /// given) [-]: the level is kept, an upper bound.
    Below(f64),
}

impl NoiseLevel {
    /// The factor the noise variances and the parameter covariance are
    /// multiplied by when no model error is added: χ²/dof for an estimated
    /// or exceeded level, else 1 [-].
    pub fn variance_scale(self) -> f64 {
        match self {
            NoiseLevel::Known | NoiseLevel::Below(_) => 1.0,
            NoiseLevel::Estimated(r) | NoiseLevel::Exceeded(r) => r,
        }
    }

    /// The factor [-] a fit's *reported* parameter variances computed under
    /// a known level are multiplied by: χ²/dof where the residuals scatter
    /// significantly less than the level says ([`NoiseLevel::Below`]), else
    /// one: the one rule `identify` (rigid ground) and `diagnose` (rigid
    /// ground and bases) report a pedestal's ± by.
    ///
    /// Why: a known level can be an upper bound by design. `diagnose` takes
    /// digits as truncated (mean square ulp²/3, four times a rounding's
    /// ulp²/12) so that a truncation bias does not pass for an effect; on
    /// data rounded to 3 digits its residuals then scatter at χ²/dof ≈ 0.2
    /// and every ± it reported was about 2.2 times too wide (docs/bases.md,
    /// "Session 38"; docs/diagnose-accuracy.md ("Session 39")). Only the reported ± move:
    /// the level the tests judge effects with does not. Where the residuals
    /// agree with the level (real noise above the digits, χ²/dof ≈ 1) or
    /// exceed it, this is 1.
    pub fn reported_scale(self) -> f64 {
        match self {
            NoiseLevel::Below(r) if r.is_finite() && r > 0.0 && r < 1.0 => r,
            _ => 1.0,
        }
    }
}

/// The verdict of a fit's `chi2` on `dof` on its noise level; `estimated`:
/// the level is the scatter's estimate (some bearing's, for a group).
pub fn noise_level(chi2: f64, dof: usize, estimated: bool) -> NoiseLevel {
    let ratio = chi2 / dof.max(1) as f64;
    let significant = chi2_two_sided_p(chi2, dof) < CHI2_P_THRESHOLD;
    let excess_limit = if estimated {
        SCATTER_LEVEL_TOLERANCE
    } else {
        1.0
    };
    if significant && ratio > excess_limit {
        NoiseLevel::Exceeded(ratio)
    } else if estimated {
        NoiseLevel::Estimated(ratio)
    } else if significant {
        NoiseLevel::Below(ratio)
    } else {
        NoiseLevel::Known
    }
}

/// The noise sd per real component [m] of the four phasors (rel y, rel z,
/// ped y, ped z) of each of a run's `rows` measurements, without a fit: the
/// scatter law floored by the digits while a bearing's source is the
/// digits, else its variances as they stand (noise columns), each channel's
/// real and imaginary variance averaged.
pub fn floor_sd(noise: &RunNoise, rows: usize) -> Vec<[f64; 4]> {
    let mut out = vec![[0.0; 4]; rows];
    for (_, index, noise) in &noise.bearings {
        let var = noise.scatter_var.as_ref().unwrap_or(&noise.var);
        for (&i, v) in index.iter().zip(var) {
            out[i] = std::array::from_fn(|ch| (0.5 * (v[2 * ch] + v[2 * ch + 1])).sqrt());
        }
    }
    out
}

/// `noise` from the data alone: the rescaling of its level by a fit's χ²
/// ([`BearingNoise::rescale`]) undone.
pub fn unscale(noise: &mut BearingNoise) {
    let scale = noise.variance_scale;
    noise.rescale(1.0 / scale);
}

/// The noise sd [m] of each real number of one row from the data alone:
/// its variance `var` [m²] under the source a fit decided, before any
/// rescaling by that fit's χ², and never below [`PRECISION`] of its
/// phasor's magnitude `magnitude` [m] (same order).
pub fn data_alone_sd(var: &[f64; 8], magnitude: &[f64; 8]) -> [f64; 8] {
    std::array::from_fn(|c| {
        var[c]
            .sqrt()
            .max(PRECISION * magnitude[c])
            .max(f64::MIN_POSITIVE)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_number_has_the_larger_of_its_digits_and_its_measured_noise() {
        let ulp = 1e-9;
        let rounding = number_variance(Quantisation::Rounding, ulp, None);
        assert!((rounding - ulp * ulp / 12.0).abs() < 1e-12 * rounding);
        let truncation = number_variance(Quantisation::Truncation, ulp, None);
        assert!((truncation - ulp * ulp / 3.0).abs() < 1e-12 * truncation);
        // A complex sd s splits s²/2 per real part...
        let s = 4e-9;
        assert_eq!(number_variance(Quantisation::Rounding, ulp, Some(s)), 8e-18);
        // ...but never below the digits.
        assert_eq!(
            number_variance(Quantisation::Rounding, ulp, Some(1e-12)),
            rounding
        );
    }

    #[test]
    fn chi2_verdicts_follow_the_source() {
        // 400 degrees of freedom: χ²/dof = 1 fits, 1.5 and 0.6 do not.
        let dof = 400;
        let chi2 = |r: f64| r * dof as f64;
        assert_eq!(noise_level(chi2(1.0), dof, false), NoiseLevel::Known);
        assert_eq!(
            noise_level(chi2(1.5), dof, false),
            NoiseLevel::Exceeded(1.5)
        );
        assert_eq!(noise_level(chi2(0.6), dof, false), NoiseLevel::Below(0.6));
        // An estimated level is set by χ², and only far beyond it is an excess.
        assert_eq!(
            noise_level(chi2(1.5), dof, true),
            NoiseLevel::Estimated(1.5)
        );
        assert_eq!(
            noise_level(chi2(0.6), dof, true),
            NoiseLevel::Estimated(0.6)
        );
        assert_eq!(noise_level(chi2(5.0), dof, true), NoiseLevel::Exceeded(5.0));
        assert_eq!(NoiseLevel::Below(0.6).variance_scale(), 1.0);
        assert_eq!(NoiseLevel::Exceeded(5.0).variance_scale(), 5.0);
        // Reported ± follow the residuals only below a known level.
        assert_eq!(NoiseLevel::Below(0.6).reported_scale(), 0.6);
        for level in [
            NoiseLevel::Known,
            NoiseLevel::Exceeded(5.0),
            NoiseLevel::Estimated(0.6),
        ] {
            assert_eq!(level.reported_scale(), 1.0);
        }
        assert!(scatters_more(chi2(1.5), dof) && !scatters_more(chi2(0.6), dof));
    }
}
