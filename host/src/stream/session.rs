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

    fn handshake(&mut self, started: Instant) -> Result<HelloAck> {
        let began = Instant::now();
        let mut deadline = began + self.options.handshake_timeout;
        if let Some(d) = self.options.duration {
            deadline = deadline.min(started + d);
        }
        self.hellos.clear();
        // Nonces of this handshake's Hellos: any of them may be answered.
        let mut nonces: Vec<u32> = Vec::new();
        loop {
            // Every Hello opens a new session: it is sequence number 0, with
            // a fresh nonce so that the box does not take a repeat for a
            // duplicated frame.
            let nonce: u32 = rand::random();
            nonces.push(nonce);
            self.tx.restart();
            self.send(&HostMessage::Hello(Hello {
                protocol_version: PROTOCOL_VERSION,
                host_nonce: nonce,
            }))?;
            let resend = Instant::now() + self.options.hello_interval;
            while Instant::now() < resend {
                self.pump()?;
                while let Some(m) = self.hellos.pop_front() {
                    match m {
                        DeviceMessage::HelloAck(ack) if nonces.contains(&ack.host_nonce) => {
                            if ack.protocol_version != PROTOCOL_VERSION {
                                bail!(
                                    "the box acknowledged Hello with protocol version {} but this host speaks {}",
                                    ack.protocol_version,
                                    PROTOCOL_VERSION
                                );
                            }
                            let v = ack.firmware_version;
                            if self.device.is_none() {
                                self.progress.note(&format!(
                                    "connected: firmware {}.{}.{}, protocol {}, {} channels, {} bearings, {} Hz",
                                    v.major,
                                    v.minor,
                                    v.patch,
                                    ack.protocol_version,
                                    ack.capabilities.max_channels,
                                    ack.capabilities.max_bearings,
                                    ack.capabilities.sample_rate_hz
                                ));
                            }
                            self.device = Some(ack);
                            self.replies.clear();
                            return Ok(ack);
                        }
                        DeviceMessage::VersionMismatch(m) if nonces.contains(&m.host_nonce) => {
                            bail!(
                                "the box speaks protocol version {} and this host {}: update one of them",
                                m.device_protocol_version,
                                m.host_protocol_version
                            );
                        }
                        _ => {} // an answer to an older Hello
                    }
                }
            }
            if Instant::now() >= deadline {
                if self.device.is_none() {
                    return Err(anyhow::Error::new(NoAnswer {
                        port: self.connector.describe(),
                        seconds: began.elapsed().as_secs_f64(),
                    }));
                }
                return Err(lost(format!(
                    "no answer to Hello within {:.1} s",
                    self.options.handshake_timeout.as_secs_f64()
                )));
            }
        }
    }

    fn configure_and_start(&mut self) -> Result<()> {
        // No `Stop` up front: a box that is not running needs none, and some
        // images end on `Stop` (the QEMU image exits). A box still running
        // refuses the first configuration command with `WrongState`; it is
        // stopped then and the command sent again.
        let mut stopped_once = false;
        let commands = self.config.device_commands(self.tables)?;
        let mut i = 0;
        let mut table_restarts = 0;
        while i < commands.len() {
            let cmd = &commands[i];
            let (answer, attempts) = self.command_counted(cmd)?;
            match answer {
                Ok(()) => i += 1,
                Err(NackReason::WrongState) if i == 0 && !stopped_once => {
                    stopped_once = true;
                    match self.command(&HostMessage::Stop)? {
                        Ok(()) | Err(NackReason::WrongState) => {}
                        Err(r) => bail!("the box refused Stop: {r:?}"),
                    }
                }
                // A resent chunk the box had already taken (its Ack was lost):
                // send this bearing's table again from its first chunk.
                Err(NackReason::TableOutOfOrder) if attempts > 1 && table_restarts < 5 => {
                    table_restarts += 1;
                    let HostMessage::BearingTable(chunk) = cmd else {
                        bail!("the box refused {} as out of order", describe(cmd));
                    };
                    let bearing = chunk.bearing;
                    while i > 0 {
                        match &commands[i - 1] {
                            HostMessage::BearingTable(c) if c.bearing == bearing => i -= 1,
                            _ => break,
                        }
                    }
                }
                Err(r) => bail!(
                    "the box refused {}: {r:?} (check the stream configuration {})",
                    describe(cmd),
                    self.config.bearings_csv.display()
                ),
            }
        }
        let (answer, attempts) = self.command_counted(&HostMessage::Start)?;
        match answer {
            Ok(()) => {}
            // A resent Start after a lost Ack finds the box running.
            Err(NackReason::WrongState) if attempts > 1 => {}
            Err(r) => bail!("the box refused Start: {r:?}"),
        }
        if let Some(j) = self.journal.as_mut() {
            let r = self.replay.as_ref().map(|r| &r.plan);
            j.box_origin = r
                .and_then(|p| p.spans().get(self.acked_blocks))
                .map_or(j.acknowledged, |s| s.start);
            j.acknowledged = j.box_origin;
            j.started = true;
        }
        self.save_journal(true)?;
        Ok(())
    }

    fn stop_and_drain(&mut self) -> Result<()> {
        let (answer, attempts) = self.command_counted(&HostMessage::Stop)?;
        match answer {
            Ok(()) => {}
            Err(NackReason::WrongState) if attempts > 1 => {}
            Err(r) => bail!("the box refused Stop: {r:?}"),
        }
        // The last frames (final estimates, status) follow the Ack. A box
        // that ends its run on Stop may close the line meanwhile: that ends
        // the drain, it is not a lost link.
        let until = Instant::now() + self.options.drain;
        while Instant::now() < until {
            match self.pump() {
                Ok(()) => {}
                Err(e) if e.is::<LinkLost>() => break,
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }

    /// Sends the replay from the first unacknowledged block (go-back-N).
    fn replay_blocks(&mut self) -> Result<()> {
        let Some(replay) = self.replay.as_ref() else {
            return Ok(());
        };
        let total = replay.plan.len();
        let origin = self.journal.as_ref().map_or(0, |j| j.box_origin);
        let window = self.options.window.max(1);
        let mut next = self.acked_blocks;
        // Block sends by sequence number: (block, rewind round it was sent in).
        let mut sent: HashMap<u32, (usize, u32)> = HashMap::new();
        let mut round = 0u32;
        let mut last_progress = Instant::now();
        // A Ping sent when acknowledgements are late: (its seq, when, blocks
        // sent before it). The box answers in order, so once its Ack is in,
        // a block sent before it and still unacknowledged was really lost.
        let mut probe: Option<(u32, Instant, usize)> = None;
        let mut stalls = 0u32;
        self.replies.clear();
        while self.acked_blocks < total {
            while next < total && next < self.acked_blocks + window {
                let replay = self.replay.as_ref().ok_or_else(|| anyhow!("no replay"))?;
                let block = replay.plan.block(replay.source, next, origin);
                let seq = self.send(&HostMessage::Samples(block))?;
                sent.insert(seq, (next, round));
                next += 1;
            }
            self.pump()?;
            let mut rewind = false;
            while let Some((seq, reply)) = self.replies.pop_front() {
                if let Some((probe_seq, _, sent_before)) = probe {
                    if seq == probe_seq {
                        probe = None;
                        if self.acked_blocks < sent_before {
                            rewind = true;
                        } else {
                            last_progress = Instant::now();
                        }
                        continue;
                    }
                }
                let Some(&(block, sent_in)) = sent.get(&seq) else {
                    continue;
                };
                match reply {
                    // The box processes blocks in order: an Ack covers every
                    // block before it too.
                    Ok(()) => {
                        if block >= self.acked_blocks {
                            self.acked_blocks = block + 1;
                            stalls = 0;
                            last_progress = Instant::now();
                            next = next.max(self.acked_blocks);
                        }
                    }
                    Err(NackReason::WrongState) => return Err(anyhow::Error::new(NotRunning)),
                    // Go-back-N: the box refused this block (a block before
                    // it went missing, or its queue was full), so it refuses
                    // every later one too; one rewind resends them all.
                    // Refusals of sends from before the last rewind are of
                    // blocks already sent again.
                    Err(NackReason::QueueFull) | Err(NackReason::BadBlock) => {
                        if block >= self.acked_blocks && sent_in == round {
                            rewind = true;
                        }
                    }
                    Err(r) => {
                        let start = self
                            .replay
                            .as_ref()
                            .and_then(|p| p.plan.spans().get(block))
                            .map_or(0, |s| s.start);
                        bail!("the box refused the sample block at sample {start}: {r:?}");
                    }
                }
            }
            let waiting = next > self.acked_blocks;
            if waiting && !rewind && last_progress.elapsed() > self.options.block_timeout {
                match probe {
                    None => {
                        let seq = self.send(&HostMessage::Ping)?;
                        probe = Some((seq, Instant::now(), next));
                    }
                    // The Ping or its Ack was lost too: resend blindly.
                    Some((_, t, _)) if t.elapsed() > self.options.block_timeout * 2 => {
                        probe = None;
                        rewind = true;
                    }
                    Some(_) => {}
                }
            }
            if rewind {
                stalls += 1;
                if stalls > self.options.max_stalls {
                    return Err(lost(format!(
                        "the box acknowledged no sample block after {} resends",
                        self.options.max_stalls
                    )));
                }
                self.state.resent_blocks += (next - self.acked_blocks) as u64;
                next = self.acked_blocks;
                round = round.wrapping_add(1);
                sent.retain(|_, (b, _)| *b >= self.acked_blocks);
                last_progress = Instant::now();
                probe = None;
                // Give a full queue time to drain.
                let until = Instant::now() + Duration::from_millis(2);
                while Instant::now() < until {
                    self.pump()?;
                }
            }
            sent.retain(|_, (b, _)| *b >= self.acked_blocks.saturating_sub(window));
            self.state.replay = Some((self.acked_blocks as u64, total as u64));
            if let Some(j) = self.journal.as_mut() {
                let replay = self.replay.as_ref().map(|r| &r.plan);
                j.acknowledged = replay
                    .and_then(|p| p.spans().get(self.acked_blocks))
                    .map_or(replay.map_or(0, |p| p.sample_vectors()), |s| s.start);
            }
            self.save_journal(false)?;
        }
        self.save_journal(true)?;
        Ok(())
    }

    fn save_journal(&mut self, now: bool) -> Result<()> {
        if !now && self.journal_written.elapsed() < Duration::from_millis(200) {
            return Ok(());
        }
        if let Some(j) = &self.journal {
            j.write(&self.out_dir)?;
            self.journal_written = Instant::now();
        }
        Ok(())
    }

    /// Sends a command and waits for its answer, resending on timeout.
    fn command(&mut self, msg: &HostMessage) -> Result<Reply> {
        Ok(self.command_counted(msg)?.0)
    }

    /// Like [`Session::command`], also saying how many sends it took.
    fn command_counted(&mut self, msg: &HostMessage) -> Result<(Reply, u32)> {
        for attempt in 1..=self.options.command_attempts {
            let seq = self.send(msg)?;
            let until = Instant::now() + self.options.command_timeout;
            while Instant::now() < until {
                self.pump()?;
                while let Some((s, reply)) = self.replies.pop_front() {
                    if s == seq {
                        return Ok((reply, attempt));
                    }
                }
            }
        }
        Err(lost(format!(
            "no answer to {} after {} attempts",
            describe(msg),
            self.options.command_attempts
        )))
    }

    /// Encodes and writes one frame; returns its sequence number.
    fn send(&mut self, msg: &HostMessage) -> Result<u32> {
        let mut wire = [0u8; MAX_FRAME_SIZE];
        let (seq, bytes) = self
            .tx
            .encode(msg, &mut wire)
            .map_err(|e| anyhow!("cannot encode {}: {e:?}", describe(msg)))?;
        let link = self.link.as_mut().ok_or_else(|| lost("not connected"))?;
        write_all_patiently(link.as_mut(), bytes, self.options.write_patience)
            .map_err(|e| lost(format!("cannot write {}: {e}", describe(msg))))?;
        Ok(seq)
    }

    /// One read: log the bytes, decode, dispatch, redraw the progress line.
    fn pump(&mut self) -> Result<()> {
        let link = self.link.as_mut().ok_or_else(|| lost("not connected"))?;
        let n = match link.read(&mut self.read_buf) {
            Ok(0) => return Err(lost("the port reached end of file")),
            Ok(n) => n,
            Err(e) if is_quiet(&e) => 0,
            Err(e) => return Err(lost(format!("read error: {e}"))),
        };
        if n > 0 {
            self.log.append(&self.read_buf[..n])?;
            self.state.bytes += n as u64;
            let mut messages = Vec::new();
            for frame in self.rx.feed(&self.read_buf[..n]).flatten() {
                messages.push(frame.message);
            }
            for m in messages {
                self.dispatch(m);
            }
            let s = self.rx.stats();
            self.state.frames = s.frames_ok as u64;
            self.state.frames_lost = s.sequence_gaps as u64;
            self.state.bad_frames = s.failures() as u64;
            self.state.resyncs = s.resyncs as u64;
        }
        self.progress.tick(&self.state);
        Ok(())
    }

    fn dispatch(&mut self, m: DeviceMessage) {
        match m {
            DeviceMessage::HelloAck(_) | DeviceMessage::VersionMismatch(_) => {
                self.hellos.push_back(m)
            }
            DeviceMessage::Ack(a) => self.replies.push_back((a.command_seq, Ok(()))),
            DeviceMessage::Nack(n) => self.replies.push_back((n.command_seq, Err(n.reason))),
            DeviceMessage::Phasors(p) => {
                self.state.phasor_frames += 1;
                self.state.speed_hz = Some(p.speed_hz as f64);
                self.state.revolutions = p.revolution as u64 + p.revolutions as u64;
            }
            DeviceMessage::Estimates(e) => {
                self.state.estimate_frames += 1;
                self.last_estimates = Some(e);
            }
            DeviceMessage::Status(s) => self.last_status = Some(s),
        }
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
