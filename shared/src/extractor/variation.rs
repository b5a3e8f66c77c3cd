//! Phasors that change from revolution to revolution: the run-down
//! correction.
//!
//! During a run-down the 1X displacement phasor D itself changes with speed
//! (near a resonance by several percent per revolution). Over revolution j,
//! in the shaft angle u = θ − π measured from the revolution's middle, write
//! D(u) = D₀ + D₁·u + D₂·u²/2 + D₃·u³/6 (Dₖ per radianᵏ). The extractor's
//! per-revolution phasor, converted to displacement by
//! [`Conversion`](super::Conversion) (exact only for a constant D), is then
//!
//! D̃ = D₀ + Σₖ (aₖ·Dₖ + bₖ·D̄ₖ),  k = 1, 2, 3,
//!
//! where the b terms are the −1X part of the real signal leaking through a
//! one-revolution window while the envelope changes, and the a terms are what
//! a seismic pick-up sees of the change itself (velocity Ω·(iD + dD/dθ),
//! acceleration Ω²·(d²D/dθ² + 2i·dD/dθ − D)):
//!
//! | sensor       | a₁  | b₁   | a₂       | b₂   | a₃     | b₃             |
//! |--------------|-----|------|----------|------|--------|----------------|
//! | displacement | 0   | i/2  | π²/6     | 1/4  | 0      | i(π²/12 − 1/8) |
//! | velocity     | −i  | −i/2 | π²/6     | 1/4  | −iπ²/6 | −i(π²/12 + 1/8)|
//! | acceleration | −2i | i/2  | π²/6 − 1 | −3/4 | −iπ²/3 | i(π²/12 − 1/8) |
//!
//! (at the revolution's mean speed; the terms in dΩ/dt·D₁ are smaller by
//! α/Ω², below 1e-3 for any realistic run-down above 10 Hz). Over the
//! revolutions j−2 … j+1 the sequence of D̃ is a cubic in the revolution
//! number whose third difference is (2π)³·D₃, whose second difference is
//! (2π)²·(D₂ + a₁D₃ + b₁D̄₃) and whose central difference is
//! D₁ + (2π)²D₃/6 + a₁D₂ + b₁D̄₂ + a₂D₃ + b₂D̄₃; solving these from the top down and then
//! the table for D₀ gives the displacement phasor in the middle of the
//! revolution: what the simulator calls the response at the revolution's
//! speed. With fewer revolutions before (just after lock-on) the cubic, then
//! the quadratic term is taken as 0. For an accelerometer passing a
//! resonance with ζ = 2 % at 1 Hz/s the uncorrected D̃ is off by
//! 2|D₁| ≈ 0.8 % of D; corrected, by the quartic remainder, ~1e-6. The
//! differences amplify per-revolution noise by about 1.3×.

use super::SensorKind;
use crate::phasor::Phasor;
use core::f32::consts::PI;

/// How a revolution's constant-D phasor D̃ depends on the change of D within
/// it (the table in the module documentation): a₁ … b₃.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Coefficients {
    a: [Phasor; 3],
    b: [Phasor; 3],
}

impl Coefficients {
    /// The coefficients for sensor `kind`.
    fn of(kind: SensorKind) -> Self {
        let c = |re: f32, im: f32| Phasor::new(re, im);
        let pi2 = PI * PI;
        let (sixth, twelfth) = (pi2 / 6.0, pi2 / 12.0);
        match kind {
            SensorKind::Displacement => Self {
                a: [c(0.0, 0.0), c(sixth, 0.0), c(0.0, 0.0)],
                b: [c(0.0, 0.5), c(0.25, 0.0), c(0.0, twelfth - 0.125)],
            },
            SensorKind::Velocity => Self {
                a: [c(0.0, -1.0), c(sixth, 0.0), c(0.0, -sixth)],
                b: [c(0.0, -0.5), c(0.25, 0.0), c(0.0, -(twelfth + 0.125))],
            },
            SensorKind::Acceleration => Self {
                a: [c(0.0, -2.0), c(sixth - 1.0, 0.0), c(0.0, -pi2 / 3.0)],
                b: [c(0.0, 0.5), c(-0.75, 0.0), c(0.0, twelfth - 0.125)],
            },
        }
    }

    /// aₖ·z + bₖ·z̄ for k = 1, 2, 3 (`k` from 1).
    #[inline]
    fn term(&self, k: usize, z: Phasor) -> Phasor {
        self.a[k - 1] * z + self.b[k - 1] * z.conj()
    }
}

