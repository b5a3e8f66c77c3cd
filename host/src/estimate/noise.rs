//! The measurement noise model: per phasor and channel, the noise of every
//! real number of `measurements.csv`, from the best source available.
//!
//! **Model.** Each measured complex phasor Q (rel y, rel z, ped y, ped z of a
//! bearing at a speed) is the true phasor plus noise n whose real and
//! imaginary parts are independent, zero-mean, with variances v_re, v_im
//! [m²]; formats.md's noise sd is sqrt(E|n|²) = sqrt(v_re + v_im). Noise of
//! different phasors and speeds is taken as independent.
//!
//! **Sources, best first** ([`NoiseSource`]):
//! 1. `columns`: formats.md's `rel_y_sd, rel_z_sd, ped_y_sd, ped_z_sd`
//!    (the scatter between the revolutions that made the phasor), split
//!    equally: v_re = v_im = sd²/2. Never below the digits' variance.
//! 2. `digits`: the rounding each number carries. A number written with D
//!    significant digits and decimal exponent e has ulp = 10^(e−D+1) (D is
//!    the column's digit count, detected as the fewest digits that reproduce
//!    every value of the column; a fixed-decimals column has an absolute ulp,
//!    and the larger of the two applies). Rounding (the default) leaves an
//!    error uniform on ±ulp/2: variance ulp²/12. Truncation
//!    ([`Quantisation::Truncation`], an option, e.g. the paper's data) leaves
//!    an error uniform on [0, ulp) toward zero: its mean square ulp²/3 is
//!    used (bias and scatter together). A number converted from a table
//!    that printed fewer digits (a field instrument's 1X vector table:
//!    3-digit amplitudes, whole-degree phases, `plinth import`) carries
//!    that table's rounding too, which its own digits (written in full
//!    precision) no longer show: `resolution.csv` gives it per phasor
//!    ([`table_variance`]), and each number's variance is the larger of
//!    the two ([`rounding_variance`]). It is the floor of every source.
//! 3. `scatter`: noise beyond the digits shows as scatter between
//!    neighbouring speeds that a smooth response does not have. Per channel,
//!    every point is compared with a quartic fitted over its 7 nearest
//!    speeds (re and im separately); the residual is a sample of that
//!    point's noise, of variance Σ c_r²·v_r over the window (c_r the
//!    residual's weight on point r, Σ c_r² = 1 − leverage), where the
//!    response is locally a quartic. Where it is not (a resonance the
//!    speed steps do not resolve) the residuals are model error, not noise,
//!    and they are smooth in speed, so they come in runs: windows of
//!    [`ADEQUACY_WINDOW`] consecutive points are judged against the current
//!    law (their sum of squared standardised residuals against its scaled
//!    χ² at p < [`ADEQUACY_P`], the overlap of the local fits allowed for),
//!    and every point of a window that fails is left out. The law is a real
//!    probe's, per channel: each real part has the variance v = α·|X|² + β
//!    (a fraction of the local magnitude |X| plus a floor; α, β ≥ 0; the
//!    two older laws, one sd and an sd proportional to |X|, are its
//!    edges), fitted to the points kept by the Gaussian pseudo-likelihood,
//!    a term dropped when the likelihood ratio does not need it
//!    ([`TERM_LR`]). It starts from one sd (the median of the samples) and
//!    alternates (windows judged, law fitted) until the points kept settle:
//!    a resonance's model error grows with |X| like a fraction would, and
//!    starting from one sd keeps it out instead of letting α take it up.
//!    What this cannot see: the noise of a resonance that is never
//!    resolved (its few points left out, the law carried there from the
//!    rest of the run). docs/trust-noise-law.md "Session 26" has the measurements.
//!
//! Without noise columns the model starts from the digits, and the fit
//! decides: when its χ² says the data scatter significantly more than their
//! digits allow (the numbers carry more digits than their noise justifies),
//! the fit switches to the scatter ([`BearingNoise::use_scatter`]; each
//! number's variance is then the larger of the two) and refits. The scatter's
//! local fits set the relative level of the channels and speeds; its absolute
//! scale is the fit's: the whitened residuals give χ², and the noise is
//! rescaled by χ²/dof ([`BearingNoise::rescale`], done by the caller).

use super::pedestal::number_variance;
use crate::rundir::Measurement;
use num_complex::Complex;
use serde::{Deserialize, Serialize};

pub mod columns;
mod digits;
mod run;
mod scatter;
pub mod variance;

use digits::digits_variances;
pub use digits::{digits_of, rounding_variance, table_variance, written_digits, ColumnDigits};

pub use run::RunNoise;
use scatter::*;
pub use scatter::{
    local_fits, local_residuals, median, scatter_law, LocalFit, ADEQUACY_P, ADEQUACY_WINDOW,
    TERM_LR,
};

