//! Sensor channels: volts to physical units, and seismic (velocity,
//! acceleration) 1X phasors to displacement phasors.
//!
//! The conversion is exact for a displacement whose 1X phasor D is constant
//! over the revolution in the shaft-angle domain, x(θ) = Re{D·e^{iθ}}, while
//! the shaft follows the revolution's constant-acceleration model
//! (Ω² linear in θ). Differentiating in time then gives
//!
//! - velocity v = Re{iΩ(θ)·D·e^{iθ}}, whose angle-domain 1X phasor is
//!   V = iΩ̄·D − i·C₂·D̄, with Ω̄ = (1/2π)∫Ω dθ and C₂ = (1/2π)∫Ω·e^{−2iθ} dθ;
//! - acceleration a = Re{(iα − Ω²)·D·e^{iθ}}, whose phasor is
//!   A = (iα − ⟨Ω²⟩)·D − iα·D̄, with ⟨Ω²⟩ = (Ω₀² + Ω₁²)/2.
//!
//! At constant speed these are the textbook V = iΩ·D and A = −Ω²·D. During a
//! run-down the D̄ terms are of relative size ΔΩ/(4πΩ) and α/Ω² (1.6 % and
//! 3 % at 5 Hz decelerating 5 Hz/s), far above the 1e-4 target, so they are
//! kept: D = (p̄·V − q·V̄)/(|p|² − |q|²) for V = p·D + q·D̄.

use core::f32::consts::FRAC_1_PI;
use num_complex::Complex;

/// What a channel's transducer measures: THE sensor kind of Plinth, used by
/// the extractor, the wire protocol (postcard encodes the variant index, in
/// this order), the signal-set header (`displacement`, `velocity`,
/// `acceleration`), the stream configuration and the field-data readers
/// (which also accept `proximity` for a displacement probe).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SensorKind {
    /// Displacement, e.g. a proximity probe (`rel`) [m].
    #[serde(alias = "proximity")]
    Displacement,
    /// Velocity, a seismic velocity pick-up on a pedestal [m/s].
    Velocity,
    /// Acceleration, an accelerometer on a pedestal [m/s²].
    Acceleration,
}

impl SensorKind {
    /// All kinds, in wire order.
    pub const ALL: [SensorKind; 3] = [
        SensorKind::Displacement,
        SensorKind::Velocity,
        SensorKind::Acceleration,
    ];

    /// The name in files: `displacement`, `velocity`, `acceleration`.
    pub const fn name(self) -> &'static str {
        match self {
            SensorKind::Displacement => "displacement",
            SensorKind::Velocity => "velocity",
            SensorKind::Acceleration => "acceleration",
        }
    }

    /// The unit of a sensitivity for this kind: V/m, V/(m/s) or V/(m/s²).
    pub const fn sensitivity_unit(self) -> &'static str {
        match self {
            SensorKind::Displacement => "V/m",
            SensorKind::Velocity => "V/(m/s)",
            SensorKind::Acceleration => "V/(m/s²)",
        }
    }

    /// Parses a name: `displacement` (or `proximity`), `velocity`,
    /// `acceleration` (or `accelerometer`), any case.
    pub fn parse(name: &str) -> Option<SensorKind> {
        let n = name.trim();
        let is = |s: &str| n.eq_ignore_ascii_case(s);
        if is("displacement") || is("proximity") {
            Some(SensorKind::Displacement)
        } else if is("velocity") {
            Some(SensorKind::Velocity)
        } else if is("acceleration") || is("accelerometer") {
            Some(SensorKind::Acceleration)
        } else {
            None
        }
    }
}

/// One channel's transducer: what it measures and how many volts it gives per
/// unit of it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sensor {
    /// Measured quantity.
    pub kind: SensorKind,
    /// Sensitivity [V/m, V/(m/s) or V/(m/s²), as `kind`]; the samples are in V.
    pub sensitivity: f32,
}

