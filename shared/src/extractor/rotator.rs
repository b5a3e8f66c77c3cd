//! The recursive complex reference oscillator that follows the predicted
//! shaft angle, so the per-sample path needs no trigonometric call.
//!
//! For the quadratic model θ(t) = ω₀·t + ½·α·t² the angle step from sample to
//! sample grows by α each sample, so the reference is a *chirp* rotator:
//! r ← r·s and s ← s·e^{−iα}, with r = e^{−iθ(t)} and s = e^{−iΔ(t)},
//! Δ(t) = θ(t+1) − θ(t). It also carries the angle weight w = θ'(t) that
//! turns the time integral into an integral over the shaft angle.
//!
//! f32 error budget: every product rounds |r| by ~6e-8 relative, which a
//! renormalisation every [`super::integrator::CHUNK`] samples removes; the
//! step s is recomputed exactly from the model at the same time (a Taylor
//! series, Δ is small), so the phase of r drifts only by the rounding random
//! walk, ~6e-8·√(samples) rad (≈ 6e-6 rad over a 10240-sample revolution).

use super::shaft::ShaftModel;
use num_complex::Complex;

/// e^{−ix} for small |x| [rad] by its Taylor series: relative error below
/// 1e-9 for |x| ≤ 0.2 (the series is truncated after x⁹).
#[inline]
pub fn expi_neg_small(x: f32) -> Complex<f32> {
    let x2 = x * x;
    let cos = 1.0 - x2 * (0.5 - x2 * (1.0 / 24.0 - x2 * (1.0 / 720.0 - x2 / 40320.0)));
    let sin =
        x * (1.0 - x2 * (1.0 / 6.0 - x2 * (1.0 / 120.0 - x2 * (1.0 / 5040.0 - x2 / 362880.0))));
    Complex::new(cos, -sin)
}

/// e^{−ix} for finite x [rad] with |x| ≤ 1e4 (once-per-revolution use
/// only): the Taylor series when |x| ≤ 0.2, otherwise reduced to the nearest
/// quadrant, x = k·π/2 + r with |r| ≤ π/4 (Cody–Waite: π/2 in three parts,
/// k·C₁ exact), and the series to r¹³ rotated by (−i)ᵏ; error ≲ 2e-7.
/// libm's `sincosf` would do as well but links its f64 reduction for
/// arguments up to 1e38 (3.4 KiB of flash with the soft-float it needs),
/// which angles bounded by a revolution never use.
#[inline]
pub fn expi_neg(x: f32) -> Complex<f32> {
    if libm::fabsf(x) <= 0.2 {
        return expi_neg_small(x);
    }
    const C1: f32 = 1.570_312_5;
    const C2: f32 = 4.837_513e-4;
    const C3: f32 = 7.549_79e-8;
    let k = libm::roundf(x * core::f32::consts::FRAC_2_PI);
    let r = ((x - k * C1) - k * C2) - k * C3;
    let r2 = r * r;
    let cos = 1.0
        - r2 * (0.5
            - r2 * (1.0 / 24.0
                - r2 * (1.0 / 720.0
                    - r2 * (1.0 / 40_320.0 - r2 * (1.0 / 3_628_800.0 - r2 / 479_001_600.0)))));
    let sin = r
        * (1.0
            - r2 * (1.0 / 6.0
                - r2 * (1.0 / 120.0
                    - r2 * (1.0 / 5_040.0
                        - r2 * (1.0 / 362_880.0
                            - r2 * (1.0 / 39_916_800.0 - r2 / 6_227_020_800.0))))));
    // e^{−ir}·(−i)ᵏ; NaN or infinite x gives a NaN k and phasor.
    match (k as i32) & 3 {
        0 => Complex::new(cos, -sin),
        1 => Complex::new(-sin, -cos),
        2 => Complex::new(-cos, sin),
        _ => Complex::new(sin, cos),
    }
}

/// The reference g(t) = θ̂'(t)·e^{−iθ̂(t)} [rad/sample] of the predicted
/// shaft angle θ̂, advanced one sample per [`Rotator::update`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rotator {
    /// e^{−iθ̂(t)} at the current sample.
    r: Complex<f32>,
    /// e^{−iΔ(t)}: the rotation to the next sample.
    s: Complex<f32>,
    /// e^{−iα}: how the step changes per sample (the chirp).
    chirp: Complex<f32>,
    /// θ̂'(t) at the current sample [rad/sample].
    weight: f32,
    /// α [rad/sample²].
    accel: f32,
}

