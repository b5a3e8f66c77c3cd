//! Protocol tests: round trips, capacity, corruption, resynchronisation and
//! sequence accounting.

extern crate std;

use std::vec::Vec;

use super::*;
use crate::bearing::BearingCoefficients;
use crate::regression::ParameterScale;

/// Deterministic xorshift64 (Marsaglia) for test data.
struct XorShift(u64);

impl XorShift {
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    fn byte(&mut self) -> u8 {
        (self.next() >> 24) as u8
    }
}

fn vec_of<T: Clone, const N: usize>(items: &[T]) -> heapless::Vec<T, N> {
    heapless::Vec::from_slice(items).expect("test data fits")
}

fn coefficients(s: f32) -> BearingCoefficients<f32> {
    BearingCoefficients {
        k: [[1.2e8 * s, -3.4e7], [5.6e7, 2.1e8 * s]],
        c: [[1.5e4, -2.5e3 * s], [3.5e3, 4.5e4 * s]],
    }
}

fn host_messages() -> Vec<HostMessage> {
    let channels = [
        ChannelConfig {
            channel: 0,
            kind: SensorKind::Displacement,
            sensitivity: 7.87e3,
            bearing: 0,
            quantity: Quantity::RelY,
        },
        ChannelConfig {
            channel: 5,
            kind: SensorKind::Velocity,
            sensitivity: 3.94,
            bearing: 1,
            quantity: Quantity::PedZ,
        },
        ChannelConfig {
            channel: 15,
            kind: SensorKind::Acceleration,
            sensitivity: 0.0102,
            bearing: 3,
            quantity: Quantity::PedY,
        },
        ChannelConfig {
            channel: 9,
            kind: SensorKind::Displacement,
            sensitivity: -7.9e3,
            bearing: 2,
            quantity: Quantity::RelZ,
        },
    ];
    let rows: Vec<BearingTableRow> = (0..5)
        .map(|i| BearingTableRow {
            speed_hz: 10.0 + 17.5 * i as f32,
            coefficients: coefficients(1.0 + 0.1 * i as f32),
        })
        .collect();
    let codes: Vec<i16> = (0..48)
        .map(|i| ((i * 1733) % 65536 - 32768) as i16)
        .collect();
    let volts: Vec<f32> = (0..96).map(|i| libm::sinf(i as f32 * 0.37) * 4.5).collect();
    std::vec![
        HostMessage::Hello(Hello {
            protocol_version: PROTOCOL_VERSION,
            host_nonce: 0xDEAD_BEEF,
        }),
        HostMessage::Ping,
        HostMessage::ConfigureChannels(ChannelSet {
            channels: vec_of(&channels),
        }),
        HostMessage::ConfigureAveraging(Averaging {
            revolutions_per_phasor: 12,
        }),
        HostMessage::ConfigureRls(RlsSettings::new(
            0.9987,
            ParameterScale {
                k: 2.0e7,
                m: 150.0,
                c: 800.0,
            },
        )),
        HostMessage::BearingTable(BearingTableChunk {
            bearing: 1,
            total_rows: 13,
            first_row: 8,
            rows: vec_of(&rows),
        }),
        HostMessage::Start,
        HostMessage::Stop,
        HostMessage::Samples(SampleBlock {
            first_sample: 4_000_000_123,
            channels: 6,
            samples: Samples::AdcCodes(vec_of(&codes)),
            keyphasor_edges: vec_of(&[
                KeyphasorEdge {
                    offset_samples: 0.25,
                },
                KeyphasorEdge {
                    offset_samples: 7.875,
                },
            ]),
        }),
        HostMessage::Samples(SampleBlock {
            first_sample: 96,
            channels: 8,
            samples: Samples::Volts(vec_of(&volts)),
            keyphasor_edges: heapless::Vec::new(),
        }),
    ]
}

