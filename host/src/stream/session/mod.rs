//! One streaming session with the field box: handshake, configuration,
//! replay pacing and the receive loop, surviving a lost port.
//!
//! # Flow
//!
//! 1. Open the link (retrying with backoff).
//! 2. Handshake: the host speaks first. `Hello` (sequence 0, a fresh nonce)
//!    is repeated every `hello_interval` until a `HelloAck` with that nonce
//!    arrives; bytes the box sent before the port was open are lost, and so
//!    may be the first `Hello`s (QEMU drops output to an unopened
//!    pseudo-terminal). A `VersionMismatch` ends the session with an error.
//! 3. Configure: channels, averaging, RLS settings, every bearing's table in
//!    chunks (a box still running refuses the first with `WrongState`: it is
//!    sent `Stop` and the command again); each command waits for its `Ack` (resent with a new
//!    sequence number on timeout; a table is resent from its first chunk if a
//!    resent chunk is refused as out of order). Then `Start`.
//! 4. Replay (with `--replay`): sample blocks go out with at most `window`
//!    unacknowledged (go-back-N). An `Ack` of a block acknowledges every block
//!    before it (the box takes blocks strictly in order: it refuses a block
//!    after a missing one with `Nack(BadBlock)`, and acknowledges a block it
//!    already processed again without processing it). A `Nack(QueueFull)`
//!    or `Nack(BadBlock)` rewinds to the oldest unacknowledged block, once:
//!    the refusals of the other blocks sent before that rewind are expected
//!    and ignored. When no
//!    block was acknowledged for `block_timeout`, a `Ping` tells a slow box
//!    from a lost frame: its `Ack` comes after the answers to every block
//!    sent before it, so a block still unacknowledged then was lost (or its
//!    `Ack` was), and the replay rewinds; no answer to the `Ping` either
//!    rewinds after twice `block_timeout`. Without a replay the session receives for
//!    `duration`.
//! 5. `Stop`, then receive for `drain` so the last frames (the box's final
//!    estimates and status) arrive; the box closing the line then (the QEMU
//!    image exits on `Stop`) just ends the drain.
//!
//! Every byte read goes to the raw log before it is decoded. Phasor,
//! estimate and status frames update the progress line at any point.
//!
//! # A lost link
//!
//! A read or write error, or no answer to a command after all retries, drops
//! the link: it is reopened with backoff and the session resumes at step 2.
//! A replay then first tries to continue where it was (the box may still be
//! running); if the box answers `Nack(WrongState)` (it stopped, or rebooted)
//! the host reconfigures and restarts it from the oldest unacknowledged block.
//! The replay position is journalled in the run directory, so a host process
//! that was killed resumes the same way.
//!
//! # Modules
//!
//! [`handshake`] (steps 2, 3 and 5: hello, configuration, stop and drain),
//! [`blocks`] (step 4: the paced, acknowledged replay and its journal),
//! [`wire`] (commands with their acknowledgements, the receive pump).

mod blocks;
mod handshake;
mod wire;

use super::config::{BearingTables, StreamConfig};
use super::port::{connect_with_backoff, is_quiet, write_all_patiently, Backoff, Connector, Link};
use super::progress::{Progress, ProgressState};
use super::rawlog::RawLog;
use super::replay::{ReplayJournal, ReplayPlan, ReplaySource};
use anyhow::{anyhow, bail, Result};
use plinth_shared::protocol::Hello;
use plinth_shared::protocol::{
    DeviceMessage, EstimateFrame, HelloAck, HostMessage, LinkStats, NackReason, Receiver,
    StatusFrame, Transmitter, MAX_FRAME_SIZE, PROTOCOL_VERSION,
};
use std::collections::{HashMap, VecDeque};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Timing and pacing of a session.
#[derive(Clone, Debug)]
pub struct SessionOptions {
    /// Most replay blocks sent but not yet acknowledged.
    pub window: usize,
    /// Time between repeated `Hello`s.
    pub hello_interval: Duration,
    /// Time without a `HelloAck` after which the link is declared lost; when
    /// the box never answered in this process, the session ends with
    /// [`NoAnswer`] instead (a wrong port, or no firmware running).
    pub handshake_timeout: Duration,
    /// Time to wait for a command's `Ack` before sending it again.
    pub command_timeout: Duration,
    /// Sends of one command before the link is declared lost.
    pub command_attempts: u32,
    /// Time without any block acknowledged before rewinding the replay.
    pub block_timeout: Duration,
    /// Rewinds in a row without progress before the link is declared lost.
    pub max_stalls: u32,
    /// Time to keep receiving after the final `Stop` was acknowledged.
    pub drain: Duration,
    /// How long a write may wait for room in the line buffer.
    pub write_patience: Duration,
    /// Reopening a lost link.
    pub backoff: Backoff,
    /// How long to receive without a replay (`None`: until the link is lost
    /// for good).
    pub duration: Option<Duration>,
}

