//! Shared by the firmware tests: a synthetic run-down of one bearing and
//! pedestal (exact 1X phasors from eq. 2 and eq. 3, sampled as the box's ADC
//! would see them), and a protocol client that talks to the box over any
//! byte stream.
#![allow(dead_code)]

use num_complex::Complex;
use plinth_shared::bearing::BearingCoefficients;
use plinth_shared::protocol::{
    Averaging, BearingTableChunk, BearingTableRow, ChannelConfig, ChannelSet, DeviceMessage, Hello,
    HostMessage, KeyphasorEdge, Quantity, Receiver, SampleBlock, Samples, SensorKind, Transmitter,
    MAX_BLOCK_VALUES, MAX_FRAME_SIZE, PROTOCOL_VERSION,
};
use std::f64::consts::TAU;

/// Proximity-probe sensitivity [V/m] (7.87 V/mm).
pub const PROBE_V_PER_M: f64 = 7870.0;
/// Sample rate of the box [Hz].
pub const FS: f64 = 51_200.0;
/// ADC step for the ±10 V range [V].
pub const VOLTS_PER_CODE: f64 = 10.0 / 32768.0;

/// A pedestal (eq. 3) under a bearing (eq. 2), and the speed profile.
#[derive(Clone, Copy, Debug)]
pub struct Scenario {
    /// θ = (k_y [N/m], k_z [N/m], m [kg], c_y, c_z [N·s/m]).
    pub pedestal: [f64; 5],
    /// Speed-independent bearing coefficients.
    pub bearing: BearingCoefficients<f64>,
    /// Start and end speed [Hz], linear in time.
    pub speed_start_hz: f64,
    /// End speed [Hz].
    pub speed_end_hz: f64,
    /// Duration [s].
    pub duration_s: f64,
}

impl Scenario {
    /// Two pedestal resonances (≈ 36.8 and 31.8 Hz) inside a 60 → 25 Hz
    /// run-down at −14 Hz/s, damping ratio ≈ 8 % (so that a run-down this
    /// fast, 0.4 Hz per revolution, still sees the steady-state response:
    /// at ζ = 2 % the phasor would change by half within a revolution).
    pub fn standard() -> Self {
        let mut bearing = BearingCoefficients::isotropic(1.0e7, 2.0e3);
        bearing.k[0][1] = 1.5e6;
        bearing.k[1][0] = -1.5e6;
        Self {
            pedestal: [8.0e6, 6.0e6, 150.0, 5500.0, 4800.0],
            bearing,
            speed_start_hz: 60.0,
            speed_end_hz: 25.0,
            duration_s: 2.5,
        }
    }

    /// The same machine over a shorter run-down, 45 → 28 Hz in 1.2 s
    /// (still through both resonances; half the data, for QEMU).
    pub fn short() -> Self {
        Self {
            speed_start_hz: 45.0,
            speed_end_hz: 28.0,
            duration_s: 1.2,
            ..Self::standard()
        }
    }

    /// Speed at time t [Hz].
    pub fn speed_hz(&self, t: f64) -> f64 {
        self.speed_start_hz + (self.speed_end_hz - self.speed_start_hz) * t / self.duration_s
    }

    /// Shaft angle at time t [rad], 0 at t = 0.
    pub fn angle(&self, t: f64) -> f64 {
        let a = (self.speed_end_hz - self.speed_start_hz) / self.duration_s;
        TAU * (self.speed_start_hz * t + 0.5 * a * t * t)
    }

    /// Times of the keyphasor edges (angle = 2πk) [s], k = 1, 2, ...
    pub fn keyphasor_times(&self) -> Vec<f64> {
        let a = (self.speed_end_hz - self.speed_start_hz) / self.duration_s;
        let f0 = self.speed_start_hz;
        let mut out = Vec::new();
        for k in 1.. {
            // f0 t + a t²/2 = k  →  t = (−f0 + sqrt(f0² + 2ak)) / a
            let disc = f0 * f0 + 2.0 * a * k as f64;
            if disc < 0.0 {
                break;
            }
            let t = if a.abs() < 1e-12 {
                k as f64 / f0
            } else {
                (-f0 + disc.sqrt()) / a
            };
            if t > self.duration_s {
                break;
            }
            out.push(t);
        }
        out
    }

