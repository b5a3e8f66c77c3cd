//! Lack of fit: is what a fit leaves behind noise, or model error?
//!
//! Two figures per bearing, both free of any assumption that the residuals
//! are white (rounded numbers are not: when a phasor changes by less than
//! its last digit from one speed to the next, the rounding errors of
//! neighbouring speeds are nearly equal).
//!
//! - **Level**: χ²/dof of the fit against a level measured *without* the
//!   model: noise columns, or the scatter of each channel about a local
//!   cubic in speed floored by the digits ([`super::noise`]). On clean data
//!   it is about 1 (0.7-1 for the scatter, whose local fits over-estimate it a
//!   little); a model error, smooth in speed, does not enter the scatter but
//!   does enter the fit, and puts it at tens to thousands.
//! - **Structure**: a scan of the whitened residuals w_i = L_i⁻¹e_i (one
//!   real 4-vector per speed) for a smooth trend in speed. Model error from
//!   a missing resonance is local in speed; a global polynomial spreads it
//!   over all its degrees of freedom. So every window of a set
//!   (`window::windows`: the whole run with Legendre polynomials of
//!   degree ≤ [`MAX_DEGREE`], and
//!   windows of n/2, n/4, ... speeds overlapping by half with degree ≤
//!   [`LOCAL_DEGREE`]) scores the sum of squares its polynomials explain
//!   (all four components), as a normal score of the χ² white residuals
//!   would give it so that windows of every size compare; the statistic is
//!   the largest score. Its null is the same maximum after the residuals
//!   are cut into blocks of [`BLOCK`] consecutive speeds and the blocks put
//!   in a random order ([`PERMUTATIONS`] times, a fixed seed): the maximum
//!   over windows is accounted for (each shuffle takes its own maximum), the
//!   shuffle keeps the short-range correlation of rounding errors and any
//!   pattern of noise level, and destroys only the trend that model error
//!   is. The p-value is the share of shuffles scoring as high as the data.
//!   The residuals are first divided by their local RMS over speed
//!   ([`LEVEL_WINDOW`]), so that a level the noise model's pattern misses
//!   does not look like a trend.
//! - **Mean** (`mean`): the residual mean over the run, which no shuffle
//!   can judge and the scan removes: a broad one-signed model error. Its
//!   null: blocks of [`BLOCK`] speeds negated at random (residuals
//!   symmetric about zero). The structure test's p-value is twice the
//!   smaller of the scan's and the mean's (Bonferroni).
//!
//! The rule built on them ([`crate::identify::trust`]) and its false-alarm
//! and detection rates (measured by `scripts/bench-trust.sh`) are in
//! docs/trust-lack-of-fit.md.

mod delay;
pub mod delay_unknown;
mod mean;
mod score;
mod structure;
mod support;
mod window;

pub use delay::{sensor_delay, SensorDelay};
pub use delay_unknown::{delay_nuisance, DelayNuisance};
pub use structure::{
    structure, Structure, BLOCK, LEVEL_WINDOW, PERMUTATIONS, STOP_AFTER_EXCEEDANCES,
};
pub use support::{support_mode, SupportMode};
pub use window::{LOCAL_DEGREE, MAX_DEGREE, MIN_WINDOW, SCALES};

use super::gauss_helmert as gh;
use super::ml::{Rigid, Weighting};
use super::noise::NoiseSource;
use super::Observation;
use plinth_shared::regression::{Parameter, PARAMETERS};
use serde::{Deserialize, Serialize};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// χ²/dof against the measured level (scatter, digits) above which a fit
/// leaves more than its noise: a test that judges the residuals' shape
/// alone (the structure scan) counts only beyond it (clean data: below 0.96 with a scatter level, 1.28 with noise
/// columns, over 3 600 runs) [-].
pub const EXCESS_LEVEL: f64 = 1.0;

