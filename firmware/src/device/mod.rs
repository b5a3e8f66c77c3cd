//! The box's side of the wire protocol, in three parts that the board's
//! tasks own separately: [`Session`] (state, receiver, commands: the
//! protocol task's), [`Extraction`] (configuration, pipeline, sample buffer:
//! the extraction task's) and [`Outbox`] (the frame queue both hand frames
//! to). [`Device`] holds all three for one thread (QEMU, tests): its
//! [`Device::poll`] is the main-loop step that ties the link, the sample
//! source and the pipeline together.
//!
//! # What the host sees
//!
//! 1. Host `Hello` → box `HelloAck` (frame seq 0 of the session) or
//!    `VersionMismatch`. Anything else before that → `Nack(NoSession)`.
//! 2. Host configures (while stopped): `ConfigureChannels`,
//!    `ConfigureAveraging`, `ConfigureRls`, `BearingTable` chunks; each →
//!    `Ack` or `Nack(reason)`.
//! 3. `Start` → `Ack` once every configured bearing has a complete table,
//!    else `Nack(WrongState)`.
//! 4. While running, each `Samples` block → `Ack` after it was processed
//!    (or `Nack`); the phasor/estimate frames it produced are queued before
//!    the `Ack`. Blocks are taken strictly in order (go-back-N): a block
//!    that repeats processed samples → `Ack` again, unprocessed; a block
//!    after a missing one → `Nack(BadBlock)`, unprocessed (see
//!    [`crate::replay`]). With an ADC source, frames come as revolutions
//!    complete.
//! 5. `Stop` → `Ack`, then the final `Estimates` (if any) and a `Status`.
//! 6. A `Status` frame every [`STATUS_PERIOD_MS`] while a session is open.
//!
//! Replies (`Ack`, `Nack`, `HelloAck`) are never dropped for data: data
//! frames only go into the queue if [`REPLY_RESERVE`] bytes stay free, and a
//! data frame that does not fit is counted in `queue_full_drops`.

use crate::config::Configuration;
use crate::link::ByteLink;
use crate::source::{SampleSource, CHANNELS};
use plinth_shared::protocol::{
    BoxHealth, Capabilities, DeviceCounters, DeviceState, FirmwareVersion, LinkStats, MAX_BEARINGS,
};

mod extraction;
mod outbox;
mod session;
mod shared;

pub use extraction::Extraction;
pub use outbox::Outbox;
pub use session::{Session, TX_CHUNK};
pub use shared::{Inline, Lock, Shared};

/// Bytes of encoded frames waiting for the transmitter.
pub const TX_QUEUE_BYTES: usize = 4096;

/// Queue bytes kept free for replies when a data frame is queued.
pub const REPLY_RESERVE: usize = 256;

/// Interval between status frames while a session is open [ms].
pub const STATUS_PERIOD_MS: u32 = 1000;

/// Received bytes handled per [`Device::poll`] (bounds one loop pass).
pub const RX_BUDGET: usize = 1024;

/// Bytes handed to the transmitter per [`Device::poll`].
pub const TX_BUDGET: usize = 1024;

/// ADC sample rate per channel [Hz].
pub const SAMPLE_RATE_HZ: f32 = 51_200.0;

/// This image's version (from Cargo.toml).
pub fn firmware_version() -> FirmwareVersion {
    let parse = |s: &str| s.parse::<u16>().unwrap_or(0);
    FirmwareVersion {
        major: parse(env!("CARGO_PKG_VERSION_MAJOR")),
        minor: parse(env!("CARGO_PKG_VERSION_MINOR")),
        patch: parse(env!("CARGO_PKG_VERSION_PATCH")),
    }
}

/// What the box can do, for `HelloAck`: `volts_per_code` is the ADC step [V].
pub fn capabilities(volts_per_code: f32) -> Capabilities {
    capabilities_at(volts_per_code, SAMPLE_RATE_HZ)
}

/// [`capabilities`] of a box sampling at `sample_rate_hz` [Hz] (a board's
/// timer gives the nominal rate rounded to whole timer ticks).
pub fn capabilities_at(volts_per_code: f32, sample_rate_hz: f32) -> Capabilities {
    Capabilities {
        max_channels: CHANNELS as u8,
        max_bearings: MAX_BEARINGS as u8,
        bearing_table_capacity: crate::config::TABLE_ROWS as u16,
        sample_rate_hz,
        adc_volts_per_code: volts_per_code,
    }
}

/// What one [`Device::poll`] did (for the caller's idle/exit decisions).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Activity {
    /// Bytes received.
    pub received: usize,
    /// Bytes sent.
    pub sent: usize,
    /// Sample vectors processed.
    pub samples: usize,
}

/// The box in one thread: session, extraction state and outbox together.
pub struct Device {
    session: Session,
    extraction: Extraction,
    outbox: Outbox,
}

impl Device {
    /// A box waiting for `Hello`, whose ADC step is `volts_per_code` [V],
    /// sampling at [`SAMPLE_RATE_HZ`].
    pub fn new(volts_per_code: f32) -> Self {
        Self::with_sample_rate(volts_per_code, SAMPLE_RATE_HZ)
    }

    /// A box waiting for `Hello` that samples at `sample_rate_hz` [Hz] (the
    /// rate its timer really gives: announced in `HelloAck`, used by the
    /// pipeline for the rotor speed).
    pub fn with_sample_rate(volts_per_code: f32, sample_rate_hz: f32) -> Self {
        Self {
            session: Session::new(capabilities_at(volts_per_code, sample_rate_hz)),
            extraction: Extraction::new(),
            outbox: Outbox::new(),
        }
    }

    /// Sets what the box reports about its platform ([`Session::set_platform`]).
    pub fn set_platform(
        &mut self,
        sample_clock: plinth_shared::protocol::SampleClock,
        previous_reset: plinth_shared::protocol::PreviousReset,
    ) {
        self.session.set_platform(sample_clock, previous_reset);
    }

    /// The health the box reports, with `source`'s fault counters.
    pub fn health<S: SampleSource>(&self, source: &S) -> BoxHealth {
        self.session.health(source)
    }

    /// Session state.
    pub fn state(&self) -> DeviceState {
        self.session.state()
    }

    /// Health counters of the session.
    pub fn counters(&self) -> DeviceCounters {
        self.session.counters(&self.extraction, &self.outbox)
    }

    /// What the box's receiver counted on the host link this session.
    pub fn link_stats(&self) -> LinkStats {
        self.session.link_stats()
    }

    /// The session's configuration.
    pub fn config(&self) -> &Configuration {
        &self.extraction.config
    }

    /// True once after each accepted `Stop` (the QEMU image exits then).
    pub fn take_stopped(&mut self) -> bool {
        self.session.take_stopped()
    }

    /// True when every queued byte has gone to the transmitter.
    pub fn tx_idle(&self) -> bool {
        self.outbox.is_empty()
    }

    /// One bounded pass of the main loop: received bytes → commands, source
    /// samples → pipeline ([`Extraction::run`], inline), periodic status,
    /// queued bytes → link. `now_ms` is the time since boot [ms] (wrapping).
    pub fn poll<L: ByteLink, S: SampleSource>(
        &mut self,
        link: &mut L,
        source: &mut S,
        now_ms: u32,
    ) -> Activity {
        let mut shared = Inline {
            extraction: &mut self.extraction,
            source,
            outbox: &mut self.outbox,
        };
        self.session.poll(link, &mut shared, now_ms)
    }
}
