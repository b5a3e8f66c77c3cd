//! Every message kind, filled with varied values, for the other tests.

use std::vec::Vec;

use super::*;
use crate::bearing::BearingCoefficients;
use crate::regression::ParameterScale;

pub(super) fn coefficients(s: f32) -> BearingCoefficients<f32> {
    BearingCoefficients {
        k: [[1.2e8 * s, -3.4e7], [5.6e7, 2.1e8 * s]],
        c: [[1.5e4, -2.5e3 * s], [3.5e3, 4.5e4 * s]],
    }
}

pub(super) fn host_messages() -> Vec<HostMessage> {
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

pub(super) fn device_messages() -> Vec<DeviceMessage> {
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
