//! The closed-form truth the tests feed the extractor: a shaft whose speed
//! falls linearly (angle and keyphasor edges in closed form) and channels
//! whose signal is built from a known displacement phasor, its envelope
//! and its exact time derivatives.

use crate::extractor::{Sensor, SensorKind};
use core::f64::consts::TAU;

/// A shaft whose speed falls linearly: f(t) = f0 − rate·t [Hz], with the
/// keyphasor at shaft angle 2π·(j + offset) for t ≥ 0, j = 0, 1, ….
#[derive(Clone, Copy)]
pub(super) struct RunDown {
    /// Speed at t = 0 [Hz].
    pub(super) f0: f64,
    /// Deceleration [Hz/s].
    pub(super) rate: f64,
    /// Keyphasor mark in revolutions after the shaft angle's zero.
    pub(super) offset: f64,
}

impl RunDown {
    /// Shaft angle from the keyphasor mark [rad] at time `t` [s].
    pub(super) fn angle(&self, t: f64) -> f64 {
        TAU * (self.f0 * t - 0.5 * self.rate * t * t - self.offset)
    }
    /// dθ/dt [rad/s].
    pub(super) fn omega(&self, t: f64) -> f64 {
        TAU * (self.f0 - self.rate * t)
    }
    /// d²θ/dt² [rad/s²].
    pub(super) fn alpha(&self) -> f64 {
        -TAU * self.rate
    }
    /// Time of keyphasor edge j [s], in closed form.
    pub(super) fn edge(&self, j: u32) -> Option<f64> {
        let revs = j as f64 + self.offset;
        if self.rate == 0.0 {
            return Some(revs / self.f0);
        }
        let disc = self.f0 * self.f0 - 2.0 * self.rate * revs;
        (disc > 0.0).then(|| 2.0 * revs / (self.f0 + disc.sqrt()))
    }
}

/// How a channel's displacement phasor changes during the run-down.
#[derive(Clone, Copy)]
pub(super) enum Envelope {
    /// D·(1 + g₁φ + g₂φ²/2), φ = θ + 2π·offset the shaft angle since t = 0
    /// [rad]; g₁ per rad, g₂ per rad².
    Growth { g1: C64, g2: C64 },
    /// D·r²/(1 − r² + 2iζr), r = f/`natural_hz`: an unbalance response
    /// through a resonance, D its high-speed limit.
    Resonance { natural_hz: f64, zeta: f64 },
}

pub(super) type C64 = num_complex::Complex<f64>;

/// One synthetic channel: the displacement it sees and what rides on top.
#[derive(Clone, Copy)]
pub(super) struct Channel {
    /// The transducer and its sensitivity.
    pub(super) sensor: Sensor,
    /// Displacement phasor [m] (scaled by the envelope).
    pub(super) d: (f64, f64),
    /// Offset [V].
    dc: f64,
    /// 2X and 3X phasors in the shaft angle [V].
    h2: (f64, f64),
    h3: (f64, f64),
    /// How D changes (constant when `None`).
    envelope: Option<Envelope>,
}

impl Channel {
    /// A channel seeing the constant displacement phasor `d` [m] and nothing else.
    pub(super) fn new(sensor: Sensor, d: (f64, f64)) -> Self {
        Self {
            sensor,
            d,
            dc: 0.0,
            h2: (0.0, 0.0),
            h3: (0.0, 0.0),
            envelope: None,
        }
    }
    /// The channel with an offset `dc` and 2X, 3X phasors `h2`, `h3` [V].
    pub(super) fn with_extras(mut self, dc: f64, h2: (f64, f64), h3: (f64, f64)) -> Self {
        self.dc = dc;
        self.h2 = h2;
        self.h3 = h3;
        self
    }
    /// The channel with its displacement changing by `envelope`.
    pub(super) fn with_envelope(mut self, envelope: Envelope) -> Self {
        self.envelope = Some(envelope);
        self
    }
    /// The displacement phasor [m] at shaft speed `f` [Hz] and shaft angle
    /// since t = 0 `phi` [rad].
    pub(super) fn displacement(&self, f: f64, phi: f64) -> C64 {
        self.derivatives(f, phi, 0.0)[0]
    }
    /// D, dD/dθ and d²D/dθ² at speed `f` [Hz], angle since t = 0 `phi`
    /// [rad] and angular acceleration `alpha` [rad/s²].
    pub(super) fn derivatives(&self, f: f64, phi: f64, alpha: f64) -> [C64; 3] {
        let d = C64::new(self.d.0, self.d.1);
        match self.envelope {
            None => [d, C64::new(0.0, 0.0), C64::new(0.0, 0.0)],
            Some(Envelope::Growth { g1, g2 }) => [
                d * (1.0 + g1 * phi + g2 * (phi * phi / 2.0)),
                d * (g1 + g2 * phi),
                d * g2,
            ],
            Some(Envelope::Resonance { natural_hz, zeta }) => {
                // H(r) = r²/(1 − r² + 2iζr); derivatives in r, then the
                // chain rule: dr/dθ = α/(Ω·ω_n), d²r/dθ² = −α²/(Ω³·ω_n).
                let r = f / natural_hz;
                let den = C64::new(1.0 - r * r, 2.0 * zeta * r);
                let dden = C64::new(-2.0 * r, 2.0 * zeta);
                let h = r * r / den;
                let dh = (2.0 * r * den - r * r * dden) / (den * den);
                // H = N/den with N = r²: H'' = (N'' − 2H'·den' − H·den'')/den.
                let d2h = (2.0 - 2.0 * dh * dden - h * (-2.0)) / den;
                let omega = TAU * f;
                let wn = TAU * natural_hz;
                let r1 = alpha / (omega * wn);
                let r2 = -alpha * alpha / (omega * omega * omega * wn);
                [d * h, d * dh * r1, d * (d2h * r1 * r1 + dh * r2)]
            }
        }
    }
    /// The sensor output [V] at time `t` [s].
    pub(super) fn volts(&self, shaft: &RunDown, t: f64) -> f64 {
        let th = shaft.angle(t);
        let (w, a) = (shaft.omega(t), shaft.alpha());
        let [d, d1, d2] = self.derivatives(w / TAU, th + TAU * shaft.offset, a);
        let i = C64::i();
        // The envelope of x, v = dx/dt, a = dv/dt with d/dt = Ω·d/dθ.
        let envelope = match self.sensor.kind {
            SensorKind::Displacement => d,
            SensorKind::Velocity => w * (i * d + d1),
            SensorKind::Acceleration => a * (d1 + i * d) + w * w * (d2 + 2.0 * i * d1 - d),
        };
        let physical = (envelope * C64::from_polar(1.0, th)).re;
        let harmonic = |k: f64, h: (f64, f64)| h.0 * (k * th).cos() - h.1 * (k * th).sin();
        self.sensor.sensitivity as f64 * physical
            + self.dc
            + harmonic(2.0, self.h2)
            + harmonic(3.0, self.h3)
    }
}
