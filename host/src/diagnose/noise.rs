//! The measurement noise the data can support: how finely the numbers were
//! written (quantisation) and how much they scatter between neighbouring speeds.
//!
//! Quantisation: every number of `measurements.csv` carries an error of up to
//! a unit in its last written digit (ulp), with ulp set by *that number's own
//! magnitude*: a value written with D significant digits and decimal exponent
//! e has ulp = 10^(e−D+1). A rounding error is uniform on ±ulp/2 (standard
//! deviation ulp/√12); a truncation error (what the paper did) is uniform on
//! [0, ulp) toward zero, a bias of ulp/2 plus the same scatter, RMS ulp/√3.
//! The written digits cannot tell the two apart, so each number's σ is the
//! RMS error of truncation, ulp/√3, which bounds both: on truncated data the
//! rounding value would let the bias pass for an effect. Quantised data are
//! not white noise either (neighbouring speeds round alike), which the
//! selection criterion allows for separately (autocorrelation-robust
//! covariance, `criterion`).
//!
//! The number of digits D of a column is detected from the values themselves:
//! the fewest significant digits that reproduce a value exactly when printed
//! and parsed again, maximised over the column (a value whose trailing digits
//! are zeros needs fewer). A column written with a fixed number of decimals
//! instead has an absolute ulp 10^E (E the lowest last-digit exponent of the
//! column); each value's ulp is the larger of the two readings, which is right
//! for both layouts.
//!
//! Scatter: noise beyond rounding (a noisy instrument) shows as scatter between
//! neighbouring speeds that a smooth response does not have. Per bearing and
//! complex channel, the third divided difference over four neighbouring speeds
//! annihilates any quadratic trend; normalised to unit noise gain it is a
//! sample of the local noise. Two noise laws are considered: a constant σ per
//! channel (an instrument's noise floor) and σ proportional to the local
//! magnitude. Each is estimated robustly (the median, so a few points at a
//! sharp resonance do not count) and the law under which the standardised
//! samples are the more homogeneous (smaller variance of log|u|) is kept.
//! Each number's σ is the larger of its quantisation σ and its scatter σ.

use crate::rundir::RunDir;
use anyhow::Result;
use serde::Serialize;

/// The real channels of a measurement row, in the order used everywhere in
/// the workflow (formats.md column names without the `_re`/`_im` pairing).
pub const CHANNELS: [&str; 8] = [
    "rel_y_re", "rel_y_im", "rel_z_re", "rel_z_im", "ped_y_re", "ped_y_im", "ped_z_re", "ped_z_im",
];

/// Complex channels per bearing: rel y, rel z, ped y, ped z.
pub const COMPLEX_CHANNELS: [&str; 4] = ["rel_y", "rel_z", "ped_y", "ped_z"];

/// Fewest significant digits (1..=17) that reproduce `v` exactly when printed
/// in scientific notation and parsed back, with the decimal exponent of that
/// printing; `None` for zero and non-finite values.
pub fn significant_digits(v: f64) -> Option<(u32, i32)> {
    if v == 0.0 || !v.is_finite() {
        return None;
    }
    for d in 1..=17u32 {
        let s = format!("{:.*e}", (d - 1) as usize, v);
        if s.parse::<f64>() == Ok(v) {
            return Some((d, exponent_of(&s)));
        }
    }
    Some((17, exponent_of(&format!("{v:e}"))))
}

/// Decimal exponent of a number printed by Rust's `{:e}`.
fn exponent_of(s: &str) -> i32 {
    s.rsplit('e')
        .next()
        .and_then(|e| e.parse().ok())
        .unwrap_or(0)
}

/// Quantisation of one column of `measurements.csv`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ColumnQuantisation {
    /// Significant digits the column is written with (max over its values).
    pub digits: u32,
    /// Lowest decimal exponent of a last written digit in the column.
    pub lowest_digit_exponent: i32,
}

impl ColumnQuantisation {
    /// Unit in the last digit [m] of a value written in this column.
    pub fn ulp(&self, v: f64) -> f64 {
        let absolute = 10f64.powi(self.lowest_digit_exponent);
        if v == 0.0 || !v.is_finite() {
            return absolute;
        }
        let s = format!("{:.*e}", (self.digits.max(1) - 1) as usize, v);
        let e = exponent_of(&s);
        10f64.powi(e - self.digits as i32 + 1).max(absolute)
    }
}

