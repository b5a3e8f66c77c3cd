//! Wire protocol between the field box (firmware) and the host, over a byte
//! stream such as a UART.
//!
//! - [`messages`]: the serde message types, [`HostMessage`] (host → box) and
//!   [`DeviceMessage`] (box → host), wrapped in a sequence-numbered [`Frame`].
//! - [`framing`]: [`encode`] a frame into a caller's buffer (postcard →
//!   CRC-32C → COBS, built from postcard's `ser_flavors`), [`decode_frame`].
//! - [`sequence`]: per-direction sequence numbers, counting lost and
//!   duplicated frames.
//! - [`receiver`]: [`Receiver`], fed arbitrary chunks, yields frames and
//!   [`LinkError`]s and keeps [`LinkStats`].
//!
//! # Sending and receiving
//!
//! ```
//! use plinth_shared::protocol::*;
//!
//! let mut tx = Transmitter::new();
//! let mut buf = [0u8; MAX_FRAME_SIZE];
//! let hello = HostMessage::Hello(Hello { protocol_version: PROTOCOL_VERSION, host_nonce: 42 });
//! let (seq, wire) = tx.encode(&hello, &mut buf).unwrap();
//! assert_eq!(seq, 0);
//!
//! let mut rx = Receiver::<HostMessage>::new();
//! let mut got = None;
//! for event in rx.feed(wire) {
//!     match event {
//!         Ok(frame) => got = Some(frame.message),
//!         Err(e) => panic!("{e:?}"),
//!     }
//! }
//! assert_eq!(got, Some(hello));
//! assert_eq!(rx.stats().frames_ok, 1);
//! ```
//!
//! # Error detection
//!
//! The CRC is CRC-32C (Castagnoli, `crc::CRC_32_ISCSI`) over the postcard
//! bytes of the frame. Any CRC of degree 32 with a non-zero constant term
//! detects every single-bit error and every burst of 32 bits or fewer, at any
//! length; CRC-32C moreover keeps Hamming distance 6 (every error of up to 5
//! bits detected) for data words up to 5 243 bits (Koopman 2002), which
//! covers every frame here (at most [`MAX_FRAME_SIZE`] = 512 bytes on the
//! wire, ≤ 507 bytes un-stuffed). These guarantees are about errors in the
//! un-stuffed bytes: a flipped bit in a COBS data byte is exactly such a
//! single-bit error. A flip in a COBS code byte, or one that creates or
//! destroys a 0x00 delimiter, changes the frame's structure (where zeros are,
//! where the frame ends); the COBS decoder, the postcard decoder (every byte
//! must be used) and the CRC then reject it with probability 1 − 2⁻³² or
//! better. The tests flip every bit of several encoded frames, delimiters
//! included, and check that no wrong frame is ever accepted.
//!
//! Sequence numbers then reveal lost and repeated frames (see [`sequence`]);
//! nothing is retransmitted at this layer.

pub mod framing;
pub mod health;
pub mod messages;
pub mod receiver;
pub mod sequence;

#[cfg(test)]
mod tests;

pub use framing::{
    decode_frame, encode, max_wire_size, EncodeError, LinkError, Transmitter, CRC_LEN, DELIMITER,
    FRAME_CRC, MAX_BODY_SIZE, MAX_FRAME_SIZE, MAX_MESSAGE_SIZE,
};
pub use health::{BoxHealth, PreviousReset, SampleClock};
pub use messages::*;
pub use receiver::{Event, Events, LinkStats, Received, Receiver};
pub use sequence::{
    SequenceCounter, SequenceTracker, SequenceVerdict, SessionOpener, DUPLICATE_WINDOW,
};
