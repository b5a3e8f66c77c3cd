//! Whether the data's pull on the speed column is spread over the run as
//! an offset's is, or comes from a few speeds only (a local model error
//! that the Δ column happens to correlate with).
//!
//! **Why.** An offset Δ of the speed column moves every speed's equations
//! by −Δ·∂e/∂f (through the bearing table read at the wrong speed, Ω²m and
//! iΩc): each speed pulls on Δ in proportion to its information, so speed
//! band by speed band the estimates Δ_k agree within their ±. A model error
//! local in speed does not: on the bundled demo (the box's 4-revolution
//! phasors in a 20 Hz/s run-down through pedestals damped at 0.18 %, whose
//! resonances are 0.1-0.2 Hz wide while one phasor spans 1-2 Hz of speed)
//! the phasors near the resonances are not the response at their speed,
//! and that error correlates with the Δ column there: Δ̂ = 0.64 ± 0.19 Hz,
//! a likelihood ratio of 11, all of it from the 44-58 Hz band, while a
//! refit with the column shifted by Δ̂ moves m by 6.7 of its ± away from
//! a truth it held within 1 ± (docs/trust-speed.md, Session 49
//! (kplag17b)). Such a pull is not an offset of the speed column, and
//! widening every ± for one is a false alarm.
//!
//! **The scatter's ±** ([`scatter_std`]): under an offset the speeds'
//! pulls scatter about I·Δ as the noise makes them; a local model error
//! scatters them more. Δ̂'s ± is the larger of the information's and the
//! scatter's (the sandwich), so a pull made of a few speeds far off the
//! others counts as what it is: on the demo the scatter's ± is 1.5-3
//! times the information's and Δ̂/σ_Δ falls from 3.3-4.7 to 1.3-2.2; on
//! clean ROSS runs it is 0.6-1.2 times it.
//!
//! **Speeds set aside** ([`set_aside`], said in the text, not in the
//! gate): the speed (all bearings at one
//! value of the speed column together) whose pull departs most from the
//! offset the other speeds give, z = (P − I·Δ̂)/√V (V the pull's variance
//! under the noise), is set aside while |z| is beyond the normal quantile
//! at [`LOCAL_P`]/(2·speeds) (1 % of clean runs over all their speeds),
//! at most [`MAX_SET_ASIDE`] of them, and Δ from the rest is said with
//! them. On the demo this is the 44.9 Hz phasor (z 5-7), which alone gave
//! 40-60 % of the pull; the speeds the fit itself left out as outliers are
//! left out before (`speed_lag::estimate`).
//!
//! **The test.** The speeds of every bearing Δ was estimated from, ordered
//! by speed, cut into [`BANDS`] bands of equal information; per band the
//! pull P_k and information I_k (the efficient score and information of
//! the joint step, [`super::linearise::joint`], each bearing's scaled by
//! its excess); Q = Σ_k (P_k − I_k·Δ̂)²/I_k, Δ̂ = ΣP/ΣI, is χ²(BANDS − 1)
//! when the pull is an offset's (or noise); the pull is called spread like
//! an offset's unless Q lies beyond the χ² quantile at [`SPREAD_P`].

use serde::{Deserialize, Serialize};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Speed bands the pull is compared over [-]: few enough that each holds
/// a quarter of Δ's information (its Δ_k to about 2σ_Δ), enough that a
/// resonance's few speeds fall in one band of the four.
pub const BANDS: usize = 4;

/// The pull is called local (not an offset's) where Q's upper-tail
/// probability under an offset is below this [-]: 1 %, the false-alarm
/// rate per run asked of every rule that marks a value (an offset of the
/// speed column passes it 99 % of the time).
pub const SPREAD_P: f64 = 0.01;

