//! Where the disagreement lives: which bearing, which direction, which speed
//! band, and how it relates to the identified pedestal resonance.

use super::data::Prepared;
use super::gap::Prediction;
use super::model::{Model, Params, Term, DIR_NAMES};
use serde::Serialize;

/// Number of equal-width speed bands the range is split into.
pub const BANDS: usize = 5;

/// The disagreement of one pedestal channel in one speed band.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Band {
    /// Lower band edge [Hz].
    pub from_hz: f64,
    /// Upper band edge [Hz].
    pub to_hz: f64,
    /// Relative RMS disagreement within the band (the gap's definition) [-].
    pub gap: f64,
    /// Share of the channel's squared disagreement in the band [-].
    pub share: f64,
    /// The relative RMS disagreement the noise alone would give in the band
    /// (the model's noise variances over the band's squared readings) [-].
    pub floor: f64,
    /// The band's squared disagreement beyond its noise (squared
    /// disagreement less the noise variances, zero where below), as a share
    /// of the channel's total excess [-].
    pub excess_share: f64,
}

/// The disagreement of one pedestal channel (bearing, direction).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Location {
    /// Bearing name.
    pub bearing: String,
    /// Direction: `y` (vertical) or `z` (horizontal).
    pub direction: String,
    /// Share of the whole machine's squared disagreement [-].
    pub share: f64,
    /// Relative RMS disagreement of this channel [-].
    pub gap: f64,
    /// The gap noise alone would give on this channel [-].
    pub floor: f64,
    /// Speed of the largest disagreement |X_pred − X_meas| [Hz].
    pub peak_hz: f64,
    /// Identified pedestal natural frequency √(k/m)/2π in this direction [Hz].
    pub resonance_hz: Option<f64>,
    /// Rank correlation of the relative disagreement with speed [-1, 1]:
    /// positive = growing with speed.
    pub trend: f64,
    /// The speed bands, low to high.
    pub bands: Vec<Band>,
    /// One-line description for the report.
    pub summary: String,
}

/// Locates the disagreement of `pred` (the prediction of `model` at `params`),
/// largest share first.
pub fn locate(prep: &Prepared, model: &Model, params: &Params, pred: &Prediction) -> Vec<Location> {
    let f_lo = prep.speeds_hz.first().copied().unwrap_or(0.0);
    let f_hi = prep.speeds_hz.last().copied().unwrap_or(0.0);
    let width = ((f_hi - f_lo) / BANDS as f64).max(f64::MIN_POSITIVE);
    let mut total = 0.0;
    let mut out = Vec::new();
    for (b, name) in prep.bearings.iter().enumerate() {
        for d in 0..2 {
            let mut num = [0.0; BANDS];
            let mut den = [0.0; BANDS];
            let mut var = [0.0; BANDS];
            let (mut n_all, mut d_all, mut v_all) = (0.0, 0.0, 0.0);
            let mut peak = (0.0, f_lo);
            let mut rel: Vec<(f64, f64)> = Vec::new();
            for (j, p) in prep.points[b].iter().enumerate() {
                let Some(p) = p else { continue };
                let diff = match pred.ped[b][j] {
                    Some(x) => (x[d] - p.ped[d]).norm_sqr(),
                    None => p.ped[d].norm_sqr(),
                };
                let band = (((p.speed_hz - f_lo) / width) as usize).min(BANDS - 1);
                num[band] += diff;
                den[band] += p.ped[d].norm_sqr();
                n_all += diff;
                d_all += p.ped[d].norm_sqr();
                let v = pred.noise_var[b][j].map_or(0.0, |v| v[d]);
                var[band] += v;
                v_all += v;
                if diff > peak.0 {
                    peak = (diff, p.speed_hz);
                }
                if p.ped[d].norm() > 0.0 {
                    rel.push((p.speed_hz, diff.sqrt() / p.ped[d].norm()));
                }
            }
            total += n_all;
            let excess: [f64; BANDS] = std::array::from_fn(|i| (num[i] - var[i]).max(0.0));
            let excess_all: f64 = excess.iter().sum();
            let relative = |x: f64, i: usize| {
                if den[i] > 0.0 {
                    (x / den[i]).sqrt()
                } else {
                    0.0
                }
            };
            let bands = (0..BANDS)
                .map(|i| Band {
                    from_hz: f_lo + width * i as f64,
                    to_hz: f_lo + width * (i + 1) as f64,
                    gap: relative(num[i], i),
                    share: if n_all > 0.0 { num[i] / n_all } else { 0.0 },
                    floor: relative(var[i], i),
                    excess_share: if excess_all > 0.0 {
                        excess[i] / excess_all
                    } else {
                        0.0
                    },
                })
                .collect();
            out.push(Location {
                bearing: name.clone(),
                direction: DIR_NAMES[d].to_string(),
                share: n_all,
                gap: if d_all > 0.0 {
                    (n_all / d_all).sqrt()
                } else {
                    0.0
                },
                floor: if d_all > 0.0 {
                    (v_all / d_all).sqrt()
                } else {
                    0.0
                },
                peak_hz: peak.1,
                resonance_hz: resonance(model, params, b, d),
                trend: spearman(&rel),
                bands,
                summary: String::new(),
            });
        }
    }
    for l in &mut out {
        l.share = if total > 0.0 { l.share / total } else { 0.0 };
        l.summary = describe(l, width);
    }
    out.sort_by(|a, b| b.share.total_cmp(&a.share));
    out
}