fn device_messages() -> Vec<DeviceMessage> {
    let phasor = |a: f32, b: f32| WirePhasor { re: a, im: b };
    let bearings = [
        BearingPhasors {
            bearing: 0,
            rel: [phasor(12.5e-6, -3.25e-6), phasor(-4.0e-6, 8.5e-6)],
            ped: [phasor(1.5e-6, 0.75e-6), phasor(-0.5e-6, -2.0e-6)],
            rel_sd: [1.25e-8, 3.0e-9],
            ped_sd: [7.5e-10, f32::NAN],
        },
        BearingPhasors {
            bearing: 1,
            rel: [phasor(-22.0e-6, 1.0e-7), phasor(3.0e-9, -6.5e-6)],
            ped: [phasor(0.0, -0.0), phasor(2.5e-6, 9.75e-7)],
            rel_sd: [0.0, 1.0e-30],
            ped_sd: [2.5e-7, 6.0e-9],
        },
    ];
    let estimate = |s: f32| crate::rls::PedestalEstimate {
        theta: [1.0e7 * s, 1.5e7 * s, 100.0 * s, 80.0 * s, 95.0 * s],
        std_err: [2.0e4, 3.0e4, 0.25, 1.5, f32::INFINITY],
        equations: 412.5,
        reduced_chi_square: 1.0625,
        rescaled: 3,
        rejected: u32::MAX,
    };
    let saturation: Vec<u32> = (0..16).map(|i| i * i * 1001).collect();
    std::vec![
        DeviceMessage::HelloAck(HelloAck {
            protocol_version: PROTOCOL_VERSION,
            host_nonce: 0xDEAD_BEEF,
            firmware_version: FirmwareVersion {
                major: 1,
                minor: 4,
                patch: 27,
            },
            capabilities: Capabilities {
                max_channels: 16,
                max_bearings: 4,
                bearing_table_capacity: 64,
                sample_rate_hz: 25_600.0,
                adc_volts_per_code: 10.0 / 32_768.0,
            },
            health: BoxHealth {
                sample_clock: SampleClock::RcOscillator,
                previous_reset: PreviousReset::Watchdog,
                sampling_refused: false,
                restarts: 3,
                slips: 2,
                late_reads: 70_000,
                stalls: 1,
                spi_errors: 5,
                dma_errors: 6,
                lost_captures: 7,
            },
        }),
        DeviceMessage::VersionMismatch(VersionMismatch {
            device_protocol_version: PROTOCOL_VERSION,
            host_protocol_version: PROTOCOL_VERSION + 3,
            host_nonce: 77,
        }),
        DeviceMessage::Ack(Ack {
            command_seq: 123_456,
        }),
        DeviceMessage::Nack(Nack {
            command_seq: u32::MAX,
            reason: NackReason::TableOutOfOrder,
        }),
        DeviceMessage::Nack(Nack {
            command_seq: 3,
            reason: NackReason::QueueFull,
        }),
        DeviceMessage::Phasors(PhasorFrame {
            revolution: 98_765,
            revolutions: 8,
            speed_hz: 57.125,
            bearings: vec_of(&bearings),
        }),
        DeviceMessage::Estimates(EstimateFrame {
            revolution: 98_772,
            pedestals: vec_of(&[
                PedestalEstimateEntry::new(0, &estimate(1.0)),
                PedestalEstimateEntry::new(3, &estimate(0.7)),
            ]),
        }),
        DeviceMessage::Status(StatusFrame {
            state: DeviceState::Running,
            uptime_ms: 3_600_000,
            counters: DeviceCounters {
                overruns: 1,
                queue_full_drops: 22,
                keyphasor_missing: 333,
                keyphasor_extra: 4444,
                frames_sent: 55_555,
                commands_rejected: 6,
                adc_saturation: vec_of(&saturation),
            },
            link: LinkStats {
                frames_ok: 1000,
                crc_failures: 3,
                cobs_failures: 1,
                decode_failures: 0,
                oversize: 2,
                resyncs: 4,
                sequence_gaps: 7,
                duplicates: 1,
                restarts: 2,
            },
            health: BoxHealth {
                previous_reset: PreviousReset::HardFault,
                ..BoxHealth::default()
            },
        }),
        DeviceMessage::Status(StatusFrame {
            state: DeviceState::AwaitingHello,
            uptime_ms: 0,
            counters: DeviceCounters::default(),
            link: LinkStats::default(),
            health: BoxHealth::default(),
        }),
    ]
}

/// Encodes `message` with sequence number `seq` into a fresh vector.
fn wire<M: serde::Serialize>(seq: u32, message: &M) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_SIZE];
    encode(seq, message, &mut buf)
        .expect("test message encodes")
        .to_vec()
}

/// Feeds `bytes` to `rx` in pieces of pseudo-random length and collects all events.
fn feed_chunked<M: serde::de::DeserializeOwned + SessionOpener>(
    rx: &mut Receiver<M>,
    bytes: &[u8],
    rng: &mut XorShift,
) -> Vec<Event<M>> {
    let mut events = Vec::new();
    let mut rest = bytes;
    while !rest.is_empty() {
        let n = 1 + rng.below(rest.len().min(97));
        let (chunk, r) = rest.split_at(n);
        events.extend(rx.feed(chunk));
        rest = r;
    }
    events
}

fn accepted<M>(events: Vec<Event<M>>) -> Vec<(u32, M)> {
    events
        .into_iter()
        .filter_map(|e| e.ok())
        .map(|r| (r.seq, r.message))
        .collect()
}