impl Default for SessionOptions {
    fn default() -> Self {
        Self {
            window: 4,
            hello_interval: Duration::from_millis(250),
            handshake_timeout: Duration::from_secs(15),
            command_timeout: Duration::from_millis(500),
            command_attempts: 8,
            block_timeout: Duration::from_millis(500),
            max_stalls: 40,
            drain: Duration::from_millis(300),
            write_patience: Duration::from_secs(5),
            backoff: Backoff::default(),
            duration: None,
        }
    }
}

/// A replay to run: the signals, their blocks, and where the journal goes.
pub struct Replay<'a> {
    /// The signals.
    pub source: &'a dyn ReplaySource,
    /// Their blocks.
    pub plan: ReplayPlan,
    /// The signals file (recorded in the journal).
    pub path: PathBuf,
}

/// What a session ended with.
#[derive(Clone, Debug)]
pub struct SessionOutcome {
    /// True when the session ran to its end (replay acknowledged and box
    /// stopped, or the duration elapsed).
    pub completed: bool,
    /// Why it did not complete.
    pub error: Option<String>,
    /// The host's receive-side link counters over this process's lifetime.
    pub link: LinkStats,
    /// Times the link was lost and reopened.
    pub reconnects: u64,
    /// Bytes received by this process.
    pub bytes: u64,
    /// What the box said about itself.
    pub device: Option<HelloAck>,
    /// The last estimate frame received.
    pub last_estimates: Option<EstimateFrame>,
    /// The last status frame received.
    pub last_status: Option<StatusFrame>,
    /// Replay blocks acknowledged and in total.
    pub replay: Option<(usize, usize)>,
    /// Replay blocks sent again after a loss.
    pub resent_blocks: u64,
}

/// The link went away (or stopped answering): reopen and resume.
#[derive(Debug, thiserror::Error)]
#[error("link lost: {0}")]
struct LinkLost(String);

fn lost(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(LinkLost(msg.into()))
}

/// The port opened but nothing on it ever answered the handshake.
#[derive(Debug, thiserror::Error)]
#[error("no answer from the box on {port} after {seconds:.1} s: is it the box's port, is the firmware running?")]
pub struct NoAnswer {
    /// The port, as the connector describes it.
    pub port: String,
    /// How long the handshake waited [s].
    pub seconds: f64,
}

/// The box is not running the session any more (it answered
/// `Nack(WrongState)` to a sample block): reconfigure and restart it.
#[derive(Debug, thiserror::Error)]
#[error("the box is not running")]
struct NotRunning;

/// A command's answer.
type Reply = std::result::Result<(), NackReason>;

/// A streaming session over links from one connector.
pub struct Session<'a> {
    connector: &'a mut dyn Connector,
    link: Option<Box<dyn Link>>,
    log: RawLog,
    out_dir: PathBuf,
    config: &'a StreamConfig,
    tables: &'a BearingTables,
    replay: Option<Replay<'a>>,
    options: SessionOptions,
    progress: Progress,
    state: ProgressState,
    rx: Receiver<DeviceMessage>,
    tx: Transmitter,
    replies: VecDeque<(u32, Reply)>,
    hellos: VecDeque<DeviceMessage>,
    device: Option<HelloAck>,
    last_estimates: Option<EstimateFrame>,
    last_status: Option<StatusFrame>,
    read_buf: Vec<u8>,
    journal: Option<ReplayJournal>,
    journal_written: Instant,
    /// Replay: first block not yet acknowledged.
    acked_blocks: usize,
}

