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

/// Host → box: opens a session.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Hello {
    /// The host's [`PROTOCOL_VERSION`] (frozen: first field).
    pub protocol_version: u16,
    /// A number the host chose for this session; echoed in the answer so that
    /// the host can tell the answer to this `Hello` from a stale one.
    pub host_nonce: u32,
}

/// Box → host: the session is open; what the box is and can do.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HelloAck {
    /// The box's [`PROTOCOL_VERSION`] (frozen: first field), equal to the host's.
    pub protocol_version: u16,
    /// The `host_nonce` of the `Hello` this answers.
    pub host_nonce: u32,
    /// Version of the firmware image.
    pub firmware_version: FirmwareVersion,
    /// Limits of this box.
    pub capabilities: Capabilities,
    /// Sample clock, previous reset, faults so far.
    pub health: BoxHealth,
}

/// Box → host: the `Hello` spoke another protocol version; nothing but a new
/// `Hello` is accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct VersionMismatch {
    /// The box's [`PROTOCOL_VERSION`] (frozen: first field).
    pub device_protocol_version: u16,
    /// The version the host's `Hello` carried.
    pub host_protocol_version: u16,
    /// The `host_nonce` of the refused `Hello`.
    pub host_nonce: u32,
}

/// Semantic version of the firmware image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FirmwareVersion {
    /// Incompatible changes.
    pub major: u16,
    /// Compatible additions.
    pub minor: u16,
    /// Fixes.
    pub patch: u16,
}

/// What one box can do; the host must stay within these limits.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Capabilities {
    /// ADC channels available (≤ [`MAX_CHANNELS`]).
    pub max_channels: u8,
    /// Bearings (= pedestals) the box can process (≤ [`MAX_BEARINGS`]).
    pub max_bearings: u8,
    /// Rows each bearing's coefficient table can hold.
    pub bearing_table_capacity: u16,
    /// ADC sample rate per channel \[Hz].
    pub sample_rate_hz: f32,
    /// ADC step: an ADC code c stands for the voltage c · this \[V].
    pub adc_volts_per_code: f32,
}

/// How a channel's transducer measures vibration: the extractor's kind
/// (one definition; encoded as its variant index, Displacement = 0,
/// Velocity = 1, Acceleration = 2).
pub use crate::extractor::SensorKind;

/// Which displacement a channel measures at its bearing (formats.md: `rel` is
/// rotor minus pedestal, `ped` is absolute pedestal; y vertical, z horizontal).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Quantity {
    /// Rotor relative to pedestal, vertical.
    RelY,
    /// Rotor relative to pedestal, horizontal.
    RelZ,
    /// Absolute pedestal, vertical.
    PedY,
    /// Absolute pedestal, horizontal.
    PedZ,
}

/// Configuration of one ADC channel.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelConfig {
    /// ADC channel index (0-based, < [`Capabilities::max_channels`]).
    pub channel: u8,
    /// Transducer type, which fixes the unit of `sensitivity`.
    pub kind: SensorKind,
    /// Transducer output per unit of measured motion: V/m, V/(m/s) or
    /// V/(m/s²) according to `kind`.
    pub sensitivity: f32,
    /// Bearing index (0-based, < [`Capabilities::max_bearings`]).
    pub bearing: u8,
    /// What the channel measures at that bearing.
    pub quantity: Quantity,
}

/// Host → box: the complete channel configuration (replaces the previous one).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChannelSet {
    /// The configured channels; channels not listed are unused.
    pub channels: heapless::Vec<ChannelConfig, MAX_CHANNELS>,
}

/// Host → box: revolution averaging of the phasor extractor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Averaging {
    /// Revolutions averaged into one phasor frame (≥ 1).
    pub revolutions_per_phasor: u16,
}

/// Host → box: settings of the per-pedestal recursive least squares.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RlsSettings {
    /// Forgetting factor λ per speed (all four equations of a phasor frame
    /// alike), in (0, 1]; 1 = never forget.
    pub forgetting_factor: f32,
    /// Stiffness column scale [N/m].
    pub scale_k: f32,
    /// Mass column scale \[kg].
    pub scale_m: f32,
    /// Damping column scale [N·s/m].
    pub scale_c: f32,
}

impl RlsSettings {
    /// The column scales as the estimator takes them.
    pub fn parameter_scale(&self) -> ParameterScale<f32> {
        ParameterScale {
            k: self.scale_k,
            m: self.scale_m,
            c: self.scale_c,
        }
    }

    /// Settings from a forgetting factor λ and column scales.
    pub fn new(forgetting_factor: f32, scale: ParameterScale<f32>) -> Self {
        Self {
            forgetting_factor,
            scale_k: scale.k,
            scale_m: scale.m,
            scale_c: scale.c,
        }
    }
}