/// √(k/m)/2π of bearing `b` in direction `d` from the model's terms [Hz].
fn resonance(model: &Model, params: &Params, b: usize, d: usize) -> Option<f64> {
    let mut k = None;
    let mut m = None;
    for (t, v) in model.terms.iter().zip(&params.beta) {
        match *t {
            Term::Stiffness { bearing, dir } if bearing == b && dir == d => k = Some(*v),
            Term::Mass { bearing, dir } if bearing == b && (dir.is_none() || dir == Some(d)) => {
                m = Some(*v)
            }
            _ => {}
        }
    }
    let (k, m) = (k?, m?);
    (k > 0.0 && m > 0.0).then(|| (k / m).sqrt() / std::f64::consts::TAU)
}

/// Spearman rank correlation of the pairs (x, y).
fn spearman(xy: &[(f64, f64)]) -> f64 {
    let n = xy.len();
    if n < 3 {
        return 0.0;
    }
    let rank = |key: &dyn Fn(&(f64, f64)) -> f64| -> Vec<f64> {
        let mut idx: Vec<usize> = (0..n).collect();
        idx.sort_by(|&a, &b| key(&xy[a]).total_cmp(&key(&xy[b])));
        let mut r = vec![0.0; n];
        for (pos, &i) in idx.iter().enumerate() {
            r[i] = pos as f64;
        }
        r
    };
    let rx = rank(&|p| p.0);
    let ry = rank(&|p| p.1);
    let mean = (n as f64 - 1.0) / 2.0;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let (a, b) = (rx[i] - mean, ry[i] - mean);
        sxy += a * b;
        sxx += a * a;
        syy += b * b;
    }
    if sxx * syy > 0.0 {
        sxy / (sxx * syy).sqrt()
    } else {
        0.0
    }
}

fn describe(l: &Location, band_width: f64) -> String {
    let mut s = format!(
        "{} {}: {:.0}% of the disagreement, gap {:.3} (noise floor {:.3}), largest at {:.1} Hz",
        l.bearing,
        l.direction,
        100.0 * l.share,
        l.gap,
        l.floor,
        l.peak_hz
    );
    if let Some(f) = l.resonance_hz {
        if (l.peak_hz - f).abs() <= 0.5 * band_width {
            s += &format!(", around the pedestal resonance ({f:.1} Hz)");
        }
    }
    if let Some((i, _)) = l
        .bands
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.share.total_cmp(&b.1.share))
    {
        if i == 0 {
            s += ", mostly at low speed";
        } else if i == l.bands.len() - 1 {
            s += ", mostly at high speed";
        }
    }
    if l.trend > 0.5 {
        s += ", relative disagreement growing with speed";
    } else if l.trend < -0.5 {
        s += ", relative disagreement falling with speed";
    }
    s
}