impl Sensor {
    /// A displacement probe giving `volts_per_m` [V/m] (7.87 V/mm = 7870 V/m).
    pub const fn displacement(volts_per_m: f32) -> Self {
        Self {
            kind: SensorKind::Displacement,
            sensitivity: volts_per_m,
        }
    }

    /// A velocity pick-up giving `volts_per_m_per_s` [V/(m/s)].
    pub const fn velocity(volts_per_m_per_s: f32) -> Self {
        Self {
            kind: SensorKind::Velocity,
            sensitivity: volts_per_m_per_s,
        }
    }

    /// An accelerometer giving `volts_per_m_per_s2` [V/(m/s²)].
    pub const fn acceleration(volts_per_m_per_s2: f32) -> Self {
        Self {
            kind: SensorKind::Acceleration,
            sensitivity: volts_per_m_per_s2,
        }
    }

    /// Whether the sensitivity is usable: finite and positive.
    pub fn is_valid(&self) -> bool {
        self.sensitivity.is_finite() && self.sensitivity > 0.0
    }
}

/// The shaft's motion over one revolution under the constant-acceleration
/// model, for the seismic conversion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kinematics {
    /// Angular speed at the opening keyphasor edge Ω₀ [rad/s].
    pub omega_start: f32,
    /// Angular speed at the closing keyphasor edge Ω₁ [rad/s].
    pub omega_end: f32,
    /// Angular acceleration α = dΩ/dt, negative in a run-down [rad/s²];
    /// consistent with the speeds: Ω₁² − Ω₀² = 4π·α.
    pub alpha: f32,
}

/// The linear map phasor = p·D + q·D̄ from a displacement phasor D to a
/// sensor's angle-domain phasor, over one revolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conversion {
    p: Complex<f32>,
    q: Complex<f32>,
}

impl Conversion {
    /// The map for sensor `kind` over a revolution with `kinematics`.
    pub fn new(kind: SensorKind, kinematics: &Kinematics) -> Self {
        let (w0, w1, alpha) = (
            kinematics.omega_start,
            kinematics.omega_end,
            kinematics.alpha,
        );
        let i = Complex::new(0.0f32, 1.0);
        match kind {
            SensorKind::Displacement => Self {
                p: Complex::new(1.0, 0.0),
                q: Complex::new(0.0, 0.0),
            },
            SensorKind::Velocity => {
                // Ω̄ = (1/2π)∫√(Ω₀² + 2αθ) dθ = 2(Ω₁² + Ω₁Ω₀ + Ω₀²)/(3(Ω₀ + Ω₁)).
                let mean = 2.0 * (w1 * w1 + w1 * w0 + w0 * w0) / (3.0 * (w0 + w1));
                // ∫₀^{2π} f·e^{−2iθ} dθ by parts, f = Ω and its θ-derivatives
                // f' = α/Ω, f'' = −α²/Ω³, f''' = 3α³/Ω⁵ (the series falls by
                // ~α/Ω² per term; the first omitted one is < 1e-6 relative at
                // 5 Hz, 5 Hz/s):
                // (i/2)[f] + ¼[f'] − (i/8)[f''] − (1/16)[f'''].
                let d1 = w1 - w0;
                let d2 = alpha * (1.0 / w1 - 1.0 / w0);
                let cube = |w: f32| 1.0 / (w * w * w);
                let d3 = -alpha * alpha * (cube(w1) - cube(w0));
                let fifth = |w: f32| 1.0 / (w * w * w * w * w);
                let d4 = 3.0 * alpha * alpha * alpha * (fifth(w1) - fifth(w0));
                let integral = Complex::new(0.25 * d2 - d4 / 16.0, 0.5 * d1 - d3 / 8.0);
                let c2 = integral * (FRAC_1_PI * 0.5);
                Self {
                    p: i * mean,
                    q: -i * c2,
                }
            }
            SensorKind::Acceleration => {
                let mean_square = 0.5 * (w0 * w0 + w1 * w1);
                Self {
                    p: Complex::new(-mean_square, alpha),
                    q: Complex::new(0.0, -alpha),
                }
            }
        }
    }

