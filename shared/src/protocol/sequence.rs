//! Per-direction frame sequence numbers: the sender's counter and the
//! receiver's tracker that counts lost and repeated frames.
//!
//! # Numbering
//!
//! A sender numbers the first frame of a session 0, then 1, 2, …; after
//! `u32::MAX` comes 1 again (0 is reserved for a session start, so the ring
//! holds 2³² − 1 numbers: 1 ..= `u32::MAX`).
//!
//! # Receiver rules (checked in this order against the last accepted number)
//!
//! 1. Nothing accepted yet: accept, no loss counted (the receiver joined late).
//! 2. The same number again: a **duplicate**, counted and **not delivered**;
//!    except number 0 opening a session with another nonce than the session
//!    accepted last (a `Hello` sent again because its answer was lost, which
//!    the host numbers 0 again with a fresh nonce; the box's answer likewise):
//!    a restart, accepted.
//! 3. Number 0: the sender restarted its session (rebooted, or the host sent a
//!    new `Hello`): accept, count a restart, no loss counted.
//! 4. Ahead by d (1 ≤ d < 2³¹ steps along the ring): accept; d − 1 frames were
//!    lost and are added to the gap count.
//! 5. Behind by at most [`DUPLICATE_WINDOW`]: an old frame sent again (a UART
//!    never reorders): counted as a duplicate, not delivered.
//! 6. Further behind: the sender restarted and its frame 0 was lost: accept,
//!    count a restart, no loss counted.
//!
//! So a frame is delivered at most once unless the sender restarts in
//! between; the cost of rule 5 is that after a restart whose frame 0 was lost
//! while the previous session had sent fewer than [`DUPLICATE_WINDOW`] frames,
//! up to that many new frames are dropped as stale.

/// How far behind the last accepted sequence number a frame still counts as a
/// repeat rather than a restart \[frames].
pub const DUPLICATE_WINDOW: u32 = 16;

/// Number of sequence numbers in the ring 1 ..= `u32::MAX`.
const RING: u64 = u32::MAX as u64;

/// The sequence number after `seq` (0 and `u32::MAX` are followed by 1).
pub const fn successor(seq: u32) -> u32 {
    if seq == u32::MAX {
        1
    } else {
        seq + 1
    }
}

/// Steps from `from` to `to` (≠ 0) along the sequence.
fn forward_distance(from: u32, to: u32) -> u64 {
    if from == 0 {
        to as u64
    } else {
        (to as u64 + RING - from as u64) % RING
    }
}

/// The sender's sequence counter for one direction.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SequenceCounter {
    next: u32,
}

impl SequenceCounter {
    /// A counter at the start of a session (next number 0).
    pub const fn new() -> Self {
        Self { next: 0 }
    }

    /// The number the next frame will carry.
    pub const fn peek(&self) -> u32 {
        self.next
    }

    /// Takes the next number and advances.
    pub fn next_seq(&mut self) -> u32 {
        let s = self.next;
        self.next = successor(s);
        s
    }

    /// Starts a new session: the next frame carries 0.
    pub fn restart(&mut self) {
        self.next = 0;
    }
}

/// What the receiver does with a frame's sequence number.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SequenceVerdict {
    /// Deliver the frame.
    Accept {
        /// Frames lost just before this one.
        missed: u32,
        /// The sender restarted its numbering (rules 3 and 6).
        restart: bool,
    },
    /// Already seen (rules 2 and 5): drop it.
    Duplicate,
}

/// A message that may open a session: `Hello` and the box's answers to it,
/// which carry the session's nonce.
pub trait SessionOpener {
    /// The session's nonce if this message opens (or answers the opening
    /// of) a session.
    fn session_nonce(&self) -> Option<u32>;
}

/// The receiver's view of one direction's sequence numbers (rules in the
/// module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SequenceTracker {
    last: Option<u32>,
    /// Nonce of the last accepted session opener.
    session: Option<u32>,
}

impl SequenceTracker {
    /// A tracker that has accepted nothing.
    pub const fn new() -> Self {
        Self {
            last: None,
            session: None,
        }
    }

    /// The last accepted sequence number.
    pub const fn last(&self) -> Option<u32> {
        self.last
    }

    /// Forgets the last accepted number and session (the next frame is
    /// accepted as is).
    pub fn reset(&mut self) {
        self.last = None;
        self.session = None;
    }

    /// Classifies `seq` and, if accepted, makes it the last accepted number.
    pub fn observe(&mut self, seq: u32) -> SequenceVerdict {
        self.observe_opener(seq, None)
    }