/// Why a pedestal channel is in the "unexplained" report.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum UnexplainedBecause {
    /// Its own gap is more than [`crate::diagnose::trust::AT_THE_FLOOR`]
    /// times its noise floor.
    AboveFloor,
    /// Its bearing is untrusted for a model error there (a trust reason
    /// `bearing NAME: ...`: the support-mode or lack-of-fit test of the base
    /// model where no effect acts, a sub-base above the range, dampings held
    /// at zero against the data), whatever its gap against the floor.
    ModelErrorAtBearing,
}

/// Where an unexplained disagreement lies: one pedestal channel whose own
/// gap is more than a factor times its noise floor, or one at a bearing
/// the verdict untrusts for a model error, with the speed bands that hold
/// most of its disagreement beyond the noise.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Unexplained {
    /// Bearing name.
    pub bearing: String,
    /// Direction: `y` or `z`.
    pub direction: String,
    /// Share of the whole machine's squared disagreement [-].
    pub share: f64,
    /// The channel's gap over its noise floor [-].
    pub times_floor: f64,
    /// The speed bands [from, to] [Hz] that together hold at least 70 % of
    /// the channel's squared disagreement beyond its noise
    /// ([`Band::excess_share`]), largest first; empty when no band's
    /// disagreement exceeds its noise.
    pub bands_hz: Vec<[f64; 2]>,
    /// Why the channel is listed.
    pub because: UnexplainedBecause,
}

/// The channels of `locations` that hold a disagreement above `factor`
/// times their noise floor, then the other channels of the bearings in
/// `untrusted_bearings` (untrusted for a model error there), largest share
/// first within each kind (module docs of [`Unexplained`]).
pub fn unexplained(
    locations: &[Location],
    factor: f64,
    untrusted_bearings: &[String],
) -> Vec<Unexplained> {
    let entry = |l: &Location, because| {
        let mut bands: Vec<&Band> = l.bands.iter().filter(|b| b.excess_share > 0.0).collect();
        bands.sort_by(|a, b| b.excess_share.total_cmp(&a.excess_share));
        let mut held = 0.0;
        let mut bands_hz = Vec::new();
        for b in bands {
            if held >= 0.7 {
                break;
            }
            held += b.excess_share;
            bands_hz.push([b.from_hz, b.to_hz]);
        }
        Unexplained {
            bearing: l.bearing.clone(),
            direction: l.direction.clone(),
            share: l.share,
            times_floor: if l.floor > 0.0 {
                l.gap / l.floor
            } else {
                f64::INFINITY
            },
            bands_hz,
            because,
        }
    };
    let above = |l: &&Location| l.gap > factor * l.floor;
    let mut out: Vec<Unexplained> = locations
        .iter()
        .filter(above)
        .map(|l| entry(l, UnexplainedBecause::AboveFloor))
        .collect();
    out.sort_by(|a, b| b.share.total_cmp(&a.share));
    let mut at: Vec<Unexplained> = locations
        .iter()
        .filter(|l| !above(l) && untrusted_bearings.contains(&l.bearing))
        .map(|l| entry(l, UnexplainedBecause::ModelErrorAtBearing))
        .collect();
    at.sort_by(|a, b| b.share.total_cmp(&a.share));
    out.extend(at);
    out
}

/// The bearings `reasons` (a verdict's trust reasons) untrust for a model
/// error there: those with a reason `bearing NAME: ...`, the form every
/// bearing-level model-error reason of [`crate::diagnose::trust`] takes
/// (support-mode and lack-of-fit tests where no effect acts, a sub-base
/// above the range, dampings held at zero against the data). A physically
/// impossible pedestal (`pedestal NAME: ...`) is not one.
pub fn untrusted_bearings(bearings: &[String], reasons: &[String]) -> Vec<String> {
    bearings
        .iter()
        .filter(|name| {
            let prefix = format!("bearing {name}: ");
            reasons.iter().any(|r| r.starts_with(&prefix))
        })
        .cloned()
        .collect()
}