/// One row of a bearing table: the coefficients at one speed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BearingTableRow {
    /// Rotor speed \[Hz]; rows must increase in speed across the whole table.
    pub speed_hz: f32,
    /// Coefficients at that speed: k [N/m], c [N·s/m].
    pub coefficients: BearingCoefficients<f32>,
}

/// Host → box: consecutive rows `first_row ..` of one bearing's table.
///
/// A table of `total_rows` rows is sent as chunks in order; a chunk with
/// `first_row == 0` starts the table afresh, and the table is complete (and
/// used) once `first_row + rows.len() == total_rows`. The box refuses a chunk
/// that does not continue the table it is building.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BearingTableChunk {
    /// Bearing index (0-based).
    pub bearing: u8,
    /// Number of rows in the whole table.
    pub total_rows: u16,
    /// Index in the table of `rows[0]`.
    pub first_row: u16,
    /// The rows of this chunk (at least one).
    pub rows: heapless::Vec<BearingTableRow, MAX_TABLE_ROWS_PER_CHUNK>,
}

impl BearingTableChunk {
    /// Splits a whole table for `bearing` into chunks of at most
    /// [`MAX_TABLE_ROWS_PER_CHUNK`] rows, in sending order (nothing for an
    /// empty table). Fails when the table has more than `u16::MAX` rows.
    pub fn split(
        bearing: u8,
        table: &[BearingTableRow],
    ) -> Result<impl Iterator<Item = Self> + '_, TableTooLong> {
        let total_rows =
            u16::try_from(table.len()).map_err(|_| TableTooLong { rows: table.len() })?;
        Ok(table
            .chunks(MAX_TABLE_ROWS_PER_CHUNK)
            .enumerate()
            .map(move |(i, rows)| {
                let mut v = heapless::Vec::new();
                for r in rows {
                    // Cannot fail: `chunks` yields at most the capacity.
                    let _ = v.push(*r);
                }
                Self {
                    bearing,
                    total_rows,
                    // i · MAX_TABLE_ROWS_PER_CHUNK < total_rows ≤ u16::MAX.
                    first_row: (i * MAX_TABLE_ROWS_PER_CHUNK) as u16,
                    rows: v,
                }
            }))
    }

    /// True when this chunk ends the table.
    pub fn is_last(&self) -> bool {
        self.first_row as usize + self.rows.len() == self.total_rows as usize
    }
}

/// A bearing table too long to describe in [`BearingTableChunk`]s.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TableTooLong {
    /// Rows in the table.
    pub rows: usize,
}

/// The sample values of a replayed block, interleaved by sample vector:
/// value `k · channels + n` is sample vector k of channel n.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Samples {
    /// Raw ADC codes; volts = code · [`Capabilities::adc_volts_per_code`].
    AdcCodes(heapless::Vec<i16, MAX_BLOCK_VALUES>),
    /// Transducer output voltages \[V] (the channel's sensitivity still applies).
    Volts(heapless::Vec<f32, MAX_BLOCK_VALUES>),
}

impl Samples {
    /// Number of values (sample vectors × channels).
    pub fn len(&self) -> usize {
        match self {
            Samples::AdcCodes(v) => v.len(),
            Samples::Volts(v) => v.len(),
        }
    }

    /// True when the block holds no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A keyphasor (once-per-revolution) pulse inside a replayed block.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct KeyphasorEdge {
    /// Time of the edge from the block's first sample vector, in sample
    /// periods (fractional: sub-sample timing), in [0, sample vectors).
    pub offset_samples: f32,
}

/// Host → box: K sample vectors of N channels to process as if the ADC had
/// produced them, with the keyphasor edges that fall inside the block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SampleBlock {
    /// Index of the block's first sample vector since `Start` (wrapping), so
    /// that the box can detect a missing block.
    pub first_sample: u32,
    /// Channels per sample vector (N ≥ 1), in the order of the channel set.
    pub channels: u8,
    /// The K · N values.
    pub samples: Samples,
    /// Keyphasor edges inside the block, in increasing time.
    pub keyphasor_edges: heapless::Vec<KeyphasorEdge, MAX_KEYPHASOR_EDGES>,
}

/// Why a [`SampleBlock`] is malformed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SampleBlockError {
    /// `channels` is zero.
    NoChannels,
    /// The number of values is not a multiple of `channels`.
    Ragged,
    /// Keyphasor edge `index` is not finite, outside [0, K) or not after the
    /// previous one.
    BadEdge {
        /// Position of the edge in `keyphasor_edges`.
        index: u8,
    },
}