/// One speed of one bearing: its pull on Δ and its information (both
/// scaled by the bearing's excess s²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpeedShare {
    /// The speed column's value [Hz].
    pub speed_hz: f64,
    /// Minus the efficient score of Δ at Δ = 0 from this speed [per Hz].
    pub pull: f64,
    /// Δ's information from this speed, the noise's share taken off
    /// [per Hz²].
    pub info: f64,
    /// The variance of `pull` under the noise, the projected column's
    /// squared norm before the noise's share is taken off [per Hz²].
    pub var: f64,
}

/// The speeds whose pull departs from an offset's (module docs, "Speeds
/// set aside") and Δ from the others.
#[derive(Clone, Debug, PartialEq)]
pub struct Kept {
    /// The shares of the speeds kept.
    pub kept: Vec<SpeedShare>,
    /// The speeds set aside, ascending [Hz].
    pub local_speeds_hz: Vec<f64>,
    /// Δ from the speeds kept, ΣP/ΣI [Hz].
    pub offset_hz: f64,
    /// Its ±, (ΣI)^(−1/2) [Hz].
    pub offset_std_hz: f64,
}

/// One speed's pull beyond an offset's is called local beyond this
/// two-sided probability over the run's speeds together (Bonferroni: the
/// bound on |z| is the normal quantile at `LOCAL_P`/(2·speeds)) [-].
pub const LOCAL_P: f64 = 0.01;

/// At most this share of a run's speeds is set aside [-]: a pull that
/// needs more is not local.
pub const MAX_SET_ASIDE: f64 = 0.25;

/// Sets aside, one at a time, the speed (every bearing's share at that
/// speed column value together) whose pull departs most from the offset
/// the others give, z = (P − I·Δ̂)/√V, while |z| is beyond the
/// Bonferroni bound at [`LOCAL_P`] (at most [`MAX_SET_ASIDE`] of the
/// speeds); Δ from the rest. `None` where the information is not positive.
pub fn set_aside(shares: &[SpeedShare]) -> Option<Kept> {
    use statrs::distribution::Normal;
    let speeds = by_speed(shares);
    let n = speeds.len();
    let bound = Normal::new(0.0, 1.0)
        .ok()?
        .inverse_cdf(1.0 - LOCAL_P / (2.0 * n.max(1) as f64));
    let mut keep = vec![true; n];
    let mut local = Vec::new();
    let offset = |keep: &[bool]| {
        let (p, i) = speeds
            .iter()
            .zip(keep)
            .filter(|(_, k)| **k)
            .fold((0.0, 0.0), |a, (x, _)| (a.0 + x.pull, a.1 + x.info));
        (i > 0.0).then(|| (p / i, i))
    };
    while (local.len() as f64) < MAX_SET_ASIDE * n as f64 {
        let (d, _) = offset(&keep)?;
        let worst = speeds
            .iter()
            .enumerate()
            .filter(|(k, x)| keep[*k] && x.var > 0.0)
            .map(|(k, x)| (k, ((x.pull - x.info * d) / x.var.sqrt()).abs()))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        match worst {
            Some((k, z)) if z > bound => {
                keep[k] = false;
                local.push(speeds[k].speed_hz);
            }
            _ => break,
        }
    }
    let (offset_hz, info) = offset(&keep)?;
    local.sort_by(f64::total_cmp);
    Some(Kept {
        kept: shares
            .iter()
            .copied()
            .filter(|x| !local.contains(&x.speed_hz))
            .collect(),
        local_speeds_hz: local,
        offset_hz,
        offset_std_hz: info.sqrt().recip(),
    })
}

/// Δ̂'s ± from the data's own scatter (the sandwich): the speeds' pulls
/// about the offset's, √Σ(P − I·Δ̂)²/ΣI, every bearing's share at one
/// value of the speed column together [Hz]. Under an offset (or none) the
/// speeds scatter as the noise does and this is about (ΣI)^(−1/2); a
/// model error local in speed scatters them more (the demo: 1.5-3 times).
/// `None` where the information is not positive.
pub fn scatter_std(shares: &[SpeedShare], offset_hz: f64) -> Option<f64> {
    let speeds = by_speed(shares);
    let info: f64 = speeds.iter().map(|x| x.info).sum();
    let meat: f64 = speeds
        .iter()
        .map(|x| (x.pull - x.info * offset_hz).powi(2))
        .sum();
    (info > 0.0 && meat.is_finite()).then(|| meat.sqrt() / info)
}