impl Default for Rotator {
    fn default() -> Self {
        Self {
            r: Complex::new(1.0, 0.0),
            s: Complex::new(1.0, 0.0),
            chirp: Complex::new(1.0, 0.0),
            weight: 0.0,
            accel: 0.0,
        }
    }
}

impl Rotator {
    /// A rotator on `model` at time `t` [samples], |θ̂(t)| ≤ 0.2 rad (the
    /// first sample of a revolution).
    pub fn start(model: &ShaftModel, t: f32) -> Self {
        let mut rotator = Self {
            r: expi_neg_small(model.angle(t)),
            chirp: expi_neg_small(model.accel),
            accel: model.accel,
            ..Self::default()
        };
        rotator.resync(model, t);
        rotator
    }

    /// Once per chunk: restore |r| = 1 and recompute the step and the weight
    /// exactly from `model` at the current time `t` [samples].
    pub fn resync(&mut self, model: &ShaftModel, t: f32) {
        // One Newton step of 1/√(|r|²) about 1: |r|² − 1 is ~1e-6, so the
        // result is unit to ~1e-12.
        let norm = self.r.re * self.r.re + self.r.im * self.r.im;
        self.r *= 1.5 - 0.5 * norm;
        self.s = expi_neg_small(model.rate(t + 0.5));
        self.weight = model.rate(t);
    }

    /// The reference at the current sample, θ̂'·e^{−iθ̂} [rad/sample]; then
    /// advance to the next sample. 8 multiplies and 5 adds, shared by every
    /// channel.
    #[inline(always)]
    pub fn update(&mut self) -> Complex<f32> {
        let g = Complex::new(self.r.re * self.weight, self.r.im * self.weight);
        self.r *= self.s;
        self.s *= self.chirp;
        self.weight += self.accel;
        g
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reduced_series_matches_sincos_over_many_turns() {
        let mut worst = 0.0f64;
        for k in -2_000_000..=2_000_000 {
            let x = k as f32 * 5e-3; // ±10⁴ rad, every quadrant
            let e = expi_neg(x);
            let want = (x as f64).cos();
            let err = (e.re as f64 - want)
                .abs()
                .max((e.im as f64 + (x as f64).sin()).abs());
            worst = worst.max(err / (1.0 + (x as f64).abs() * 1e-4));
        }
        assert!(worst < 3e-7, "worst {worst:e}");
        assert!(expi_neg(f32::NAN).re.is_nan());
        assert!(expi_neg(f32::INFINITY).im.is_nan());
    }

    #[test]
    fn taylor_matches_sincos() {
        for k in -20..=20 {
            let x = k as f64 * 0.01;
            let e = expi_neg_small(x as f32);
            assert!((e.re as f64 - x.cos()).abs() < 1e-7, "{x}");
            assert!((e.im as f64 + x.sin()).abs() < 1e-7, "{x}");
        }
    }

    #[test]
    fn rotator_follows_a_chirp_over_a_long_revolution() {
        // 5 Hz at 51.2 kHz decelerating 5 Hz/s: the hardest case, 10240+
        // samples per revolution. Compare with the angle in f64.
        let fs = 51_200.0f64;
        let speed = core::f64::consts::TAU * 5.0 / fs;
        let accel = -core::f64::consts::TAU * 5.0 / (fs * fs);
        let model = ShaftModel {
            speed: speed as f32,
            accel: accel as f32,
        };
        let t0 = 0.3f32;
        let mut rotator = Rotator::start(&model, t0);
        let mut worst = 0.0f64;
        for n in 0..12_000u32 {
            let t = n as f32 + t0;
            if n > 0 && n % 32 == 0 {
                rotator.resync(&model, t);
            }
            let g = rotator.update();
            let td = n as f64 + t0 as f64;
            let theta = td * (model.speed as f64 + 0.5 * model.accel as f64 * td);
            let w = model.speed as f64 + model.accel as f64 * td;
            let (gre, gim) = (w * theta.cos(), -w * theta.sin());
            let err = ((g.re as f64 - gre).powi(2) + (g.im as f64 - gim).powi(2)).sqrt() / w;
            worst = worst.max(err);
        }
        assert!(worst < 1e-5, "relative reference error {worst:e}");
    }
}
