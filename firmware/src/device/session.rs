//! The protocol task's own state: the session, the frame receiver and the
//! command handling. [`Session::poll`] is one bounded pass; it reaches the
//! extraction state, the source and the outbox only through [`Shared`], in
//! short sections, so that on the board the extraction task (above it) is
//! held off for one section at most, never for a whole pass.

use super::outbox::Outbox;
use super::shared::Shared;
use super::{firmware_version, Activity, REPLY_RESERVE, RX_BUDGET, STATUS_PERIOD_MS, TX_BUDGET};
use crate::link::ByteLink;
use crate::source::SampleSource;
use plinth_shared::protocol::{
    Ack, BoxHealth, Capabilities, DeviceCounters, DeviceMessage, DeviceState, HelloAck,
    HostMessage, LinkStats, Nack, NackReason, Receiver, StatusFrame, VersionMismatch,
    PROTOCOL_VERSION,
};

/// Bytes moved from the outbox to the link per lock [B] (bounds that
/// section: a few hundred cycles).
pub const TX_CHUNK: usize = 64;

/// Session state, receiver and command handling (the protocol task's).
pub struct Session {
    state: DeviceState,
    rx: Receiver<HostMessage>,
    counters: DeviceCounters,
    capabilities: Capabilities,
    last_status_ms: u32,
    stopped: bool,
    /// The platform's part of the health (clock, previous reset).
    platform: BoxHealth,
}

