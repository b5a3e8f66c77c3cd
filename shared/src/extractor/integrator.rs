//! The revolution integrator: the angle-domain 1X integral of every channel
//! over one revolution, with fractional (trapezoid) weights at the keyphasor
//! edges and the once-per-revolution correction from the predicted to the
//! measured shaft angle.
//!
//! Per sample it does only the shared [`Rotator`] step and one complex
//! multiply-accumulate per channel, acc += x·g, into a chunk accumulator of
//! [`CHUNK`] samples. Each chunk is then added to one of [`SEGMENTS`]
//! per-revolution segment sums, chosen by the predicted angle. At the closing
//! edge, when the true revolution is known, each segment sum is rotated by
//! the angle error e^{−iφ} and scaled by the speed ratio θ'/θ̂' at its angle
//! centroid, which corrects a prediction error φ(t) = θ(t) − θ̂(t) up to
//! φ's variation within a segment. Measured (see the tests): a prediction
//! 0.13-0.24 rad off by the closing edge, with DC and 2X/3X riding on the 1X,
//! leaves 5e-5 relative error instead of 0.13-0.24 uncorrected.
//! Memory is fixed: N·(1 + SEGMENTS) complex sums (4.6 KiB for N = 8),
//! whatever the speed.

use super::rotator::{expi_neg, expi_neg_small, Rotator};
use super::shaft::ShaftModel;
use core::f32::consts::{FRAC_1_PI, TAU};
use num_complex::Complex;

/// Samples per chunk: how often the rotator is renormalised and the segment
/// chosen.
pub const CHUNK: u32 = 16;
/// Segment sums per revolution for the closing-edge correction.
pub const SEGMENTS: usize = 64;

const ZERO: Complex<f32> = Complex::new(0.0, 0.0);

/// The running 1X integral of N channels over the current revolution.
#[derive(Clone, Debug)]
pub struct RevolutionIntegrator<const N: usize> {
    /// Predicted shaft angle θ̂ of this revolution.
    model: ShaftModel,
    /// Segments per radian of predicted angle [1/rad].
    segments_per_rad: f32,
    /// Time of the revolution's first sample after its opening edge, 1 − u.
    t0: f32,
    /// Samples integrated since the opening edge.
    n: u32,
    rotator: Rotator,
    /// Σ x·g over the current chunk.
    chunk: [Complex<f32>; N],
    /// Samples in the current chunk.
    chunk_fill: u32,
    /// Segment the current chunk goes to.
    chunk_segment: usize,
    /// Σ x·g over each segment [sensor unit·rad].
    segments: [[Complex<f32>; N]; SEGMENTS],
    /// First and last sample time of each segment [samples]; empty when first > last.
    spans: [(f32, f32); SEGMENTS],
}

impl<const N: usize> Default for RevolutionIntegrator<N> {
    fn default() -> Self {
        Self {
            model: ShaftModel::constant(1.0),
            segments_per_rad: SEGMENTS as f32 / TAU,
            t0: 0.0,
            n: 0,
            rotator: Rotator::default(),
            chunk: [ZERO; N],
            chunk_fill: 0,
            chunk_segment: 0,
            segments: [[ZERO; N]; SEGMENTS],
            spans: [(f32::INFINITY, f32::NEG_INFINITY); SEGMENTS],
        }
    }
}

/// θ'(t)·e^{−i(θ(t) − offset)} for a time where that angle is small.
#[inline]
fn reference_near(model: &ShaftModel, t: f32, angle: f32) -> Complex<f32> {
    expi_neg_small(angle) * model.rate(t)
}

impl<const N: usize> RevolutionIntegrator<N> {
    /// Start a revolution at a keyphasor edge at `fraction` u ∈ [0, 1) of the
    /// interval between samples `previous` and `current` (sample vectors
    /// [sensor unit]), integrating along the predicted angle `model`. The
    /// segments share out the predicted angles 0…`reach` [rad], which should
    /// be the largest angle before the revolution times out
    /// (≈ 2π·(1 + tolerance)): one segment collecting everything beyond 2π
    /// would spoil the correction after a late edge.
    /// `current` must then be passed to [`Self::accumulate`] as usual: the
    /// opening trapezoid weights are completed here.
    pub fn start(
        &mut self,
        model: ShaftModel,
        reach: f32,
        fraction: f32,
        previous: &[f32; N],
        current: &[f32; N],
    ) {
        let u = fraction;
        self.model = model;
        self.segments_per_rad = SEGMENTS as f32 / reach.max(TAU);
        self.t0 = 1.0 - u;
        self.n = 0;
        self.chunk = [ZERO; N];
        self.chunk_fill = 0;
        self.chunk_segment = 0;
        self.segments = [[ZERO; N]; SEGMENTS];
        self.spans = [(f32::INFINITY, f32::NEG_INFINITY); SEGMENTS];
        self.rotator = Rotator::start(&model, self.t0);
        // Trapezoid over [−u·h… the edge, first sample] with the integrand at
        // the edge interpolated linearly: weights (1−u)²/2 on the previous
        // sample and (1−u)(1+u)/2 + ½ = 1 − u²/2 on the current one, of which
        // accumulate() adds the 1.
        let g_prev = reference_near(&model, -u, model.angle(-u)) * (0.5 * (1.0 - u) * (1.0 - u));
        let g_cur = reference_near(&model, self.t0, model.angle(self.t0)) * (-0.5 * u * u);
        for c in 0..N {
            self.segments[0][c] = g_prev * previous[c] + g_cur * current[c];
        }
        self.spans[0] = (-u, -u);
    }