/// What a fit says about its own lack of fit (`identify --json`:
/// `noise.<bearing>.lack_of_fit`): made when the bearing's noise level was
/// not known beforehand (taken from the scatter) or the fit's χ² exceeded
/// the known one, the cases where model error could pass for noise.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LackOfFit {
    /// The structure tests of the whitened residuals (`None`: too few speeds).
    pub structure: Option<Structure>,
    /// Where the level the fit is compared with comes from: `columns` (noise
    /// columns) or `scatter` (local fits of each channel, before any
    /// rescaling); `digits` when only the rounding floor is known (then no
    /// level test: data may carry more noise than their digits).
    pub level_from: NoiseSource,
    /// χ²/dof of the fit against that level [-].
    pub level_ratio: f64,
    /// Upper-tail p-value of χ² under χ²(dof): exact for noise columns,
    /// informative only for the other sources; where the residuals are
    /// correlated along the run ([`super::serial`]) with the degrees of
    /// freedom that correlation leaves ([`super::serial::level_p`]).
    pub level_p: f64,
    /// Standard errors of c_y and c_z [N·s/m] from the residuals themselves
    /// (the sandwich of [`super::robust::sandwich_std_errs`]: right whatever
    /// the noise model's pattern over speed), for the negative-damping rule
    /// ([`crate::identify::physical`]); `None` when not estimable.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping_std_err_from_residuals: Option<[f64; 2]>,
    /// The support-mode test ([`support_mode`]: an Ω⁴ fall of the
    /// stiffness, a second support mode above the range), made when the
    /// noise is known from noise columns (`None` otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub support_mode: Option<SupportMode>,
    /// The sensor-delay test ([`sensor_delay`]: a phase error of the `rel`
    /// probes growing linearly with speed), made when the noise is known
    /// from noise columns (`None` otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensor_delay: Option<SensorDelay>,
    /// The fit linearised with a delay on the `rel` probes
    /// ([`delay_nuisance`]: τ̂, its ±, each parameter's ρ): what
    /// [`crate::identify`] counts in the pedestal ± where the data do not
    /// exclude the delay ([`delay_unknown`]); with every noise source.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delay_unknown: Option<DelayNuisance>,
}

