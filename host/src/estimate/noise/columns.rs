//! Noise columns on trial: do formats.md's `*_sd` columns describe the noise
//! the fit's residuals show?
//!
//! **Why.** With noise columns identify weights every number by them and
//! keeps their level (a known level, [`super::NoiseSource::Columns`]). Field
//! instruments often write one sd per channel (a figure for the whole
//! record) while a real probe's noise grows with the amplitude at a
//! resonance: the columns then understate the noise at the peak and
//! overstate it elsewhere, χ²/dof over the run can still look right (the
//! RMS of the columns is the RMS of the noise), the fit leans on the speeds
//! the columns call precise, and its ± do not mean what they say. Measured
//! on ROSS unseen-overhung (`scripts/bench_hetero.py`, variant `h1c-const`:
//! each bearing-channel's RMS sd written as a constant column): 4/30 runs
//! printed an `ok` pedestal whose k or m was more than 3 ± off, B1 c_z's ±
//! 2.8× and k_z's 1.3× the ± under the true columns.
//!
//! **Test.** Under the columns the residuals of a speed's equations are
//! N(0, Σ_s) with Σ_s the columns' variances through the equations'
//! sensitivities. The scatter's score statistic
//! ([`super::variance::homoscedasticity_p`]) tests that covariance (one
//! scale free: this judges the columns' shape, the level test of
//! [`crate::estimate::lack_of_fit`] judges their level) against the
//! addition of a variance α_ch·|X_ch|² + β_ch + γ_ch/Ω² per real part and
//! channel, and against the floors alone, made only where the model fits
//! (χ²/dof within [`crate::estimate::pedestal::SCATTER_LEVEL_TOLERANCE`]:
//! beyond, the residuals are model error that no variance law describes).
//! Its null must not lean on the χ² law nor on the speed's own |X|
//! ([`variance::columns_shape_p`]): the fraction's regressor is read from
//! the neighbouring speeds (a pedestal read near its noise had its true
//! columns rejected at p = 1e-67 when it was the speed's own |X|², that
//! speed's noise), and the p-value is that of a parametric bootstrap under
//! the columns themselves (the leverage of a few peak speeds put 1 in 300
//! true-column fits at χ² p = 4e-13), rejected at [`COLUMNS_P`], the
//! test's size. Measured figures: docs/estimation.md, Session 41 (lowsnr17).
//!
//! **Remedy.** When the residuals reject the columns' shape the pedestal is
//! refitted under the variance function of its residuals
//! ([`super::variance::refit_under`]: its level and shape both from the
//! residuals, floored by the digits; a fraction of |X|, a floor and a
//! velocity pick-up's floor ∝ 1/Ω per channel, [`Family::VelocityFloor`],
//! as columns written flat over a pick-up's floor need), its ± are those of
//! that fit widened to the residuals' where these give more
//! ([`widen_to_residuals`]: the variance function is itself estimated), and the
//! fit says so ([`rejected`], warning `noise_scale_mismatch`; `--json`:
//! `noise.<bearing>.variance_function`). The lack-of-fit tests keep the
//! columns and the fit under them, as they keep the scatter's law: their
//! verdicts do not move. Measured figures: docs/estimation.md "Session 29".

use super::variance::{self, columns_shape_p, Family, Refit};
use super::{BearingNoise, NoiseSource};
use crate::estimate::ml::MlFit;
use crate::estimate::{robust, Observation};
use plinth_shared::regression::{Parameter, PARAMETERS};

/// p-value of the columns' shape test ([`columns_shape_p`]) at or below
/// which the fit's residuals reject the noise columns' shape [-]: the least
/// its bootstrap gives, 2/([`variance::BOOTSTRAP_DRAWS`] + 1) (none of the
/// draws under the columns reached either observed statistic), the test's
/// size.
pub const COLUMNS_P: f64 = 1e-3;

