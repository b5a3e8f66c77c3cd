//! Messages through the wire unchanged (NaN payloads included); every
//! message at full capacity fits; encode errors for small buffers.

use super::catalog::{coefficients, device_messages, host_messages};
use super::*;

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
