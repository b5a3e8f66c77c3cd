//! End-to-end tests on synthetic run-downs with a closed-form shaft angle.
//!
//! The truth is the phasor the signal was built from (a displacement
//! Re{D·e^{iθ(t)}} and its exact time derivatives for seismic channels), not
//! a re-run of the extractor's formulas; signals and edge times are computed
//! in f64 and then rounded to f32 as an ADC and timer capture would deliver.

extern crate std;

use super::*;
use core::f64::consts::TAU;
use std::vec::Vec;

mod noise;

const FS: f64 = 51_200.0;

/// A shaft whose speed falls linearly: f(t) = f0 − rate·t [Hz], with the
/// keyphasor at shaft angle 2π·(j + offset) for t ≥ 0, j = 0, 1, ….
#[derive(Clone, Copy)]
struct RunDown {
    f0: f64,
    rate: f64,
    offset: f64,
}

impl RunDown {
    /// Shaft angle from the keyphasor mark [rad] at time `t` [s].
    fn angle(&self, t: f64) -> f64 {
        TAU * (self.f0 * t - 0.5 * self.rate * t * t - self.offset)
    }
    /// dθ/dt [rad/s].
    fn omega(&self, t: f64) -> f64 {
        TAU * (self.f0 - self.rate * t)
    }
    /// d²θ/dt² [rad/s²].
    fn alpha(&self) -> f64 {
        -TAU * self.rate
    }
    /// Time of keyphasor edge j [s], in closed form.
    fn edge(&self, j: u32) -> Option<f64> {
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
enum Envelope {
    /// D·(1 + g₁φ + g₂φ²/2), φ = θ + 2π·offset the shaft angle since t = 0
    /// [rad]; g₁ per rad, g₂ per rad².
    Growth { g1: C64, g2: C64 },
    /// D·r²/(1 − r² + 2iζr), r = f/`natural_hz`: an unbalance response
    /// through a resonance, D its high-speed limit.
    Resonance { natural_hz: f64, zeta: f64 },
}

type C64 = num_complex::Complex<f64>;

/// One synthetic channel: the displacement it sees and what rides on top.
#[derive(Clone, Copy)]
struct Channel {
    sensor: Sensor,
    /// Displacement phasor [m] (scaled by the envelope).
    d: (f64, f64),
    /// Offset [V].
    dc: f64,
    /// 2X and 3X phasors in the shaft angle [V].
    h2: (f64, f64),
    h3: (f64, f64),
    /// How D changes (constant when `None`).
    envelope: Option<Envelope>,
}

impl Channel {
    fn new(sensor: Sensor, d: (f64, f64)) -> Self {
        Self {
            sensor,
            d,
            dc: 0.0,
            h2: (0.0, 0.0),
            h3: (0.0, 0.0),
            envelope: None,
        }
    }
    fn with_extras(mut self, dc: f64, h2: (f64, f64), h3: (f64, f64)) -> Self {
        self.dc = dc;
        self.h2 = h2;
        self.h3 = h3;
        self
    }
    fn with_envelope(mut self, envelope: Envelope) -> Self {
        self.envelope = Some(envelope);
        self
    }
    /// The displacement phasor [m] at shaft speed `f` [Hz] and shaft angle
    /// since t = 0 `phi` [rad].
    fn displacement(&self, f: f64, phi: f64) -> C64 {
        self.derivatives(f, phi, 0.0)[0]
    }
    /// D, dD/dθ and d²D/dθ² at speed `f` [Hz], angle since t = 0 `phi`
    /// [rad] and angular acceleration `alpha` [rad/s²].
    fn derivatives(&self, f: f64, phi: f64, alpha: f64) -> [C64; 3] {
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
    fn volts(&self, shaft: &RunDown, t: f64) -> f64 {
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

#[test]
fn constant_speed_with_non_integer_samples_per_revolution() {
    let channels = three_sensors();
    for f in [5.3, 37.3, 199.7] {
        let shaft = RunDown {
            f0: f,
            rate: 0.0,
            offset: 0.41,
        };
        let run = simulate(
            ExtractorConfig::new(FS as f32, channels.map(|c| c.sensor)),
            shaft,
            &channels,
            12.0 / f,
            1000,
            |_| {},
        );
        let n = run.phasors().count();
        assert!(n >= 6, "{f} Hz: only {n} outputs");
        assert!(run.faults().is_empty(), "{:?}", run.faults());
        let worst = check(&run, &channels, 1e-4);
        std::println!(
            "{f} Hz: worst relative errors {:.1e} {:.1e} {:.1e}",
            worst[0],
            worst[1],
            worst[2]
        );
    }
}

#[test]
fn run_down_200_to_5_hz_at_5_hz_per_s() {
    let channels = three_sensors();
    let shaft = RunDown {
        f0: 200.0,
        rate: 5.0,
        offset: 0.73,
    };
    let run = simulate(
        ExtractorConfig::new(FS as f32, channels.map(|c| c.sensor)),
        shaft,
        &channels,
        39.0,
        4096,
        |_| {},
    );
    assert!(run.faults().is_empty(), "{:?}", run.faults());
    // Every revolution but the first acquisition ones and the one still held back.
    let outputs = run.phasors().count();
    assert!(
        outputs + 6 >= run.edges.len(),
        "{outputs} outputs from {} edges",
        run.edges.len()
    );
    // Worst error per speed band, down to the slowest revolutions.
    let bands = [(150.0, 201.0), (50.0, 150.0), (15.0, 50.0), (5.0, 15.0)];
    for (lo, hi) in bands {
        let mut worst = [0.0f64; 3];
        let mut count = 0;
        for p in run
            .phasors()
            .filter(|p| p.speed_hz >= lo && p.speed_hz < hi)
        {
            count += 1;
            for c in 0..3 {
                worst[c] = worst[c].max(relative_error(p.displacement[c], channels[c].d));
            }
        }
        std::println!(
            "{lo}-{hi} Hz: {count} revolutions, worst relative errors {:.1e} {:.1e} {:.1e}",
            worst[0],
            worst[1],
            worst[2]
        );
        assert!(count > 0, "no revolution in {lo}-{hi} Hz");
    }
    check(&run, &channels, 1e-4);
}

#[test]
fn dc_and_harmonics_are_rejected_during_the_run_down() {
    // The same channel with and without a DC 10× and 2X, 3X as large as the
    // 1X: the difference must be below the accuracy target.
    let clean = Channel::new(Sensor::displacement(1.0), (1.0, 0.5));
    let dirty = clean.with_extras(11.0, (1.0, -0.7), (-0.6, 0.9));
    let channels = [clean, dirty];
    let shaft = RunDown {
        f0: 60.0,
        rate: 5.0,
        offset: 0.2,
    };
    let run = simulate(
        ExtractorConfig::new(FS as f32, channels.map(|c| c.sensor)),
        shaft,
        &channels,
        11.0,
        777,
        |_| {},
    );
    let worst = check(&run, &channels, 1e-4);
    std::println!("clean {:.1e}, with DC+2X+3X {:.1e}", worst[0], worst[1]);
    assert!(run.phasors().count() > 200);
}

#[test]
fn missing_pulse_is_flagged_and_tracking_recovers() {
    let channels = three_sensors();
    let shaft = RunDown {
        f0: 40.0,
        rate: 5.0,
        offset: 0.5,
    };
    let dropped = 60;
    let run = simulate(
        ExtractorConfig::new(FS as f32, channels.map(|c| c.sensor)),
        shaft,
        &channels,
        4.0,
        1000,
        |e| {
            e.remove(dropped);
        },
    );
    assert_eq!(run.faults(), [FaultKind::MissingPulse]);
    // Nothing garbled came out, and outputs resume after the gap.
    check(&run, &channels, 1e-4);
    let after = run
        .phasors()
        .filter(|p| p.revolution as usize > dropped + 1)
        .count();
    assert!(after > 50, "{after} outputs after the missing pulse");
    // The revolution spanning the gap (ids dropped and dropped+1) was not emitted.
    assert!(run.phasors().all(|p| p.revolution as usize != dropped + 1));
}

#[test]
fn extra_pulse_is_flagged_and_tracking_recovers() {
    let channels = three_sensors();
    let shaft = RunDown {
        f0: 40.0,
        rate: 5.0,
        offset: 0.5,
    };
    // A glitch in mid-revolution, and one just before the true edge (which
    // passes the period check and is only caught by the next revolution).
    for position in [0.4, 0.985] {
        let run = simulate(
            ExtractorConfig::new(FS as f32, channels.map(|c| c.sensor)),
            shaft,
            &channels,
            4.0,
            1000,
            |e| {
                let p = e[70] + position * (e[71] - e[70]);
                e.insert(71, p);
            },
        );
        let faults = run.faults();
        assert_eq!(
            faults.first(),
            Some(&FaultKind::ExtraPulse),
            "{position}: {faults:?}"
        );
        check(&run, &channels, 1e-4);
        let after = run.phasors().filter(|p| p.revolution > 75).count();
        assert!(
            after > 35,
            "{position}: {after} outputs after the extra pulse"
        );
        // Neither revolution touching the glitch (closed by edge counts 72,
        // the glitch, and 73) was emitted.
        assert!(
            run.phasors().all(|p| !(72..=73).contains(&p.revolution)),
            "{position}"
        );
    }
}

#[test]
fn timeout_when_the_keyphasor_stops() {
    let channels = [Channel::new(Sensor::displacement(1.0), (1.0, 0.0))];
    let shaft = RunDown {
        f0: 20.0,
        rate: 0.0,
        offset: 0.1,
    };
    let run = simulate(
        ExtractorConfig::new(FS as f32, [channels[0].sensor]),
        shaft,
        &channels,
        3.0,
        512,
        |e| {
            e.truncate(20);
        },
    );
    // While tracking, the first missing edge is flagged once; the extractor
    // then waits for a new edge without further events.
    assert_eq!(run.faults(), [FaultKind::MissingPulse]);
    check(&run, &channels, 1e-4);
    assert!(run.phasors().all(|p| p.revolution <= 20));
    // While acquiring (two edges seen), silence beyond 1/min_speed_hz is a timeout.
    let run = simulate(
        ExtractorConfig::new(FS as f32, [channels[0].sensor]),
        shaft,
        &channels,
        3.0,
        512,
        |e| {
            e.truncate(2);
        },
    );
    assert_eq!(run.faults(), [FaultKind::Timeout]);
    assert_eq!(run.phasors().count(), 0);
}

#[test]
fn averaging_over_r_revolutions() {
    // D grows with shaft angle, so each revolution has its own phasor: the
    // average must be the mean of the R displacements in the middle of each
    // revolution and the speed R over their duration.
    let growth = 1e-3; // per rad
    let channel =
        Channel::new(Sensor::displacement(1.0), (0.8, -0.3)).with_envelope(Envelope::Growth {
            g1: C64::new(growth, 0.0),
            g2: C64::new(0.0, 0.0),
        });
    let shaft = RunDown {
        f0: 30.0,
        rate: 5.0,
        offset: 0.6,
    };
    let r = 4u16;
    let mut config = ExtractorConfig::new(FS as f32, [channel.sensor]);
    config.revolutions_per_output = r;
    let run = simulate(config, shaft, &[channel], 3.0, 2048, |_| {});
    let mut outputs = 0;
    let mut last_id = 0;
    for p in run.phasors() {
        assert_eq!(p.revolutions, r);
        // Edge count c is the edge at θ = 2π(c − 1); the R revolutions of this
        // output are those closed by edges c − R + 1 … c, revolution n
        // starting at θ = 2π(n − 1), i.e. φ = 2π(n − 1 + offset).
        let mut want = C64::new(0.0, 0.0);
        for n in (p.revolution - r as u32)..p.revolution {
            let mid = TAU * (n as f64 - 1.0 + shaft.offset) + core::f64::consts::PI;
            want += channel.displacement(0.0, mid);
        }
        let want = want / r as f64;
        let err = relative_error(p.displacement[0], (want.re, want.im));
        assert!(err < 1e-5, "revolution {}: {err:.2e}", p.revolution);
        let speed = FS * r as f64 / run.duration(p);
        assert!((p.speed_hz as f64 - speed).abs() / speed < 1e-6);
        assert!(p.revolution >= last_id + r as u32);
        last_id = p.revolution;
        outputs += 1;
    }
    assert!(outputs >= 15, "{outputs}");
}

/// The three sensors through a resonance (ζ = 2 %) during a run-down at
/// `rate` [Hz/s]: every revolution's displacement phasor against the
/// response at the revolution's speed, relative to the peak response.
fn through_a_resonance(rate: f64) -> [f64; 3] {
    let resonance = Envelope::Resonance {
        natural_hz: 45.0,
        zeta: 0.02,
    };
    let channels = three_sensors().map(|c| c.with_envelope(resonance));
    let shaft = RunDown {
        f0: 60.0,
        rate,
        offset: 0.37,
    };
    let run = simulate(
        ExtractorConfig::new(FS as f32, channels.map(|c| c.sensor)),
        shaft,
        &channels,
        25.0 / rate,
        4096,
        |_| {},
    );
    assert!(run.faults().is_empty(), "{:?}", run.faults());
    let mut worst = [0.0f64; 3];
    let mut count = 0;
    for p in run.phasors() {
        let f = p.speed_hz as f64;
        count += 1;
        for (c, ch) in channels.iter().enumerate() {
            let want = ch.displacement(f, 0.0);
            let peak = C64::new(ch.d.0, ch.d.1).norm() / (2.0 * 0.02);
            let got = C64::new(p.displacement[c].re as f64, p.displacement[c].im as f64);
            worst[c] = worst[c].max((got - want).norm() / peak);
        }
    }
    assert!(
        count as f64 > 0.9 * 25.0 * 45.0 / rate,
        "{count} revolutions"
    );
    std::println!(
        "{rate} Hz/s through 45 Hz, ζ = 2 %: worst error / peak {:.1e} {:.1e} {:.1e}",
        worst[0],
        worst[1],
        worst[2]
    );
    worst
}

#[test]
fn a_field_run_down_through_a_resonance_gives_the_response_at_speed() {
    // 1 Hz/s: a large machine coasting down; the phasor changes by up to
    // 2.5 % per revolution at the peak.
    for (c, w) in through_a_resonance(1.0).iter().enumerate() {
        assert!(*w < 1e-4, "channel {c}: {w:.2e}");
    }
}

#[test]
fn a_fast_run_down_through_a_resonance_gives_the_response_at_speed() {
    // 4 Hz/s: up to 10 % per revolution; the cubic remainder grows as the
    // cube of that.
    for (c, w) in through_a_resonance(4.0).iter().enumerate() {
        assert!(*w < 1e-3, "channel {c}: {w:.2e}");
    }
}

#[test]
fn sample_by_sample_equals_block_feeding() {
    let channels = three_sensors();
    let shaft = RunDown {
        f0: 90.0,
        rate: 5.0,
        offset: 0.3,
    };
    let config = ExtractorConfig::new(FS as f32, channels.map(|c| c.sensor));
    let blocks = simulate(config, shaft, &channels, 0.4, 333, |_| {});
    let single = simulate(config, shaft, &channels, 0.4, 1, |_| {});
    assert!(blocks.phasors().count() > 20);
    assert_eq!(blocks.events, single.events);
}

#[test]
fn bad_edges_are_rejected_before_anything_happens() {
    let mut x =
        PhasorExtractor::new(ExtractorConfig::new(51_200.0, [Sensor::displacement(1.0)])).unwrap();
    let samples = [[0.0f32]; 4];
    let mut sink = |_e: Event<1>| panic!("no event expected");
    let edge = |index, fraction| KeyphasorEdge { index, fraction };
    assert_eq!(
        x.update_block(&samples, &[edge(4, 0.5)], &mut sink),
        Err(InputError::EdgeIndex { edge: 0 })
    );
    assert_eq!(
        x.update_block(&samples, &[edge(1, 0.5), edge(2, f32::NAN)], &mut sink),
        Err(InputError::EdgeFraction { edge: 1 })
    );
    assert_eq!(
        x.update_block(&samples, &[edge(1, 1.0)], &mut sink),
        Err(InputError::EdgeFraction { edge: 0 })
    );
    assert_eq!(
        x.update_block(&samples, &[edge(2, 0.5), edge(1, 0.5)], &mut sink),
        Err(InputError::EdgeOrder { edge: 1 })
    );
    assert_eq!(x.sample_index(), 0, "a rejected block is not consumed");
}

#[test]
fn bad_configurations_are_named() {
    let ok = ExtractorConfig::new(
        51_200.0,
        [Sensor::displacement(1.0), Sensor::velocity(20.0)],
    );
    assert!(PhasorExtractor::new(ok).is_ok());
    let mut c = ok;
    c.sensors[1].sensitivity = 0.0;
    assert_eq!(
        PhasorExtractor::new(c).err(),
        Some(ConfigError::Sensitivity { channel: 1 })
    );
    let mut c = ok;
    c.max_speed_hz = 1000.0;
    assert_eq!(PhasorExtractor::new(c).err(), Some(ConfigError::SpeedRange));
    let mut c = ok;
    c.sample_rate_hz = f32::NAN;
    assert_eq!(PhasorExtractor::new(c).err(), Some(ConfigError::SampleRate));
    let mut c = ok;
    c.revolutions_per_output = 0;
    assert_eq!(
        PhasorExtractor::new(c).err(),
        Some(ConfigError::Revolutions)
    );
    let mut c = ok;
    c.period_tolerance = 0.7;
    assert_eq!(
        PhasorExtractor::new(c).err(),
        Some(ConfigError::PeriodTolerance)
    );
}