    /// Time of the next sample to integrate, after the opening edge [samples].
    #[inline]
    pub fn next_time(&self) -> f32 {
        self.n as f32 + self.t0
    }

    /// The per-sample path: integrate consecutive sample vectors [sensor unit].
    pub fn accumulate(&mut self, mut samples: &[[f32; N]]) {
        while !samples.is_empty() {
            if self.chunk_fill == 0 {
                self.open_chunk();
            }
            let room = (CHUNK - self.chunk_fill) as usize;
            let take = room.min(samples.len());
            let (now, rest) = samples.split_at(take);
            self.accumulate_chunk(now);
            samples = rest;
            self.chunk_fill += take as u32;
            self.n += take as u32;
            if self.chunk_fill == CHUNK {
                self.flush_chunk();
            }
        }
    }

    /// The hot loop: one shared rotator step and one complex multiply-add
    /// (two multiply-adds) per channel and sample.
    #[inline(always)]
    fn accumulate_chunk(&mut self, samples: &[[f32; N]]) {
        let mut acc = self.chunk;
        let mut rotator = self.rotator;
        for x in samples {
            let g = rotator.update();
            for c in 0..N {
                acc[c].re += x[c] * g.re;
                acc[c].im += x[c] * g.im;
            }
        }
        self.chunk = acc;
        self.rotator = rotator;
    }

    fn open_chunk(&mut self) {
        let t = self.next_time();
        if self.n > 0 {
            self.rotator.resync(&self.model, t);
        }
        let middle = self.model.angle(t + 0.5 * CHUNK as f32);
        let index = libm::floorf(middle * self.segments_per_rad);
        self.chunk_segment = if index > 0.0 {
            (index as usize).min(SEGMENTS - 1)
        } else {
            0
        };
    }

    fn flush_chunk(&mut self) {
        if self.chunk_fill == 0 {
            return;
        }
        let m = self.chunk_segment;
        for c in 0..N {
            self.segments[m][c] += self.chunk[c];
        }
        self.chunk = [ZERO; N];
        let first = (self.n - self.chunk_fill) as f32 + self.t0;
        let last = (self.n - 1) as f32 + self.t0;
        let span = &mut self.spans[m];
        span.0 = span.0.min(first);
        span.1 = span.1.max(last);
        self.chunk_fill = 0;
    }