impl Session {
    /// A box waiting for `Hello` that announces `capabilities`.
    pub fn new(capabilities: Capabilities) -> Self {
        Self {
            state: DeviceState::AwaitingHello,
            rx: Receiver::new(),
            counters: DeviceCounters::default(),
            capabilities,
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

    /// What the box's receiver counted on the host link this session.
    pub fn link_stats(&self) -> LinkStats {
        *self.rx.stats()
    }

    /// True once after each accepted `Stop` (the QEMU image exits then).
    pub fn take_stopped(&mut self) -> bool {
        core::mem::take(&mut self.stopped)
    }

    /// Health counters of the session, with the extraction's and the
    /// outbox's parts.
    pub fn counters(&self, extraction: &super::Extraction, outbox: &Outbox) -> DeviceCounters {
        let mut c = self.counters.clone();
        extraction.fold_counters(&mut c);
        c.frames_sent = outbox.frames_sent();
        c.queue_full_drops = outbox.drops();
        c
    }

    /// One bounded pass: received bytes → commands, periodic status, queued
    /// bytes → link (and the extraction, where `shared` runs it inline).
    /// `now_ms` is the time since boot [ms] (wrapping).
    pub fn poll<L: ByteLink, H: Shared>(
        &mut self,
        link: &mut L,
        shared: &mut H,
        now_ms: u32,
    ) -> Activity {
        let mut activity = Activity::default();
        while activity.received < RX_BUDGET {
            let Some(byte) = link.read_byte() else { break };
            activity.received += 1;
            if let Some(Ok(frame)) = self.rx.push_byte(byte) {
                self.command(frame.seq, &frame.message, shared, now_ms);
                activity.samples += shared.extract_inline();
            }
        }
        activity.samples += shared.extract_inline();
        if self.state != DeviceState::AwaitingHello
            && now_ms.wrapping_sub(self.last_status_ms) >= STATUS_PERIOD_MS
        {
            self.send_status(shared, now_ms);
        }
        while activity.sent < TX_BUDGET {
            let max = TX_CHUNK.min(TX_BUDGET - activity.sent);
            let n = shared.outbox(|o| o.drain_to(link, max));
            activity.sent += n;
            if n < max {
                break;
            }
        }
        activity
    }

    /// Handles one host command.
    fn command<H: Shared>(&mut self, seq: u32, message: &HostMessage, shared: &mut H, now_ms: u32) {
        if let HostMessage::Hello(hello) = message {
            self.hello(hello, shared, now_ms);
            return;
        }
        if self.state == DeviceState::AwaitingHello {
            self.nack(shared, seq, NackReason::NoSession);
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
            HostMessage::ConfigureChannels(set) => {
                shared.acquisition(|e, _| e.config.set_channels(set))
            }
            HostMessage::ConfigureAveraging(a) => {
                shared.acquisition(|e, _| e.config.set_averaging(a))
            }
            HostMessage::ConfigureRls(r) => shared.acquisition(|e, _| e.config.set_rls(r)),
            HostMessage::BearingTable(chunk) => {
                shared.acquisition(|e, _| e.config.add_table_chunk(chunk))
            }
            HostMessage::Start if running => Err(NackReason::WrongState),
            HostMessage::Start => {
                let rate = self.capabilities.sample_rate_hz;
                let r = shared.acquisition(|e, s| e.start(s, rate));
                if r.is_ok() {
                    self.state = DeviceState::Running;
                }
                r
            }
            HostMessage::Stop => {
                self.ack(shared, seq);
                self.stop(shared, now_ms);
                return;
            }
            HostMessage::Samples(_) if !running => Err(NackReason::WrongState),
            HostMessage::Samples(block) => {
                shared.acquisition(|e, s| s.replay(block, &e.config.layout()))
            }
        };
        match result {
            Ok(()) => self.ack(shared, seq),
            Err(reason) => self.nack(shared, seq, reason),
        }
    }

    /// Opens a session (or refuses the version).
    fn hello<H: Shared>(
        &mut self,
        hello: &plinth_shared::protocol::Hello,
        shared: &mut H,
        now_ms: u32,
    ) {
        if hello.protocol_version != PROTOCOL_VERSION {
            self.state = DeviceState::AwaitingHello;
            shared.acquisition(|e, s| {
                e.close_session();
                s.stop();
            });
            let m = DeviceMessage::VersionMismatch(VersionMismatch {
                device_protocol_version: PROTOCOL_VERSION,
                host_protocol_version: hello.protocol_version,
                host_nonce: hello.host_nonce,
            });
            shared.outbox(|o| o.push(&m, 0));
            return;
        }
        let health = shared.acquisition(|e, s| {
            s.stop();
            e.open_session();
            self.health(s)
        });
        self.counters = DeviceCounters::default();
        self.rx.clear_stats();
        self.state = DeviceState::Idle;
        self.last_status_ms = now_ms;
        let m = DeviceMessage::HelloAck(HelloAck {
            protocol_version: PROTOCOL_VERSION,
            host_nonce: hello.host_nonce,
            firmware_version: firmware_version(),
            capabilities: self.capabilities,
            health,
        });
        shared.outbox(|o| {
            o.reset();
            o.push(&m, 0)
        });
    }

    /// Stops acquisition; sends the final estimates and a status frame.
    fn stop<H: Shared>(&mut self, shared: &mut H, now_ms: u32) {
        if self.state == DeviceState::Running {
            if let Some(estimates) = shared.acquisition(|e, s| e.stop(s)) {
                let m = DeviceMessage::Estimates(estimates);
                shared.outbox(|o| o.push(&m, REPLY_RESERVE));
            }
            self.state = DeviceState::Idle;
        }
        self.send_status(shared, now_ms);
        self.stopped = true;
    }

    /// Queues a status frame (the counters and health are a snapshot taken
    /// under one short lock; the frame is encoded under the outbox's).
    fn send_status<H: Shared>(&mut self, shared: &mut H, now_ms: u32) {
        self.last_status_ms = now_ms;
        let mut counters = self.counters.clone();
        let health = shared.acquisition(|e, s| {
            e.fold_counters(&mut counters);
            self.health(s)
        });
        let mut status = StatusFrame {
            state: self.state,
            uptime_ms: now_ms,
            counters,
            link: *self.rx.stats(),
            health,
        };
        shared.outbox(|o| {
            status.counters.frames_sent = o.frames_sent();
            status.counters.queue_full_drops = o.drops();
            o.push(&DeviceMessage::Status(status), REPLY_RESERVE)
        });
    }

    fn ack<H: Shared>(&mut self, shared: &mut H, seq: u32) {
        let m = DeviceMessage::Ack(Ack { command_seq: seq });
        shared.outbox(|o| o.push(&m, 0));
    }

    fn nack<H: Shared>(&mut self, shared: &mut H, seq: u32, reason: NackReason) {
        self.counters.commands_rejected = self.counters.commands_rejected.saturating_add(1);
        let m = DeviceMessage::Nack(Nack {
            command_seq: seq,
            reason,
        });
        shared.outbox(|o| o.push(&m, 0));
    }
}
