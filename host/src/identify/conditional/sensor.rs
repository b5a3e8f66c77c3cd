//! What the values are conditional on, channel by channel: each channel's
//! sensitivity (a probe's mV/µm, a pick-up's mV/(m/s²)) is taken as given,
//! and a relative error ε in one channel's moves each value along its path
//! b (the shift of the fitted θ per unit ε of that channel alone,
//! [`crate::identify::sensor_gain`]); the run sees only the y/z ratios
//! where the mass or the table's cross terms tie the directions, and never
//! a gain common to a kind of channel.
//!
//! Carrying a stated calibration uncertainty (`--sensor-uncertainty PCT`):
//! each channel's relative sensitivity error ε_c independent, mean 0,
//! standard deviation σ_c (σ_rel for the two probes, σ_ped for the two
//! pick-ups), independent of the noise; to first order the fit is
//! θ̂ + Σ_c b_c·ε_c, so its covariance is Σ + Σ_c σ_c²·b_c·b_cᵀ (the
//! sandwich of the sensitivities), each variance gaining Σ_c (σ_c·b_c,i)².
//! A gain common to the two probes (b_rel_y + b_rel_z ≈ −θ, a scale) is
//! inside this sum: the table's scale and the transducers' add alike.

use super::Conditional;
use crate::identify::sensor_gain::{GainEvidence, CHANNELS};
use crate::identify::{Identification, PedestalFit};
use plinth_shared::regression::{Parameter, PARAMETERS};
use serde::Serialize;
use std::collections::BTreeMap;

/// Largest `--sensor-uncertainty` [%]: a sensitivity known to 100 % or
/// worse is no sensitivity.
pub const MAX_SENSOR_UNCERTAINTY_PCT: f64 = 100.0;

/// `--sensor-uncertainty`: the relative standard uncertainty of each
/// channel's sensitivity, independent between channels [-].
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SensorUncertainty {
    /// Of each `rel` probe [-].
    pub rel: f64,
    /// Of each `ped` pick-up [-].
    pub ped: f64,
}

impl SensorUncertainty {
    /// Of channel `c` ([`CHANNELS`]) [-].
    pub fn of(&self, c: usize) -> f64 {
        if c < 2 {
            self.rel
        } else {
            self.ped
        }
    }
}

/// One percentage of `--sensor-uncertainty` (text `text`, the whole value
/// `whole` for the message) [%] → [-].
fn percent(text: &str, whole: &str) -> Result<f64, String> {
    let v: f64 = text.trim().parse().map_err(|_| {
        format!("`{whole}`: `{text}` is not a number (a percentage, e.g. 5 or rel=2,ped=5)")
    })?;
    if !(v.is_finite() && v > 0.0 && v < MAX_SENSOR_UNCERTAINTY_PCT) {
        return Err(format!(
            "`{whole}`: {v} %: each sensitivity's relative standard uncertainty must be greater than 0 and below {MAX_SENSOR_UNCERTAINTY_PCT} %"
        ));
    }
    Ok(v / 100.0)
}

/// `--sensor-uncertainty PCT` (every channel) or `rel=PCT,ped=PCT` (either
/// or both; a kind not named is taken as exact, 0).
pub fn parse_sensor_uncertainty(text: &str) -> Result<SensorUncertainty, String> {
    if !text.contains('=') {
        let v = percent(text, text)?;
        return Ok(SensorUncertainty { rel: v, ped: v });
    }
    let mut out = SensorUncertainty { rel: 0.0, ped: 0.0 };
    let mut seen = Vec::new();
    for part in text.split(',') {
        let Some((key, value)) = part.split_once('=') else {
            return Err(format!(
                "`{text}`: `{part}` is not KIND=PCT (rel=PCT, ped=PCT or one PCT for every channel)"
            ));
        };
        let key = key.trim();
        if seen.contains(&key) {
            return Err(format!("`{text}`: `{key}` given twice"));
        }
        let v = percent(value, text)?;
        match key {
            "rel" => out.rel = v,
            "ped" => out.ped = v,
            _ => {
                return Err(format!(
                    "`{text}`: unknown kind `{key}` (rel for the probes, ped for the pick-ups)"
                ))
            }
        }
        seen.push(key);
    }
    Ok(out)
}

/// How far a 1 % error in one channel's sensitivity moves one value.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ChannelSensitivity {
    /// `rel_y`, `rel_z`, `ped_y` or `ped_z`.
    pub channel: String,
    /// Per value (k_y, k_z, m, c_y, c_z): the relative move per 1 % of
    /// that channel's sensitivity, b·0.01/θ [%] (`null` for a fixed value).
    pub percent_per_percent: BTreeMap<String, Option<f64>>,
    /// The same in the value's noise-only ±, b·0.01/σ [-].
    pub std_errs_per_percent: BTreeMap<String, Option<f64>>,
}

/// One bearing's values against each channel's sensitivity
/// (`conditional_on.sensor_sensitivity[]`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BearingSensitivity {
    /// Bearing name.
    pub bearing: String,
    /// Each channel.
    pub channels: Vec<ChannelSensitivity>,
    /// The channel and value moved most (in ±) by a 1 % error.
    pub largest_channel: String,
    /// That value's name.
    pub largest_value: String,
    /// Its relative move per 1 % [%].
    pub largest_percent: f64,
    /// Its move in its noise-only ± per 1 % [-].
    pub largest_std_errs: f64,
}

