//! `plinth stream`: the laptop side of the field box link.
//!
//! Opens the serial port (or QEMU's pseudo-terminal), shakes hands, sends the
//! configuration, optionally replays simulated time signals to the box, and
//! receives its phasor, estimate and status frames. Every received byte goes
//! to an append-only raw log first; at the end the run directory is
//! re-derived from the whole log (so a restarted host keeps what an earlier
//! one received), fitted in batch, and compared with the box's own recursive
//! estimates.
//!
//! One file per idea: [`port`] (opening and reopening the link), [`rawlog`]
//! (the append-only byte log), [`config`] (the configuration file),
//! [`replay`] (signals cut into sample blocks, and the replay journal),
//! [`session`] (handshake, configuration, replay pacing, receive loop: the
//! exact flow is documented there), [`derive`] (raw log → run directory),
//! [`progress`] (the live status line), [`report`] (box vs batch).
//!
//! Files in the output directory: `raw.bin` (every received byte, appended
//! across runs), `replay-journal.json` (replay position), `stream.toml` (a
//! copy of the configuration), `measurements.csv` and `bearings.csv`
//! (formats.md), `stream-report.json` (link counters, box vs batch).
//!
//! # The raw log and the previous run directory
//!
//! `plinth stream --out OUT` never writes into `OUT` while it runs. It works
//! in the sibling directory `OUT.incomplete` ([`staging_dir`]): the raw log
//! there starts as a copy of `OUT/raw.bin` (when `OUT` is an earlier stream
//! run) and every received byte is appended to it as it arrives. Only when
//! the session completed is `OUT.incomplete` moved into place as `OUT`
//! (through [`crate::output::OutputDir`]: `OUT/raw.bin` is replaced only by a
//! log that starts with all of its bytes, files Plinth did not write are
//! kept). So:
//!
//! - a stream that fails or is killed leaves `OUT` exactly as it was, and
//!   everything received in `OUT.incomplete/raw.bin` (with the run directory
//!   derived from it when the process could still write it);
//! - running the same command again resumes from `OUT.incomplete` (the raw
//!   log is appended to, the replay continues from its journal);
//! - a stream that received nothing (the box never answered) removes the
//!   `OUT.incomplete` it created and changes nothing;
//! - `--offline` rebuilds the run directory from `OUT.incomplete/raw.bin`
//!   when there is one, else from `OUT/raw.bin`, and moves it into place the
//!   same way (a `--config OUT/stream.toml` is read before anything is
//!   written, and is never truncated); a log without a valid phasor frame
//!   (empty, cut short or foreign) is refused and changes nothing.
//!
//! An `OUT` that holds anything but an earlier stream run (a `raw.bin`) is
//! refused unless `--force`.

pub mod config;
pub mod derive;
pub mod port;
pub mod progress;
pub mod rawlog;
pub mod replay;
pub mod report;
pub mod session;

use crate::output::OutputDir;
use anyhow::{bail, Context, Result};
use config::{BearingTables, StreamConfig};
use port::{Connector, SerialConnector};
use progress::Progress;
use rawlog::{RawLog, RAW_LOG_FILE};
use replay::{ReplayPlan, ReplaySource};
use report::{LinkSummary, StreamReport, REPORT_FILE};
use session::{Replay, Session, SessionOptions, SessionOutcome};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Command-line arguments of `plinth stream`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Serial port of the field box, e.g. /dev/ttyUSB0 or QEMU's /dev/pts/N.
    #[arg(long, required_unless_present = "offline")]
    pub port: Option<String>,
    /// Line speed [bit/s] (pseudo-terminals ignore it).
    #[arg(long, allow_negative_numbers = true, default_value_t = 115_200, value_parser = line_speed)]
    pub baud: u32,
    /// Stream configuration (TOML: channel map, averaging, RLS, bearings.csv;
    /// documented in `plinth::stream::config`).
    #[arg(long)]
    pub config: PathBuf,
    /// Run directory to write: new, empty, or an earlier stream run (its
    /// raw.bin is extended, never truncated); staged in OUT.incomplete and
    /// moved into place only when the stream completes.
    #[arg(long)]
    pub out: PathBuf,
    /// Write into an --out that holds files other than an earlier stream run
    /// (files Plinth did not write there are kept, never replaced).
    #[arg(long)]
    pub force: bool,
    /// Replay these simulated time signals (`plinth signals` output) to the box.
    #[arg(long)]
    pub replay: Option<PathBuf>,
    /// Sample blocks in flight without an acknowledgement.
    #[arg(long, allow_negative_numbers = true, default_value_t = 4, value_parser = crate::args::count)]
    pub window: usize,
    /// Without --replay: how long to stream [s] (default: until the port is
    /// gone for good); also bounds every wait for a lost link.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::args::seconds, conflicts_with = "replay")]
    pub duration: Option<Duration>,
    /// Give up reopening a lost port, or waiting for a box that stopped
    /// answering, after this long [s].
    #[arg(long, allow_negative_numbers = true, default_value = "60", value_parser = crate::args::seconds)]
    pub reconnect_timeout: Duration,
    /// How long the box may take to answer the handshake [s]; a port where
    /// nothing ever answers is given up after this long.
    #[arg(long, allow_negative_numbers = true, default_value = "15", value_parser = crate::args::seconds)]
    pub handshake_timeout: Duration,
    /// Do not open the port: rebuild the run directory from the raw log.
    #[arg(long, conflicts_with_all = ["port", "replay", "duration"])]
    pub offline: bool,
    /// No progress line.
    #[arg(skip)]
    pub quiet: bool,
}

