//! Amplitude units of field instruments and the conversion of a transducer's
//! 1X reading (amplitude, phase) to a displacement phasor [m].
//!
//! formats.md lists the units: displacement `um pp`, `mil pp`, `mm pp`,
//! `um 0-pk`, `m 0-pk`; velocity `mm/s pk`, `mm/s rms`, `in/s pk`, `m/s pk`;
//! acceleration `g pk`, `m/s2 pk`, `g rms`. Any length, velocity or
//! acceleration unit below combines with any measure: `pp` (`pk-pk`, `p-p`)
//! = peak to peak, `pk` (`0-pk`, `0-p`) = zero to peak, `rms` of the 1X
//! sinusoid (0-pk = √2·rms). 1 mil = 25.4 µm, 1 g = 9.80665 m/s².

use num_complex::Complex;
use plinth_shared::extractor::SensorKind;

/// One g [m/s²] (standard gravity).
pub const STANDARD_GRAVITY: f64 = 9.80665;
/// One mil [m].
pub const MIL: f64 = 25.4e-6;
/// One inch [m].
pub const INCH: f64 = 0.0254;

/// A parsed amplitude unit: what it measures and the factor from a reading
/// to the 0-pk amplitude in SI (m, m/s or m/s²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmplitudeUnit {
    /// Displacement, velocity or acceleration.
    pub kind: SensorKind,
    /// SI 0-pk amplitude per unit of reading.
    pub to_si_zero_peak: f64,
}

/// The unit spellings accepted, for error messages.
pub const UNIT_HELP: &str = "displacement `um pp`, `mil pp`, `mm pp`, `um 0-pk`, `m 0-pk`; \
velocity `mm/s pk`, `mm/s rms`, `in/s pk`, `m/s pk`; acceleration `g pk`, `m/s2 pk`, `g rms` \
(any of um, mil, mm, m, mm/s, in/s, m/s, g, m/s2 with pp, 0-pk/pk or rms)";

impl AmplitudeUnit {
    /// Parses a unit string such as `um pp` or `mm/s rms`; `None` if unknown.
    pub fn parse(text: &str) -> Option<AmplitudeUnit> {
        let mut words = text.split_whitespace();
        let (unit, measure) = (words.next()?, words.next()?);
        if words.next().is_some() {
            return None;
        }
        let (kind, scale) = match unit.to_ascii_lowercase().as_str() {
            "um" | "µm" | "μm" | "micron" | "microns" => (SensorKind::Displacement, 1e-6),
            "mil" | "mils" => (SensorKind::Displacement, MIL),
            "mm" => (SensorKind::Displacement, 1e-3),
            "m" => (SensorKind::Displacement, 1.0),
            "mm/s" => (SensorKind::Velocity, 1e-3),
            "in/s" | "ips" => (SensorKind::Velocity, INCH),
            "m/s" => (SensorKind::Velocity, 1.0),
            "g" => (SensorKind::Acceleration, STANDARD_GRAVITY),
            "m/s2" | "m/s^2" | "m/s²" => (SensorKind::Acceleration, 1.0),
            _ => return None,
        };
        let factor = match measure.to_ascii_lowercase().as_str() {
            "pp" | "pk-pk" | "p-p" => 0.5,
            "pk" | "0-pk" | "0-p" | "peak" => 1.0,
            "rms" => core::f64::consts::SQRT_2,
            _ => return None,
        };
        Some(AmplitudeUnit {
            kind,
            to_si_zero_peak: scale * factor,
        })
    }
}

/// How an instrument prints phase.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PhaseConvention {
    /// Degrees from the keyphasor pulse to the first positive peak (Bently
    /// Nevada): amplitude A at lag φ is A·e^{−iφ}.
    Lag,
    /// Phase lead: A·e^{+iφ}.
    Lead,
}

/// The phasor of a reading of 0-pk amplitude `amplitude` (any unit) and
/// phase `phase_deg` [deg] in `convention` (formats.md).
pub fn reading_phasor(amplitude: f64, phase_deg: f64, convention: PhaseConvention) -> Complex<f64> {
    let phi = phase_deg.to_radians();
    match convention {
        PhaseConvention::Lag => Complex::from_polar(amplitude, -phi),
        PhaseConvention::Lead => Complex::from_polar(amplitude, phi),
    }
}

/// The displacement phasor [m] behind a steady 1X phasor `q` of a `kind`
/// transducer [m, m/s or m/s²] at `omega` [rad/s]: D = V/(iΩ) for
/// velocity, D = −A/Ω² for acceleration.
pub fn to_displacement(kind: SensorKind, q: Complex<f64>, omega: f64) -> Complex<f64> {
    match kind {
        SensorKind::Displacement => q,
        SensorKind::Velocity => q / Complex::new(0.0, omega),
        SensorKind::Acceleration => -q / (omega * omega),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_of_formats_md() {
        let u = |s| AmplitudeUnit::parse(s).unwrap();
        assert_eq!(u("um pp").to_si_zero_peak, 0.5e-6);
        assert!((u("mil pp").to_si_zero_peak - 12.7e-6).abs() < 1e-18);
        assert_eq!(u("m 0-pk").to_si_zero_peak, 1.0);
        assert_eq!(u("mm/s pk").kind, SensorKind::Velocity);
        assert!((u("mm/s rms").to_si_zero_peak - 1.414_213_562e-3).abs() < 1e-12);
        assert!((u("g rms").to_si_zero_peak - 13.868_697).abs() < 1e-6);
        assert_eq!(u("m/s2 pk").kind, SensorKind::Acceleration);
        assert!(AmplitudeUnit::parse("um").is_none());
        assert!(AmplitudeUnit::parse("furlong pp").is_none());
    }

    #[test]
    fn lag_is_a_negative_angle_and_seismic_conversion() {
        // 10 µm 0-pk at 90° lag: x(t) = 10 cos(Ωt − 90°) peaks a quarter
        // revolution after the pulse.
        let q = reading_phasor(10.0, 90.0, PhaseConvention::Lag);
        assert!((q - Complex::new(0.0, -10.0)).norm() < 1e-12);
        // A velocity leads displacement by 90°: V = iΩD.
        let d = Complex::new(1e-6, 2e-6);
        let w = 100.0;
        let v = Complex::new(0.0, w) * d;
        assert!((to_displacement(SensorKind::Velocity, v, w) - d).norm() < 1e-18);
        let a = -d * w * w;
        assert!((to_displacement(SensorKind::Acceleration, a, w) - d).norm() < 1e-18);
    }
}
