//! Protocol tests: round trips, capacity, corruption, resynchronisation and
//! sequence accounting, one file per idea:
//!
//! - [`catalog`]: every message kind, filled, for the other tests;
//! - [`round_trip`]: messages through the wire unchanged, capacity limits;
//! - [`corruption`]: bit flips, bursts, truncation, garbage, oversize;
//! - [`accounting`]: sequence gaps, duplicates, decode failures, handshake,
//!   message shapes (bearing tables, sample blocks).

extern crate std;

mod accounting;
mod catalog;
mod corruption;
mod round_trip;

use std::vec::Vec;

use super::*;

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