/// `--baud`: a line speed [bit/s], a whole number from 1 to 2³² − 1 (0 is
/// no speed: termios' B0 hangs the line up, and the port never opens).
fn line_speed(text: &str) -> Result<u32, String> {
    let n = crate::args::count(text)?;
    u32::try_from(n).map_err(|_| {
        format!("{n} bit/s is beyond any serial line: give a line speed such as 115200")
    })
}

/// The directory a stream into `out` works in until it completes:
/// `OUT.incomplete`, beside `out` (see the module docs).
pub fn staging_dir(out: &Path) -> PathBuf {
    let mut name = out
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_else(|| "stream".into());
    name.push(".incomplete");
    out.with_file_name(name)
}

/// File name of the copy of the configuration in the run directory.
pub const CONFIG_COPY_FILE: &str = "stream.toml";

/// Runs `plinth stream`.
pub fn run(args: &Args) -> Result<()> {
    // Everything that is read is read before anything is written.
    let config_text = crate::input_file::read_to_string(&args.config).with_context(|| {
        format!(
            "cannot read the stream configuration {}",
            args.config.display()
        )
    })?;
    let config = StreamConfig::load(&args.config)?;
    let tables = config.load_bearing_tables()?;
    let staging = staging_dir(&args.out);
    let resuming = staging.is_dir();
    let earlier_run = args.out.join(RAW_LOG_FILE).is_file();
    if args.offline && !resuming && !earlier_run {
        bail!(
            "--offline: neither {} nor {} holds a raw log ({RAW_LOG_FILE}) to rebuild the run from",
            args.out.display(),
            staging.display()
        );
    }
    let mut out = OutputDir::resume(&args.out, &staging, args.force || earlier_run)?;
    out.appends(RAW_LOG_FILE);
    if !resuming && earlier_run {
        for name in [RAW_LOG_FILE, replay::JOURNAL_FILE] {
            let from = args.out.join(name);
            if from.is_file() {
                std::fs::copy(&from, staging.join(name)).with_context(|| {
                    format!("cannot copy {} into {}", from.display(), staging.display())
                })?;
            }
        }
    }
    if resuming {
        eprintln!(
            "continuing the unfinished stream in {} ({} is unchanged until it completes)",
            staging.display(),
            args.out.display()
        );
    }
    crate::output::write_atomically(&staging.join(CONFIG_COPY_FILE), config_text.as_bytes())?;
    let raw_before = std::fs::metadata(staging.join(RAW_LOG_FILE)).map_or(0, |m| m.len());
    let result = stream_into(args, &staging, &config, &tables);
    let raw_after = std::fs::metadata(staging.join(RAW_LOG_FILE)).map_or(0, |m| m.len());
    let failed = match &result {
        Ok(report) => report.error.clone(),
        Err(e) => Some(crate::error_text(e)),
    };
    match failed {
        None => {
            out.commit()?;
            if let Ok(report) = &result {
                print!("{}", summary(report));
            }
            Ok(())
        }
        Some(e) => {
            let nothing = !resuming && raw_after == raw_before;
            if let (Ok(report), false) = (&result, nothing) {
                print!("{}", summary(report));
            }
            if nothing {
                out.discard(); // nothing arrived: the staging directory goes
                bail!(
                    "the stream did not complete: {e}; nothing was received, {} is unchanged",
                    args.out.display()
                );
            }
            bail!(
                "the stream did not complete: {e}; {} is unchanged; everything received ({raw_after} bytes) is in {}: run the same command again to continue it, or --offline to rebuild the run from it",
                args.out.display(),
                staging.join(RAW_LOG_FILE).display()
            )
        }
    }
}