impl SampleBlock {
    /// Checks the block's shape and returns K, the number of sample vectors.
    pub fn sample_vectors(&self) -> Result<usize, SampleBlockError> {
        let n = self.channels as usize;
        if n == 0 {
            return Err(SampleBlockError::NoChannels);
        }
        let len = self.samples.len();
        if !len.is_multiple_of(n) {
            return Err(SampleBlockError::Ragged);
        }
        let k = len / n;
        let mut prev = f32::NEG_INFINITY;
        for (i, e) in self.keyphasor_edges.iter().enumerate() {
            let t = e.offset_samples;
            if !t.is_finite() || t < 0.0 || t >= k as f32 || t <= prev {
                return Err(SampleBlockError::BadEdge { index: i as u8 });
            }
            prev = t;
        }
        Ok(k)
    }
}

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

/// A 1X phasor as a real/imaginary pair on the wire.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WirePhasor {
    /// Real part (unit of the quantity, m for displacements).
    pub re: f32,
    /// Imaginary part (same unit).
    pub im: f32,
}

impl From<Complex<f32>> for WirePhasor {
    fn from(c: Complex<f32>) -> Self {
        Self { re: c.re, im: c.im }
    }
}

impl From<WirePhasor> for Complex<f32> {
    fn from(p: WirePhasor) -> Self {
        Complex::new(p.re, p.im)
    }
}

/// The 1X phasors at one bearing, (y, z) each, in m (formats.md convention:
/// q(t) = Re{Q·e^{iΩt}}, t = 0 at the keyphasor).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BearingPhasors {
    /// Bearing index (0-based).
    pub bearing: u8,
    /// Rotor relative to pedestal, (y, z) \[m].
    pub rel: [WirePhasor; 2],
    /// Absolute pedestal, (y, z) \[m].
    pub ped: [WirePhasor; 2],
    /// Noise of each `rel` phasor, (y, z): sqrt(E|n|²) of its complex noise
    /// \[m] (formats.md's `rel_y_sd`, `rel_z_sd`); NaN where not measured.
    pub rel_sd: [f32; 2],
    /// Noise of each `ped` phasor, (y, z) \[m] (`ped_y_sd`, `ped_z_sd`).
    pub ped_sd: [f32; 2],
}

/// Box → host: one revolution-average of 1X phasors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhasorFrame {
    /// Index since `Start` (wrapping) of the first revolution in the average.
    pub revolution: u32,
    /// Revolutions averaged.
    pub revolutions: u16,
    /// Mean rotor speed over the averaged revolutions \[Hz].
    pub speed_hz: f32,
    /// Phasors per configured bearing.
    pub bearings: heapless::Vec<BearingPhasors, MAX_BEARINGS>,
}

/// One pedestal's estimate on the wire: θ = (k_y [N/m], k_z [N/m], m \[kg],
/// c_y [N·s/m], c_z [N·s/m]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PedestalEstimateEntry {
    /// Bearing index (0-based) of the pedestal.
    pub bearing: u8,
    /// Parameter values in θ order.
    pub theta: [f32; PARAMETERS],
    /// Standard errors in θ order, same units; NaN when not yet estimable.
    pub std_err: [f32; PARAMETERS],
    /// Number of equations folded in (effective, with forgetting).
    pub equations: f32,
    /// Σ(whitened residual)²/(n − 5): 1 when the residuals are as large as
    /// the phasors' noise says (dimensionless); NaN while n ≤ 5.
    pub reduced_chi_square: f32,
    /// Equations scaled down because their squares would overflow f32.
    pub rescaled: u32,
    /// Equations rejected as not finite.
    pub rejected: u32,
}

impl PedestalEstimateEntry {
    /// The entry for the pedestal at `bearing`.
    pub fn new(bearing: u8, e: &PedestalEstimate<f32>) -> Self {
        Self {
            bearing,
            theta: e.theta,
            std_err: e.std_err,
            equations: e.equations,
            reduced_chi_square: e.reduced_chi_square,
            rescaled: e.rescaled,
            rejected: e.rejected,
        }
    }

    /// The estimate in the estimator's own type.
    pub fn estimate(&self) -> PedestalEstimate<f32> {
        PedestalEstimate {
            theta: self.theta,
            std_err: self.std_err,
            equations: self.equations,
            reduced_chi_square: self.reduced_chi_square,
            rescaled: self.rescaled,
            rejected: self.rejected,
        }
    }
}

/// Box → host: the current estimates of every pedestal that has one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EstimateFrame {
    /// Index since `Start` of the last revolution folded in.
    pub revolution: u32,
    /// Per pedestal.
    pub pedestals: heapless::Vec<PedestalEstimateEntry, MAX_BEARINGS>,
}

