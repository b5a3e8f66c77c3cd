//! Encoded frames waiting for the transmitter, with the session's sequence
//! numbering: the one place where the protocol task and the extraction
//! task hand frames over (each push is one short critical section).

use crate::link::ByteLink;
use plinth_shared::protocol::{DeviceMessage, Transmitter, MAX_FRAME_SIZE};

use super::TX_QUEUE_BYTES;

/// Encoded frames waiting for the transmitter (frame numbers in queue order).
pub struct Outbox {
    tx: Transmitter,
    queue: heapless::Deque<u8, TX_QUEUE_BYTES>,
    frame: [u8; MAX_FRAME_SIZE],
    /// Frames queued.
    frames_sent: u32,
    /// Frames dropped because the queue was full.
    drops: u32,
}

impl Default for Outbox {
    fn default() -> Self {
        Self::new()
    }
}

impl Outbox {
    /// An empty queue; the next frame is numbered 0.
    pub fn new() -> Self {
        Self {
            tx: Transmitter::new(),
            queue: heapless::Deque::new(),
            frame: [0; MAX_FRAME_SIZE],
            frames_sent: 0,
            drops: 0,
        }
    }

    /// Empties the queue and numbers the next frame 0 (a new session).
    pub fn reset(&mut self) {
        self.tx = Transmitter::new();
        self.queue.clear();
        self.frames_sent = 0;
        self.drops = 0;
    }

    /// Encodes `m` and queues it if it fits with `reserve` bytes [B] to
    /// spare; otherwise counts a drop. A dropped frame still used up its
    /// sequence number, so the host also sees the drop as a sequence gap.
    pub fn push(&mut self, m: &DeviceMessage, reserve: usize) {
        let free = self.queue.capacity() - self.queue.len();
        let fits = match self.tx.encode(m, &mut self.frame) {
            Ok((_, encoded)) if encoded.len() + reserve <= free => {
                for &b in encoded.iter() {
                    // Cannot fail: the room was checked above.
                    let _ = self.queue.push_back(b);
                }
                true
            }
            _ => false,
        };
        if fits {
            self.frames_sent = self.frames_sent.saturating_add(1);
        } else {
            self.drops = self.drops.saturating_add(1);
        }
    }

    /// Moves up to `max` queued bytes to `link` (fewer when it is full);
    /// returns how many.
    pub fn drain_to<L: ByteLink>(&mut self, link: &mut L, max: usize) -> usize {
        let mut sent = 0;
        while sent < max {
            let Some(&byte) = self.queue.front() else {
                break;
            };
            if !link.write_byte(byte) {
                break;
            }
            self.queue.pop_front();
            sent += 1;
        }
        sent
    }

    /// Bytes [B] waiting.
    pub fn len(&self) -> usize {
        self.queue.len()
    }

    /// True when every queued byte has gone to the transmitter.
    pub fn is_empty(&self) -> bool {
        self.queue.is_empty()
    }

    /// Frames queued this session.
    pub fn frames_sent(&self) -> u32 {
        self.frames_sent
    }

    /// Data frames dropped this session because the queue was full.
    pub fn drops(&self) -> u32 {
        self.drops
    }
}