impl Unexplained {
    /// One line: `B3 z: 62 % of the disagreement, 14× its floor, at 45-60 Hz, 90-105 Hz`
    /// (a channel listed for its bearing's model error says so; one with no
    /// band above its noise says that).
    pub fn summary(&self) -> String {
        let bands: Vec<String> = self
            .bands_hz
            .iter()
            .map(|[a, b]| format!("{a:.0}-{b:.0} Hz"))
            .collect();
        let at = if bands.is_empty() {
            "within its noise in every speed band".to_string()
        } else {
            format!("beyond its noise at {}", bands.join(", "))
        };
        let why = match self.because {
            UnexplainedBecause::AboveFloor => "",
            UnexplainedBecause::ModelErrorAtBearing => {
                " (its bearing is untrusted for a model error there)"
            }
        };
        format!(
            "{} {}: {:.0} % of the disagreement, {:.1}× its noise floor, {at}{why}",
            self.bearing,
            self.direction,
            100.0 * self.share,
            self.times_floor,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn location(bearing: &str, gap: f64, floor: f64, share: f64, bands: [f64; BANDS]) -> Location {
        Location {
            bearing: bearing.into(),
            direction: "y".into(),
            share,
            gap,
            floor,
            peak_hz: 0.0,
            resonance_hz: None,
            trend: 0.0,
            bands: bands
                .iter()
                .enumerate()
                .map(|(i, s)| Band {
                    from_hz: 10.0 * i as f64,
                    to_hz: 10.0 * (i + 1) as f64,
                    gap: 0.0,
                    share: *s,
                    floor: 0.0,
                    excess_share: *s,
                })
                .collect(),
            summary: String::new(),
        }
    }

    #[test]
    fn names_the_channels_and_bands_above_the_floor() {
        let locs = [
            location("A", 0.01, 0.01, 0.1, [0.2; BANDS]),
            location("B", 0.5, 0.01, 0.9, [0.05, 0.6, 0.25, 0.05, 0.05]),
        ];
        let u = unexplained(&locs, 3.0, &[]);
        assert_eq!(u.len(), 1);
        assert_eq!(u[0].bearing, "B");
        assert_eq!(u[0].bands_hz, vec![[10.0, 20.0], [20.0, 30.0]]);
        assert_eq!(u[0].because, UnexplainedBecause::AboveFloor);
        assert!(u[0].summary().contains("B y: 90 %"), "{}", u[0].summary());
    }

    #[test]
    fn names_the_channels_of_a_bearing_untrusted_for_a_model_error() {
        let mut quiet = location("C", 0.01, 0.01, 0.05, [0.2; BANDS]);
        for b in &mut quiet.bands {
            b.excess_share = 0.0;
        }
        let locs = [
            location("A", 0.012, 0.01, 0.3, [0.0, 0.0, 0.1, 0.2, 0.7]),
            location("B", 0.5, 0.01, 0.65, [0.05, 0.6, 0.25, 0.05, 0.05]),
            quiet,
        ];
        let reasons = [
            "bearing A: its base model's fit fails the rule".to_string(),
            "pedestal C: negative mass".to_string(),
        ];
        let names = ["A".to_string(), "B".to_string(), "C".to_string()];
        let flagged = untrusted_bearings(&names, &reasons);
        assert_eq!(flagged, ["A"]);
        let u = unexplained(&locs, 3.0, &flagged);
        assert_eq!(u.len(), 2);
        assert_eq!(
            (u[0].bearing.as_str(), u[0].because),
            ("B", UnexplainedBecause::AboveFloor)
        );
        assert_eq!(u[1].bearing, "A");
        assert_eq!(u[1].because, UnexplainedBecause::ModelErrorAtBearing);
        assert_eq!(u[1].bands_hz, vec![[40.0, 50.0]]);
        assert!(
            u[1].summary().contains("untrusted for a model error"),
            "{}",
            u[1].summary()
        );
        // A bearing listed for its model error with no band above its noise
        // says so.
        let v = unexplained(&locs[2..], 3.0, &["C".to_string()]);
        assert!(v[0].bands_hz.is_empty());
        assert!(
            v[0].summary()
                .contains("within its noise in every speed band"),
            "{}",
            v[0].summary()
        );
    }
}
