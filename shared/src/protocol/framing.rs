//! Frame encoding and decoding: postcard serialization, CRC-32C appended,
//! COBS byte stuffing, 0x00 delimiters, composed from postcard's flavours.
//!
//! On the wire a frame is
//!
//! ```text
//! 0x00 | COBS( postcard(Frame<M>) | CRC-32C(postcard bytes) as 4 LE bytes ) | 0x00
//! ```
//!
//! The leading delimiter ends whatever garbage preceded the frame on the line
//! (an interrupted frame, noise at power-up), so the frame after garbage is
//! never lost; the receiver ignores empty frames (two 0x00 in a row). It costs
//! one byte per frame.

use crc::{Crc, CRC_32_ISCSI};
use postcard::ser_flavors::{crc::CrcModifier, Cobs, Slice};
use serde::de::DeserializeOwned;
use serde::Serialize;

use super::messages::Frame;

/// The frame check: CRC-32C (Castagnoli, `CRC_32_ISCSI`), appended little-endian.
pub static FRAME_CRC: Crc<u32> = Crc::<u32>::new(&CRC_32_ISCSI);

/// Bytes of CRC at the end of every (un-stuffed) frame.
pub const CRC_LEN: usize = 4;

/// The frame delimiter; COBS guarantees it occurs nowhere else.
pub const DELIMITER: u8 = 0x00;

/// Largest frame on the wire \[bytes], both delimiters included. Encoding a
/// larger frame fails; a receiver discards one as oversize.
pub const MAX_FRAME_SIZE: usize = 512;

/// Largest COBS body between the two delimiters \[bytes]: the receive buffer.
pub const MAX_BODY_SIZE: usize = MAX_FRAME_SIZE - 2;

/// Largest postcard-serialized `Frame` \[bytes] guaranteed to fit in
/// [`MAX_FRAME_SIZE`] whatever its bytes are (worst-case COBS overhead). Every
/// message type at full capacity stays below it (checked by a test).
pub const MAX_MESSAGE_SIZE: usize = 500;

/// Wire size bound \[bytes] of a frame whose postcard serialization is
/// `message_len` bytes: CRC, worst-case COBS overhead (one code byte per 254
/// bytes, plus one) and both delimiters.
pub const fn max_wire_size(message_len: usize) -> usize {
    let raw = message_len + CRC_LEN;
    2 + raw + raw / 254 + 1
}

const _: () = assert!(max_wire_size(MAX_MESSAGE_SIZE) <= MAX_FRAME_SIZE);

/// Why a frame could not be encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EncodeError {
    /// The caller's buffer is smaller than the frame (and than [`MAX_FRAME_SIZE`]).
    BufferTooSmall,
    /// The frame would exceed [`MAX_FRAME_SIZE`] on the wire.
    FrameTooLarge,
    /// serde could not serialize the message (not possible for this
    /// protocol's message types).
    Serialize,
}

/// Why received bytes did not give a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkError {
    /// More than [`MAX_BODY_SIZE`] bytes without a delimiter; `len` bytes
    /// (saturating at `u32::MAX`) were discarded up to the next 0x00.
    Oversize {
        /// Length of the discarded body \[bytes].
        len: u32,
    },
    /// The body is not valid COBS.
    Cobs,
    /// The CRC does not match, or the body is too short to hold one.
    Crc,
    /// The CRC matches but the bytes are not a `Frame` of the expected message
    /// type: the peer speaks another protocol (or has a bug), not line noise.
    Decode,
    /// A valid frame whose sequence number was already accepted (see
    /// [`SequenceTracker`](super::SequenceTracker)); it is not delivered again.
    Duplicate {
        /// Its sequence number.
        seq: u32,
    },
}

