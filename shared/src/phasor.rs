//! 1X phasors: complex amplitudes of synchronous (once-per-revolution) motion.
//!
//! Convention (formats.md): a signal q(t) has phasor Q when
//! q(t) = Re{Q · e^{iΩt}}, with t = 0 at the keyphasor pulse.

pub use num_complex::Complex;

/// A 1X phasor in single precision, as computed on the field box.
pub type Phasor = Complex<f32>;

/// The (y, z) pair of 1X phasors at one bearing: y vertical, z horizontal [m].
pub type Phasor2<T = f32> = [Complex<T>; 2];

/// Rotor speed in rad/s from speed in Hz (rev/s): Ω = 2π·f.
#[inline]
pub fn omega_from_hz<T: num_traits::Float>(speed_hz: T) -> T {
    let two_pi = T::from(core::f64::consts::TAU).unwrap_or_else(T::zero);
    two_pi * speed_hz
}

/// Peak-to-peak amplitude [same unit as the phasor] and phase lag [deg] of a
/// phasor, as field instruments print them: q(t) = A/2·cos(Ωt − lag).
#[inline]
pub fn peak_to_peak_and_lag_deg(q: Complex<f64>) -> (f64, f64) {
    let amplitude = q.norm();
    let lag = -q.arg().to_degrees();
    let lag = lag % 360.0;
    (2.0 * amplitude, if lag < 0.0 { lag + 360.0 } else { lag })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lag_of_a_delayed_cosine_is_positive() {
        // q(t) = cos(Ωt − 30°) has phasor e^{−i30°}: a 30° lag.
        let q = Complex::from_polar(1.0, -30f64.to_radians());
        let (pp, lag) = peak_to_peak_and_lag_deg(q);
        assert!((pp - 2.0).abs() < 1e-12);
        assert!((lag - 30.0).abs() < 1e-9);
    }

    #[test]
    fn omega_is_two_pi_f() {
        assert!((omega_from_hz(50.0f64) - 100.0 * core::f64::consts::PI).abs() < 1e-12);
    }
}