/// Bit-exact equality (NaN payloads, ±0), through the wire bytes.
fn same<M: serde::Serialize>(a: &M, b: &M) -> bool {
    wire(0, a) == wire(0, b)
}

#[test]
fn every_message_round_trips() {
    let mut rx = Receiver::<HostMessage>::new();
    for (i, m) in host_messages().iter().enumerate() {
        let seq = 1000 + i as u32;
        let bytes = wire(seq, m);
        assert!(bytes.len() <= MAX_FRAME_SIZE);
        assert_eq!(bytes.first(), Some(&DELIMITER));
        assert_eq!(bytes.last(), Some(&DELIMITER));
        assert!(!bytes[1..bytes.len() - 1].contains(&DELIMITER));
        let got = accepted(rx.feed(&bytes).collect());
        assert_eq!(got.len(), 1, "message {i}");
        assert_eq!(got[0].0, seq);
        assert_eq!(&got[0].1, m, "message {i}");
    }
    let mut rx = Receiver::<DeviceMessage>::new();
    for (i, m) in device_messages().iter().enumerate() {
        let seq = u32::MAX - 20 + i as u32;
        let got = accepted(rx.feed(&wire(seq, m)).collect());
        assert_eq!(got.len(), 1, "message {i}");
        assert_eq!(got[0].0, seq);
        // PartialEq fails on NaN; compare bit patterns through the encoding.
        assert!(same(&got[0].1, m), "message {i}: {:?} != {m:?}", got[0].1);
    }
    assert_eq!(rx.stats().frames_ok, device_messages().len() as u32);
    assert_eq!(rx.stats().failures(), 0);
}

#[test]
fn nan_estimates_survive_the_wire() {
    let e = crate::rls::PedestalEstimate {
        theta: [f32::NAN; 5],
        std_err: [f32::NAN; 5],
        equations: 0.0,
        reduced_chi_square: f32::NAN,
        rescaled: 0,
        rejected: 0,
    };
    let m = DeviceMessage::Estimates(EstimateFrame {
        revolution: 1,
        pedestals: vec_of(&[PedestalEstimateEntry::new(2, &e)]),
    });
    let mut rx = Receiver::<DeviceMessage>::new();
    let got = accepted(rx.feed(&wire(5, &m)).collect());
    match &got[..] {
        [(5, DeviceMessage::Estimates(f))] => {
            let back = f.pedestals[0].estimate();
            assert!(back.theta.iter().all(|x| x.is_nan()));
            assert!(back.reduced_chi_square.is_nan());
            assert_eq!(f.pedestals[0].bearing, 2);
        }
        other => panic!("unexpected {other:?}"),
    }
}