/// The fit `fit` of `obs` (parameters `columns`) redone under the variance
/// function of its residuals when they reject the pattern of its noise
/// `noise`'s source ([`NoiseSource::pattern_on_trial`]): the scatter's law
/// at [`variance::HETEROSCEDASTIC_P`], or always where it is mostly carried
/// ([`BearingNoise::scatter_mostly_carried`], [`variance::refit`]); noise columns'
/// shape at [`COLUMNS_P`] ([`variance::columns_shape_p`]), refitted under
/// [`Family::VelocityFloor`] ([`variance::refit_under`]) with ± never
/// below the residuals' ([`widen_to_residuals`]); `floor` gives each
/// observation's digits' variances [m²].
/// `None` when the source is not on trial, the test does not reject or a
/// step fails.
pub fn refit(
    noise: &BearingNoise,
    obs: &[Observation],
    floor: impl Fn(&Observation) -> [f64; 8],
    columns: &[Parameter],
    fit: &MlFit,
) -> Option<Refit> {
    match noise.source {
        NoiseSource::Scatter => {
            variance::refit(obs, floor, columns, fit, !noise.scatter_mostly_carried())
        }
        NoiseSource::Columns => {
            let p_value = columns_shape_p(obs, &fit.theta, columns)?;
            if p_value <= COLUMNS_P {
                let mut r = variance::refit_under(
                    obs,
                    floor,
                    columns,
                    fit,
                    Family::VelocityFloor,
                    p_value,
                )?;
                widen_to_residuals(&mut r, columns);
                Some(r)
            } else {
                None
            }
        }
        NoiseSource::Digits => None,
    }
}

/// Widens the covariance of the refit `r` (parameters `columns`) so that no
/// standard error is below the one its residuals give
/// ([`robust::sandwich_std_errs`], HC3: right whatever the weights): each
/// parameter's row and column scaled by max(1, sandwich / own), the
/// correlations kept. Its own ± hold only if the variance function is the
/// noise's; fitted from the residuals of ~100 speeds it can miss a
/// channel's noise where one parameter's information lies (measured on
/// `bench_hetero.py` h1v-const seed 27: B1 rel_z's fraction 0.4 % and floor
/// 0.04 of the true ones, c_z's ± 10.4 against 18.5 under the true
/// columns, 5.5 ± off). Unchanged when the sandwich fails.
fn widen_to_residuals(r: &mut Refit, columns: &[Parameter]) {
    let Some(sandwich) = robust::sandwich_std_errs(&r.obs, &r.fit.theta, columns) else {
        return;
    };
    let cov = &mut r.fit.covariance;
    let ratio: [f64; PARAMETERS] = std::array::from_fn(|i| {
        let own = cov[i][i].sqrt();
        if own > 0.0 && sandwich[i] > own {
            sandwich[i] / own
        } else {
            1.0
        }
    });
    for (i, row) in cov.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v *= ratio[i] * ratio[j];
        }
    }
}

/// The message of a fit whose residuals rejected its noise columns' shape
/// (score test p-value `p_value` [-]) while the columns' overall level gave
/// χ²/dof `chi2_per_dof` [-]: what was rejected, and which noise the fit
/// and its ± are under instead.
pub fn rejected(p_value: f64, chi2_per_dof: f64) -> String {
    format!(
        "the noise columns misdescribe this bearing's noise: the fit's residuals reject their shape over the speeds (score tests against a fraction of |X|, a floor and a velocity floor per channel and against the floors alone, one scale free: p = {p_value:.1e} ≤ {COLUMNS_P:.0e}, from a parametric bootstrap of the statistic under the columns) although their overall level gives χ²/dof = {chi2_per_dof:.3}; the fit and its ± are those under the variance function of its residuals (noise.variance_function), not under the columns"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_message_gives_the_test_and_the_noise_used_instead() {
        let m = rejected(1e-3, 0.704);
        assert!(m.contains("p = 1.0e-3 ≤ 1e-3"), "{m}");
        assert!(m.contains("χ²/dof = 0.704"), "{m}");
        assert!(m.contains("variance function"), "{m}");
    }
}
