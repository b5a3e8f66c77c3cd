//! Line corruption: every bit flip, bursts, truncation, garbage between
//! frames, oversize frames; chunked and byte-at-a-time feeding agree.

use std::vec::Vec;

use super::catalog::{device_messages, host_messages};
use super::*;

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