impl<'a> Session<'a> {
    /// A session writing received bytes to `log`, journalling into `out_dir`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        connector: &'a mut dyn Connector,
        log: RawLog,
        out_dir: &Path,
        config: &'a StreamConfig,
        tables: &'a BearingTables,
        replay: Option<Replay<'a>>,
        options: SessionOptions,
        progress: Progress,
    ) -> Result<Self> {
        let mut journal = None;
        let mut acked_blocks = 0;
        if let Some(r) = &replay {
            let previous = ReplayJournal::read(out_dir)?;
            let j = match previous {
                Some(j) if j.sample_vectors == r.plan.sample_vectors() => {
                    let Some(block) = r.plan.block_starting_at(j.acknowledged) else {
                        bail!(
                            "{}: acknowledged position {} is not a block boundary of {}",
                            out_dir.join(super::replay::JOURNAL_FILE).display(),
                            j.acknowledged,
                            r.path.display()
                        );
                    };
                    acked_blocks = block;
                    j
                }
                Some(j) => bail!(
                    "{} records a replay of {} sample vectors from {}, but {} has {}: use another output directory",
                    out_dir.join(super::replay::JOURNAL_FILE).display(),
                    j.sample_vectors,
                    j.signals.display(),
                    r.path.display(),
                    r.plan.sample_vectors()
                ),
                None => ReplayJournal {
                    signals: r.path.clone(),
                    sample_vectors: r.plan.sample_vectors(),
                    acknowledged: 0,
                    box_origin: 0,
                    started: false,
                    finished: false,
                },
            };
            journal = Some(j);
        }
        let mut state = ProgressState::default();
        if let Some(r) = &replay {
            state.replay = Some((acked_blocks as u64, r.plan.len() as u64));
        }
        Ok(Self {
            connector,
            link: None,
            log,
            out_dir: out_dir.to_path_buf(),
            config,
            tables,
            replay,
            options,
            progress,
            state,
            rx: Receiver::new(),
            tx: Transmitter::new(),
            replies: VecDeque::new(),
            hellos: VecDeque::new(),
            device: None,
            last_estimates: None,
            last_status: None,
            read_buf: vec![0; 4096],
            journal,
            journal_written: Instant::now(),
            acked_blocks,
        })
    }

    /// True when the journal says a previous run already finished the replay.
    pub fn replay_already_finished(&self) -> bool {
        self.journal.as_ref().is_some_and(|j| j.finished)
    }

    /// Runs the session to its end, reopening the link whenever it is lost.
    /// Errors that retrying cannot fix (a refused configuration, another
    /// protocol version, a full disk) end it with `Err`; running out of
    /// reconnection attempts ends it with an incomplete outcome.
    pub fn run(mut self) -> Result<SessionOutcome> {
        let started = Instant::now();
        let mut error = None;
        let mut completed = false;
        // Since when the link has been down (None: up, or never lost).
        let mut lost_since: Option<Instant> = None;
        loop {
            if let Some(d) = self.options.duration {
                if started.elapsed() >= d && self.link.is_none() {
                    error = Some(format!(
                        "the link was lost and --duration ({:.1} s) ran out before it came back",
                        d.as_secs_f64()
                    ));
                    break;
                }
            }
            let give_up = self.options.backoff.give_up;
            if let Some(t) = lost_since {
                if t.elapsed() >= give_up {
                    error = Some(format!(
                        "the link stayed lost (no answer from the box) for {:.1} s, the --reconnect-timeout",
                        t.elapsed().as_secs_f64()
                    ));
                    break;
                }
            }
            if self.link.is_none() {
                let mut notes = Vec::new();
                let mut backoff = self.options.backoff;
                let mut left = lost_since.map_or(give_up, |t| give_up.saturating_sub(t.elapsed()));
                if let Some(d) = self.options.duration {
                    left = left.min(d.saturating_sub(started.elapsed()));
                }
                backoff.give_up = left;
                let connected = connect_with_backoff(self.connector, backoff, |n, e, w| {
                    notes.push(format!(
                        "cannot open the link (attempt {n}: {e}); retrying in {:.2} s",
                        w.as_secs_f64()
                    ))
                });
                for n in notes {
                    self.progress.note(&n);
                }
                match connected {
                    Ok(link) => self.link = Some(link),
                    Err(e) => {
                        error = Some(format!("{e:#}"));
                        break;
                    }
                }
            }
            match self.attempt(started, &mut lost_since) {
                Ok(()) => {
                    completed = true;
                    break;
                }
                Err(e) if e.is::<LinkLost>() => {
                    lost_since.get_or_insert_with(Instant::now);
                    self.progress
                        .note(&format!("{e}; reopening {}", self.connector.describe()));
                    self.link = None;
                    self.rx.reset();
                    self.state.reconnects += 1;
                    std::thread::sleep(self.options.backoff.initial);
                }
                Err(e) => {
                    self.progress.finish(&self.state);
                    self.save_journal(true)?;
                    return Err(e);
                }
            }
        }
        self.progress.finish(&self.state);
        self.save_journal(true)?;
        Ok(SessionOutcome {
            completed,
            error,
            link: *self.rx.stats(),
            reconnects: self.state.reconnects,
            bytes: self.state.bytes,
            device: self.device,
            last_estimates: self.last_estimates,
            last_status: self.last_status,
            replay: self
                .replay
                .as_ref()
                .map(|r| (self.acked_blocks, r.plan.len())),
            resent_blocks: self.state.resent_blocks,
        })
    }

    /// One pass over a live link: handshake, (re)configure, stream.
    fn attempt(&mut self, started: Instant, lost_since: &mut Option<Instant>) -> Result<()> {
        let hello = self.handshake(started)?;
        *lost_since = None;
        self.config
            .check_capabilities(&hello.capabilities, self.tables)?;
        if self.replay.is_some() {
            let source_rate = self
                .replay
                .as_ref()
                .map_or(0.0, |r| r.source.sample_rate_hz());
            let box_rate = hello.capabilities.sample_rate_hz as f64;
            if (source_rate - box_rate).abs() > 1e-6 * box_rate.abs().max(1.0) {
                bail!(
                    "the replay signals are sampled at {source_rate} Hz but the box samples at {box_rate} Hz"
                );
            }
            let was_started = self.journal.as_ref().is_some_and(|j| j.started);
            let resumed = if was_started {
                match self.replay_blocks() {
                    Ok(()) => true,
                    Err(e) if e.is::<NotRunning>() => false,
                    Err(e) => return Err(e),
                }
            } else {
                false
            };
            if !resumed {
                self.configure_and_start()?;
                match self.replay_blocks() {
                    Ok(()) => {}
                    Err(e) if e.is::<NotRunning>() => {
                        return Err(lost("the box stopped running right after Start"))
                    }
                    Err(e) => return Err(e),
                }
            }
            self.stop_and_drain()?;
            if let Some(j) = self.journal.as_mut() {
                j.started = false;
                j.finished = true;
            }
            self.save_journal(true)?;
        } else {
            self.configure_and_start()?;
            loop {
                if let Some(d) = self.options.duration {
                    if started.elapsed() >= d {
                        break;
                    }
                }
                self.pump()?;
            }
            self.stop_and_drain()?;
        }
        Ok(())
    }
}

/// A short name of a host message for error messages.
pub fn describe(msg: &HostMessage) -> String {
    match msg {
        HostMessage::Hello(_) => "Hello".into(),
        HostMessage::Ping => "Ping".into(),
        HostMessage::ConfigureChannels(_) => "the channel configuration".into(),
        HostMessage::ConfigureAveraging(_) => "the averaging configuration".into(),
        HostMessage::ConfigureRls(_) => "the RLS configuration".into(),
        HostMessage::BearingTable(c) => format!(
            "bearing {}'s table rows {}..{} of {}",
            c.bearing,
            c.first_row,
            c.first_row as usize + c.rows.len(),
            c.total_rows
        ),
        HostMessage::Start => "Start".into(),
        HostMessage::Stop => "Stop".into(),
        HostMessage::Samples(b) => format!("the sample block at box sample {}", b.first_sample),
    }
}