    /// The displacement phasor D [m] behind a sensor phasor `phasor` [m, m/s
    /// or m/s²]: solves phasor = p·D + q·D̄.
    #[inline]
    pub fn to_displacement(&self, phasor: Complex<f32>) -> Complex<f32> {
        let det = self.p.norm_sqr() - self.q.norm_sqr();
        (self.p.conj() * phasor - self.q * phasor.conj()) / det
    }

    /// The sensor phasor of a displacement phasor `d` [m] (the forward map).
    #[inline]
    pub fn from_displacement(&self, d: Complex<f32>) -> Complex<f32> {
        self.p * d + self.q * d.conj()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kin(f0: f64, rate: f64) -> Kinematics {
        // One revolution of a linear run-down starting at f0 [Hz], rate [Hz/s].
        let tau = core::f64::consts::TAU;
        let period = (f0 - (f0 * f0 - 2.0 * rate).sqrt()) / rate;
        let f1 = f0 - rate * period;
        Kinematics {
            omega_start: (tau * f0) as f32,
            omega_end: (tau * f1) as f32,
            alpha: (-tau * rate) as f32,
        }
    }

    #[test]
    fn constant_speed_is_the_textbook_conversion() {
        let k = Kinematics {
            omega_start: 100.0,
            omega_end: 100.0,
            alpha: 0.0,
        };
        let d = Complex::new(1e-5f32, -2e-5);
        let v = Conversion::new(SensorKind::Velocity, &k).from_displacement(d);
        let a = Conversion::new(SensorKind::Acceleration, &k).from_displacement(d);
        assert!((v - Complex::new(0.0, 100.0) * d).norm() < 1e-9);
        assert!((a + d * 1e4).norm() < 1e-6);
    }

    #[test]
    fn velocity_coefficients_match_quadrature_in_f64() {
        // Independent check of Ω̄ and C₂ by brute-force quadrature of
        // Ω(θ) = √(Ω₀² + 2αθ) at 5 Hz, 5 Hz/s (the worst case).
        let k = kin(5.0, 5.0);
        let (w0, a) = (k.omega_start as f64, k.alpha as f64);
        let n = 200_000;
        let (mut mean, mut c2re, mut c2im) = (0.0, 0.0, 0.0);
        for j in 0..n {
            let th = (j as f64 + 0.5) / n as f64 * core::f64::consts::TAU;
            let w = (w0 * w0 + 2.0 * a * th).sqrt();
            mean += w / n as f64;
            c2re += w * (2.0 * th).cos() / n as f64;
            c2im -= w * (2.0 * th).sin() / n as f64;
        }
        let conv = Conversion::new(SensorKind::Velocity, &k);
        assert!(
            (conv.p.im as f64 - mean).abs() / mean < 2e-6,
            "{} {mean}",
            conv.p.im
        );
        // q = −i·C₂ → C₂ = i·q.
        let c2 = Complex::new(0.0f32, 1.0) * conv.q;
        assert!(
            (c2.re as f64 - c2re).abs() / mean < 1e-6,
            "{} {c2re}",
            c2.re
        );
        assert!(
            (c2.im as f64 - c2im).abs() / mean < 1e-6,
            "{} {c2im}",
            c2.im
        );
    }

    #[test]
    fn inverse_undoes_forward() {
        let k = kin(5.0, 5.0);
        let d = Complex::new(3e-6f32, 1e-6);
        for kind in [
            SensorKind::Displacement,
            SensorKind::Velocity,
            SensorKind::Acceleration,
        ] {
            let c = Conversion::new(kind, &k);
            let back = c.to_displacement(c.from_displacement(d));
            assert!((back - d).norm() / d.norm() < 1e-6, "{kind:?}");
        }
    }
}