/// Complex channels per bearing: rel y, rel z, ped y, ped z.
pub const CHANNELS: [&str; 4] = ["rel_y", "rel_z", "ped_y", "ped_z"];

/// The real numbers of a measurement row, in the order used for variances
/// (formats.md column names).
pub const REAL_CHANNELS: [&str; 8] = [
    "rel_y_re", "rel_y_im", "rel_z_re", "rel_z_im", "ped_y_re", "ped_y_im", "ped_z_re", "ped_z_im",
];

/// Where a bearing's noise model comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NoiseSource {
    /// formats.md's `*_sd` columns.
    Columns,
    /// The digits each number is written with.
    Digits,
    /// The scatter between neighbouring speeds.
    Scatter,
}

impl NoiseSource {
    /// The name used in output: `columns`, `digits`, `scatter`.
    pub fn name(self) -> &'static str {
        match self {
            NoiseSource::Columns => "columns",
            NoiseSource::Digits => "digits",
            NoiseSource::Scatter => "scatter",
        }
    }

    /// True when the absolute noise level is an estimate the fit's χ² should
    /// rescale (scatter), false when it is known (columns, digits).
    pub fn scale_estimated(self) -> bool {
        self == NoiseSource::Scatter
    }

    /// True when a fit's residuals put this source's pattern of noise over
    /// the speeds on trial (its shape, one scale free) and the fit is redone
    /// under the variance function they give when they reject it
    /// ([`variance::refit`]): the scatter (its law is estimated) and noise
    /// columns ([`columns`]: an instrument may write one sd per channel
    /// while the noise grows with the amplitude at a resonance); never the
    /// digits (a floor under the noise, not its pattern).
    pub fn pattern_on_trial(self) -> bool {
        matches!(self, NoiseSource::Scatter | NoiseSource::Columns)
    }

    /// What the fit's residuals reject when they reject this source's
    /// pattern ([`NoiseSource::pattern_on_trial`]), for messages.
    pub fn pattern_name(self) -> &'static str {
        match self {
            NoiseSource::Columns => "the noise columns' shape",
            NoiseSource::Scatter | NoiseSource::Digits => "the scatter's law",
        }
    }
}

/// How the written numbers were reduced to their digits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantisation {
    /// Rounded to nearest: error uniform on ±ulp/2, variance ulp²/12.
    #[default]
    Rounding,
    /// Truncated toward zero: error on [0, ulp), mean square ulp²/3.
    Truncation,
}

impl Quantisation {
    /// Mean square error [ulp²] of one number reduced this way.
    pub fn mean_square_ulps(self) -> f64 {
        match self {
            Quantisation::Rounding => 1.0 / 12.0,
            Quantisation::Truncation => 1.0 / 3.0,
        }
    }
}

/// Real number `c` ([`REAL_CHANNELS`] order) of a measurement row [m].
pub fn real_value(m: &Measurement, c: usize) -> f64 {
    let z = complex_value(m, c / 2);
    if c.is_multiple_of(2) {
        z.re
    } else {
        z.im
    }
}

/// Complex channel `ch` ([`CHANNELS`] order) of a measurement row [m].
pub fn complex_value(m: &Measurement, ch: usize) -> Complex<f64> {
    if ch < 2 {
        m.rel[ch]
    } else {
        m.ped[ch - 2]
    }
}

/// The scatter law of one complex channel: the sd of each real part.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scatter {
    /// The same sd [m] at every speed.
    Absolute(f64),
    /// sd = value·|phasor| (a fraction of the local magnitude) [-].
    Relative(f64),
    /// sd = sqrt((fraction·|phasor|)² + floor²): a fraction of the local
    /// magnitude plus a floor, both present.
    Mixed {
        /// The part proportional to the magnitude [-].
        fraction: f64,
        /// The floor [m].
        floor: f64,
    },
}

impl Scatter {
    /// The sd [m] of each real part of a phasor of magnitude `magnitude` [m].
    pub fn sd(&self, magnitude: f64) -> f64 {
        self.sd_with(|| magnitude)
    }

    /// [`Scatter::sd`] of the magnitude [m] `magnitude` gives, called only
    /// by a law that reads it (not by [`Scatter::Absolute`]).
    pub fn sd_with(&self, magnitude: impl FnOnce() -> f64) -> f64 {
        match *self {
            Scatter::Absolute(s) => s,
            Scatter::Relative(f) => f * magnitude(),
            Scatter::Mixed { fraction, floor } => (fraction * magnitude()).hypot(floor),
        }
    }
}

