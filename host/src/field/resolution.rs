//! The rounding a 1X vector table leaves on each phasor `plinth import`
//! makes of it: a floor under the noise, written to `resolution.csv`
//! ([`crate::rundir::resolution`]).
//!
//! A reading is printed as an amplitude A with its column's digits (unit in
//! the last place u_A) and a phase φ with its column's step u_φ (whole
//! degrees: 1°). Rounding to nearest leaves errors uniform on ±u/2,
//! independent: variance u_A²/12 along the phasor (radial) and
//! (A·u_φ)²/12 across it (tangential, u_φ in radians; small angles). Their
//! sum is E|n|² of the reading's complex error, whatever its direction. The
//! unit conversion multiplies the reading by a number c (its SI scale, then
//! 1/(iΩ) for a velocity or −1/Ω² for an acceleration): E|n|² by |c|². The
//! y/z resolution (`super::angle::resolve`) is Y = Σ_k w_k·D_k with real
//! weights w_k, so E|n_Y|² = Σ_k w_k²·E|n_k|² (readings rounded
//! independently): what `resolve` computes from the readings' sds.
//!
//! Whole-degree phases are the larger part: 1° is 1.75 % of the amplitude
//! (sd 0.50 %), 3 digits at most 1 % (sd 0.29 %). The rounding is not white
//! in speed (a phase that moves by less than a degree between speeds rounds
//! alike), so the scatter between neighbouring speeds reads it low; this
//! floor does not depend on it.

use super::units::AmplitudeUnit;
use crate::estimate::noise::ColumnDigits;
use plinth_shared::extractor::SensorKind;

/// The printing steps of one transducer's two columns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReadingSteps {
    /// The amplitude column's digits.
    pub amplitude: ColumnDigits,
    /// The phase column's digits (its unit in the last place is the step
    /// [deg]).
    pub phase: ColumnDigits,
}

impl ReadingSteps {
    /// The steps of a transducer's `amplitudes` and `phases` [deg] as read
    /// (every row of its columns): each column's digits, the fewest that
    /// reproduce every value ([`ColumnDigits::of`]).
    pub fn of(amplitudes: &[f64], phases: &[f64]) -> Self {
        Self {
            amplitude: ColumnDigits::of(amplitudes.iter().copied()),
            phase: ColumnDigits::of(phases.iter().copied()),
        }
    }

    /// sd [m] of the complex rounding error, sqrt(E|n|²), of the
    /// displacement phasor made of the reading (`amplitude` in `unit`,
    /// `phase_deg` [deg]) at `omega` [rad/s] (module docs).
    pub fn displacement_sd(
        &self,
        unit: &AmplitudeUnit,
        amplitude: f64,
        phase_deg: f64,
        omega: f64,
    ) -> f64 {
        let u_a = self.amplitude.ulp(amplitude);
        let u_phi = self.phase.ulp(phase_deg).to_radians();
        let reading = ((u_a * u_a + (amplitude * u_phi).powi(2)) / 12.0).sqrt();
        let conversion = match unit.kind {
            SensorKind::Displacement => 1.0,
            SensorKind::Velocity => 1.0 / omega,
            SensorKind::Acceleration => 1.0 / (omega * omega),
        };
        unit.to_si_zero_peak * conversion * reading
    }
}

#[cfg(test)]
mod tests {
    use super::super::angle::resolve;
    use super::super::units::{reading_phasor, to_displacement, PhaseConvention};
    use super::*;
    use num_complex::Complex;

    /// The floor against the rounding itself: readings of known phasors
    /// printed as a table prints them (3 significant digits, whole degrees),
    /// converted and resolved as `import` does, the mean square error over
    /// many phasors against the propagated E|n|².
    #[test]
    fn the_floor_is_the_mean_square_rounding_error_after_conversion_and_resolution() {
        let unit_um = AmplitudeUnit::parse("um pp").unwrap();
        let unit_vel = AmplitudeUnit::parse("mm/s pk").unwrap();
        let angles = [45.0, -45.0];
        let print3 = |x: f64| -> f64 { format!("{:.2e}", x).parse().unwrap() };
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for (unit, kind) in [(unit_um, "displacement"), (unit_vel, "velocity")] {
            let (mut error2, mut floor2) = ([0.0; 2], [0.0; 2]);
            let n = 4000;
            for _ in 0..n {
                let omega = 100.0 + 300.0 * uniform();
                // Two readings of amplitudes 0.1-10 and any phase.
                let truth: Vec<(f64, f64)> = (0..2)
                    .map(|_| (10f64.powf(2.0 * uniform() - 1.0), 360.0 * uniform()))
                    .collect();
                let printed: Vec<(f64, f64)> =
                    truth.iter().map(|&(a, p)| (print3(a), p.round())).collect();
                let disp = |r: &[(f64, f64)]| -> Vec<Complex<f64>> {
                    r.iter()
                        .map(|&(a, p)| {
                            let q =
                                reading_phasor(a * unit.to_si_zero_peak, p, PhaseConvention::Lag);
                            to_displacement(unit.kind, q, omega)
                        })
                        .collect()
                };
                let (exact, _) = resolve(&angles, &disp(&truth), None);
                // Steps as the columns give them: 3 digits, whole degrees.
                let steps = ReadingSteps {
                    amplitude: ColumnDigits::of([1.23, 0.456]),
                    phase: ColumnDigits::of([12.0, 345.0, 7.0]),
                };
                let sd: Vec<f64> = printed
                    .iter()
                    .map(|&(a, p)| steps.displacement_sd(&unit, a, p, omega))
                    .collect();
                let (rounded, floor) = resolve(&angles, &disp(&printed), Some(&sd));
                let floor = floor.unwrap();
                for ch in 0..2 {
                    error2[ch] += (rounded[ch] - exact[ch]).norm_sqr();
                    floor2[ch] += floor[ch] * floor[ch];
                }
            }
            for ch in 0..2 {
                // 4000 samples of a squared error: the mean within 5 %.
                let ratio = error2[ch] / floor2[ch];
                assert!(
                    (0.95..1.05).contains(&ratio),
                    "{kind} channel {ch}: {ratio}"
                );
            }
        }
    }
}
