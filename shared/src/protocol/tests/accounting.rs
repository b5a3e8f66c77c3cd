//! What the receiver counts and tells apart (sequence gaps, duplicates,
//! decode failures vs corruption), the handshake, message shapes.

use std::vec::Vec;

use super::catalog::{coefficients, device_messages};
use super::*;

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