/// The session (unless `--offline`) and the run directory, in `dir`.
fn stream_into(
    args: &Args,
    dir: &Path,
    config: &StreamConfig,
    tables: &BearingTables,
) -> Result<StreamReport> {
    let outcome = if args.offline {
        None
    } else {
        let port = args.port.as_deref().unwrap_or_default();
        let mut connector = SerialConnector::new(port, args.baud);
        let mut options = SessionOptions {
            window: args.window,
            duration: args.duration,
            handshake_timeout: args.handshake_timeout,
            ..SessionOptions::default()
        };
        options.backoff.give_up = args.reconnect_timeout;
        let signals = match &args.replay {
            Some(path) => Some((path.clone(), replay::SignalSetReplay::load(path, config)?)),
            None => None,
        };
        let replay = signals
            .as_ref()
            .map(|(p, s)| (p.as_path(), s as &dyn ReplaySource));
        let progress = if args.quiet {
            Progress::hidden()
        } else {
            Progress::stderr()
        };
        Some(stream(
            &mut connector,
            dir,
            config,
            tables,
            replay,
            options,
            progress,
        )?)
    };
    finish(dir, config, tables, outcome.as_ref())
}

/// Streams over links from `connector` into `out` (raw log and journal);
/// returns how the session ended. The run directory is written by [`finish`].
pub fn stream(
    connector: &mut dyn Connector,
    out: &Path,
    config: &StreamConfig,
    tables: &BearingTables,
    replay: Option<(&Path, &dyn ReplaySource)>,
    options: SessionOptions,
    progress: Progress,
) -> Result<SessionOutcome> {
    let log = RawLog::open(&out.join(RAW_LOG_FILE))?;
    let replay = match replay {
        Some((path, source)) => {
            let columns: Vec<u8> = config.channels.iter().map(|c| c.adc).collect();
            if source.adc_channels() != columns.as_slice() {
                bail!(
                    "{}: the signals carry ADC channels {:?} but the configuration assigns {:?}",
                    path.display(),
                    source.adc_channels(),
                    columns
                );
            }
            Some(Replay {
                source,
                plan: ReplayPlan::new(source)?,
                path: path.to_path_buf(),
            })
        }
        None => None,
    };
    let session = Session::new(
        connector, log, out, config, tables, replay, options, progress,
    )?;
    if session.replay_already_finished() {
        eprintln!(
            "the replay journal in {} says this replay already finished: rebuilding the run directory only",
            out.display()
        );
        return Ok(SessionOutcome {
            completed: true,
            error: None,
            link: Default::default(),
            reconnects: 0,
            bytes: 0,
            device: None,
            last_estimates: None,
            last_status: None,
            replay: None,
            resent_blocks: 0,
        });
    }
    session.run()
}

