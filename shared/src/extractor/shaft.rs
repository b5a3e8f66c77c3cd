//! The shaft-angle model between keyphasor edges: constant angular
//! acceleration, so the angle is quadratic in time.
//!
//! Times are in sample units (1 = one sample interval), angles in rad. A
//! revolution's model is θ(t) = ω₀·t + ½·α·t² with t = 0 at its opening
//! keyphasor edge, so θ = 2π at its closing edge.

use core::f32::consts::TAU;

/// When a keyphasor edge happened, in sample units: between absolute sample
/// `sample − 1` and `sample`, a `fraction` ∈ [0, 1) of that interval after
/// sample `sample − 1`. Its time is `sample − 1 + fraction` [samples].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeTime {
    /// Absolute index of the first sample after the edge.
    pub sample: u64,
    /// Position of the edge inside the sample interval before `sample` [0, 1).
    pub fraction: f32,
}

impl EdgeTime {
    /// Time from `earlier` to `self` [samples]. Exact to f32 rounding as long
    /// as the two edges are less than 2²⁴ samples apart.
    #[inline]
    pub fn since(self, earlier: EdgeTime) -> f32 {
        let whole = self.sample.wrapping_sub(earlier.sample) as f32;
        whole + (self.fraction - earlier.fraction)
    }
}

/// Quadratic shaft angle of one revolution: θ(t) = `speed`·t + ½·`accel`·t²
/// [rad], t [samples] from the revolution's opening keyphasor edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShaftModel {
    /// Angular speed at the opening edge [rad/sample].
    pub speed: f32,
    /// Angular acceleration, negative in a run-down [rad/sample²].
    pub accel: f32,
}

impl ShaftModel {
    /// Constant speed: one revolution every `period` samples.
    pub fn constant(period: f32) -> Self {
        Self {
            speed: TAU / period,
            accel: 0.0,
        }
    }

    /// The constant-acceleration model through three consecutive keyphasor
    /// edges, for the revolution between the second and the third: the one
    /// before lasted `previous` samples, this one `current` samples. It gives
    /// θ(−previous) = −2π, θ(0) = 0, θ(current) = 2π exactly.
    pub fn fit(previous: f32, current: f32) -> Self {
        let accel = 2.0 * TAU * (previous - current) / (previous * current * (previous + current));
        let speed = TAU / current - 0.5 * accel * current;
        Self { speed, accel }
    }

    /// Shaft angle at time `t` [samples] after the opening edge [rad].
    #[inline]
    pub fn angle(&self, t: f32) -> f32 {
        t * (self.speed + 0.5 * self.accel * t)
    }

    /// Angular speed at time `t` [samples] after the opening edge [rad/sample].
    #[inline]
    pub fn rate(&self, t: f32) -> f32 {
        self.speed + self.accel * t
    }

    /// The same motion seen from the next revolution, when this one lasted
    /// `period` samples: speed at its opening edge, same acceleration.
    pub fn advance(&self, period: f32) -> Self {
        Self {
            speed: self.rate(period),
            accel: self.accel,
        }
    }

    /// Duration of this revolution, the t > 0 where θ(t) = 2π [samples];
    /// `None` when the shaft would stop (or turn backwards) before.
    pub fn period(&self) -> Option<f32> {
        // ½·α·T² + ω₀·T − 2π = 0, in the form without cancellation.
        let discriminant = self.speed * self.speed + 2.0 * TAU * self.accel;
        if !(self.speed > 0.0 && discriminant > 0.0) {
            return None;
        }
        let period = 2.0 * TAU / (self.speed + libm::sqrtf(discriminant));
        period.is_finite().then_some(period)
    }

    /// Angle-weighted mean time of the interval [t0, t1] [samples],
    /// ∫ t·θ'(t) dt / ∫ θ'(t) dt: the time at which the interval's shaft
    /// angle is centred.
    pub fn angle_centroid(&self, t0: f32, t1: f32) -> f32 {
        let sum = t0 + t1;
        let squares = t1 * t1 + t1 * t0 + t0 * t0;
        let numerator = 0.5 * self.speed * sum + self.accel * squares / 3.0;
        let denominator = self.speed + 0.5 * self.accel * sum;
        if denominator > 0.0 {
            numerator / denominator
        } else {
            0.5 * sum
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_passes_through_the_three_edges() {
        let m = ShaftModel::fit(1000.0, 1010.0);
        assert!((m.angle(-1000.0) + TAU).abs() < 1e-5);
        assert!(m.angle(0.0).abs() < 1e-7);
        assert!((m.angle(1010.0) - TAU).abs() < 1e-5);
        assert!(m.accel < 0.0, "a longer revolution means deceleration");
        // The next revolution is predicted longer still.
        let next = m.advance(1010.0).period().unwrap();
        assert!(next > 1010.0 && next < 1021.0, "{next}");
    }

    #[test]
    fn period_inverts_the_angle() {
        let m = ShaftModel {
            speed: 0.01,
            accel: -2e-7,
        };
        let t = m.period().unwrap();
        assert!((m.angle(t) - TAU).abs() < 1e-5);
        let stopping = ShaftModel {
            speed: 0.001,
            accel: -1e-6,
        };
        assert_eq!(stopping.period(), None);
    }

    #[test]
    fn centroid_of_constant_speed_is_the_midpoint() {
        let m = ShaftModel::constant(500.0);
        assert!((m.angle_centroid(10.0, 30.0) - 20.0).abs() < 1e-5);
        // With deceleration the angle is front-loaded: centroid before the middle.
        let d = ShaftModel {
            speed: 0.01,
            accel: -1e-5,
        };
        assert!(d.angle_centroid(0.0, 100.0) < 50.0);
    }
}