/// The noise model of one bearing's rows.
#[derive(Clone, Debug, PartialEq)]
pub struct BearingNoise {
    /// Where the variances come from.
    pub source: NoiseSource,
    /// How the digits were taken to be reduced.
    pub quantisation: Quantisation,
    /// Variance [m²] of every real number, per row in the order given to
    /// [`BearingNoise::estimate`], in [`REAL_CHANNELS`] order.
    pub var: Vec<[f64; 8]>,
    /// The scatter law found per complex channel (`None`: too few speeds).
    pub scatter: [Option<Scatter>; 4],
    /// Per complex channel, how many speeds the scatter's windows left out
    /// (a response the local fits cannot follow there, e.g. a resonance the
    /// speed steps do not resolve): its law is carried to them from the
    /// other speeds, not measured there.
    pub scatter_left_out: [usize; 4],
    /// The variances under the scatter law (floored by the digits), while
    /// the source is still the digits.
    pub scatter_var: Option<Vec<[f64; 8]>>,
    /// Variance [m²] each real number has from its rounding alone
    /// ([`rounding_variance`]: its digits, or the table it was converted
    /// from), row for row ([`REAL_CHANNELS`] order): the floor of every
    /// noise law (no reading is more precise than the digits it is written
    /// with), kept when the source moves on. Never rescaled.
    pub digits_var: Vec<[f64; 8]>,
    /// Factor the variances were multiplied by after the fit (1 until
    /// [`BearingNoise::rescale`]).
    pub variance_scale: f64,
}

/// Variance ratio of the scatter to the digits above which
/// [`BearingNoise::digits_negligible`] rules the digits out without a fit
/// (a thousand in standard deviation) [-].
pub const DIGITS_NEGLIGIBLE: f64 = 1e6;

/// Most points a local smooth fit uses.
const WINDOW: usize = 7;
/// Degree of the local smooth fit (a quartic: on ROSS unseen-overhung's
/// coast-down grid its model error exceeds a 1 % white noise at 12 % of the
/// points, a cubic's at 29 %).
const DEGREE: usize = 4;
const MEDIAN_ABS_NORMAL: f64 = 0.674_489_750_196_081_7;

impl BearingNoise {
    /// The noise of one bearing's `rows` (any order; each row one speed),
    /// with the digits of its own columns ([`ColumnDigits::of_rows`]).
    pub fn estimate(
        rows: &[&Measurement],
        columns: &[ColumnDigits; 8],
        quantisation: Quantisation,
    ) -> Self {
        // Each number's variance: the one rule of `estimate::pedestal`,
        // never below the rounding the number carries.
        let variance = |m: &Measurement, c: usize, sd: Option<f64>| {
            number_variance(quantisation, columns[c].ulp_of(m, c), sd).max(table_variance(m, c))
        };
        let with_columns = !rows.is_empty() && rows.iter().all(|m| m.noise_sd.is_some());
        let digits_var = digits_variances(rows, columns, quantisation);
        if with_columns {
            let var = rows
                .iter()
                .map(|m| {
                    let sd = m.noise_sd.unwrap_or([0.0; 4]);
                    std::array::from_fn(|c| variance(m, c, Some(sd[c / 2])))
                })
                .collect();
            return Self {
                source: NoiseSource::Columns,
                quantisation,
                var,
                scatter: [None; 4],
                scatter_left_out: [0; 4],
                scatter_var: None,
                digits_var,
                variance_scale: 1.0,
            };
        }
        Self::with_scatter(rows, digits_var, quantisation, [None; 4])
    }

    /// The noise of `rows` under the digits, whose variances `digits_var`
    /// (row for row) are given, with the scatter law of each complex channel
    /// estimated from `rows`, or taken from `known` where given (a channel
    /// whose values and speeds are those the law was estimated from: its
    /// law and the speeds its windows left out).
    fn with_scatter(
        rows: &[&Measurement],
        digits_var: Vec<[f64; 8]>,
        quantisation: Quantisation,
        known: [Option<(Option<Scatter>, usize)>; 4],
    ) -> Self {
        let mut order: Vec<usize> = (0..rows.len()).collect();
        order.sort_by(|&a, &b| rows[a].speed_hz.total_cmp(&rows[b].speed_hz));
        // The local fits depend on the speeds only: made once, used by every channel.
        let fits = if known.iter().all(Option::is_some) {
            Vec::new()
        } else {
            let speeds: Vec<f64> = order.iter().map(|&i| rows[i].speed_hz).collect();
            local_fits(&speeds)
        };
        // The channels' samples are at the same points as a rule: one set of windows.
        let mut windows = WindowCache::default();
        let laws: [(Option<Scatter>, usize); 4] = std::array::from_fn(|ch| match known[ch] {
            Some(law) => law,
            None => {
                let values: Vec<Complex<f64>> =
                    order.iter().map(|&i| complex_value(rows[i], ch)).collect();
                scatter_law_with(&fits, &values, &mut windows)
            }
        });
        let scatter = laws.map(|l| l.0);
        let scatter_left_out = laws.map(|l| l.1);
        let scatter_var = rows
            .iter()
            .zip(&digits_var)
            .map(|(m, dv)| {
                // Each channel's sd once, for its real and imaginary part.
                let sd: [f64; 4] = std::array::from_fn(|ch| {
                    scatter[ch].map_or(0.0, |law| law.sd_with(|| complex_value(m, ch).norm()))
                });
                std::array::from_fn(|c| {
                    let s = sd[c / 2];
                    (s * s).max(dv[c])
                })
            })
            .collect();
        Self {
            source: NoiseSource::Digits,
            quantisation,
            var: digits_var.clone(),
            scatter,
            scatter_left_out,
            scatter_var: Some(scatter_var),
            digits_var,
            variance_scale: 1.0,
        }
    }