/// The noise model of a run: quantisation per column and relative scatter per
/// bearing and complex channel.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NoiseModel {
    /// Quantisation of each real column, in the order of [`CHANNELS`].
    pub columns: Vec<ColumnQuantisation>,
    /// Scatter law per bearing and complex channel ([`COMPLEX_CHANNELS`]
    /// order); `None` with fewer than 4 speeds.
    pub scatter: Vec<[Option<Scatter>; 4]>,
}

impl NoiseModel {
    /// Estimates the noise of a run; `bearings` gives the bearing order.
    pub fn estimate(run: &RunDir, bearings: &[String]) -> Result<Self> {
        let mut columns = Vec::with_capacity(CHANNELS.len());
        for c in 0..CHANNELS.len() {
            let mut digits = 1;
            let mut lowest = i32::MAX;
            for m in &run.measurements {
                if let Some((d, e)) = significant_digits(value(m, c)) {
                    digits = digits.max(d);
                    lowest = lowest.min(e - d as i32 + 1);
                }
            }
            if lowest == i32::MAX {
                // An all-zero column: no information about its digits; zero
                // values are taken to be exact.
                lowest = -330;
            }
            columns.push(ColumnQuantisation {
                digits,
                lowest_digit_exponent: lowest,
            });
        }
        let mut scatter = Vec::with_capacity(bearings.len());
        for name in bearings {
            let mut rows: Vec<_> = run
                .measurements
                .iter()
                .filter(|m| &m.bearing == name)
                .collect();
            rows.sort_by(|a, b| a.speed_hz.total_cmp(&b.speed_hz));
            let mut per_channel = [None; 4];
            for (ch, slot) in per_channel.iter_mut().enumerate() {
                let series: Vec<(f64, num_complex::Complex<f64>)> = rows
                    .iter()
                    .map(|m| {
                        let z = if ch < 2 { m.rel[ch] } else { m.ped[ch - 2] };
                        (m.speed_hz, z)
                    })
                    .collect();
                *slot = self::scatter(&series);
            }
            scatter.push(per_channel);
        }
        Ok(Self { columns, scatter })
    }

    /// Noise standard deviation [m] of real channel `c` of bearing `b` whose
    /// value is `v` [m] and whose complex phasor has magnitude `magnitude` [m].
    pub fn sigma(&self, b: usize, c: usize, v: f64, magnitude: f64) -> f64 {
        let quantisation = self.columns[c].ulp(v) / 3f64.sqrt();
        let scatter = match self.scatter.get(b).and_then(|s| s[c / 2]) {
            Some(Scatter::Absolute(sigma)) => sigma,
            Some(Scatter::Relative(s)) => s * magnitude,
            None => 0.0,
        };
        quantisation.max(scatter)
    }

    /// Fewest digits any column is written with (the coarsest column).
    pub fn digits(&self) -> u32 {
        self.columns.iter().map(|c| c.digits).min().unwrap_or(0)
    }
}

fn value(m: &crate::rundir::Measurement, c: usize) -> f64 {
    let z = if c < 4 {
        m.rel[c / 2]
    } else {
        m.ped[(c - 4) / 2]
    };
    if c % 2 == 0 {
        z.re
    } else {
        z.im
    }
}

/// The noise law of one complex channel, per real component.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Scatter {
    /// Constant σ [m] at every speed.
    Absolute(f64),
    /// σ = value·|phasor| (a fraction of the local magnitude) [-].
    Relative(f64),
}

const MEDIAN_ABS_NORMAL: f64 = 0.674_489_750_196_081_7;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn log_spread(u: &[f64]) -> f64 {
    let logs: Vec<f64> = u.iter().filter(|x| **x > 0.0).map(|x| x.ln()).collect();
    if logs.len() < 2 {
        return f64::INFINITY;
    }
    let mean = logs.iter().sum::<f64>() / logs.len() as f64;
    logs.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / (logs.len() - 1) as f64
}