/// `shares` ordered by speed, every bearing's share at one value of the
/// speed column summed into one.
fn by_speed(shares: &[SpeedShare]) -> Vec<SpeedShare> {
    let mut sorted: Vec<SpeedShare> = shares
        .iter()
        .copied()
        .filter(|x| x.speed_hz.is_finite() && x.pull.is_finite() && x.info.is_finite())
        .collect();
    sorted.sort_by(|a, b| a.speed_hz.total_cmp(&b.speed_hz));
    let mut speeds: Vec<SpeedShare> = Vec::new();
    for x in sorted {
        match speeds.last_mut() {
            Some(g) if g.speed_hz == x.speed_hz => {
                g.pull += x.pull;
                g.info += x.info;
                g.var += x.var;
            }
            _ => speeds.push(x),
        }
    }
    speeds
}

/// One band of speeds ([`spread`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Band {
    /// Its lowest speed [Hz].
    pub from_hz: f64,
    /// Its highest speed [Hz].
    pub to_hz: f64,
    /// Δ from this band alone, P_k/I_k [Hz].
    pub offset_hz: f64,
    /// Its ±, I_k^(−1/2) [Hz].
    pub offset_std_hz: f64,
}

/// The pull's spread over the run ([`spread`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// The bands, lowest speed first.
    pub bands: Vec<Band>,
    /// Q = Σ_k (P_k − I_k·Δ̂)²/I_k [-], χ²(bands − 1) under an offset.
    pub heterogeneity: f64,
    /// Q's upper-tail probability under an offset [-].
    pub p_value: f64,
}

impl Spread {
    /// Whether the pull is spread like an offset's (p ≥ [`SPREAD_P`]).
    pub fn like_an_offset(&self) -> bool {
        self.p_value >= SPREAD_P
    }

    /// The band that departs most from the pooled Δ̂ [-].
    pub fn most_local(&self, offset_hz: f64) -> Option<&Band> {
        self.bands.iter().max_by(|a, b| {
            let z = |x: &Band| ((x.offset_hz - offset_hz) / x.offset_std_hz).abs();
            z(a).total_cmp(&z(b))
        })
    }
}

