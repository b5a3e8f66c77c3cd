//! `plinth paper`: reproduces the numerical experiment of Feng & Hahn (1997)
//! on Plinth's reconstruction of their machine (`examples/feng-hahn-1997.toml`
//! and its damped twin, bundled into the binary; see their comments for what
//! is the paper's and what is ours).
//!
//! - **Digits**: the simulated phasors are reduced to a number of significant
//!   digits to imitate instrument accuracy. The paper says its data were
//!   "truncated", but also that two digits mean "a maximum error of 5 %",
//!   which is what *rounding* gives (truncation is off by up to 10 %, always
//!   towards zero). Rounding is therefore the default; `--truncate` gives the
//!   literal reading. The tables say which was used.
//! - **Table 1** (no pedestal damping): the unbalance response at the speeds
//!   (default 5-200 Hz every 1 Hz) reduced to 12, 3 and 2 significant digits,
//!   and k_y, k_z, m of both pedestals identified with all four equations of
//!   eq. 4 (R&I) and the undamped model (c fixed at 0, as in the paper's
//!   Table 1).
//! - **Table 2** (damped pedestals, 2 digits): the four ways of using eq. 4 —
//!   R&I (all equations, the full model k_y, k_z, m, c_y, c_z), R+I, R and I
//!   (the undamped model, as the paper's Table 2 lists only k and m for them)
//!   — in two cases: (a) `scan_damping`, the damped example as the scan reads
//!   it (70-100 N·s/m, a damping ratio of about 0.2 %, whose damping force is
//!   below what 2-digit data resolve, so the paper's contrast cannot appear),
//!   and (b) `heavy_damping`, the same machine with the pedestal damping
//!   scaled so the mean damping ratio is about 10 % (the smooth phase of the
//!   paper's Fig. 9), where only R&I is right, as the paper found.
//! - **Figures** (with `--plots DIR`, PNG and SVG): response amplitudes and
//!   phase lags at the measurement points (Figs. 3-4 undamped, 7-8 damped:
//!   rotor relative to pedestal and absolute pedestal, Ly/Lz/Ry/Rz), the phase
//!   lag of each pedestal's response behind the force transmitted to it
//!   (Figs. 5, 9), and the 2-digit measured rotor response against the one
//!   re-predicted with the 2-digit identified pedestals (Fig. 6). Figs. 7-9
//!   are drawn for both damping cases (`*_heavy_damping` for case b).
//!
//! Errors are 100·(identified − truth)/truth [%]. The bearing coefficients are
//! known exactly (they are the paper's "assumed known" bearing properties);
//! only the measured phasors are reduced to digits.
//!
//! Files: `experiment` (simulate, reduce, identify, re-predict),
//! `tables` (the rows and their text), `figures` (the plots); this file
//! holds the command.

mod experiment;
mod figures;
mod tables;

pub use experiment::*;
pub use figures::*;
pub use tables::*;

use crate::rundir::DigitsMode;
use crate::sim::cli::parse_speeds;
use anyhow::{Context, Result};
use serde::Serialize;
use std::io::Write;
use std::path::PathBuf;

/// The undamped paper machine (Table 1), bundled.
pub const UNDAMPED_MACHINE: &str = include_str!("../../../examples/feng-hahn-1997.toml");

/// The damped paper machine (Table 2), bundled.
pub const DAMPED_MACHINE: &str = include_str!("../../../examples/feng-hahn-1997-damped.toml");

/// Command-line arguments of `plinth paper`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Digits: the phasors are ROUNDED to the digit counts by default. The paper says \
its data were \"truncated\" but also that two digits mean \"a maximum error of 5 %\", which is \
what rounding gives (truncation is off by up to 10 %, one-sided); --truncate gives the literal \
reading. Table 2 is computed twice: with the scan's pedestal damping (70-100 N·s/m, damping \
ratio ~0.2 %, below what 2-digit data resolve) and with that damping scaled to a damping ratio \
of ~10 % (--heavy-damping-ratio), where the paper's finding (only R&I is right) appears."
)]
pub struct Args {
    /// Print the tables as JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Write the figures (PNG and SVG) into this directory.
    #[arg(long)]
    pub plots: Option<PathBuf>,
    /// Write into an existing --plots/--out directory that already holds
    /// files (files Plinth did not write there are kept, never replaced).
    #[arg(long, requires = "plots")]
    pub force: bool,
    /// Measurement speeds [Hz]: START:STOP:STEP (inclusive) or a list.
    #[arg(long, default_value = "5:200:1")]
    pub speeds: String,
    /// Undamped machine file instead of the bundled examples/feng-hahn-1997.toml.
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// Damped machine file instead of the bundled examples/feng-hahn-1997-damped.toml.
    #[arg(long)]
    pub damped_machine: Option<PathBuf>,
    /// Truncate to the digits (the paper's word) instead of rounding (the
    /// paper's "maximum error of 5 %" at 2 digits, the default).
    #[arg(long)]
    pub truncate: bool,
    /// Mean pedestal damping ratio [-] of Table 2's heavy-damping case: the
    /// damped machine's c_y, c_z are scaled by one factor (2 significant
    /// digits) to reach it.
    #[arg(long, default_value_t = 0.10, allow_negative_numbers = true, value_parser = crate::args::probability)]
    pub heavy_damping_ratio: f64,
}

