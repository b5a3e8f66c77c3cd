//! End-to-end tests on synthetic run-downs with a closed-form shaft angle.
//!
//! The truth is the phasor the signal was built from (a displacement
//! Re{D·e^{iθ(t)}} and its exact time derivatives for seismic channels), not
//! a re-run of the extractor's formulas; signals and edge times are computed
//! in f64 and then rounded to f32 as an ADC and timer capture would deliver.
//!
//! This module is the harness (feed a run to an extractor, check its
//! outputs); `signal` is the truth, `accuracy`, `faults`, `interface` and
//! `noise` the tests.

extern crate std;

use super::*;
use core::f64::consts::TAU;
use std::vec::Vec;

mod accuracy;
mod faults;
mod interface;
mod noise;
mod signal;

use signal::*;

const FS: f64 = 51_200.0;

/// Everything a run produced.
struct Outcome<const N: usize> {
    events: Vec<Event<N>>,
    /// Times of the edges actually fed [samples], in order.
    edges: Vec<f64>,
}

impl<const N: usize> Outcome<N> {
    fn phasors(&self) -> impl Iterator<Item = &Phasors<N>> {
        self.events.iter().filter_map(|e| match e {
            Event::Phasors(p) => Some(p),
            Event::Fault(_) => None,
        })
    }
    fn faults(&self) -> Vec<FaultKind> {
        self.events
            .iter()
            .filter_map(|e| match e {
                Event::Fault(f) => Some(f.kind),
                Event::Phasors(_) => None,
            })
            .collect()
    }
    /// Duration [samples] of the R revolutions ending at the output's edge.
    fn duration(&self, p: &Phasors<N>) -> f64 {
        let end = p.revolution as usize - 1;
        self.edges[end] - self.edges[end - p.revolutions as usize]
    }
}

/// The extractor's default configuration at [`FS`] for `channels`' sensors.
fn configured<const N: usize>(channels: &[Channel; N]) -> ExtractorConfig<N> {
    ExtractorConfig::new(FS as f32, core::array::from_fn(|c| channels[c].sensor))
}

/// Feed `seconds` of the run-down to an extractor in blocks of `block`
/// samples; `edit` may drop or add edge times [samples] before feeding.
fn simulate<const N: usize>(
    config: ExtractorConfig<N>,
    shaft: RunDown,
    channels: &[Channel; N],
    seconds: f64,
    block: usize,
    edit: impl FnOnce(&mut Vec<f64>),
) -> Outcome<N> {
    simulate_with_noise(config, shaft, channels, seconds, block, edit, |_| 0.0)
}

/// [`simulate`] with `noise(channel)` [V] added to every sample.
fn simulate_with_noise<const N: usize>(
    config: ExtractorConfig<N>,
    shaft: RunDown,
    channels: &[Channel; N],
    seconds: f64,
    block: usize,
    edit: impl FnOnce(&mut Vec<f64>),
    mut noise: impl FnMut(usize) -> f64,
) -> Outcome<N> {
    let total = (seconds * FS) as usize;
    let mut edges: Vec<f64> = (0..)
        .map_while(|j| shaft.edge(j))
        .map(|t| t * FS)
        .take_while(|&p| p < total as f64 - 1.0)
        .collect();
    edit(&mut edges);
    let mut extractor = PhasorExtractor::new(config).expect("valid config");
    let mut events = Vec::new();
    let mut next_edge = 0;
    let mut samples = Vec::with_capacity(block);
    let mut marks = Vec::new();
    let mut start = 0;
    while start < total {
        let len = block.min(total - start);
        samples.clear();
        marks.clear();
        for i in 0..len {
            let k = start + i;
            let t = k as f64 / FS;
            samples.push(core::array::from_fn(|c| {
                (channels[c].volts(&shaft, t) + noise(c)) as f32
            }));
            // Edges in (k − 1, k] belong to sample k.
            while next_edge < edges.len() && edges[next_edge] <= k as f64 {
                let p = edges[next_edge];
                let fraction = (p - (k as f64 - 1.0)).clamp(0.0, 1.0 - 1e-7) as f32;
                marks.push(KeyphasorEdge { index: i, fraction });
                next_edge += 1;
            }
        }
        extractor
            .update_block(&samples, &marks, &mut |e| events.push(e))
            .expect("valid edges");
        start += len;
    }
    Outcome { events, edges }
}

fn relative_error(got: Phasor, want: (f64, f64)) -> f64 {
    let (dr, di) = (got.re as f64 - want.0, got.im as f64 - want.1);
    (dr * dr + di * di).sqrt() / (want.0 * want.0 + want.1 * want.1).sqrt()
}

/// Probe with a large gap voltage, 2X and 3X; a velocity pick-up and an
/// accelerometer with offsets and harmonics of their own.
fn three_sensors() -> [Channel; 3] {
    [
        Channel::new(Sensor::displacement(7870.0), (30e-6, -12e-6)).with_extras(
            -9.0,
            (0.2, 0.1),
            (-0.05, 0.08),
        ),
        Channel::new(Sensor::velocity(20.0), (-4e-6, 6e-6)).with_extras(
            0.01,
            (0.01, -0.02),
            (0.004, 0.0),
        ),
        Channel::new(Sensor::acceleration(0.1), (2e-6, 5e-6)).with_extras(
            0.02,
            (0.05, 0.01),
            (0.0, -0.03),
        ),
    ]
}

/// Every output's phasors and speed against the truth; returns the worst
/// relative phasor error per channel.
fn check<const N: usize>(run: &Outcome<N>, channels: &[Channel; N], tolerance: f64) -> [f64; N] {
    let mut worst = [0.0f64; N];
    for p in run.phasors() {
        let speed = FS * p.revolutions as f64 / run.duration(p);
        let speed_err = (p.speed_hz as f64 - speed).abs() / speed;
        assert!(speed_err < 1e-6, "speed {} Hz vs {speed} Hz", p.speed_hz);
        for c in 0..N {
            let err = relative_error(p.displacement[c], channels[c].d);
            assert!(
                err <= tolerance,
                "channel {c} at {speed:.3} Hz (revolution {}): relative error {err:.2e}",
                p.revolution
            );
            worst[c] = worst[c].max(err);
        }
    }
    worst
}