/// Every message at full capacity with worst-case varints fits.
#[test]
fn largest_messages_fit() {
    let max_row = BearingTableRow {
        speed_hz: f32::MAX,
        coefficients: coefficients(f32::MAX),
    };
    let channel = ChannelConfig {
        channel: u8::MAX,
        kind: SensorKind::Acceleration,
        sensitivity: f32::MAX,
        bearing: u8::MAX,
        quantity: Quantity::PedZ,
    };
    let edge = KeyphasorEdge {
        offset_samples: 1.0,
    };
    let phasor = WirePhasor { re: 1.0, im: 1.0 };
    let host = [
        HostMessage::ConfigureChannels(ChannelSet {
            channels: vec_of(&[channel; MAX_CHANNELS]),
        }),
        HostMessage::BearingTable(BearingTableChunk {
            bearing: u8::MAX,
            total_rows: u16::MAX,
            first_row: u16::MAX,
            rows: vec_of(&[max_row; MAX_TABLE_ROWS_PER_CHUNK]),
        }),
        HostMessage::Samples(SampleBlock {
            first_sample: u32::MAX,
            channels: u8::MAX,
            samples: Samples::Volts(vec_of(&[f32::MAX; MAX_BLOCK_VALUES])),
            keyphasor_edges: vec_of(&[edge; MAX_KEYPHASOR_EDGES]),
        }),
        HostMessage::Samples(SampleBlock {
            first_sample: u32::MAX,
            channels: u8::MAX,
            samples: Samples::AdcCodes(vec_of(&[i16::MIN; MAX_BLOCK_VALUES])),
            keyphasor_edges: vec_of(&[edge; MAX_KEYPHASOR_EDGES]),
        }),
    ];
    let entry = PedestalEstimateEntry {
        bearing: u8::MAX,
        theta: [1.0; 5],
        std_err: [1.0; 5],
        equations: 1.0,
        reduced_chi_square: 1.0,
        rescaled: u32::MAX,
        rejected: u32::MAX,
    };
    let stats = LinkStats {
        frames_ok: u32::MAX,
        crc_failures: u32::MAX,
        cobs_failures: u32::MAX,
        decode_failures: u32::MAX,
        oversize: u32::MAX,
        resyncs: u32::MAX,
        sequence_gaps: u32::MAX,
        duplicates: u32::MAX,
        restarts: u32::MAX,
    };
    let device = [
        DeviceMessage::Phasors(PhasorFrame {
            revolution: u32::MAX,
            revolutions: u16::MAX,
            speed_hz: 1.0,
            bearings: vec_of(
                &[BearingPhasors {
                    bearing: u8::MAX,
                    rel: [phasor; 2],
                    ped: [phasor; 2],
                    rel_sd: [1.0; 2],
                    ped_sd: [1.0; 2],
                }; MAX_BEARINGS],
            ),
        }),
        DeviceMessage::Estimates(EstimateFrame {
            revolution: u32::MAX,
            pedestals: vec_of(&[entry; MAX_BEARINGS]),
        }),
        DeviceMessage::Status(StatusFrame {
            state: DeviceState::Running,
            uptime_ms: u32::MAX,
            counters: DeviceCounters {
                overruns: u32::MAX,
                queue_full_drops: u32::MAX,
                keyphasor_missing: u32::MAX,
                keyphasor_extra: u32::MAX,
                frames_sent: u32::MAX,
                commands_rejected: u32::MAX,
                adc_saturation: vec_of(&[u32::MAX; MAX_CHANNELS]),
            },
            link: stats,
            health: BoxHealth {
                sample_clock: SampleClock::RcOscillatorNoPll,
                previous_reset: PreviousReset::HardFault,
                sampling_refused: true,
                restarts: u32::MAX,
                slips: u32::MAX,
                late_reads: u32::MAX,
                stalls: u32::MAX,
                spi_errors: u32::MAX,
                dma_errors: u32::MAX,
                lost_captures: u32::MAX,
            },
        }),
    ];
    let check = |size: usize, what: &str| {
        assert!(size <= MAX_MESSAGE_SIZE, "{what}: {size} bytes");
    };
    for m in &host {
        let frame = Frame {
            seq: u32::MAX,
            message: m,
        };
        check(
            postcard::experimental::serialized_size(&frame).unwrap(),
            "host",
        );
        let mut buf = [0u8; MAX_FRAME_SIZE];
        let n = encode(u32::MAX, m, &mut buf).unwrap().len();
        assert!(n <= max_wire_size(postcard::experimental::serialized_size(&frame).unwrap()));
    }
    for m in &device {
        let frame = Frame {
            seq: u32::MAX,
            message: m,
        };
        check(
            postcard::experimental::serialized_size(&frame).unwrap(),
            "device",
        );
    }
}

#[test]
fn encode_reports_small_buffers_and_large_frames() {
    let m = &host_messages()[2];
    let full = wire(9, m);
    let mut small = std::vec![0u8; full.len() - 1];
    assert_eq!(
        encode(9, m, &mut small).unwrap_err(),
        EncodeError::BufferTooSmall
    );
    assert_eq!(
        encode(9, m, &mut []).unwrap_err(),
        EncodeError::BufferTooSmall
    );
    let mut exact = std::vec![0u8; full.len()];
    assert_eq!(encode(9, m, &mut exact).unwrap(), &full[..]);
    // A message beyond the protocol's limit fails even with a large buffer.
    let big: heapless::Vec<u8, 600> = (0..600).map(|i| (i % 200 + 1) as u8).collect();
    let mut large = [0u8; 2048];
    assert_eq!(
        encode(1, &big, &mut large).unwrap_err(),
        EncodeError::FrameTooLarge
    );
    // The transmitter does not use up a sequence number on failure.
    let mut tx = Transmitter::new();
    assert!(tx.encode(m, &mut small).is_err());
    assert_eq!(tx.next_seq(), 0);
    let (seq, _) = tx.encode(m, &mut exact).unwrap();
    assert_eq!((seq, tx.next_seq()), (0, 1));
}

/// Frames used by the corruption tests: different types and sizes, some with
/// many zero bytes (many COBS code bytes), one longer than 254 bytes.
fn probe_frames() -> Vec<(u32, DeviceMessage)> {
    let mut out: Vec<(u32, DeviceMessage)> = device_messages()
        .into_iter()
        .enumerate()
        .map(|(i, m)| (40 + i as u32, m))
        .collect();
    // Zeros everywhere: a status frame of a fresh box.
    out.push((
        0,
        DeviceMessage::Status(StatusFrame {
            state: DeviceState::Idle,
            uptime_ms: 0,
            counters: DeviceCounters {
                adc_saturation: vec_of(&[0; MAX_CHANNELS]),
                ..DeviceCounters::default()
            },
            link: LinkStats::default(),
            health: BoxHealth::default(),
        }),
    ));
    out
}

