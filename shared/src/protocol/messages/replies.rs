//! The box's answer to every command: `Ack` or `Nack` with its reason.

use super::*;

/// Box → host: a command was accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ack {
    /// Sequence number of the host frame that carried the command.
    pub command_seq: u32,
}

/// Box → host: a command was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Nack {
    /// Sequence number of the host frame that carried the command.
    pub command_seq: u32,
    /// Why it was refused.
    pub reason: NackReason,
}

/// Why the box refused a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NackReason {
    /// No session: send `Hello` first.
    NoSession,
    /// Not allowed in the current state (e.g. configuring while running,
    /// samples while stopped, start without a complete configuration).
    WrongState,
    /// A channel index is at or beyond the box's channel count, or is listed twice.
    BadChannel,
    /// A bearing index is at or beyond the box's bearing count.
    BadBearing,
    /// A number is out of its range (non-finite, zero sensitivity, λ outside
    /// (0, 1], zero revolutions, non-positive scale).
    BadValue,
    /// A bearing-table chunk does not continue the table being built.
    TableOutOfOrder,
    /// A bearing table has more rows than the box can hold.
    TableFull,
    /// Bearing-table speeds do not increase.
    TableNotIncreasing,
    /// A sample block is malformed (see [`SampleBlockError`]) or its channel
    /// count differs from the channel set.
    BadBlock,
    /// The processing queue is full; send the block again later.
    QueueFull,
    /// `Start` refused: the box cannot sample at its clock (see
    /// [`BoxHealth::sampling_refused`] and its `sample_clock`).
    SamplingUnavailable,
}