/// The lack-of-fit evidence of a fit at `theta` (θ units) to `obs` whose
/// variances are the noise model's level (before any χ² rescaling; a
/// robust fit's down-weighting included, [`super::robust`]) over the
/// estimated `columns`, with χ² = `chi2` on `dof`; `None` when the noise
/// is known (digits or columns) and explains χ² (upper-tail p ≥ `p_limit`)
/// and, for noise columns, the support-mode test cannot be made: then
/// nothing could pass for noise. With noise columns the support-mode and
/// sensor-delay tests are always made (a second support mode just above the range leaves a
/// χ² excess the level test cannot see; its own test can); the structure
/// scan only under the level gate above.
pub fn assess(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    columns: &[Parameter],
    source: NoiseSource,
    chi2: f64,
    dof: usize,
    p_limit: f64,
) -> Option<LackOfFit> {
    if dof == 0 || !chi2.is_finite() {
        return None;
    }
    let eq = Rigid::new(obs, &Weighting::default());
    let speeds: Vec<f64> = obs.iter().map(|o| o.speed_hz).collect();
    let w = gh::whitened(&eq, theta, None)?;
    let rows: Vec<[f64; 4]> = (0..obs.len())
        .map(|j| std::array::from_fn(|c| w[4 * j + c]))
        .collect();
    // Noise correlated along the run is not model error: where the
    // residuals show a correlation beyond what white noise gives
    // ([`super::serial`]), χ² is judged with the degrees of freedom that
    // correlation leaves ([`super::serial::level_p`]), the scan is made on
    // the residuals prewhitened by it, and the score tests of a support mode
    // and of a sensor delay (whose columns are smooth in speed: their
    // statistics grow by up to (1 + ρ)/(1 − ρ) under the correlation) are
    // deflated by that largest factor.
    //
    // These tests take the measured ρ̂ as it is; the AR(1)'s ρ with the
    // detrending's bias removed ([`super::serial::ar1_rho`], larger) is for
    // the ± (the widening, the delay's linearisation below). A model error
    // local in speed leaves a correlated residual too, and prewhitening it
    // by the larger ρ took it for noise: the scan found the ROSS machine-d
    // sub-base alone in 3 of 20 runs instead of 6 or more
    // (`identify_trust`, a_local_model_error_inside_the_level_limit_is_found_by_the_scan;
    // docs/estimation-scatter.md, Session 49 (corr17b)).
    let measured = super::serial::measured(&speeds, &rows);
    let rho = measured.map(|(_, lag_one, _)| lag_one.min(super::serial::MAX_RHO));
    let level_p = super::serial::level_p(chi2, dof, rho.unwrap_or(0.0));
    let scanned = source.scale_estimated() || level_p < p_limit;
    // With noise columns only. A form without them (the score over the
    // extended fit's residual variance) was measured and is not made: on
    // the fourth machine's clean field table (3 digits, 0.1°, through
    // `plinth import`) it flagged B1 at p = 7e-5 (docs/trust-support-mode.md, session
    // 29): neighbouring speeds' rounding errors are alike, a smooth Ω⁴
    // column collects them, and a residual variance does not see that
    // correlation (the structure scan's block shuffles do).
    let mut support_mode = (source == NoiseSource::Columns)
        .then(|| support_mode(&eq, theta, &speeds))
        .flatten();
    // The same with the sensor-delay test (columns only, as above).
    let omega: Vec<f64> = obs.iter().map(|o| o.omega()).collect();
    let mut sensor_delay = (source == NoiseSource::Columns)
        .then(|| sensor_delay(&eq, theta, &omega))
        .flatten();
    if !scanned && support_mode.is_none() && sensor_delay.is_none() {
        return None;
    }
    // The delay's linearisation under the same AR(1) (its equations
    // prewhitened by ρ: the generalised fit's τ̂, σ_τ and ρ).
    let delay_unknown = delay_nuisance(&eq, theta, &omega, columns, measured.map(|m| m.0));
    if let Some(rho) = rho {
        let inflation = super::serial::long_run_factor(rho);
        if let Some(s) = &mut support_mode {
            s.deflate(inflation);
        }
        if let Some(d) = &mut sensor_delay {
            d.deflate(inflation);
        }
    }
    let rows = match rho {
        Some(rho) if scanned => super::serial::prewhitened(&rows, rho),
        _ => rows,
    };
    Some(LackOfFit {
        structure: if scanned {
            structure(&speeds, &rows)
        } else {
            None
        },
        support_mode,
        sensor_delay,
        delay_unknown,
        level_from: source,
        level_ratio: chi2 / dof as f64,
        level_p,
        damping_std_err_from_residuals: super::robust::sandwich_std_errs(obs, theta, columns)
            .map(|se| [se[Parameter::Cy as usize], se[Parameter::Cz as usize]]),
    })
}

impl SupportMode {
    /// The test under noise correlated along the run, whose statistic it
    /// inflates by up to `inflation` [-] ([`super::serial::long_run_factor`]):
    /// the statistic divided by it, the p-value the chi-bar-squared one with
    /// the χ²₂ weight at its largest, ½ (never smaller than the exact one:
    /// conservative), the ± of the drop widened by √`inflation`.
    fn deflate(&mut self, inflation: f64) {
        self.statistic /= inflation;
        self.p_value = if self.statistic > 0.0 {
            let tail = |q: f64| {
                ChiSquared::new(q)
                    .map(|d| 1.0 - d.cdf(self.statistic))
                    .unwrap_or(1.0)
            };
            (0.5 * tail(1.0) + 0.5 * tail(2.0)).min(1.0)
        } else {
            1.0
        };
        for v in &mut self.drop_at_top_std_err {
            *v *= inflation.sqrt();
        }
    }
}

impl SensorDelay {
    /// The test under noise correlated along the run, whose statistic it
    /// inflates by up to `inflation` [-]: the statistic divided by it, its
    /// χ²(1) p-value, the delay's ± widened by √`inflation`.
    fn deflate(&mut self, inflation: f64) {
        self.statistic /= inflation;
        self.p_value = ChiSquared::new(1.0)
            .map(|d| 1.0 - d.cdf(self.statistic))
            .unwrap_or(1.0);
        self.delay_std_us *= inflation.sqrt();
    }
}
