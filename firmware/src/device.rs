//! The box's side of the wire protocol: session state, command handling,
//! the outgoing frame queue, and the main-loop step that ties the link, the
//! sample source and the pipeline together.
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
use crate::pipeline::Pipeline;
use crate::source::{SampleBuffer, SampleSource, CHANNELS};
use plinth_shared::protocol::{
    Ack, BoxHealth, Capabilities, DeviceCounters, DeviceMessage, DeviceState, FirmwareVersion,
    HelloAck, HostMessage, LinkStats, Nack, NackReason, Receiver, StatusFrame, Transmitter,
    VersionMismatch, MAX_BEARINGS, MAX_FRAME_SIZE, PROTOCOL_VERSION,
};

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

/// The box: protocol endpoint, configuration and pipeline.
pub struct Device {
    state: DeviceState,
    rx: Receiver<HostMessage>,
    outbox: Outbox,
    config: Configuration,
    pipeline: Option<Pipeline>,
    buffer: SampleBuffer,
    counters: DeviceCounters,
    capabilities: Capabilities,
    last_status_ms: u32,
    stopped: bool,
    /// The platform's part of the health (clock, previous reset).
    platform: BoxHealth,
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
            state: DeviceState::AwaitingHello,
            rx: Receiver::new(),
            outbox: Outbox::new(),
            config: Configuration::new(),
            pipeline: None,
            buffer: SampleBuffer::default(),
            counters: DeviceCounters::default(),
            capabilities: capabilities_at(volts_per_code, sample_rate_hz),
            last_status_ms: 0,
            stopped: false,
            platform: BoxHealth::default(),
        }
    }

    /// Sets what the box reports about its platform in `HelloAck` and
    /// every `Status`: where the sample clock comes from and how the
    /// previous boot ended (the fault counters come from the source).
    pub fn set_platform(
        &mut self,
        sample_clock: plinth_shared::protocol::SampleClock,
        previous_reset: plinth_shared::protocol::PreviousReset,
    ) {
        self.platform.sample_clock = sample_clock;
        self.platform.previous_reset = previous_reset;
    }

    /// The health the box reports, with `source`'s fault counters.
    pub fn health<S: SampleSource>(&self, source: &S) -> BoxHealth {
        let mut h = self.platform;
        source.health(&mut h);
        h
    }

    /// Session state.
    pub fn state(&self) -> DeviceState {
        self.state
    }

    /// Health counters of the session.
    pub fn counters(&self) -> DeviceCounters {
        let mut c = self.counters.clone();
        c.frames_sent = self.outbox.frames_sent;
        c.queue_full_drops = self.outbox.drops;
        if let Some(p) = &self.pipeline {
            p.counters.fold_into(&mut c);
        }
        c
    }

    /// What the box's receiver counted on the host link this session.
    pub fn link_stats(&self) -> LinkStats {
        *self.rx.stats()
    }

    /// The session's configuration.
    pub fn config(&self) -> &Configuration {
        &self.config
    }

    /// True once after each accepted `Stop` (the QEMU image exits then).
    pub fn take_stopped(&mut self) -> bool {
        core::mem::take(&mut self.stopped)
    }

    /// True when every queued byte has gone to the transmitter.
    pub fn tx_idle(&self) -> bool {
        self.outbox.queue.is_empty()
    }

    /// One bounded pass of the main loop: received bytes → commands, source
    /// samples → pipeline, periodic status, queued bytes → link. `now_ms` is
    /// the time since boot [ms] (wrapping).
    pub fn poll<L: ByteLink, S: SampleSource>(
        &mut self,
        link: &mut L,
        source: &mut S,
        now_ms: u32,
    ) -> Activity {
        let mut activity = Activity::default();
        while activity.received < RX_BUDGET {
            let Some(byte) = link.read_byte() else { break };
            activity.received += 1;
            if let Some(Ok(frame)) = self.rx.push_byte(byte) {
                self.command(frame.seq, &frame.message, source, now_ms);
                activity.samples += self.drain_source(source);
            }
        }
        activity.samples += self.drain_source(source);
        if self.state != DeviceState::AwaitingHello
            && now_ms.wrapping_sub(self.last_status_ms) >= STATUS_PERIOD_MS
        {
            self.send_status(source, now_ms);
        }
        while activity.sent < TX_BUDGET {
            let Some(&byte) = self.outbox.queue.front() else {
                break;
            };
            if !link.write_byte(byte) {
                break;
            }
            self.outbox.queue.pop_front();
            activity.sent += 1;
        }
        activity
    }

    /// The extraction step alone: runs whatever the source has through
    /// the pipeline (phasor and estimate frames go to the outbox) and
    /// returns the sample vectors taken. [`Device::poll`] does this too;
    /// `plinth-box` also runs it in its own task, pended by each completed
    /// DMA half, above the protocol's.
    pub fn extract<S: SampleSource>(&mut self, source: &mut S) -> usize {
        self.drain_source(source)
    }

    /// Runs whatever the source has through the pipeline.
    fn drain_source<S: SampleSource>(&mut self, source: &mut S) -> usize {
        if self.state != DeviceState::Running {
            return 0;
        }
        self.buffer.clear();
        source.poll(&mut self.buffer);
        let n = self.buffer.samples.len();
        if n == 0 && self.buffer.lost_before == 0 {
            return 0;
        }
        for (total, add) in self
            .counters
            .adc_saturation
            .iter_mut()
            .zip(self.buffer.saturated)
        {
            *total = total.saturating_add(add);
        }
        if let Some(mut pipeline) = self.pipeline.take() {
            let outbox = &mut self.outbox;
            let mut out = |m: DeviceMessage| outbox.push(&m, REPLY_RESERVE);
            pipeline.process(&self.buffer, &self.config.tables, &mut out);
            self.pipeline = Some(pipeline);
        }
        n
    }

    /// Handles one host command.
    fn command<S: SampleSource>(
        &mut self,
        seq: u32,
        message: &HostMessage,
        source: &mut S,
        now_ms: u32,
    ) {
        if let HostMessage::Hello(hello) = message {
            self.hello(hello, source, now_ms);
            return;
        }
        if self.state == DeviceState::AwaitingHello {
            self.nack(seq, NackReason::NoSession);
            return;
        }
        let running = self.state == DeviceState::Running;
        let result = match message {
            HostMessage::Hello(_) => Ok(()),
            HostMessage::Ping => Ok(()),
            HostMessage::ConfigureChannels(_)
            | HostMessage::ConfigureAveraging(_)
            | HostMessage::ConfigureRls(_)
            | HostMessage::BearingTable(_)
                if running =>
            {
                Err(NackReason::WrongState)
            }
            HostMessage::ConfigureChannels(set) => self.config.set_channels(set),
            HostMessage::ConfigureAveraging(a) => self.config.set_averaging(a),
            HostMessage::ConfigureRls(r) => self.config.set_rls(r),
            HostMessage::BearingTable(chunk) => self.config.add_table_chunk(chunk),
            HostMessage::Start if running => Err(NackReason::WrongState),
            HostMessage::Start => self.start(source),
            HostMessage::Stop => {
                self.ack(seq);
                self.stop(source, now_ms);
                return;
            }
            HostMessage::Samples(_) if !running => Err(NackReason::WrongState),
            HostMessage::Samples(block) => source.replay(block, &self.config.layout()),
        };
        match result {
            Ok(()) => self.ack(seq),
            Err(reason) => self.nack(seq, reason),
        }
    }

    /// Opens a session (or refuses the version).
    fn hello<S: SampleSource>(
        &mut self,
        hello: &plinth_shared::protocol::Hello,
        source: &mut S,
        now_ms: u32,
    ) {
        if hello.protocol_version != PROTOCOL_VERSION {
            self.state = DeviceState::AwaitingHello;
            self.pipeline = None;
            source.stop();
            self.enqueue_reply(&DeviceMessage::VersionMismatch(VersionMismatch {
                device_protocol_version: PROTOCOL_VERSION,
                host_protocol_version: hello.protocol_version,
                host_nonce: hello.host_nonce,
            }));
            return;
        }
        source.stop();
        self.pipeline = None;
        self.config = Configuration::new();
        self.counters = DeviceCounters::default();
        for _ in 0..CHANNELS {
            let _ = self.counters.adc_saturation.push(0);
        }
        self.rx.clear_stats();
        self.outbox = Outbox::new();
        self.state = DeviceState::Idle;
        self.last_status_ms = now_ms;
        let health = self.health(source);
        self.enqueue_reply(&DeviceMessage::HelloAck(HelloAck {
            protocol_version: PROTOCOL_VERSION,
            host_nonce: hello.host_nonce,
            firmware_version: firmware_version(),
            capabilities: self.capabilities,
            health,
        }));
    }

    /// Starts acquisition if the configuration is complete.
    fn start<S: SampleSource>(&mut self, source: &mut S) -> Result<(), NackReason> {
        if !self.config.ready() {
            return Err(NackReason::WrongState);
        }
        let pipeline = Pipeline::new(&self.config, self.capabilities.sample_rate_hz)
            .map_err(|_| NackReason::BadValue)?;
        source.start()?;
        self.pipeline = Some(pipeline);
        self.state = DeviceState::Running;
        Ok(())
    }

    /// Stops acquisition; sends the final estimates and a status frame.
    fn stop<S: SampleSource>(&mut self, source: &mut S, now_ms: u32) {
        if self.state == DeviceState::Running {
            source.stop();
            if let Some(p) = &self.pipeline {
                let estimates = p.estimates();
                if !estimates.pedestals.is_empty() {
                    self.enqueue_data(&DeviceMessage::Estimates(estimates));
                }
            }
            self.state = DeviceState::Idle;
        }
        self.send_status(source, now_ms);
        self.stopped = true;
    }

    /// Queues a status frame.
    fn send_status<S: SampleSource>(&mut self, source: &S, now_ms: u32) {
        self.last_status_ms = now_ms;
        let status = StatusFrame {
            state: self.state,
            uptime_ms: now_ms,
            counters: self.counters(),
            link: *self.rx.stats(),
            health: self.health(source),
        };
        self.enqueue_data(&DeviceMessage::Status(status));
    }

    fn ack(&mut self, seq: u32) {
        self.enqueue_reply(&DeviceMessage::Ack(Ack { command_seq: seq }));
    }

    fn nack(&mut self, seq: u32, reason: NackReason) {
        self.counters.commands_rejected = self.counters.commands_rejected.saturating_add(1);
        self.enqueue_reply(&DeviceMessage::Nack(Nack {
            command_seq: seq,
            reason,
        }));
    }

    /// Queues a reply; may use the reserve.
    fn enqueue_reply(&mut self, m: &DeviceMessage) {
        self.outbox.push(m, 0);
    }

    /// Queues a data frame, keeping [`REPLY_RESERVE`] bytes free.
    fn enqueue_data(&mut self, m: &DeviceMessage) {
        self.outbox.push(m, REPLY_RESERVE);
    }
}

/// Encoded frames waiting for the transmitter, with the session's sequence
/// numbering.
struct Outbox {
    tx: Transmitter,
    queue: heapless::Deque<u8, TX_QUEUE_BYTES>,
    frame: [u8; MAX_FRAME_SIZE],
    /// Frames queued.
    frames_sent: u32,
    /// Frames dropped because the queue was full.
    drops: u32,
}

impl Outbox {
    /// An empty queue; the next frame is numbered 0.
    fn new() -> Self {
        Self {
            tx: Transmitter::new(),
            queue: heapless::Deque::new(),
            frame: [0; MAX_FRAME_SIZE],
            frames_sent: 0,
            drops: 0,
        }
    }

    /// Encodes `m` and queues it if it fits with `reserve` bytes to spare;
    /// otherwise counts a drop. A dropped frame still used up its sequence
    /// number, so the host also sees the drop as a sequence gap.
    fn push(&mut self, m: &DeviceMessage, reserve: usize) {
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
}
