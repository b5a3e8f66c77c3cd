//! `plinth stream`: the laptop side of the field box link.
//!
//! Opens the serial port (or QEMU's pseudo-terminal), shakes hands, sends the
//! configuration, optionally replays simulated time signals to the box, and
//! receives its phasor, estimate and status frames. Every received byte goes
//! to an append-only raw log first; at the end the run directory is re-derived
//! from the whole log, fitted in batch, and compared with the box's own
//! recursive estimates.
//!
//! One file per idea: [`port`] (opening and reopening the link), [`rawlog`]
//! (the append-only byte log), [`config`] (the configuration file),
//! [`progress`] (the live status line).

pub mod config;
pub mod port;
pub mod progress;
pub mod rawlog;

use std::path::PathBuf;

/// Command-line arguments of `plinth stream`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Serial port of the field box, e.g. /dev/ttyUSB0 or QEMU's /dev/pts/N.
    #[arg(long)]
    pub port: String,
    /// Line speed [bit/s] (pseudo-terminals ignore it).
    #[arg(long, default_value_t = 115_200)]
    pub baud: u32,
    /// Stream configuration (TOML: channel map, averaging, RLS, bearings.csv).
    #[arg(long)]
    pub config: PathBuf,
    /// Run directory to write (created; raw.bin in it is appended to, never truncated).
    #[arg(long)]
    pub out: PathBuf,
    /// Replay these simulated time signals (`plinth signals` output) to the box.
    #[arg(long)]
    pub replay: Option<PathBuf>,
}

/// Runs `plinth stream`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("`plinth stream` is not available in this build yet")
}
