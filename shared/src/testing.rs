//! Test helpers: reproducible Gaussian noise without a dependency.

use crate::phasor::Complex;
use core::f64::consts::{FRAC_1_SQRT_2, TAU};

/// Gaussian draws from xorshift64* and Box–Muller.
pub(crate) struct Gauss(pub u64);

impl Gauss {
    /// Uniform in (0, 1).
    pub fn uniform(&mut self) -> f64 {
        let s = &mut self.0;
        *s ^= *s >> 12;
        *s ^= *s << 25;
        *s ^= *s >> 27;
        ((s.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// Standard normal.
    pub fn next(&mut self) -> f64 {
        let (a, b) = (self.uniform(), self.uniform());
        libm::sqrt(-2.0 * libm::log(a)) * libm::cos(TAU * b)
    }

    /// Circular complex normal with E|n|² = `sd`².
    pub fn complex(&mut self, sd: f64) -> Complex<f64> {
        Complex::new(self.next(), self.next()) * (sd * FRAC_1_SQRT_2)
    }
}
