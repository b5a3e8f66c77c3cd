//! Number and duration options of the command line, validated before use.
//!
//! Every command parses its numeric options with these `clap` value parsers
//! (`#[arg(long, value_parser = plinth::args::seconds)]`), so that `-1`,
//! `nan`, `inf` or `1e30` are refused with the option's name and what it
//! accepts, and never reach a conversion that could panic (such as
//! `Duration::from_secs_f64`).

use std::time::Duration;

/// The highest rotor speed an option accepts [Hz]: 100 kHz (6 million
/// rpm), beyond any rotor (dental turbines turn at about 7 kHz); a larger
/// speed is a typo or a unit mistake, and would only fail later with a
/// singular matrix or a sample rate that cannot follow it.
pub const MAX_SPEED_HZ: f64 = 1e5;

/// The longest duration an option accepts [s]: one year.
pub const MAX_SECONDS: f64 = 365.0 * 24.0 * 3600.0;

fn number(text: &str) -> Result<f64, String> {
    let t = text.trim();
    let v: f64 = t.parse().map_err(|_| {
        if t.contains(',') && t.replace(',', ".").parse::<f64>().is_ok() {
            format!("{t:?} is not a number: use a decimal point, not a comma")
        } else {
            format!("{t:?} is not a number")
        }
    })?;
    if !v.is_finite() {
        return Err(format!("{t} is not a finite number"));
    }
    Ok(v)
}

/// A duration in seconds: a finite number, 0 to [`MAX_SECONDS`].
pub fn seconds(text: &str) -> Result<Duration, String> {
    let v = number(text)?;
    if v < 0.0 {
        return Err(format!(
            "{v} s is negative: give a duration in seconds >= 0"
        ));
    }
    if v > MAX_SECONDS {
        return Err(format!(
            "{v:e} s is longer than a year ({MAX_SECONDS} s): give a duration in seconds"
        ));
    }
    Ok(Duration::from_secs_f64(v))
}

/// Any finite number (an offset, a voltage that may be negative).
pub fn finite(text: &str) -> Result<f64, String> {
    number(text)
}

/// A finite number > 0.
pub fn positive(text: &str) -> Result<f64, String> {
    let v = number(text)?;
    if v <= 0.0 {
        return Err(format!("{v} must be greater than 0"));
    }
    Ok(v)
}

/// A finite number >= 0.
pub fn non_negative(text: &str) -> Result<f64, String> {
    let v = number(text)?;
    if v < 0.0 {
        return Err(format!("{v} must not be negative"));
    }
    Ok(v)
}

/// A probability strictly between 0 and 1 (a significance level).
pub fn probability(text: &str) -> Result<f64, String> {
    let v = number(text)?;
    if !(v > 0.0 && v < 1.0) {
        return Err(format!("{v} must be between 0 and 1 (exclusive)"));
    }
    Ok(v)
}

/// A whole number >= 1.
pub fn count(text: &str) -> Result<usize, String> {
    let t = text.trim();
    let v: usize = t
        .parse()
        .map_err(|_| format!("{t:?} is not a whole number >= 1"))?;
    if v == 0 {
        return Err("0 is not allowed: give a whole number >= 1".into());
    }
    Ok(v)
}

/// A band of rotor speeds `LO:HI` [Hz] (`--speeds`): the fit uses only the
/// measured speeds in it, ends included.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpeedBand {
    /// Lowest speed kept [Hz].
    pub lo_hz: f64,
    /// Highest speed kept [Hz].
    pub hi_hz: f64,
}

/// `LO:HI` in Hz, 0 <= LO < HI, both finite (e.g. `20:120`).
pub fn speed_band(text: &str) -> Result<SpeedBand, String> {
    let (lo, hi) = text
        .split_once(':')
        .ok_or_else(|| format!("{text:?}: give a speed band as LO:HI in Hz, e.g. 20:120"))?;
    let lo = non_negative(lo).map_err(|e| format!("LO of {text:?}: {e}"))?;
    let hi = positive(hi).map_err(|e| format!("HI of {text:?}: {e}"))?;
    if lo >= hi {
        return Err(format!("{text:?}: LO ({lo} Hz) must be below HI ({hi} Hz)"));
    }
    Ok(SpeedBand {
        lo_hz: lo,
        hi_hz: hi,
    })
}

impl SpeedBand {
    /// True when `speed_hz` lies in the band.
    pub fn contains(&self, speed_hz: f64) -> bool {
        (self.lo_hz..=self.hi_hz).contains(&speed_hz)
    }

    /// Keeps the measurements of `run` in the band; an error naming the
    /// option and the run's speed range when none is left.
    pub fn select(&self, run: &mut crate::rundir::RunDir) -> Result<(), String> {
        let (lo, hi) = run
            .measurements
            .iter()
            .map(|m| m.speed_hz)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
                (a.min(s), b.max(s))
            });
        run.measurements.retain(|m| self.contains(m.speed_hz));
        if run.measurements.is_empty() {
            return Err(format!(
                "--speeds {}:{}: no measured speed in this band (the run has {lo}..{hi} Hz)",
                self.lo_hz, self.hi_hz
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_bands_are_validated() {
        assert_eq!(
            speed_band("20:120").unwrap(),
            SpeedBand {
                lo_hz: 20.0,
                hi_hz: 120.0
            }
        );
        assert!(speed_band("0:1e3").is_ok());
        for bad in ["120:20", "20", "-1:5", "5:5", "a:9", "1:inf", ":"] {
            assert!(speed_band(bad).is_err(), "{bad}");
        }
        assert!(speed_band("20-120").unwrap_err().contains("LO:HI"));
    }

    #[test]
    fn durations_are_validated_before_conversion() {
        assert_eq!(seconds("1.5").unwrap(), Duration::from_millis(1500));
        assert_eq!(seconds("0").unwrap(), Duration::ZERO);
        for bad in ["-1", "nan", "inf", "1e30", "", "ten", "1,5"] {
            assert!(seconds(bad).is_err(), "{bad}");
        }
        assert!(seconds("1,5").unwrap_err().contains("decimal point"));
        assert!(positive("0").is_err());
        assert!(positive("-0.1").is_err());
        assert_eq!(positive("2e3").unwrap(), 2000.0);
        assert!(non_negative("-1e-9").is_err());
        assert_eq!(non_negative("0").unwrap(), 0.0);
        assert!(probability("1").is_err());
        assert!(probability("0.01").is_ok());
        assert!(count("0").is_err());
        assert_eq!(finite("-9").unwrap(), -9.0);
        assert!(finite("nan").is_err() && finite("-inf").is_err());
        assert_eq!(count("4").unwrap(), 4);
    }
}
