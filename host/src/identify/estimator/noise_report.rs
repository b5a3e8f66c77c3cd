//! What `identify` reports of a bearing's noise (`identify --json`:
//! `"noise"`): the model the fit used, its χ², the variance function and
//! the correlation along the run where they were taken.

use crate::estimate::lack_of_fit::LackOfFit;
use crate::estimate::ml;
use crate::estimate::noise::{variance, BearingNoise, NoiseSource, Quantisation, CHANNELS};
use crate::estimate::robust;
use crate::estimate::Observation;
use crate::identify::PedestalFit;
use plinth_shared::regression::PARAMETERS;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One bearing's noise model as `identify --json` reports it (`"noise"`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoiseReport {
    /// `columns`, `digits` or `scatter` (see [`crate::estimate::noise`]).
    pub source: NoiseSource,
    /// How digits were taken to be reduced: `rounding` or `truncation`.
    pub quantisation: Quantisation,
    /// RMS over speeds of each channel's complex noise sd, sqrt(E|n|²) [m],
    /// keyed `rel_y`, `rel_z`, `ped_y`, `ped_z` (after any χ² rescaling).
    pub sd: BTreeMap<String, f64>,
    /// Σ eᵀΣ⁻¹e of the fit under the noise model before rescaling [-].
    pub chi2: f64,
    /// Its degrees of freedom (equations − parameters).
    pub dof: usize,
    /// Two-sided p-value of χ² under χ²(dof).
    pub p_value: f64,
    /// True when the absolute noise level was estimated from the data and
    /// set by χ²/dof (source `scatter`); false when it was known.
    pub scale_estimated: bool,
    /// Factor applied to the noise variances and the parameter covariance
    /// (χ²/dof when the level was estimated, else 1) [-].
    pub variance_scale: f64,
    /// sd τ [N] of the equation error added to the noise on every real
    /// equation when the data scatter far more than the noise allows
    /// (a model discrepancy; 0 when the noise explains the residuals).
    #[serde(default)]
    pub equation_error_sd: f64,
    /// The lack-of-fit evidence ([`crate::estimate::lack_of_fit`]) when the
    /// noise level was not known beforehand or the fit exceeded it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lack_of_fit: Option<LackOfFit>,
    /// Speeds [Hz] left out of the fit as outliers or whose phasors look
    /// flipped by 180° ([`crate::estimate::robust`]), ascending.
    #[serde(default)]
    pub outlier_speeds_hz: Vec<f64>,
    /// The variance function the fit's residuals gave when they rejected the
    /// scatter's law ([`crate::estimate::noise::variance`]); the fit and its
    /// standard errors are those under it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub variance_function: Option<VarianceLaw>,
    /// The noise's correlation along the run when the residuals show it
    /// ([`crate::estimate::serial`]): the ± are widened for it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub serial_correlation: Option<crate::estimate::serial::SerialCorrelation>,
    /// What the ML fit's test in speed found ([`robust::flip_search`]),
    /// for the test across bearings that follows it
    /// ([`crate::identify::flips::mark_cross_bearing_flips`], which takes it): not
    /// reported.
    #[serde(skip)]
    pub flip_search: Option<robust::FlipSearch>,
}

/// A variance function per channel as reported: complex noise sd
/// sqrt(E|n|²) = sqrt(fraction²·|X|² + floor²) [m] at a phasor of magnitude |X|.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VarianceLaw {
    /// The part proportional to |X| per channel (`rel_y`, …) [-].
    pub fraction: BTreeMap<String, f64>,
    /// The floor per channel [m].
    pub floor_sd: BTreeMap<String, f64>,
    /// A velocity pick-up's floor per channel, complex sd in velocity
    /// [m/s] (sd floor/Ω in displacement): only where the fit freed it
    /// (noise columns on trial, [`variance::Family::VelocityFloor`]).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub velocity_floor_sd: BTreeMap<String, f64>,
    /// p-value of the score test of the source's own law [-]: below
    /// [`variance::HETEROSCEDASTIC_P`] it rejected that law; at or above it
    /// the variance function was taken because the scatter's law was carried
    /// to most speeds rather than measured there
    /// ([`crate::estimate::noise::BearingNoise::scatter_mostly_carried`]).
    pub p_value: f64,
}

impl VarianceLaw {
    /// The report of [`variance::COMPONENTS`] `p` (per real part α [-], β
    /// [m²], γ [m²/s²]) whose variances were scaled by `scale` [-] after the fit, chosen
    /// at the score test's `p_value` [-].
    pub(crate) fn of(p: &[f64; variance::COMPONENTS], scale: f64, p_value: f64) -> Self {
        let per = |offset: usize| {
            CHANNELS
                .iter()
                .enumerate()
                .map(|(ch, n)| (n.to_string(), (2.0 * scale * p[3 * ch + offset]).sqrt()))
                .collect::<BTreeMap<String, f64>>()
        };
        let velocity = per(2);
        Self {
            fraction: per(0),
            floor_sd: per(1),
            velocity_floor_sd: if velocity.values().any(|v| *v > 0.0) {
                velocity
            } else {
                BTreeMap::new()
            },
            p_value,
        }
    }
}

/// The noise report of a fit with `chi2` on `dof` under `noise`, its
/// variances scaled by `variance_scale`, with an equation error of
/// `equation_error_sd` [N] added where the noise model could not explain the
/// residuals.
pub(crate) fn report(
    noise: &BearingNoise,
    chi2: f64,
    dof: usize,
    variance_scale: f64,
    equation_error_sd: f64,
) -> NoiseReport {
    let sd = noise.sd();
    NoiseReport {
        source: noise.source,
        quantisation: noise.quantisation,
        sd: CHANNELS
            .iter()
            .zip(sd)
            .map(|(n, v)| (n.to_string(), v))
            .collect(),
        chi2,
        dof,
        p_value: if dof > 0 {
            ml::chi2_two_sided_p(chi2, dof)
        } else {
            f64::NAN
        },
        scale_estimated: noise.source.scale_estimated(),
        variance_scale,
        equation_error_sd,
        lack_of_fit: None,
        outlier_speeds_hz: Vec::new(),
        variance_function: None,
        serial_correlation: None,
        flip_search: None,
    }
}

/// The noise report of an OLS fit: χ² of the OLS estimate under the noise model.
pub fn ols_noise_report(
    fit: &PedestalFit,
    observations: &[Observation],
    noise: &BearingNoise,
) -> NoiseReport {
    let finite = || observations.iter().filter(|o| o.is_finite());
    let p = PARAMETERS - fit.fixed.len();
    let chi2 = ml::cost_over(finite(), &fit.pedestal.theta(), 0.0).unwrap_or(f64::NAN);
    report(
        noise,
        chi2,
        (4 * finite().count()).saturating_sub(p),
        1.0,
        0.0,
    )
}