/// Feeds A, corrupted B, C and checks that exactly A and C come out, intact.
fn check_corruption<M>(a: &[u8], b_corrupt: &[u8], c: &[u8], want: [&(u32, M); 2], what: &str)
where
    M: serde::Serialize + serde::de::DeserializeOwned + core::fmt::Debug + SessionOpener,
{
    let mut stream = Vec::new();
    stream.extend_from_slice(a);
    stream.extend_from_slice(b_corrupt);
    stream.extend_from_slice(c);
    let mut rx = Receiver::<M>::new();
    let events: Vec<_> = rx.feed(&stream).collect();
    let errors = events.iter().filter(|e| e.is_err()).count();
    let got = accepted(events);
    assert_eq!(got.len(), 2, "{what}: accepted {got:?}");
    for (g, w) in got.iter().zip(want) {
        assert_eq!(g.0, w.0, "{what}");
        assert!(same(&g.1, &w.1), "{what}");
    }
    assert!(errors >= 1, "{what}: corruption went unnoticed");
    assert_eq!(rx.stats().frames_ok, 2);
}

/// Flips every bit of every frame B in turn, sent as A, B, C; returns the
/// number of flips tried.
fn flip_every_bit<M>(frames: &[M]) -> usize
where
    M: serde::Serialize + serde::de::DeserializeOwned + core::fmt::Debug + Clone + SessionOpener,
{
    let mut flips = 0;
    for (i, b) in frames.iter().enumerate() {
        let a = &frames[(i + 1) % frames.len()];
        let c = &frames[(i + 2) % frames.len()];
        // Consecutive sequence numbers, so that nothing is a duplicate.
        let a_bytes = wire(1, a);
        let b_bytes = wire(2, b);
        let c_bytes = wire(3, c);
        let want = [&(1, a.clone()), &(3, c.clone())];
        for bit in 0..b_bytes.len() * 8 {
            let mut corrupt = b_bytes.clone();
            corrupt[bit / 8] ^= 1 << (bit % 8);
            let what = std::format!("frame {i} ({} bytes), bit {bit}", b_bytes.len());
            check_corruption(&a_bytes, &corrupt, &c_bytes, want, &what);
            flips += 1;
        }
    }
    flips
}

/// A sample block whose 384 value bytes are all non-zero: a COBS run longer
/// than 254 bytes (a 0xFF code byte) in a frame of over 400 bytes.
fn long_block() -> HostMessage {
    let volts: Vec<f32> = (0..MAX_BLOCK_VALUES as u32)
        .map(|i| f32::from_bits(0x3F81_8181 + i))
        .collect();
    HostMessage::Samples(SampleBlock {
        first_sample: 0x0101_0101,
        channels: 3,
        samples: Samples::Volts(vec_of(&volts)),
        keyphasor_edges: vec_of(&[KeyphasorEdge {
            offset_samples: 17.5,
        }]),
    })
}

#[test]
fn every_single_bit_flip_is_detected() {
    let device: Vec<DeviceMessage> = probe_frames().into_iter().map(|(_, m)| m).collect();
    let mut host = host_messages();
    host.push(long_block());
    assert!(wire(2, &long_block()).len() > 400);
    let flips = flip_every_bit(&device) + flip_every_bit(&host);
    assert!(flips > 10_000, "only {flips} flips tried");
}

#[test]
fn bursts_up_to_32_bits_in_the_payload_are_detected() {
    let mut rng = XorShift(0x0123_4567_89AB_CDEF);
    for (seq, m) in probe_frames().iter().take(7) {
        // The un-stuffed bytes (postcard + CRC) of the frame.
        let mut encoded = wire(*seq, m);
        let body_len = encoded.len() - 2;
        let n = cobs::decode_in_place(&mut encoded[1..1 + body_len]).unwrap();
        let raw = encoded[1..1 + n].to_vec();
        let bits = raw.len() * 8;
        for len in 1..=32usize {
            for start in (0..=bits - len).step_by(3) {
                // A burst: first and last bit flipped, the ones between random.
                let mut corrupt = raw.clone();
                for k in 0..len {
                    let edge = k == 0 || k == len - 1;
                    if edge || rng.next() & 1 == 1 {
                        let b = start + k;
                        corrupt[b / 8] ^= 1 << (b % 8);
                    }
                }
                let mut stuffed = std::vec![0u8; cobs::max_encoding_length(corrupt.len())];
                let k = cobs::encode(&corrupt, &mut stuffed);
                let r = decode_frame::<DeviceMessage>(&mut stuffed[..k]);
                assert!(
                    r.is_err(),
                    "burst of {len} bits at bit {start} of frame {seq} accepted"
                );
            }
        }
    }
}

