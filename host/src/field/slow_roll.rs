//! Slow-roll compensation (`--slow-roll LO:HI`): the field's practice against
//! probe runout (mechanical and electrical, formats.md `probe_runout`).
//!
//! At speeds where the rotor's dynamic response is negligible, a proximity
//! probe's 1X vector is the runout of the shaft surface under it, the same at
//! every speed. Its estimate is the mean `rel` phasor of each bearing over the
//! rows with LO ≤ speed ≤ HI [Hz]; it is subtracted from every `rel` phasor
//! of that bearing (pedestal phasors are absolute motion and are untouched).
//!
//! What was subtracted goes to `slow_roll.csv` in the run directory:
//!
//! ```text
//! bearing,rel_y_re,rel_y_im,rel_z_re,rel_z_im,lo_hz,hi_hz,speeds,change
//! ```
//!
//! (the vectors [m], the band [Hz], how many speeds were averaged and the
//! band's `change`: the largest distance of a band reading from the mean,
//! relative to the mean's size). A change above [`MAX_CHANGE`] means the
//! response is not small against the runout there: the band is not slow,
//! and a warning says so.

use crate::rundir::Measurement;
use anyhow::{bail, Context, Result};
use num_complex::Complex;
use std::fmt::Write as _;
use std::path::Path;

/// File the subtracted vectors are recorded in.
pub const SLOW_ROLL_FILE: &str = "slow_roll.csv";

/// Largest relative change of the 1X vector across the band for it to count
/// as slow roll.
pub const MAX_CHANGE: f64 = 0.1;

/// A slow-roll speed band [Hz].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlowRollBand {
    /// Lowest speed [Hz].
    pub lo_hz: f64,
    /// Highest speed [Hz].
    pub hi_hz: f64,
}

impl std::str::FromStr for SlowRollBand {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (a, b) = s
            .split_once(':')
            .ok_or_else(|| format!("`{s}`: expected LO:HI in Hz, e.g. 5:8"))?;
        let num = |t: &str| -> Result<f64, String> {
            t.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v >= 0.0)
                .ok_or_else(|| format!("`{s}`: `{t}` is not a speed in Hz (finite, >= 0)"))
        };
        let (lo_hz, hi_hz) = (num(a)?, num(b)?);
        if lo_hz > hi_hz {
            return Err(format!("`{s}`: LO must not exceed HI"));
        }
        Ok(SlowRollBand { lo_hz, hi_hz })
    }
}

/// The vector subtracted from one bearing's `rel` phasors.
#[derive(Clone, Debug, PartialEq)]
pub struct SlowRollVector {
    /// Bearing name.
    pub bearing: String,
    /// Subtracted rel_y, rel_z [m].
    pub rel: [Complex<f64>; 2],
    /// Speeds averaged.
    pub speeds: usize,
    /// Largest |reading − mean| / |mean| in the band [-].
    pub change: f64,
}

/// What [`subtract_slow_roll`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct SlowRoll {
    /// The band.
    pub band: SlowRollBand,
    /// One vector per bearing.
    pub vectors: Vec<SlowRollVector>,
    /// Warnings for the user (band not slow).
    pub warnings: Vec<String>,
}

