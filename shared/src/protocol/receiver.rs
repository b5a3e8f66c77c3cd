//! The receiving end of a link: fed arbitrary byte chunks (a UART RX buffer
//! on the box, a serial-port read on the host), it yields decoded frames and
//! errors, resynchronising on the next 0x00 after anything bad, and counts
//! what happened in [`LinkStats`].
//!
//! Like postcard's `CobsAccumulator` it gathers bytes in a fixed buffer up to
//! a delimiter, but it discards an oversize frame up to the *next* delimiter
//! (the accumulator restarts mid-frame), checks the CRC, classifies every
//! failure and tracks sequence numbers. Fixed memory (about
//! [`MAX_BODY_SIZE`] bytes plus counters), no allocation, no panics.

use core::marker::PhantomData;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::framing::{decode_frame, LinkError, DELIMITER, MAX_BODY_SIZE};
use super::sequence::{SequenceTracker, SequenceVerdict, SessionOpener};

/// Counters of one receiving link, all saturating at `u32::MAX`.
///
/// Every non-empty stretch of bytes between two delimiters ends up in exactly
/// one of `frames_ok`, `crc_failures`, `cobs_failures`, `decode_failures`,
/// `oversize` or `duplicates`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkStats {
    /// Frames accepted and delivered.
    pub frames_ok: u32,
    /// Frames whose CRC did not match (line corruption), runts included.
    pub crc_failures: u32,
    /// Frames that were not valid COBS.
    pub cobs_failures: u32,
    /// Frames with a good CRC whose content did not decode (protocol mismatch).
    pub decode_failures: u32,
    /// Frames longer than the receive buffer, discarded.
    pub oversize: u32,
    /// Times a frame was accepted after one or more failures: how often the
    /// link lost and regained frame sync.
    pub resyncs: u32,
    /// Frames missing according to sequence numbers (sum of the gaps).
    pub sequence_gaps: u32,
    /// Valid frames dropped, not delivered, because their sequence number is
    /// the last accepted one or at most
    /// [`DUPLICATE_WINDOW`](super::DUPLICATE_WINDOW) behind it (rules 2 and 5
    /// of [`sequence`](super::sequence)); each copy counts once.
    pub duplicates: u32,
    /// Times the sender restarted its numbering (new session or reboot).
    pub restarts: u32,
}

impl LinkStats {
    /// Frames rejected for corruption or format, all causes.
    pub fn failures(&self) -> u32 {
        self.crc_failures
            .saturating_add(self.cobs_failures)
            .saturating_add(self.decode_failures)
            .saturating_add(self.oversize)
    }
}

fn bump(c: &mut u32) {
    *c = c.saturating_add(1);
}

/// A frame the receiver accepted.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Received<M> {
    /// Its sequence number.
    pub seq: u32,
    /// Frames lost just before it according to the sequence numbers.
    pub missed: u32,
    /// The sender restarted its numbering with this frame.
    pub restart: bool,
    /// The message.
    pub message: M,
}

/// What one delimiter-terminated piece of input gave.
pub type Event<M> = Result<Received<M>, LinkError>;

/// A frame receiver for messages of type `M` ([`HostMessage`] on the box,
/// [`DeviceMessage`] on the host).
///
/// [`HostMessage`]: super::HostMessage
/// [`DeviceMessage`]: super::DeviceMessage
pub struct Receiver<M> {
    buf: [u8; MAX_BODY_SIZE],
    len: usize,
    /// Bytes of an oversize body seen so far (discarding until a delimiter).
    overflow: Option<usize>,
    /// A failure occurred since the last accepted frame.
    failing: bool,
    sequence: SequenceTracker,
    stats: LinkStats,
    _message: PhantomData<fn() -> M>,
}

impl<M> Default for Receiver<M> {
    fn default() -> Self {
        Self::new()
    }
}