#[test]
fn truncated_frame_then_good_frame() {
    let frames = probe_frames();
    for (i, (seq, m)) in frames.iter().enumerate() {
        let t = wire(*seq, m);
        let (gseq, good) = &frames[(i + 3) % frames.len()];
        let g = wire(gseq + 100, good);
        // Every cut that loses at least one body byte (cutting only the
        // trailing delimiter leaves a complete frame, ended by the next one's
        // leading delimiter).
        for cut in 1..t.len() - 1 {
            let mut stream = t[..cut].to_vec();
            stream.extend_from_slice(&g);
            let mut rx = Receiver::<DeviceMessage>::new();
            let events: Vec<_> = rx.feed(&stream).collect();
            let got = accepted(events);
            assert_eq!(got.len(), 1, "frame {i} cut at {cut}: {got:?}");
            assert_eq!(got[0].0, gseq + 100);
            assert!(same(&got[0].1, good));
            // Only the leading delimiter alone gives no error (an idle line).
            let expected_failures = u32::from(cut > 1);
            assert_eq!(rx.stats().failures(), expected_failures, "cut {cut}");
            assert_eq!(rx.stats().resyncs, expected_failures);
        }
    }
}

#[test]
fn garbage_between_frames_resyncs() {
    let mut rng = XorShift(0x9E37_79B9_7F4A_7C15);
    let frames = probe_frames();
    let mut tx = Transmitter::new();
    let mut stream = Vec::new();
    let mut sent = Vec::new();
    let mut buf = [0u8; MAX_FRAME_SIZE];
    for round in 0..200 {
        // Garbage: random bytes (zeros included), sometimes a long burst
        // without zeros (oversize), sometimes none.
        match round % 5 {
            0 => {}
            1 => stream.extend((0..1 + rng.below(1500)).map(|_| rng.byte() | 1)),
            _ => stream.extend((0..rng.below(300)).map(|_| rng.byte())),
        }
        let m = &frames[rng.below(frames.len())].1;
        let (seq, bytes) = tx.encode(m, &mut buf).unwrap();
        stream.extend_from_slice(bytes);
        sent.push((seq, m.clone()));
    }
    let mut rx = Receiver::<DeviceMessage>::new();
    let events = feed_chunked(&mut rx, &stream, &mut rng);
    let got = accepted(events);
    assert_eq!(got.len(), sent.len());
    for ((gs, gm), (ss, sm)) in got.iter().zip(&sent) {
        assert_eq!(gs, ss);
        assert!(same(gm, sm));
    }
    let st = *rx.stats();
    assert_eq!(st.frames_ok, 200);
    assert_eq!(st.sequence_gaps, 0);
    assert_eq!(st.duplicates, 0);
    // Every delimited non-empty piece is counted exactly once, the long ones
    // as oversize.
    let pieces = stream
        .split(|&b| b == DELIMITER)
        .filter(|p| !p.is_empty())
        .count() as u32;
    let long = stream
        .split(|&b| b == DELIMITER)
        .filter(|p| p.len() > MAX_BODY_SIZE)
        .count() as u32;
    assert!(long >= 10, "{long}");
    assert_eq!(st.oversize, long, "{st:?}");
    assert!(st.crc_failures + st.cobs_failures > 100, "{st:?}");
    assert!(st.resyncs >= 100 && st.resyncs <= 160, "{st:?}");
    assert_eq!(
        st.frames_ok + st.failures() + st.duplicates,
        pieces,
        "{st:?}"
    );
}

#[test]
fn byte_at_a_time_matches_chunks() {
    let mut rng = XorShift(7);
    let mut stream = Vec::new();
    for (i, (_, m)) in probe_frames().iter().enumerate() {
        stream.extend((0..rng.below(40)).map(|_| rng.byte()));
        stream.extend(wire(i as u32 * 2, m));
    }
    let mut a = Receiver::<DeviceMessage>::new();
    let whole: Vec<_> = a.feed(&stream).collect();
    let mut b = Receiver::<DeviceMessage>::new();
    let bytewise: Vec<_> = stream.iter().filter_map(|&x| b.push_byte(x)).collect();
    assert_eq!(whole.len(), bytewise.len());
    for (x, y) in whole.iter().zip(&bytewise) {
        match (x, y) {
            (Ok(p), Ok(q)) => assert!(p.seq == q.seq && same(&p.message, &q.message)),
            (Err(p), Err(q)) => assert_eq!(p, q),
            _ => panic!("{x:?} vs {y:?}"),
        }
    }
    assert_eq!(a.stats(), b.stats());
}