/// What to reproduce and how.
#[derive(Clone, Debug, PartialEq)]
pub struct PaperOptions {
    /// Measurement speeds [Hz].
    pub speeds_hz: Vec<f64>,
    /// Digit counts of Table 1 (the paper: 12, 3, 2).
    pub table1_digits: Vec<u32>,
    /// Digits of Table 2 (the paper: 2).
    pub table2_digits: u32,
    /// Round (default: the paper's "maximum error of 5 %") or truncate (the
    /// paper's word).
    pub digits_mode: DigitsMode,
    /// Mean pedestal damping ratio c/(2·sqrt(k·m)) [-] of Table 2's
    /// heavy-damping case (default 0.10).
    pub heavy_damping_ratio: f64,
}

impl Default for PaperOptions {
    fn default() -> Self {
        Self {
            speeds_hz: (5..=200).map(f64::from).collect(),
            table1_digits: vec![12, 3, 2],
            table2_digits: 2,
            digits_mode: DigitsMode::Round,
            heavy_damping_ratio: 0.10,
        }
    }
}

/// Runs `plinth paper`.
pub fn run(args: &Args) -> Result<()> {
    let undamped = load_machine(
        args.machine.as_deref(),
        UNDAMPED_MACHINE,
        "examples/feng-hahn-1997.toml",
    )?;
    let damped = load_machine(
        args.damped_machine.as_deref(),
        DAMPED_MACHINE,
        "examples/feng-hahn-1997-damped.toml",
    )?;
    let opts = PaperOptions {
        speeds_hz: parse_speeds(&args.speeds)?,
        digits_mode: if args.truncate {
            DigitsMode::Truncate
        } else {
            DigitsMode::Round
        },
        heavy_damping_ratio: args.heavy_damping_ratio,
        ..PaperOptions::default()
    };
    for machine in [&undamped, &damped] {
        crate::sim::budget::check_solves(
            &format!("--speeds {}", args.speeds),
            machine,
            opts.speeds_hz.len(),
        )
        .map_err(anyhow::Error::msg)?;
    }
    // --plots is checked (and locked) before anything is computed.
    let staged = (args.plots.as_deref())
        .map(|dir| crate::output::OutputDir::create_as("--plots", dir, args.force))
        .transpose()?;
    let steps = if args.plots.is_some() { 2 } else { 1 };
    let mut ticker =
        crate::progress::Ticker::new("paper: simulate, identify, figures", steps, true);
    let paper = reproduce_with(&undamped, &damped, &opts)?;
    ticker.tick(1);
    let mut text = if args.json {
        let report = JsonReport {
            tables: &paper.tables,
            fig6_reprediction: Fig6Gap {
                digits: paper.fig6_digits,
                overall: &paper.reprediction.overall,
                concentration: &paper.reprediction_gap,
            },
        };
        serde_json::to_string_pretty(&report)? + "\n"
    } else {
        format!(
            "{}\n{}",
            tables_text(&paper.tables),
            reprediction_text(&paper)
        )
    };
    if let (Some(staged), Some(dir)) = (staged, &args.plots) {
        let files = write_figures(&paper, staged.path())?;
        staged.commit()?;
        ticker.tick(2);
        if !args.json {
            text += &format!(
                "{} figure files written to {}\n",
                files.len(),
                dir.display()
            );
        }
    }
    ticker.finish();
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|_| out.flush()) {
        // A closed pipe (`plinth paper | head`) is the reader's choice.
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => r.context("writing the tables to standard output"),
    }
}

/// What `plinth paper --json` prints: the tables' keys at the top level,
/// plus the Fig. 6 re-prediction gap.
#[derive(Serialize)]
struct JsonReport<'a> {
    #[serde(flatten)]
    tables: &'a Tables,
    fig6_reprediction: Fig6Gap<'a>,
}

/// The Fig. 6 re-prediction gap in the JSON.
#[derive(Serialize)]
struct Fig6Gap<'a> {
    digits: u32,
    overall: &'a crate::sim::predict::ChannelDifference,
    concentration: &'a GapLocation,
}