/// What the box is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DeviceState {
    /// No session: waiting for a `Hello` with a matching version.
    AwaitingHello,
    /// Session open, stopped: configuration accepted.
    Idle,
    /// Acquiring and processing.
    Running,
}

/// The box's health counters, all since the session opened (saturating).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct DeviceCounters {
    /// ADC DMA buffer overruns (samples lost before processing).
    pub overruns: u32,
    /// Blocks or frames dropped because a queue was full.
    pub queue_full_drops: u32,
    /// Keyphasor pulses missing (a revolution far longer than expected).
    pub keyphasor_missing: u32,
    /// Extra keyphasor pulses (a revolution far shorter than expected).
    pub keyphasor_extra: u32,
    /// Frames sent to the host.
    pub frames_sent: u32,
    /// Commands answered with a `Nack`.
    pub commands_rejected: u32,
    /// Samples at the ADC's limits, per configured channel (index = channel).
    pub adc_saturation: heapless::Vec<u32, MAX_CHANNELS>,
}

/// Box → host: periodic health report.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct StatusFrame {
    /// Current state.
    pub state: DeviceState,
    /// Time since boot \[ms] (wrapping).
    pub uptime_ms: u32,
    /// Processing counters.
    pub counters: DeviceCounters,
    /// The box's receive-side link statistics (frames from the host).
    pub link: LinkStats,
    /// Sample clock, previous reset, acquisition faults.
    pub health: BoxHealth,
}

#[cfg(feature = "defmt")]
mod defmt_impls {
    //! `defmt::Format` for the types holding a `heapless::Vec` (heapless 0.8
    //! only supports defmt 0.3, so these are written out).
    use super::*;

    impl defmt::Format for ChannelSet {
        fn format(&self, f: defmt::Formatter) {
            defmt::write!(
                f,
                "ChannelSet {{ channels: {=[?]} }}",
                self.channels.as_slice()
            )
        }
    }

    impl defmt::Format for BearingTableChunk {
        fn format(&self, f: defmt::Formatter) {
            defmt::write!(
                f,
                "BearingTableChunk {{ bearing: {=u8}, total_rows: {=u16}, first_row: {=u16}, rows: {=usize} }}",
                self.bearing,
                self.total_rows,
                self.first_row,
                self.rows.len()
            )
        }
    }

    impl defmt::Format for SampleBlock {
        fn format(&self, f: defmt::Formatter) {
            let kind = match self.samples {
                Samples::AdcCodes(_) => "codes",
                Samples::Volts(_) => "volts",
            };
            defmt::write!(
                f,
                "SampleBlock {{ first_sample: {=u32}, channels: {=u8}, values: {=usize} {=str}, edges: {=[?]} }}",
                self.first_sample,
                self.channels,
                self.samples.len(),
                kind,
                self.keyphasor_edges.as_slice()
            )
        }
    }

    impl defmt::Format for PhasorFrame {
        fn format(&self, f: defmt::Formatter) {
            defmt::write!(
                f,
                "PhasorFrame {{ revolution: {=u32}, revolutions: {=u16}, speed_hz: {=f32}, bearings: {=[?]} }}",
                self.revolution,
                self.revolutions,
                self.speed_hz,
                self.bearings.as_slice()
            )
        }
    }

    impl defmt::Format for EstimateFrame {
        fn format(&self, f: defmt::Formatter) {
            defmt::write!(
                f,
                "EstimateFrame {{ revolution: {=u32}, pedestals: {=[?]} }}",
                self.revolution,
                self.pedestals.as_slice()
            )
        }
    }

    impl defmt::Format for DeviceCounters {
        fn format(&self, f: defmt::Formatter) {
            defmt::write!(
                f,
                "DeviceCounters {{ overruns: {=u32}, queue_full_drops: {=u32}, keyphasor_missing: {=u32}, keyphasor_extra: {=u32}, frames_sent: {=u32}, commands_rejected: {=u32}, adc_saturation: {=[?]} }}",
                self.overruns,
                self.queue_full_drops,
                self.keyphasor_missing,
                self.keyphasor_extra,
                self.frames_sent,
                self.commands_rejected,
                self.adc_saturation.as_slice()
            )
        }
    }

    impl defmt::Format for StatusFrame {
        fn format(&self, f: defmt::Formatter) {
            defmt::write!(
                f,
                "StatusFrame {{ state: {}, uptime_ms: {=u32}, counters: {}, link: {}, health: {} }}",
                self.state,
                self.uptime_ms,
                self.counters,
                self.link,
                self.health
            )
        }
    }
}
