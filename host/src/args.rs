//! Number and duration options of the command line, validated before use.
//!
//! Every command parses its numeric options with these `clap` value parsers
//! (`#[arg(long, value_parser = plinth::args::seconds)]`), so that `-1`,
//! `nan`, `inf` or `1e30` are refused with the option's name and what it
//! accepts, and never reach a conversion that could panic (such as
//! `Duration::from_secs_f64`).

use std::time::Duration;

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

#[cfg(test)]
mod tests {
    use super::*;

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