#[test]
fn oversize_is_discarded_to_the_next_delimiter() {
    let mut stream: Vec<u8> = (0..MAX_BODY_SIZE + 77)
        .map(|i| (i % 255 + 1) as u8)
        .collect();
    stream.push(DELIMITER);
    let ping = HostMessage::Ping;
    stream.extend(wire(4, &ping));
    // Exactly MAX_BODY_SIZE bytes are still a (bad) frame, not oversize.
    stream.extend((0..MAX_BODY_SIZE).map(|i| (i % 7 + 1) as u8));
    stream.extend(wire(5, &ping));
    let mut rx = Receiver::<HostMessage>::new();
    let events: Vec<_> = rx.feed(&stream).collect();
    assert_eq!(
        events[0],
        Err(LinkError::Oversize {
            len: (MAX_BODY_SIZE + 77) as u32
        })
    );
    assert!(matches!(&events[1], Ok(r) if r.seq == 4 && r.message == ping));
    assert!(matches!(events[2], Err(LinkError::Crc | LinkError::Cobs)));
    assert!(matches!(&events[3], Ok(r) if r.seq == 5));
    assert_eq!(events.len(), 4);
    let st = rx.stats();
    assert_eq!((st.oversize, st.frames_ok, st.resyncs), (1, 2, 2));
}

#[test]
fn sequence_gaps_and_duplicates_are_counted() {
    let ping = HostMessage::Ping;
    let mut stream = Vec::new();
    // 0, 1, 2, (3, 4 lost), 5, 5 again, 6, 4 again (stale), 10 (7-9 lost), 0 (restart), 1.
    for seq in [0u32, 1, 2, 5, 5, 6, 4, 10, 0, 1] {
        stream.extend(wire(seq, &ping));
    }
    let mut rx = Receiver::<HostMessage>::new();
    let events: Vec<_> = rx.feed(&stream).collect();
    let delivered: Vec<(u32, u32, bool)> = events
        .iter()
        .filter_map(|e| e.as_ref().ok())
        .map(|r| (r.seq, r.missed, r.restart))
        .collect();
    assert_eq!(
        delivered,
        [
            (0, 0, false),
            (1, 0, false),
            (2, 0, false),
            (5, 2, false),
            (6, 0, false),
            (10, 3, false),
            (0, 0, true),
            (1, 0, false),
        ]
    );
    let dups: Vec<_> = events.iter().filter_map(|e| e.as_ref().err()).collect();
    assert_eq!(
        dups,
        [
            &LinkError::Duplicate { seq: 5 },
            &LinkError::Duplicate { seq: 4 }
        ]
    );
    let st = rx.stats();
    assert_eq!(
        (
            st.frames_ok,
            st.sequence_gaps,
            st.duplicates,
            st.restarts,
            st.resyncs
        ),
        (8, 5, 2, 1, 0)
    );
}

#[test]
fn decode_failures_are_told_from_corruption() {
    // A CRC-valid device frame fed to a host receiver: the peer speaks
    // something else. Variant 6 of HostMessage is `Start` (no payload), so
    // the status frame parses short and the rest is left over.
    let status = &device_messages()[7];
    let mut rx = Receiver::<HostMessage>::new();
    let events: Vec<_> = rx.feed(&wire(3, status)).collect();
    assert_eq!(events, [Err(LinkError::Decode)]);
    // An unknown variant index.
    let mut bytes = Vec::new();
    bytes.extend(wire(3, &200u8));
    // A heapless::Vec longer than its capacity.
    #[derive(serde::Serialize)]
    #[allow(clippy::large_enum_variant)]
    enum Fake {
        _Hello(Hello),
        _Ping,
        ConfigureChannels(heapless::Vec<ChannelConfig, 32>),
    }
    let c = ChannelConfig {
        channel: 1,
        kind: SensorKind::Velocity,
        sensitivity: 1.0,
        bearing: 0,
        quantity: Quantity::RelY,
    };
    let fake = Fake::ConfigureChannels(vec_of(&[c; MAX_CHANNELS + 1]));
    bytes.extend(wire(4, &fake));
    // The same channel set within capacity is fine: the fake is faithful.
    let ok = Fake::ConfigureChannels(vec_of(&[c; MAX_CHANNELS]));
    bytes.extend(wire(5, &ok));
    let events: Vec<_> = rx.feed(&bytes).collect();
    assert_eq!(events[0], Err(LinkError::Decode));
    assert_eq!(events[1], Err(LinkError::Decode));
    assert!(matches!(&events[2], Ok(r) if matches!(&r.message,
        HostMessage::ConfigureChannels(s) if s.channels.len() == MAX_CHANNELS)));
    assert_eq!(rx.stats().decode_failures, 3);
    // Runts: a body too short to hold a CRC.
    let events: Vec<_> = rx.feed(&[0, 3, 1, 1, 0, 1, 0]).collect();
    assert_eq!(events, [Err(LinkError::Crc), Err(LinkError::Crc)]);
    // Invalid COBS: a code byte pointing past the end.
    let events: Vec<_> = rx.feed(&[0, 9, 1, 2, 0]).collect();
    assert_eq!(events, [Err(LinkError::Cobs)]);
}