/// The displacement phasor [m] in the middle of a revolution from the
/// constant-D phasors [m] of that revolution (`this`), the one after it
/// (`next`) and the two before it (`earlier` = [j−2, j−1], each `None`
/// unless contiguous), for a channel with a `kind` sensor. Allocation-free,
/// about a hundred flops.
pub fn mid_revolution(
    kind: SensorKind,
    earlier: [Option<Phasor>; 2],
    this: Phasor,
    next: Phasor,
) -> Phasor {
    let k = Coefficients::of(kind);
    let h = 2.0 * PI;
    let zero = Phasor::new(0.0, 0.0);
    let (d1, d2, d3) = match earlier {
        [Some(two), Some(one)] => {
            let d3 = (next - this * 3.0 + one * 3.0 - two) * (1.0 / (h * h * h));
            let d2 = (next - this * 2.0 + one) * (1.0 / (h * h)) - k.term(1, d3);
            let central = (next - one) * (1.0 / (2.0 * h));
            let d1 = central - d3 * (h * h / 6.0) - k.term(1, d2) - k.term(2, d3);
            (d1, d2, d3)
        }
        [None, Some(one)] => {
            let d2 = (next - this * 2.0 + one) * (1.0 / (h * h));
            let central = (next - one) * (1.0 / (2.0 * h));
            (central - k.term(1, d2), d2, zero)
        }
        [_, None] => ((next - this) * (1.0 / h), zero, zero),
    };
    this - k.term(1, d1) - k.term(2, d2) - k.term(3, d3)
}

#[cfg(test)]
mod tests {
    use super::*;

    const KINDS: [SensorKind; 3] = [
        SensorKind::Displacement,
        SensorKind::Velocity,
        SensorKind::Acceleration,
    ];

    /// D̃ of a revolution centred `shift` radians from u = 0 for the cubic
    /// D(u) = d0 + d1·u + d2·u²/2 + d3·u³/6: the table applied to the local
    /// expansion there.
    fn constant_d(kind: SensorKind, d: [Phasor; 4], shift: f32) -> Phasor {
        let k = Coefficients::of(kind);
        let [d0, d1, d2, d3] = d;
        let s = shift;
        let l0 = d0 + d1 * s + d2 * (s * s / 2.0) + d3 * (s * s * s / 6.0);
        let l1 = d1 + d2 * s + d3 * (s * s / 2.0);
        let l2 = d2 + d3 * s;
        l0 + k.term(1, l1) + k.term(2, l2) + k.term(3, d3)
    }

    fn envelope(order: usize) -> [Phasor; 4] {
        let all = [
            Phasor::new(0.3, -0.7),
            Phasor::new(0.02, 0.05),
            Phasor::new(-0.004, 0.003),
            Phasor::new(0.0007, 0.0009),
        ];
        core::array::from_fn(|i| {
            if i <= order {
                all[i]
            } else {
                Phasor::new(0.0, 0.0)
            }
        })
    }

    fn at(kind: SensorKind, d: [Phasor; 4], s: f32) -> Phasor {
        constant_d(kind, d, 2.0 * PI * s)
    }

    #[test]
    fn four_revolutions_recover_a_cubic_envelope_exactly() {
        let d = envelope(3);
        for kind in KINDS {
            let got = mid_revolution(
                kind,
                [Some(at(kind, d, -2.0)), Some(at(kind, d, -1.0))],
                at(kind, d, 0.0),
                at(kind, d, 1.0),
            );
            assert!((got - d[0]).norm() < 2e-6, "{kind:?}: {got}");
        }
    }

    #[test]
    fn three_revolutions_recover_a_quadratic_envelope_exactly() {
        let d = envelope(2);
        for kind in KINDS {
            let got = mid_revolution(
                kind,
                [None, Some(at(kind, d, -1.0))],
                at(kind, d, 0.0),
                at(kind, d, 1.0),
            );
            assert!((got - d[0]).norm() < 1e-6, "{kind:?}: {got}");
        }
    }

    #[test]
    fn two_revolutions_recover_a_linear_envelope_exactly() {
        let d = envelope(1);
        for kind in KINDS {
            let got = mid_revolution(kind, [None, None], at(kind, d, 0.0), at(kind, d, 1.0));
            assert!((got - d[0]).norm() < 1e-6, "{kind:?}: {got}");
        }
    }

    #[test]
    fn a_constant_phasor_is_left_alone() {
        let d = Phasor::new(-2e-6, 5e-6);
        for kind in KINDS {
            assert_eq!(mid_revolution(kind, [Some(d), Some(d)], d, d), d);
            assert_eq!(mid_revolution(kind, [None, Some(d)], d, d), d);
            assert_eq!(mid_revolution(kind, [None, None], d, d), d);
        }
    }
}