    /// Close the revolution at a keyphasor edge at `fraction` u of the
    /// interval between samples `previous` (already integrated) and
    /// `current` (not yet), once its true shaft angle `actual` is known
    /// (θ(period) = 2π, `period` [samples]). Writes each channel's 1X
    /// phasor with respect to the shaft angle,
    /// Q = (1/π)∫₀^{2π} x(θ)·e^{−iθ} dθ [sensor unit], to `out`.
    pub fn close(
        &mut self,
        actual: &ShaftModel,
        period: f32,
        fraction: f32,
        previous: &[f32; N],
        current: &[f32; N],
        out: &mut [Complex<f32>; N],
    ) {
        self.flush_chunk();
        let predicted = self.model;
        let d_speed = actual.speed - predicted.speed;
        let d_accel = actual.accel - predicted.accel;
        *out = [ZERO; N];
        for m in 0..SEGMENTS {
            let (first, last) = self.spans[m];
            if first > last {
                continue;
            }
            let t = predicted.angle_centroid(first - 0.5, last + 0.5);
            // φ(t) = θ(t) − θ̂(t) without cancellation.
            let phi = t * (d_speed + 0.5 * d_accel * t);
            let rate = predicted.rate(t);
            let scale = if rate > 0.0 {
                actual.rate(t) / rate
            } else {
                1.0
            };
            let rho = expi_neg(phi) * scale;
            for c in 0..N {
                out[c] += self.segments[m][c] * rho;
            }
        }
        // Closing trapezoid: the previous sample had weight 1, it needs
        // ½ + u − u²/2; the current one gets u²/2. Angles are taken from the
        // true model, relative to 2π.
        let u = fraction;
        let end_rate = actual.rate(period);
        let near = |delta: f32| delta * (end_rate + 0.5 * actual.accel * delta);
        let g_prev = reference_near(actual, period - u, near(-u)) * (u - 0.5 * u * u - 0.5);
        let g_cur = reference_near(actual, period + 1.0 - u, near(1.0 - u)) * (0.5 * u * u);
        for c in 0..N {
            out[c] = (out[c] + g_prev * previous[c] + g_cur * current[c]) * FRAC_1_PI;
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    /// One revolution of x(θ) = Re{Q e^{iθ}} + DC + 2X + 3X along a true
    /// quadratic angle, integrated along `predicted`, closed with
    /// `close_with`. Returns the relative error of the 1X phasor and the
    /// prediction's angle error at the closing edge [rad].
    fn one_revolution(
        truth: ShaftModel,
        predicted: ShaftModel,
        close_with: ShaftModel,
    ) -> (f64, f64) {
        let q = (0.7f64, -0.4f64);
        let u_open = 0.37f64;
        let period = truth.period().unwrap() as f64;
        let speed = truth.speed as f64;
        let accel = truth.accel as f64;
        let signal = |t: f64| {
            let th = t * (speed + 0.5 * accel * t);
            q.0 * th.cos() - q.1 * th.sin()
                + 2.5
                + 0.8 * (2.0 * th + 0.3).cos()
                + 0.5 * (3.0 * th - 1.0).cos()
        };
        // The opening edge is between samples −1 and 0 at u_open, so sample
        // k sits at t = k + 1 − u_open.
        let time = |k: i64| k as f64 + 1.0 - u_open;
        let last = (period - (1.0 - u_open)).floor() as i64; // last sample before the closing edge
        let u_close = period - time(last);
        let xs: Vec<[f32; 1]> = (-1..=last + 1).map(|k| [signal(time(k)) as f32]).collect();
        let mut integ = RevolutionIntegrator::<1>::default();
        integ.start(predicted, 1.05 * TAU, u_open as f32, &xs[0], &xs[1]);
        // Feed in uneven blocks.
        let body = &xs[1..xs.len() - 1];
        let (a, b) = body.split_at(body.len() / 3);
        integ.accumulate(a);
        integ.accumulate(b);
        let mut out = [ZERO; 1];
        let n = xs.len();
        integ.close(
            &close_with,
            period as f32,
            u_close as f32,
            &xs[n - 2],
            &xs[n - 1],
            &mut out,
        );
        let (re, im) = (out[0].re as f64, out[0].im as f64);
        let err = ((re - q.0).powi(2) + (im - q.1).powi(2)).sqrt() / (q.0 * q.0 + q.1 * q.1).sqrt();
        let phi = (predicted.angle(period as f32) - truth.angle(period as f32)) as f64;
        (err, phi.abs())
    }

    fn truth(hz: f64) -> ShaftModel {
        // Decelerating 5 Hz/s at 51.2 kHz.
        ShaftModel {
            speed: (TAU as f64 * hz / 51_200.0) as f32,
            accel: -(TAU as f64 * 5.0 / (51_200.0f64 * 51_200.0)) as f32,
        }
    }

    #[test]
    fn exact_prediction_gives_the_angle_domain_phasor() {
        // 37.3 Hz: 1372.65 samples per revolution.
        let truth = truth(37.3);
        let (err, _) = one_revolution(truth, truth, truth);
        assert!(err < 1e-5, "{err:e}");
    }

    #[test]
    fn closing_correction_repairs_a_wrong_prediction() {
        // Predictions 0.2 % to 2 % fast with no deceleration at 12 Hz: the
        // angle is 0.02 to 0.2 rad off by the end of the revolution, with a
        // DC 3× and 2X, 3X as large as the 1X riding along.
        let truth = truth(12.0);
        for error in [0.002f32, 0.005, 0.01, 0.02] {
            let predicted = ShaftModel {
                speed: truth.speed * (1.0 + error),
                accel: 0.0,
            };
            let (corrected, phi) = one_revolution(truth, predicted, truth);
            let (uncorrected, _) = one_revolution(truth, predicted, predicted);
            std::println!("angle error {phi:.3} rad: corrected {corrected:.1e}, uncorrected {uncorrected:.1e}");
            // The residual is second order in the angle error per segment and
            // first order in the DC and harmonics: ≤ 1e-3 × the angle error.
            assert!(
                corrected < 1e-3 * phi + 1e-5,
                "corrected {corrected:e} at {phi} rad"
            );
            // Without the correction the error is the angle error itself: the
            // test does exercise the correction.
            assert!(
                uncorrected > 0.3 * phi,
                "uncorrected {uncorrected:e} at {phi} rad"
            );
        }
    }
}