/// Estimates each bearing's slow-roll vector in `band` and subtracts it from
/// all its `rel` phasors. Errors when a bearing has no speed in the band.
pub fn subtract_slow_roll(rows: &mut [Measurement], band: SlowRollBand) -> Result<SlowRoll> {
    let mut bearings: Vec<String> = Vec::new();
    for m in rows.iter() {
        if !bearings.contains(&m.bearing) {
            bearings.push(m.bearing.clone());
        }
    }
    let mut vectors = Vec::new();
    let mut warnings = Vec::new();
    for b in bearings {
        let in_band: Vec<[Complex<f64>; 2]> = rows
            .iter()
            .filter(|m| m.bearing == b && m.speed_hz >= band.lo_hz && m.speed_hz <= band.hi_hz)
            .map(|m| m.rel)
            .collect();
        if in_band.is_empty() {
            let (lo, hi) = rows
                .iter()
                .filter(|m| m.bearing == b)
                .fold((f64::INFINITY, 0.0f64), |(lo, hi), m| {
                    (lo.min(m.speed_hz), hi.max(m.speed_hz))
                });
            bail!(
                "--slow-roll {}:{}: bearing `{b}` has no speed in the band (its speeds are {lo}..={hi} Hz)",
                band.lo_hz,
                band.hi_hz
            );
        }
        let n = in_band.len() as f64;
        let mean = [0, 1].map(|i| in_band.iter().map(|r| r[i]).sum::<Complex<f64>>() / n);
        let size = (mean[0].norm_sqr() + mean[1].norm_sqr()).sqrt();
        let spread = in_band
            .iter()
            .map(|r| ((r[0] - mean[0]).norm_sqr() + (r[1] - mean[1]).norm_sqr()).sqrt())
            .fold(0.0, f64::max);
        let change = if size > 0.0 { spread / size } else { 0.0 };
        if change > MAX_CHANGE {
            warnings.push(format!(
                "--slow-roll {}:{}: bearing `{b}`: the 1X vector changes by {:.0} % of its mean across the band: the rotor's response is not negligible there (not slow roll); choose a lower band",
                band.lo_hz,
                band.hi_hz,
                100.0 * change
            ));
        } else if in_band.len() < 2 {
            warnings.push(format!(
                "--slow-roll {}:{}: bearing `{b}`: one speed in the band, so whether the response is negligible there cannot be checked",
                band.lo_hz, band.hi_hz
            ));
        }
        for m in rows.iter_mut().filter(|m| m.bearing == b) {
            // A table's rounding floor (`resolution.csv`) stays with the row:
            // the vector subtracted is one offset per bearing, not noise.
            let floor = m.resolution_sd();
            m.rel[0] -= mean[0];
            m.rel[1] -= mean[1];
            if let Some(sd) = floor {
                m.set_resolution(sd);
            }
        }
        vectors.push(SlowRollVector {
            bearing: b,
            rel: mean,
            speeds: in_band.len(),
            change,
        });
    }
    Ok(SlowRoll {
        band,
        vectors,
        warnings,
    })
}

impl SlowRoll {
    /// Writes [`SLOW_ROLL_FILE`] into `dir`.
    pub fn write(&self, dir: &Path) -> Result<()> {
        let mut text =
            String::from("bearing,rel_y_re,rel_y_im,rel_z_re,rel_z_im,lo_hz,hi_hz,speeds,change\n");
        for v in &self.vectors {
            let _ = writeln!(
                text,
                "{},{:e},{:e},{:e},{:e},{},{},{},{:.4}",
                v.bearing,
                v.rel[0].re,
                v.rel[0].im,
                v.rel[1].re,
                v.rel[1].im,
                self.band.lo_hz,
                self.band.hi_hz,
                v.speeds,
                v.change
            );
        }
        let path = dir.join(SLOW_ROLL_FILE);
        std::fs::write(&path, text).with_context(|| format!("{}: cannot write", path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(speed_hz: f64, rel: Complex<f64>) -> Measurement {
        Measurement {
            speed_hz,
            bearing: "B1".into(),
            rel: [rel, rel * 2.0],
            ped: [Complex::new(1.0, 0.0); 2],
            noise_sd: None,
            written: None,
        }
    }

    #[test]
    fn subtracts_the_band_mean_and_warns_when_not_slow() {
        let runout = Complex::new(5e-6, -2e-6);
        // Response ∝ speed² (well below resonance), 1e-9 m at 1 Hz.
        let mut rows: Vec<_> = (1..=50)
            .map(|f| row(f as f64, runout + Complex::new(1e-9 * (f * f) as f64, 0.0)))
            .collect();
        let band: SlowRollBand = "1:3".parse().unwrap();
        let s = subtract_slow_roll(&mut rows, band).unwrap();
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        assert!((s.vectors[0].rel[0] - runout).norm() < 1e-8);
        assert!((rows[49].rel[0] - Complex::new(2.5e-6, 0.0)).norm() < 1e-8);
        assert!((rows[49].ped[0] - Complex::new(1.0, 0.0)).norm() == 0.0);
        let mut rows: Vec<_> = (1..=50)
            .map(|f| row(f as f64, runout + Complex::new(1e-9 * (f * f) as f64, 0.0)))
            .collect();
        let s = subtract_slow_roll(&mut rows, "20:40".parse().unwrap()).unwrap();
        assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
        assert!(subtract_slow_roll(&mut rows, "60:70".parse().unwrap()).is_err());
        assert!("5".parse::<SlowRollBand>().is_err());
        assert!("8:5".parse::<SlowRollBand>().is_err());
    }
}