    /// Rotor-relative 1X displacement at the bearing (y, z) [m]: a smooth,
    /// speed-dependent unbalance-like response of ~10-30 µm.
    pub fn rel(&self, speed_hz: f64) -> [Complex<f64>; 2] {
        let s = speed_hz / 60.0;
        [
            Complex::from_polar(2.0e-5 * s * s, 0.3 + speed_hz / 40.0),
            Complex::from_polar(1.5e-5 * s * s, -0.7 + speed_hz / 55.0),
        ]
    }

    /// Force on the pedestal (eq. 2) [N].
    pub fn force(&self, speed_hz: f64) -> [Complex<f64>; 2] {
        self.bearing.force(TAU * speed_hz, &self.rel(speed_hz))
    }

    /// Absolute pedestal displacement (eq. 3 solved for it) [m].
    pub fn ped(&self, speed_hz: f64) -> [Complex<f64>; 2] {
        let w = TAU * speed_hz;
        let [ky, kz, m, cy, cz] = self.pedestal;
        let f = self.force(speed_hz);
        [
            f[0] / Complex::new(ky - w * w * m, w * cy),
            f[1] / Complex::new(kz - w * w * m, w * cz),
        ]
    }

    /// Probe voltages [V] at time t on channels (rel y, rel z, ped y, ped z):
    /// Re{Q·e^{iθ}} × sensitivity plus a gap-voltage DC offset on the rel
    /// probes and a 2X component, which the extractor must reject.
    pub fn volts(&self, t: f64) -> [f64; 4] {
        let f = self.speed_hz(t);
        let theta = self.angle(t);
        let e = Complex::from_polar(1.0, theta);
        let rel = self.rel(f);
        let ped = self.ped(f);
        let x = |q: Complex<f64>| (q * e).re;
        let two_x = 3.0e-6 * (2.0 * theta + 0.4).cos();
        [
            (x(rel[0]) + two_x) * PROBE_V_PER_M - 2.0,
            (x(rel[1]) - two_x) * PROBE_V_PER_M - 2.5,
            x(ped[0]) * PROBE_V_PER_M,
            x(ped[1]) * PROBE_V_PER_M,
        ]
    }

    /// The true 1X phasors (rel y, rel z, ped y, ped z) [m] of revolution
    /// `r` (between keyphasor edges r and r + 1 of
    /// [`Scenario::keyphasor_times`], 0-based): the steady-state response at
    /// the revolution's mean speed [Hz], which is returned with them.
    pub fn revolution_phasors(&self, r: usize) -> Option<([Complex<f64>; 4], f64)> {
        let kt = self.keyphasor_times();
        let (t0, t1) = (*kt.get(r)?, *kt.get(r + 1)?);
        let speed = 1.0 / (t1 - t0);
        let (rel, ped) = (self.rel(speed), self.ped(speed));
        Some(([rel[0], rel[1], ped[0], ped[1]], speed))
    }

