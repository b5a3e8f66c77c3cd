//! The measurement noise the data can support: how finely the numbers were
//! written (quantisation) and how much they scatter between neighbouring speeds.
//!
//! Quantisation: every number of `measurements.csv` is taken to be rounded to
//! a unit in its last written digit (ulp). A rounding error is uniform on
//! ±ulp/2, so its standard deviation is σ = ulp/√12, per real component, with
//! ulp set by *that number's own magnitude*: a value written with D significant
//! digits and decimal exponent e has ulp = 10^(e−D+1). Rounded data are not
//! white noise (neighbouring speeds round alike), which the selection criterion
//! allows for separately (autocorrelation-robust covariance, `criterion`).
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
//! annihilates any quadratic trend; normalised to unit noise gain and divided
//! by the local magnitude it estimates the relative noise level, robustly (the
//! median, so a few points at a sharp resonance do not count). Each number's
//! σ is the larger of its quantisation σ and its scatter σ.

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
    /// Relative scatter σ/|phasor| per bearing and complex channel
    /// ([`COMPLEX_CHANNELS`] order); `None` with fewer than 4 speeds.
    pub scatter: Vec<[Option<f64>; 4]>,
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
                *slot = relative_scatter(&series);
            }
            scatter.push(per_channel);
        }
        Ok(Self { columns, scatter })
    }

    /// Noise standard deviation [m] of real channel `c` of bearing `b` whose
    /// value is `v` [m] and whose complex phasor has magnitude `magnitude` [m].
    pub fn sigma(&self, b: usize, c: usize, v: f64, magnitude: f64) -> f64 {
        let quantisation = self.columns[c].ulp(v) / 12f64.sqrt();
        let scatter = self
            .scatter
            .get(b)
            .and_then(|s| s[c / 2])
            .map_or(0.0, |s| s * magnitude);
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

/// Robust relative noise level σ/|x| (per real component) of a complex series
/// sampled at increasing speeds, from third divided differences over four
/// neighbouring speeds (which cancel any quadratic trend). `None` when fewer
/// than four usable points.
pub fn relative_scatter(series: &[(f64, num_complex::Complex<f64>)]) -> Option<f64> {
    let mut u = Vec::new();
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
        let d = d / (gain * level);
        u.push(d.re.abs());
        u.push(d.im.abs());
    }
    if u.len() < 2 {
        return None;
    }
    u.sort_by(f64::total_cmp);
    let median = if u.len() % 2 == 1 {
        u[u.len() / 2]
    } else {
        0.5 * (u[u.len() / 2 - 1] + u[u.len() / 2])
    };
    // Median of |N(0, σ²)| is 0.6745·σ.
    Some(median / 0.674_489_750_196_081_7)
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
    fn scatter_of_a_smooth_series_is_small_and_of_noise_is_right() {
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
        let s = relative_scatter(&smooth).unwrap();
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
        let s = relative_scatter(&noisy).unwrap();
        assert!((s - 0.01).abs() < 0.0015, "{s}");
    }
}