/// Encodes `Frame { seq, message }` into `buf`, returning the used part: the
/// complete wire bytes, both 0x00 delimiters included. Never allocates.
///
/// A buffer of [`MAX_FRAME_SIZE`] bytes holds any frame that can be sent.
pub fn encode<'b, M: Serialize + ?Sized>(
    seq: u32,
    message: &M,
    buf: &'b mut [u8],
) -> Result<&'b mut [u8], EncodeError> {
    let limited = buf.len() >= MAX_FRAME_SIZE;
    let full = if limited {
        EncodeError::FrameTooLarge
    } else {
        EncodeError::BufferTooSmall
    };
    let limit = buf.len().min(MAX_FRAME_SIZE);
    let (first, rest) = buf[..limit].split_first_mut().ok_or(full)?;
    *first = DELIMITER;
    // Serialize → CRC over the postcard bytes, appended → COBS with its
    // trailing 0x00 (CrcModifier feeds Cobs, which writes into the slice).
    let cobs = Cobs::try_new(Slice::new(rest)).map_err(|_| full)?;
    let flavor = CrcModifier::new(cobs, FRAME_CRC.digest());
    let frame = Frame { seq, message };
    let used = match postcard::serialize_with_flavor(&frame, flavor) {
        Ok(used) => used.len(),
        Err(postcard::Error::SerializeBufferFull) => return Err(full),
        Err(_) => return Err(EncodeError::Serialize),
    };
    Ok(&mut buf[..1 + used])
}

/// Decodes one frame body (the bytes between two delimiters, not empty),
/// un-stuffing it in place. Errors are [`LinkError::Cobs`],
/// [`LinkError::Crc`] and [`LinkError::Decode`]; never panics.
///
/// A frame is accepted only if the message uses every byte before the last
/// four and those four are its CRC. A rejected body is classified by the CRC
/// over all but its last four bytes: a mismatch means line corruption
/// ([`LinkError::Crc`]), a match means a protocol disagreement
/// ([`LinkError::Decode`]).
pub fn decode_frame<M: DeserializeOwned>(body: &mut [u8]) -> Result<Frame<M>, LinkError> {
    let n = cobs::decode_in_place(body).map_err(|_| LinkError::Cobs)?;
    let raw = body.get(..n).ok_or(LinkError::Cobs)?;
    if raw.len() <= CRC_LEN {
        return Err(LinkError::Crc);
    }
    if let Ok((frame, rest)) =
        postcard::de_flavors::crc::take_from_bytes_u32::<Frame<M>>(raw, FRAME_CRC.digest())
    {
        if rest.is_empty() {
            return Ok(frame);
        }
    }
    // Rejected: tell corruption from a well-protected frame of another shape
    // by the CRC at the true end of the body.
    let (data, crc) = raw.split_at(raw.len() - CRC_LEN);
    let mut le = [0u8; CRC_LEN];
    le.copy_from_slice(crc);
    if FRAME_CRC.checksum(data) == u32::from_le_bytes(le) {
        Err(LinkError::Decode)
    } else {
        Err(LinkError::Crc)
    }
}

/// The sending end of a link: numbers frames with a
/// [`SequenceCounter`](super::SequenceCounter) and encodes them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Transmitter {
    sequence: super::SequenceCounter,
}

impl Transmitter {
    /// A transmitter at the start of a session (first frame numbered 0).
    pub const fn new() -> Self {
        Self {
            sequence: super::SequenceCounter::new(),
        }
    }

    /// Encodes `message` as the next frame into `buf`; returns its sequence
    /// number and the wire bytes. The number is used up only on success, so a
    /// failed encode leaves no gap.
    pub fn encode<'b, M: Serialize + ?Sized>(
        &mut self,
        message: &M,
        buf: &'b mut [u8],
    ) -> Result<(u32, &'b mut [u8]), EncodeError> {
        let seq = self.sequence.peek();
        let bytes = encode(seq, message, buf)?;
        self.sequence.next_seq();
        Ok((seq, bytes))
    }

    /// The number the next frame will carry.
    pub const fn next_seq(&self) -> u32 {
        self.sequence.peek()
    }

    /// Starts a new session: the next frame is numbered 0 (the host does this
    /// before each `Hello`, the box on accepting one).
    pub fn restart(&mut self) {
        self.sequence.restart();
    }
}