    /// Switches from the digits to the scatter between neighbouring speeds
    /// (floored by the digits): what a fit does when its χ² says the numbers
    /// carry more noise than their digits. False when there is no scatter
    /// estimate (too few speeds, or the source is not the digits).
    pub fn use_scatter(&mut self) -> bool {
        if self.source != NoiseSource::Digits {
            return false;
        }
        match self.scatter_var.take() {
            Some(v) if self.scatter.iter().any(Option::is_some) => {
                self.var = v;
                self.source = NoiseSource::Scatter;
                true
            }
            _ => false,
        }
    }

    /// True while the source is the digits and, on every real channel, the
    /// scatter between neighbouring speeds exceeds the digits' variance (summed
    /// over the rows) by more than [`DIGITS_NEGLIGIBLE`]: numbers written with
    /// far more digits than their noise (full-precision output). No fit can
    /// then find the digits enough, so the caller switches to the scatter
    /// ([`BearingNoise::use_scatter`]) before fitting instead of after a
    /// fit under the digits (a long one: its noise is wrong by that factor).
    pub fn digits_negligible(&self) -> bool {
        let Some(scatter) = self.scatter_var.as_ref() else {
            return false;
        };
        if self.source != NoiseSource::Digits || scatter.is_empty() {
            return false;
        }
        (0..8).all(|c| {
            let digits: f64 = self.var.iter().map(|v| v[c]).sum();
            let spread: f64 = scatter.iter().map(|v| v[c]).sum();
            spread > DIGITS_NEGLIGIBLE * digits
        })
    }

    /// Multiplies every variance by `factor` (> 0, finite): the absolute
    /// scale of an estimated noise level corrected by a fit's χ²/dof.
    pub fn rescale(&mut self, factor: f64) {
        if factor.is_finite() && factor > 0.0 {
            for v in &mut self.var {
                for x in v.iter_mut() {
                    *x *= factor;
                }
            }
            self.variance_scale *= factor;
        }
    }

    /// True when on some channel the scatter's windows left out more
    /// speeds than they kept ([`BearingNoise::scatter_left_out`]): its law
    /// there is carried from a minority of the speeds more than measured.
    pub fn scatter_mostly_carried(&self) -> bool {
        let n = self.var.len();
        self.scatter
            .iter()
            .zip(&self.scatter_left_out)
            .any(|(law, &left)| law.is_some() && 2 * left > n)
    }

    /// RMS over rows of each complex channel's noise sd, sqrt(mean E|n|²)
    /// [m], in [`CHANNELS`] order.
    pub fn sd(&self) -> [f64; 4] {
        let n = self.var.len().max(1) as f64;
        std::array::from_fn(|ch| {
            (self
                .var
                .iter()
                .map(|v| v[2 * ch] + v[2 * ch + 1])
                .sum::<f64>()
                / n)
                .sqrt()
        })
    }
}

/// Real channels ([`REAL_CHANNELS`] order) with y and z exchanged.
const SWAP_YZ_REAL: [usize; 8] = [2, 3, 0, 1, 6, 7, 4, 5];

impl BearingNoise {
    /// The same noise with y and z exchanged in every channel: what
    /// [`BearingNoise::estimate`] gives for rows whose y and z readings (and
    /// noise columns) were exchanged, since each channel's scatter and each
    /// column's digits are estimated on their own.
    pub fn swapped_yz(&self) -> Self {
        let swap = |v: &[f64; 8]| SWAP_YZ_REAL.map(|c| v[c]);
        Self {
            var: self.var.iter().map(swap).collect(),
            scatter: [1, 0, 3, 2].map(|ch| self.scatter[ch]),
            scatter_left_out: [1, 0, 3, 2].map(|ch| self.scatter_left_out[ch]),
            scatter_var: self
                .scatter_var
                .as_ref()
                .map(|v| v.iter().map(swap).collect()),
            digits_var: self.digits_var.iter().map(swap).collect(),
            ..self.clone()
        }
    }
}

#[cfg(test)]
mod tests;