impl<M> Receiver<M> {
    /// An empty receiver.
    pub const fn new() -> Self {
        Self {
            buf: [0; MAX_BODY_SIZE],
            len: 0,
            overflow: None,
            failing: false,
            sequence: SequenceTracker::new(),
            stats: LinkStats {
                frames_ok: 0,
                crc_failures: 0,
                cobs_failures: 0,
                decode_failures: 0,
                oversize: 0,
                resyncs: 0,
                sequence_gaps: 0,
                duplicates: 0,
                restarts: 0,
            },
            _message: PhantomData,
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> &LinkStats {
        &self.stats
    }

    /// Zeroes the counters (the partial frame and sequence state are kept).
    pub fn clear_stats(&mut self) {
        self.stats = LinkStats::default();
    }

    /// Drops any partial frame and forgets the last sequence number, as after
    /// reopening the port; counters are kept.
    pub fn reset(&mut self) {
        self.len = 0;
        self.overflow = None;
        self.failing = false;
        self.sequence.reset();
    }

    /// The sequence-number state.
    pub fn sequence(&self) -> &SequenceTracker {
        &self.sequence
    }

    fn absorb(&mut self, bytes: &[u8]) {
        if let Some(n) = self.overflow.as_mut() {
            *n = n.saturating_add(bytes.len());
            return;
        }
        let end = self.len + bytes.len();
        match self.buf.get_mut(self.len..end) {
            Some(dst) => {
                dst.copy_from_slice(bytes);
                self.len = end;
            }
            None => {
                self.overflow = Some(end);
                self.len = 0;
            }
        }
    }

    fn fail(&mut self, e: LinkError) -> Option<Event<M>> {
        match e {
            LinkError::Oversize { .. } => bump(&mut self.stats.oversize),
            LinkError::Cobs => bump(&mut self.stats.cobs_failures),
            LinkError::Crc => bump(&mut self.stats.crc_failures),
            LinkError::Decode => bump(&mut self.stats.decode_failures),
            LinkError::Duplicate { .. } => {
                bump(&mut self.stats.duplicates);
                return Some(Err(e));
            }
        }
        self.failing = true;
        Some(Err(e))
    }
}

impl<M: DeserializeOwned + SessionOpener> Receiver<M> {
    /// Consumes `input` up to and including the first delimiter and returns
    /// what that completed (if anything) and the unconsumed rest. Without a
    /// delimiter everything is buffered and `(None, &[])` returned.
    pub fn feed_one<'a>(&mut self, input: &'a [u8]) -> (Option<Event<M>>, &'a [u8]) {
        match input.iter().position(|&b| b == DELIMITER) {
            None => {
                self.absorb(input);
                (None, &[])
            }
            Some(p) => {
                let (body, rest) = input.split_at(p);
                self.absorb(body);
                (self.end_of_frame(), rest.get(1..).unwrap_or(&[]))
            }
        }
    }

    /// Feeds one byte (for a byte-at-a-time UART interrupt).
    pub fn push_byte(&mut self, byte: u8) -> Option<Event<M>> {
        self.feed_one(core::slice::from_ref(&byte)).0
    }

    /// Feeds a chunk and iterates over the frames and errors it completes.
    /// Bytes after the last delimiter stay buffered for the next chunk. The
    /// iterator must be run to its end: bytes it has not reached are dropped
    /// with it.
    pub fn feed<'r, 'a>(&'r mut self, input: &'a [u8]) -> Events<'r, 'a, M> {
        Events { rx: self, input }
    }

    fn end_of_frame(&mut self) -> Option<Event<M>> {
        if let Some(len) = self.overflow.take() {
            let len = u32::try_from(len).unwrap_or(u32::MAX);
            return self.fail(LinkError::Oversize { len });
        }
        if self.len == 0 {
            return None; // an idle or leading delimiter
        }
        let n = core::mem::take(&mut self.len);
        let frame = match self.buf.get_mut(..n) {
            Some(body) => decode_frame::<M>(body),
            None => Err(LinkError::Oversize {
                len: u32::try_from(n).unwrap_or(u32::MAX),
            }),
        };
        let frame = match frame {
            Ok(f) => f,
            Err(e) => return self.fail(e),
        };
        match self
            .sequence
            .observe_opener(frame.seq, frame.message.session_nonce())
        {
            SequenceVerdict::Duplicate => self.fail(LinkError::Duplicate { seq: frame.seq }),
            SequenceVerdict::Accept { missed, restart } => {
                bump(&mut self.stats.frames_ok);
                self.stats.sequence_gaps = self.stats.sequence_gaps.saturating_add(missed);
                if restart {
                    bump(&mut self.stats.restarts);
                }
                if core::mem::take(&mut self.failing) {
                    bump(&mut self.stats.resyncs);
                }
                Some(Ok(Received {
                    seq: frame.seq,
                    missed,
                    restart,
                    message: frame.message,
                }))
            }
        }
    }
}

/// The frames and errors completed by one chunk; see [`Receiver::feed`].
pub struct Events<'r, 'a, M> {
    rx: &'r mut Receiver<M>,
    input: &'a [u8],
}

impl<M: DeserializeOwned + SessionOpener> Iterator for Events<'_, '_, M> {
    type Item = Event<M>;

    fn next(&mut self) -> Option<Self::Item> {
        while !self.input.is_empty() {
            let (event, rest) = self.rx.feed_one(self.input);
            self.input = rest;
            if event.is_some() {
                return event;
            }
        }
        None
    }
}