    /// Classifies frame `seq` whose message opens the session `nonce` (if
    /// any; see [`SessionOpener`]) and, if accepted, makes it the last
    /// accepted number and session.
    pub fn observe_opener(&mut self, seq: u32, nonce: Option<u32>) -> SequenceVerdict {
        let new_session = seq == 0 && nonce.is_some() && nonce != self.session;
        let verdict = match self.last {
            None => SequenceVerdict::Accept {
                missed: 0,
                restart: false,
            },
            Some(0) if new_session => SequenceVerdict::Accept {
                missed: 0,
                restart: true,
            },
            Some(last) if seq == last => SequenceVerdict::Duplicate,
            Some(_) if seq == 0 => SequenceVerdict::Accept {
                missed: 0,
                restart: true,
            },
            Some(last) => {
                let ahead = forward_distance(last, seq);
                if ahead < 1 << 31 {
                    SequenceVerdict::Accept {
                        missed: (ahead - 1) as u32,
                        restart: false,
                    }
                } else if RING - ahead <= DUPLICATE_WINDOW as u64 {
                    SequenceVerdict::Duplicate
                } else {
                    SequenceVerdict::Accept {
                        missed: 0,
                        restart: true,
                    }
                }
            }
        };
        if let SequenceVerdict::Accept { .. } = verdict {
            self.last = Some(seq);
            if seq == 0 {
                self.session = nonce;
            }
        }
        verdict
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn accept(missed: u32, restart: bool) -> SequenceVerdict {
        SequenceVerdict::Accept { missed, restart }
    }

    #[test]
    fn counter_starts_at_zero_and_wraps_to_one() {
        let mut c = SequenceCounter::new();
        assert_eq!(c.next_seq(), 0);
        assert_eq!(c.next_seq(), 1);
        c.next = u32::MAX;
        assert_eq!(c.next_seq(), u32::MAX);
        assert_eq!(c.next_seq(), 1);
        c.restart();
        assert_eq!(c.peek(), 0);
    }

    #[test]
    fn in_order_gaps_and_wrap() {
        let mut t = SequenceTracker::new();
        assert_eq!(t.observe(7), accept(0, false)); // joined late
        assert_eq!(t.observe(8), accept(0, false));
        assert_eq!(t.observe(12), accept(3, false)); // 9, 10, 11 lost
        t.last = Some(u32::MAX - 1);
        assert_eq!(t.observe(u32::MAX), accept(0, false));
        assert_eq!(t.observe(1), accept(0, false)); // wrap skips 0
        t.last = Some(u32::MAX - 1);
        assert_eq!(t.observe(2), accept(2, false)); // MAX and 1 lost
        t.last = Some(0);
        assert_eq!(t.observe(1), accept(0, false));
        t.last = Some(0);
        assert_eq!(t.observe(5), accept(4, false));
    }

    #[test]
    fn a_session_opener_sent_again_with_a_fresh_nonce_is_a_restart() {
        let mut t = SequenceTracker::new();
        assert_eq!(t.observe_opener(0, Some(7)), accept(0, false));
        // The same frame repeated by the line: dropped.
        assert_eq!(t.observe_opener(0, Some(7)), SequenceVerdict::Duplicate);
        // Sent again (its answer was lost) with a fresh nonce: delivered.
        assert_eq!(t.observe_opener(0, Some(8)), accept(0, true));
        assert_eq!(t.observe_opener(0, Some(8)), SequenceVerdict::Duplicate);
        // A frame 0 that opens nothing is a plain duplicate.
        assert_eq!(t.observe(0), SequenceVerdict::Duplicate);
        assert_eq!(t.observe(1), accept(0, false));
        // Later in the session a new opener restarts as before.
        assert_eq!(t.observe_opener(0, Some(8)), accept(0, true));
        t.reset();
        assert_eq!(t.observe_opener(0, Some(8)), accept(0, false));
    }

    #[test]
    fn duplicates_and_restarts() {
        let mut t = SequenceTracker::new();
        assert_eq!(t.observe(0), accept(0, false));
        assert_eq!(t.observe(0), SequenceVerdict::Duplicate);
        for s in 1..=100 {
            assert_eq!(t.observe(s), accept(0, false));
        }
        assert_eq!(t.observe(100), SequenceVerdict::Duplicate);
        assert_eq!(
            t.observe(100 - DUPLICATE_WINDOW),
            SequenceVerdict::Duplicate
        );
        assert_eq!(t.last(), Some(100));
        // A restart: frame 0 arrives.
        assert_eq!(t.observe(0), accept(0, true));
        assert_eq!(t.observe(1), accept(0, false));
        // A restart whose frame 0 was lost, far behind the old session.
        for s in 2..=60 {
            t.observe(s);
        }
        assert_eq!(t.observe(60 - DUPLICATE_WINDOW - 1), accept(0, true));
        // Behind across the wrap.
        t.last = Some(3);
        assert_eq!(t.observe(u32::MAX - 2), SequenceVerdict::Duplicate);
        assert_eq!(t.observe(u32::MAX - 100), accept(0, true));
    }
}