#[test]
fn handshake_version_mismatch_is_a_message() {
    // A host of another version still gets an explicit answer: the Hello and
    // VersionMismatch layouts are frozen (variant 0 / 1, version first).
    let hello = HostMessage::Hello(Hello {
        protocol_version: 0x7FFF,
        host_nonce: 9,
    });
    let bytes = wire(0, &hello);
    // Pin the frozen prefix: seq 0, variant 0, version 0x7FFF as varint.
    let mut raw = bytes[1..bytes.len() - 1].to_vec();
    let n = cobs::decode_in_place(&mut raw).unwrap();
    assert_eq!(&raw[..5], &[0, 0, 0xFF, 0xFF, 0x01]);
    assert_eq!(n, 5 + 1 + CRC_LEN);
    let answer = DeviceMessage::VersionMismatch(VersionMismatch {
        device_protocol_version: PROTOCOL_VERSION,
        host_protocol_version: 0x7FFF,
        host_nonce: 9,
    });
    let bytes = wire(0, &answer);
    let mut raw = bytes[1..bytes.len() - 1].to_vec();
    cobs::decode_in_place(&mut raw).unwrap();
    assert_eq!(&raw[..3], &[0, 1, PROTOCOL_VERSION as u8]);
}

#[test]
fn bearing_table_splits_into_chunks() {
    let rows: Vec<BearingTableRow> = (0..19)
        .map(|i| BearingTableRow {
            speed_hz: 5.0 * (i + 1) as f32,
            coefficients: coefficients(i as f32),
        })
        .collect();
    let chunks: Vec<_> = BearingTableChunk::split(2, &rows).unwrap().collect();
    assert_eq!(chunks.len(), 3);
    assert_eq!(
        chunks
            .iter()
            .map(|c| (c.first_row, c.rows.len(), c.is_last()))
            .collect::<Vec<_>>(),
        [(0, 8, false), (8, 8, false), (16, 3, true)]
    );
    let back: Vec<BearingTableRow> = chunks.iter().flat_map(|c| c.rows.clone()).collect();
    assert_eq!(back, rows);
    assert!(chunks.iter().all(|c| c.bearing == 2 && c.total_rows == 19));
    assert_eq!(BearingTableChunk::split(0, &[]).unwrap().count(), 0);
    for c in &chunks {
        let m = HostMessage::BearingTable(c.clone());
        assert!(wire(0, &m).len() < MAX_FRAME_SIZE);
    }
}

#[test]
fn sample_block_shape_is_checked() {
    let mut block = SampleBlock {
        first_sample: 0,
        channels: 4,
        samples: Samples::AdcCodes(vec_of(&[1; 12])),
        keyphasor_edges: vec_of(&[
            KeyphasorEdge {
                offset_samples: 0.0,
            },
            KeyphasorEdge {
                offset_samples: 2.999,
            },
        ]),
    };
    assert_eq!(block.sample_vectors(), Ok(3));
    block.keyphasor_edges[1].offset_samples = 3.0;
    assert_eq!(
        block.sample_vectors(),
        Err(SampleBlockError::BadEdge { index: 1 })
    );
    block.keyphasor_edges[1].offset_samples = 0.0;
    assert_eq!(
        block.sample_vectors(),
        Err(SampleBlockError::BadEdge { index: 1 })
    );
    block.keyphasor_edges[0].offset_samples = f32::NAN;
    assert_eq!(
        block.sample_vectors(),
        Err(SampleBlockError::BadEdge { index: 0 })
    );
    block.keyphasor_edges.clear();
    block.channels = 5;
    assert_eq!(block.sample_vectors(), Err(SampleBlockError::Ragged));
    block.channels = 0;
    assert_eq!(block.sample_vectors(), Err(SampleBlockError::NoChannels));
}