    /// The whole run as replay blocks of raw ADC codes (4 channels, 24
    /// sample vectors per block), with the keyphasor edges inside each.
    pub fn blocks(&self) -> Vec<SampleBlock> {
        let channels = 4usize;
        let per_block = MAX_BLOCK_VALUES / channels;
        let total = (self.duration_s * FS) as usize;
        let edges = self.keyphasor_times();
        let mut next_edge = 0;
        let mut out = Vec::new();
        let mut first = 0usize;
        while first + per_block <= total {
            let mut codes = heapless::Vec::<i16, MAX_BLOCK_VALUES>::new();
            for k in first..first + per_block {
                for v in self.volts(k as f64 / FS) {
                    let c = (v / VOLTS_PER_CODE).round().clamp(-32768.0, 32767.0) as i16;
                    codes.push(c).unwrap();
                }
            }
            let mut kp = heapless::Vec::new();
            while next_edge < edges.len() {
                let pos = edges[next_edge] * FS - first as f64;
                if pos >= per_block as f64 {
                    break;
                }
                kp.push(KeyphasorEdge {
                    offset_samples: pos as f32,
                })
                .unwrap();
                next_edge += 1;
            }
            out.push(SampleBlock {
                first_sample: first as u32,
                channels: channels as u8,
                samples: Samples::AdcCodes(codes),
                keyphasor_edges: kp,
            });
            first += per_block;
        }
        out
    }

    /// The configuration commands for bearing 0, in sending order: channels
    /// 0-3 = rel y, rel z, ped y, ped z; averaging; the bearing table.
    pub fn configuration(&self) -> Vec<HostMessage> {
        let q = [
            Quantity::RelY,
            Quantity::RelZ,
            Quantity::PedY,
            Quantity::PedZ,
        ];
        let mut set = ChannelSet {
            channels: heapless::Vec::new(),
        };
        for (i, quantity) in q.into_iter().enumerate() {
            set.channels
                .push(ChannelConfig {
                    channel: i as u8,
                    kind: SensorKind::Displacement,
                    sensitivity: PROBE_V_PER_M as f32,
                    bearing: 0,
                    quantity,
                })
                .unwrap();
        }
        let coefficients = self.bearing.cast::<f32>();
        let rows: Vec<BearingTableRow> = [1.0f32, 100.0, 400.0]
            .iter()
            .map(|&speed_hz| BearingTableRow {
                speed_hz,
                coefficients,
            })
            .collect();
        let mut out = vec![
            HostMessage::ConfigureChannels(set),
            HostMessage::ConfigureAveraging(Averaging {
                revolutions_per_phasor: 1,
            }),
        ];
        out.extend(
            BearingTableChunk::split(0, &rows)
                .unwrap()
                .map(HostMessage::BearingTable),
        );
        out
    }
}

/// The host end of the protocol over some byte transport.
pub struct Client {
    pub tx: Transmitter,
    pub rx: Receiver<DeviceMessage>,
    /// Every message received, in order.
    pub received: Vec<DeviceMessage>,
}

impl Default for Client {
    fn default() -> Self {
        Self::new()
    }
}

impl Client {
    pub fn new() -> Self {
        Self {
            tx: Transmitter::new(),
            rx: Receiver::new(),
            received: Vec::new(),
        }
    }

    /// Encodes `m` as the next frame; returns (seq, wire bytes).
    pub fn encode(&mut self, m: &HostMessage) -> (u32, Vec<u8>) {
        let mut buf = [0u8; MAX_FRAME_SIZE];
        let (seq, bytes) = self.tx.encode(m, &mut buf).expect("encodable");
        (seq, bytes.to_vec())
    }

    /// A `Hello`: restarts the host's sequence numbers and forgets the
    /// box's (its `HelloAck` is frame 0 of the new session).
    pub fn hello(&mut self, nonce: u32) -> (u32, Vec<u8>) {
        self.tx.restart();
        self.rx.reset();
        self.encode(&HostMessage::Hello(Hello {
            protocol_version: PROTOCOL_VERSION,
            host_nonce: nonce,
        }))
    }

    /// Feeds received bytes; returns how many messages they completed.
    pub fn feed(&mut self, bytes: &[u8]) -> usize {
        let mut n = 0;
        for event in self.rx.feed(bytes) {
            let frame = event.unwrap_or_else(|e| panic!("link error from the box: {e:?}"));
            self.received.push(frame.message);
            n += 1;
        }
        n
    }
}