/// Rebuilds the run directory in `out` from the whole raw log, fits it in
/// batch, compares with the box's last estimates, and writes
/// `stream-report.json`.
pub fn finish(
    out: &Path,
    config: &StreamConfig,
    tables: &BearingTables,
    outcome: Option<&SessionOutcome>,
) -> Result<StreamReport> {
    let raw_path = out.join(RAW_LOG_FILE);
    let raw = RawLog::read_all(&raw_path)?;
    let derived = derive::derive(&raw, config, tables);
    if outcome.is_none() {
        rawlog::require_frames(&raw_path, raw.len(), derived.phasor_frames)?;
    }
    derived
        .run
        .write(out)
        .with_context(|| format!("cannot write the run directory {}", out.display()))?;
    let fit = |options: crate::identify::Options| {
        if derived.run.measurements.is_empty() {
            (None, Some("no phasor frames were received".to_string()))
        } else {
            match crate::identify::identify_run(&derived.run, &options) {
                Ok(id) => (Some(id), None),
                Err(e) => (None, Some(e.to_string())),
            }
        }
    };
    // The paper's OLS: the same least-squares problem the box's RLS solves;
    // and the maximum-likelihood fit `plinth identify` makes by default.
    let (batch, batch_error) = fit(crate::identify::Options::default().ols());
    let (ml, ml_error) = fit(crate::identify::Options::default());
    let pedestals = report::compare(
        &config.bearings,
        derived.last_estimates.as_ref(),
        batch.as_ref(),
        ml.as_ref(),
    );
    let report = StreamReport {
        completed: outcome.is_none_or(|o| o.completed),
        error: outcome.and_then(|o| o.error.clone()),
        link_this_process: outcome.map(|o| LinkSummary::from(o.link)),
        link_raw_log: LinkSummary::from(derived.link),
        link_box: outcome
            .and_then(|o| o.last_status.as_ref())
            .map(|s| LinkSummary::from(s.link)),
        raw_log_bytes: raw.len() as u64,
        reconnects: outcome.map_or(0, |o| o.reconnects),
        phasor_frames: derived.phasor_frames,
        measurement_rows: derived.run.measurements.len(),
        merged_rows: derived.merged_rows,
        dropped_rows: derived.dropped_rows.clone(),
        replay_blocks: outcome.and_then(|o| o.replay),
        resent_blocks: outcome.map_or(0, |o| o.resent_blocks),
        box_sessions: derived.sessions,
        pedestals,
        batch_error,
        ml_error,
        box_health: outcome.and_then(|o| {
            o.last_status
                .as_ref()
                .map(|s| s.health)
                .or(o.device.map(|d| d.health))
        }),
    };
    let path = out.join(REPORT_FILE);
    let text = serde_json::to_string_pretty(&report).context("cannot encode the stream report")?;
    std::fs::write(&path, text + "\n")
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(report)
}

/// The end-of-stream text: link counters, run directory, box vs batch.
pub fn summary(report: &StreamReport) -> String {
    let mut s = String::new();
    if let Some(l) = &report.link_this_process {
        s.push_str(&report::render_link("link (this run)", l));
        s.push('\n');
    }
    s.push_str(&report::render_link(
        "link (whole raw log)",
        &report.link_raw_log,
    ));
    s.push('\n');
    match &report.link_box {
        Some(l) => {
            s.push_str(&report::render_link("link (box side, last status)", l));
            s.push('\n');
        }
        // A box was streamed from but none of its status frames arrived
        // intact: its own counters are unknown, not zero.
        None if report.link_this_process.is_some() => {
            s.push_str(
                "link (box side): no status frame received intact; the box's own counters are unknown\n",
            );
        }
        None => {}
    }
    if let Some(h) = &report.box_health {
        s.push_str(&report::render_health(h));
        s.push('\n');
    }
    if let Some((done, total)) = report.replay_blocks {
        s.push_str(&format!(
            "replay: {done} of {total} sample blocks acknowledged, {} sent again\n",
            report.resent_blocks
        ));
    }
    s.push_str(&format!(
        "raw log: {} bytes; {} phasor frames -> {} measurement rows ({} merged, {} dropped)\n",
        report.raw_log_bytes,
        report.phasor_frames,
        report.measurement_rows,
        report.merged_rows,
        report.dropped_rows.len()
    ));
    for d in report.dropped_rows.iter().take(5) {
        s.push_str(&format!("  dropped: {d}\n"));
    }
    if report.box_sessions > 1 {
        s.push_str(&format!(
            "note: the raw log holds {} box sessions (the host reconnected or restarted); the box's estimates cover only the last one, the batch fit all of them\n",
            report.box_sessions
        ));
    }
    if let Some(e) = &report.batch_error {
        s.push_str(&format!("host OLS fit: not possible: {e}\n"));
    }
    if let Some(e) = &report.ml_error {
        if report.batch_error.as_ref() != Some(e) {
            s.push_str(&format!("host ML fit: not possible: {e}\n"));
        }
    }
    s.push_str(&report::render(&report.pedestals));
    s
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_line_speed_is_a_whole_number_of_bits_per_second_above_zero() {
        assert_eq!(super::line_speed("115200"), Ok(115_200));
        assert!(super::line_speed("0")
            .unwrap_err()
            .contains("0 is not allowed"));
        assert!(super::line_speed("-9600").is_err());
        assert!(super::line_speed("4294967296")
            .unwrap_err()
            .contains("beyond any serial line"));
    }
}