impl BearingSensitivity {
    /// One sentence for people.
    pub fn message(&self) -> String {
        format!(
            "a 1 % error in {b} {}'s sensitivity moves {} by about {:+.2} % ({:+.1} ±), the most of its four channels; a gain common to its two probes (or its two pick-ups) scales k, c, m alike unseen, a y/z ratio is tested by the data (untrusted where significant)",
            self.largest_channel,
            self.largest_value,
            self.largest_percent,
            self.largest_std_errs,
            b = self.bearing
        )
    }
}

fn fixed(p: &PedestalFit, c: Parameter) -> bool {
    p.fixed.iter().any(|f| f == c.name())
}

/// Each judged bearing's sensitivities ([`BearingSensitivity`]) from its
/// evidence `e` and fit `p` (the ± as they are: call before any widening).
fn bearing(e: &GainEvidence, p: &PedestalFit) -> Option<BearingSensitivity> {
    let theta = p.pedestal.theta();
    let se = p.std_err.theta();
    let mut largest: Option<(usize, usize, f64, f64)> = None;
    let channels = CHANNELS
        .iter()
        .enumerate()
        .map(|(c, name)| {
            let mut pct = BTreeMap::new();
            let mut pm = BTreeMap::new();
            for q in Parameter::ALL {
                let i = q as usize;
                let (r, s) = if fixed(p, q) {
                    (None, None)
                } else {
                    let mv = 0.01 * e.path[c][i];
                    let r = 100.0 * mv / theta[i];
                    let s = mv / se[i];
                    let keep = |v: f64| v.is_finite().then_some(v);
                    (keep(r), keep(s))
                };
                if let (Some(r), Some(s)) = (r, s) {
                    if largest.is_none_or(|l| s.abs() > l.3.abs()) {
                        largest = Some((c, i, r, s));
                    }
                }
                pct.insert(q.name().to_string(), r);
                pm.insert(q.name().to_string(), s);
            }
            ChannelSensitivity {
                channel: name.to_string(),
                percent_per_percent: pct,
                std_errs_per_percent: pm,
            }
        })
        .collect();
    let (c, i, r, s) = largest?;
    Some(BearingSensitivity {
        bearing: p.bearing.clone(),
        channels,
        largest_channel: CHANNELS[c].to_string(),
        largest_value: Parameter::ALL[i].name().to_string(),
        largest_percent: r,
        largest_std_errs: s,
    })
}

/// Every judged bearing's sensitivities, from `identification` as fitted
/// (call before any widening: the ± are the noise's).
pub fn of(identification: &Identification) -> Vec<BearingSensitivity> {
    identification
        .sensor_gain
        .iter()
        .filter_map(|e| bearing(e, identification.pedestal(&e.bearing)?))
        .collect()
}

/// Folds `u` into the ± and covariance of every judged pedestal
/// (module docs): Σ' = Σ + Σ_c σ_c²·b_c·b_cᵀ. A fixed value (σ = 0) stays
/// 0; a ± that is not finite stays as it is. Pedestals on a base are not
/// judged and keep their ± (said in the text).
pub fn widen(identification: &mut Identification, u: SensorUncertainty) {
    let evidence = identification.sensor_gain.clone();
    for e in &evidence {
        let Some(p) = identification
            .pedestals
            .iter_mut()
            .find(|p| p.bearing == e.bearing)
        else {
            continue;
        };
        let mut add = [[0.0; PARAMETERS]; PARAMETERS];
        for (c, b) in e.path.iter().enumerate() {
            let s2 = u.of(c).powi(2);
            for i in 0..PARAMETERS {
                for j in 0..PARAMETERS {
                    add[i][j] += s2 * b[i] * b[j];
                }
            }
        }
        p.add_covariance(&add);
    }
}

impl Conditional {
    /// The statement with the channels' sensitivities (`sensors`, made by
    /// [`of`] before any widening) and the calibration uncertainty `u`
    /// folded into the ± (`--sensor-uncertainty`, [`widen`]) when given.
    pub fn with_sensors(
        mut self,
        sensors: Vec<BearingSensitivity>,
        u: Option<SensorUncertainty>,
    ) -> Self {
        let doubt = match u {
            Some(u) => format!(
                " The ± include each channel's sensitivity uncertainty (--sensor-uncertainty: {:.3} % per probe, {:.3} % per pick-up, independent): σ² = σ_noise² + Σ_c (σ_c·b_c)², b_c the value's shift per unit error of channel c (pedestals on a base excepted).",
                100.0 * u.rel,
                100.0 * u.ped
            ),
            None => " Each channel's sensitivity is taken as exact too: a 1 % error in one channel moves its direction's values by up to about 1 % (the lines below, per bearing, say which and how far, in ±); give the calibration's uncertainty with --sensor-uncertainty PCT (or rel=PCT,ped=PCT) to carry it into the ±.".to_string(),
        };
        self.statement.push_str(&doubt);
        self.sensor_uncertainty = u;
        self.sensor_sensitivity = sensors;
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_option_is_read_and_checked() {
        assert_eq!(
            parse_sensor_uncertainty("5"),
            Ok(SensorUncertainty {
                rel: 0.05,
                ped: 0.05
            })
        );
        assert_eq!(
            parse_sensor_uncertainty("rel=2,ped=5"),
            Ok(SensorUncertainty {
                rel: 0.02,
                ped: 0.05
            })
        );
        assert_eq!(
            parse_sensor_uncertainty("ped=3"),
            Ok(SensorUncertainty {
                rel: 0.0,
                ped: 0.03
            })
        );
        for bad in [
            "0",
            "100",
            "x",
            "-1",
            "rel=2,rel=3",
            "probe=2",
            "rel2",
            "rel=nan",
        ] {
            let e = parse_sensor_uncertainty(bad).expect_err(bad);
            assert!(e.contains(bad), "{bad}: {e}");
        }
    }
}