/// Robust noise law (module docs) of a complex series sampled at increasing
/// speeds [Hz], from third divided differences over four neighbouring speeds
/// (which cancel any quadratic trend). `None` with fewer than four points.
pub fn scatter(series: &[(f64, num_complex::Complex<f64>)]) -> Option<Scatter> {
    // (|component of the unit-gain difference|, local magnitude)
    let mut samples: Vec<(f64, f64)> = Vec::new();
    for w in series.windows(4) {
        let xs = [w[0].0, w[1].0, w[2].0, w[3].0];
        let mut weights = [0.0; 4];
        for i in 0..4 {
            let mut p = 1.0;
            for k in 0..4 {
                if k != i {
                    p *= xs[i] - xs[k];
                }
            }
            if p == 0.0 {
                return None;
            }
            weights[i] = 1.0 / p;
        }
        let gain = weights.iter().map(|w| w * w).sum::<f64>().sqrt();
        let level = w.iter().map(|(_, z)| z.norm()).sum::<f64>() / 4.0;
        if level == 0.0 || !level.is_finite() {
            continue;
        }
        let d: num_complex::Complex<f64> = w.iter().zip(weights).map(|((_, z), wi)| z * wi).sum();
        let d = d / gain;
        samples.push((d.re.abs(), level));
        samples.push((d.im.abs(), level));
    }
    if samples.len() < 2 {
        return None;
    }
    let mut abs: Vec<f64> = samples.iter().map(|s| s.0).collect();
    let mut rel: Vec<f64> = samples.iter().map(|s| s.0 / s.1).collect();
    let sigma = median(&mut abs) / MEDIAN_ABS_NORMAL;
    let fraction = median(&mut rel) / MEDIAN_ABS_NORMAL;
    let u_abs: Vec<f64> = samples
        .iter()
        .map(|s| s.0 / sigma.max(f64::MIN_POSITIVE))
        .collect();
    let u_rel: Vec<f64> = samples
        .iter()
        .map(|s| s.0 / (fraction * s.1).max(f64::MIN_POSITIVE))
        .collect();
    if log_spread(&u_abs) < log_spread(&u_rel) {
        Some(Scatter::Absolute(sigma))
    } else {
        Some(Scatter::Relative(fraction))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn digits_of_printed_numbers() {
        assert_eq!(significant_digits(1.23e-6), Some((3, -6)));
        assert_eq!(significant_digits(-4.5e-9), Some((2, -9)));
        assert_eq!(significant_digits(1.0), Some((1, 0)));
        assert_eq!(significant_digits(0.0), None);
        let v: f64 = "1.23456789012e-5".parse().unwrap();
        assert_eq!(significant_digits(v), Some((12, -5)));
        assert_eq!(
            significant_digits(std::f64::consts::PI).map(|d| d.0),
            Some(16)
        );
    }

    #[test]
    fn ulp_follows_each_values_magnitude() {
        let q = ColumnQuantisation {
            digits: 3,
            lowest_digit_exponent: -12,
        };
        assert!((q.ulp(1.23e-6) - 1e-8).abs() < 1e-20);
        assert!((q.ulp(-9.87e-9) - 1e-11).abs() < 1e-23);
        // Fixed decimals: 1e-9 absolute dominates for large values.
        let f = ColumnQuantisation {
            digits: 7,
            lowest_digit_exponent: -9,
        };
        assert!((f.ulp(1.234567e-3) - 1e-9).abs() < 1e-21);
    }

    #[test]
    fn scatter_law_and_level_are_recognised() {
        use rand::{Rng, SeedableRng};
        let smooth: Vec<_> = (0..200)
            .map(|j| {
                let f = 10.0 + j as f64;
                (
                    f,
                    num_complex::Complex::from_polar(1e-6 * (1.0 + f / 100.0), f / 50.0),
                )
            })
            .collect();
        let s = match scatter(&smooth).unwrap() {
            Scatter::Relative(s) => s,
            Scatter::Absolute(a) => a / 1e-6,
        };
        assert!(s < 1e-4, "{s}");
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let noisy: Vec<_> = smooth
            .iter()
            .map(|(f, z)| {
                let n = num_complex::Complex::new(
                    rng.sample::<f64, _>(rand_distr::StandardNormal),
                    rng.sample::<f64, _>(rand_distr::StandardNormal),
                );
                (*f, z + n * (0.01 * z.norm()))
            })
            .collect();
        match scatter(&noisy).unwrap() {
            Scatter::Relative(s) => assert!((s - 0.01).abs() < 0.0015, "{s}"),
            other => panic!("relative noise read as {other:?}"),
        }
        // Constant noise on a response spanning two decades: absolute law.
        let mut rng = rand::rngs::StdRng::seed_from_u64(8);
        let wide: Vec<_> = (0..200)
            .map(|j| {
                let f = 5.0 + j as f64;
                let z = num_complex::Complex::from_polar(1e-8 * f * f / 25.0, f / 40.0);
                let n = num_complex::Complex::new(
                    rng.sample::<f64, _>(rand_distr::StandardNormal),
                    rng.sample::<f64, _>(rand_distr::StandardNormal),
                );
                (f, z + n * 2e-8)
            })
            .collect();
        match scatter(&wide).unwrap() {
            Scatter::Absolute(a) => assert!((a / 2e-8 - 1.0).abs() < 0.15, "{a}"),
            other => panic!("constant noise read as {other:?}"),
        }
    }
}
