//! The messages exchanged between the host and the field box, as serde types
//! with fixed capacities (no allocation on either side).
//!
//! Every frame on the wire is a [`Frame`]: a per-direction sequence number and
//! one message, [`HostMessage`] from host to box or [`DeviceMessage`] from box
//! to host.
//!
//! # Compatibility rule
//!
//! The frame header (`seq`, then the enum variant index) and the handshake
//! variants ([`HostMessage::Hello`] = 0, [`DeviceMessage::HelloAck`] = 0,
//! [`DeviceMessage::VersionMismatch`] = 1) with the leading
//! `protocol_version` field are frozen across protocol versions, so that two
//! different versions can always tell each other that they differ. Any other
//! change to a message's layout bumps [`PROTOCOL_VERSION`].
//!
//! # Conversation
//!
//! The host speaks first with `Hello`; the box answers `HelloAck` (same
//! version) or `VersionMismatch` and then ignores everything but `Hello` until
//! a version matches. Every other host message is a command answered by
//! exactly one [`DeviceMessage::Ack`] or [`DeviceMessage::Nack`] carrying the
//! command's sequence number (sample blocks included: the acks pace a replay).
//!
//! Sequence numbers restart with the session: the host restarts its
//! [`Transmitter`](super::Transmitter) before each `Hello` (so `Hello` is frame
//! 0) and the box restarts its own on accepting a `Hello` (so `HelloAck` is
//! frame 0). A receiver takes frame 0 as a restart, not as a loss. A
//! `Hello` sent again because no answer came carries a fresh nonce, so the
//! box takes it (and its answer the host) as a new session rather than as a
//! repeated frame 0 (see [`sequence`](super::sequence), rule 2).

use crate::bearing::BearingCoefficients;
use crate::phasor::Complex;
use crate::regression::{ParameterScale, PARAMETERS};
use crate::rls::PedestalEstimate;
use serde::{Deserialize, Serialize};

use super::health::BoxHealth;
use super::receiver::LinkStats;

/// Version of this protocol; both ends must agree (see the compatibility rule
/// in the module docs). 2: phasor frames carry each phasor's noise, estimate
/// entries the reduced χ² and the guarded-equation counts. 3: `HelloAck`
/// and `Status` carry the box's health ([`BoxHealth`]: sample clock,
/// previous reset, acquisition faults); `Nack(SamplingUnavailable)`.
pub const PROTOCOL_VERSION: u16 = 3;

/// Most ADC channels one [`HostMessage::ConfigureChannels`] can describe and
/// [`DeviceCounters::adc_saturation`] can report.
pub const MAX_CHANNELS: usize = 16;

/// Most bearings (and so pedestals: one pedestal per bearing) in one phasor or
/// estimate frame.
pub const MAX_BEARINGS: usize = 4;

/// Most bearing-table rows in one [`BearingTableChunk`]; a table is sent as
/// several chunks so that each frame stays well below
/// [`MAX_FRAME_SIZE`](super::MAX_FRAME_SIZE).
pub const MAX_TABLE_ROWS_PER_CHUNK: usize = 8;

/// Most sample values (sample vectors × channels) in one replayed
/// [`SampleBlock`].
pub const MAX_BLOCK_VALUES: usize = 96;

/// Most keyphasor edges inside one replayed [`SampleBlock`].
pub const MAX_KEYPHASOR_EDGES: usize = 8;

/// One frame on the wire: a sequence number and a message.
///
/// Each direction numbers its frames independently with a
/// [`SequenceCounter`](super::SequenceCounter): 0 for the first frame of a
/// session, then 1, 2, … wrapping from `u32::MAX` back to 1 (0 is never
/// reused inside a session). The receiver counts what was lost or repeated
/// (see [`SequenceTracker`](super::SequenceTracker)).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame<M> {
    /// Sequence number of this frame in its direction.
    pub seq: u32,
    /// The message.
    pub message: M,
}

/// Messages from the host to the field box.
///
/// Variant order is part of the wire format: append new variants at the end.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HostMessage {
    /// Opens a session (frozen layout, variant 0).
    Hello(Hello),
    /// Liveness check; answered by an `Ack`.
    Ping,
    /// Replaces the whole channel configuration (only while stopped).
    ConfigureChannels(ChannelSet),
    /// Sets how many revolutions are averaged into one phasor frame.
    ConfigureAveraging(Averaging),
    /// Sets the recursive least-squares settings (only while stopped).
    ConfigureRls(RlsSettings),
    /// One chunk of one bearing's coefficient table (only while stopped).
    BearingTable(BearingTableChunk),
    /// Starts acquisition, phasor extraction and estimation.
    Start,
    /// Stops acquisition; the configuration is kept.
    Stop,
    /// A block of replayed samples, used instead of the ADC (only while running).
    Samples(SampleBlock),
}

/// Messages from the field box to the host.
///
/// Variant order is part of the wire format: append new variants at the end.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DeviceMessage {
    /// Accepts a `Hello` (frozen layout, variant 0).
    HelloAck(HelloAck),
    /// Refuses a `Hello` whose protocol version differs (frozen layout, variant 1).
    VersionMismatch(VersionMismatch),
    /// The command with this sequence number was accepted.
    Ack(Ack),
    /// The command with this sequence number was refused, and why.
    Nack(Nack),
    /// One averaged set of 1X phasors.
    Phasors(PhasorFrame),
    /// The current pedestal parameter estimates.
    Estimates(EstimateFrame),
    /// Health counters and state.
    Status(StatusFrame),
}

impl super::SessionOpener for HostMessage {
    fn session_nonce(&self) -> Option<u32> {
        match self {
            HostMessage::Hello(h) => Some(h.host_nonce),
            _ => None,
        }
    }
}

impl super::SessionOpener for DeviceMessage {
    fn session_nonce(&self) -> Option<u32> {
        match self {
            DeviceMessage::HelloAck(a) => Some(a.host_nonce),
            DeviceMessage::VersionMismatch(m) => Some(m.host_nonce),
            _ => None,
        }
    }
}

mod configure;
#[cfg(feature = "defmt")]
mod defmt_impls;
mod handshake;
mod replies;
mod reports;
mod samples;

pub use configure::*;
pub use handshake::*;
pub use replies::*;
pub use reports::*;
pub use samples::*;