/// The spread test over `shares` (module docs); `None` where there are
/// fewer speeds than bands or a band's information is not positive.
pub fn spread(shares: &[SpeedShare]) -> Option<Spread> {
    let mut s: Vec<SpeedShare> = shares
        .iter()
        .copied()
        .filter(|x| x.speed_hz.is_finite() && x.pull.is_finite() && x.info.is_finite())
        .collect();
    if s.len() < 2 * BANDS {
        return None;
    }
    s.sort_by(|a, b| a.speed_hz.total_cmp(&b.speed_hz));
    // Cut on the cumulative information (a speed's noise-corrected share
    // can come out below zero; cut on its positive part).
    let total: f64 = s.iter().map(|x| x.info.max(0.0)).sum();
    if total <= 0.0 {
        return None;
    }
    let mut sums = [(f64::INFINITY, f64::NEG_INFINITY, 0.0, 0.0); BANDS];
    let mut before = 0.0;
    for x in &s {
        let w = x.info.max(0.0);
        let k = ((BANDS as f64 * (before + 0.5 * w) / total) as usize).min(BANDS - 1);
        before += w;
        let b = &mut sums[k];
        b.0 = b.0.min(x.speed_hz);
        b.1 = b.1.max(x.speed_hz);
        b.2 += x.pull;
        b.3 += x.info;
    }
    if sums.iter().any(|b| b.3.is_nan() || b.3 <= 0.0) {
        return None;
    }
    let pull: f64 = sums.iter().map(|b| b.2).sum();
    let info: f64 = sums.iter().map(|b| b.3).sum();
    let pooled = pull / info;
    let heterogeneity: f64 = sums
        .iter()
        .map(|b| (b.2 - b.3 * pooled).powi(2) / b.3)
        .sum();
    let p_value = ChiSquared::new((BANDS - 1) as f64).ok()?.sf(heterogeneity);
    let bands = sums
        .iter()
        .map(|b| Band {
            from_hz: b.0,
            to_hz: b.1,
            offset_hz: b.2 / b.3,
            offset_std_hz: b.3.sqrt().recip(),
        })
        .collect();
    (heterogeneity.is_finite() && p_value.is_finite()).then_some(Spread {
        bands,
        heterogeneity,
        p_value,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shares(pull: impl Fn(f64) -> f64) -> Vec<SpeedShare> {
        (0..40)
            .map(|i| {
                let f = 20.0 + i as f64;
                SpeedShare {
                    speed_hz: f,
                    pull: pull(f),
                    info: 1.0,
                    var: 1.0,
                }
            })
            .collect()
    }

    /// An offset pulls every speed alike: Q = 0, spread; the same pull
    /// from five speeds only is local, and the band it lies in is named.
    #[test]
    fn an_offset_is_spread_a_local_pull_is_not() {
        let even = spread(&shares(|_| 0.5)).expect("spread");
        assert_eq!(even.bands.len(), BANDS);
        assert!(even.heterogeneity < 1e-12 && even.like_an_offset());
        assert!((even.bands[0].offset_hz - 0.5).abs() < 1e-12);
        assert!((even.bands[0].offset_std_hz - 0.1f64.sqrt()).abs() < 1e-12);
        assert_eq!((even.bands[0].from_hz, even.bands[0].to_hz), (20.0, 29.0));
        let local = spread(&shares(
            |f| if (45.0..50.0).contains(&f) { 4.0 } else { 0.0 },
        ))
        .expect("spread");
        assert!(!local.like_an_offset(), "{local:?}");
        let b = local.most_local(0.5).expect("a band");
        assert_eq!((b.from_hz, b.to_hz), (40.0, 49.0));
        assert!(spread(&shares(|_| 0.5)[..7]).is_none());
    }

    /// One speed pulling 8 of its ± beyond the others' offset is set
    /// aside (the bound over 40 speeds is 3.48), Δ from the rest; an
    /// offset's even pull sets nothing aside.
    #[test]
    fn a_speed_pulling_alone_is_set_aside() {
        let k = set_aside(&shares(|f| if f == 45.0 { 8.5 } else { 0.5 })).expect("kept");
        assert_eq!(k.local_speeds_hz, vec![45.0]);
        assert_eq!(k.kept.len(), 39);
        assert!((k.offset_hz - 0.5).abs() < 1e-12);
        assert!((k.offset_std_hz - 39f64.sqrt().recip()).abs() < 1e-12);
        let even = set_aside(&shares(|_| 0.5)).expect("kept");
        assert!(even.local_speeds_hz.is_empty() && (even.offset_hz - 0.5).abs() < 1e-12);
        // The scatter's ±: none about an even pull; the lone speed's
        // departure of 8 (info 1 each, ΣI = 40) gives √(7.8² + 39·0.2²)/40.
        assert!(scatter_std(&shares(|_| 0.5), 0.5).expect("σ") < 1e-12);
        let all = shares(|f| if f == 45.0 { 8.5 } else { 0.5 });
        let want = (7.8f64.powi(2) + 39.0 * 0.2f64.powi(2)).sqrt() / 40.0;
        assert!((scatter_std(&all, 0.7).expect("σ") - want).abs() < 1e-12);
    }
}
