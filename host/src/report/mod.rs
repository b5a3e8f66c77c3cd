//! `plinth report RUN --out REPORT.html` and the figures of an
//! identification: one self-contained HTML page (inline SVG, no network
//! access, no script, prints well) with what was measured, the identified
//! pedestals with their modal view and trust, the measured-vs-fitted
//! figures, Bode and polar figures and, with `--diagnose`, the diagnosis;
//! and the exact command and version that made it.
//!
//! Files: this one (the command), `fitted` (measured-vs-fitted dynamic
//! stiffness from an identification), `page` (the HTML).

pub mod fitted;
pub mod page;

use crate::field::plot::{PlotOptions, PlotTransducer, PolarArgs};
use crate::identify::Identification;
use crate::rundir::RunDir;
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// Command-line arguments of `plinth report`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Identifies every pedestal of RUN (as `plinth identify RUN` does, default options, with \
--speeds and --unmeasured-base passed on) and writes \
one HTML file: the run's files, transducers, speeds and noise; the identified table with the \
modal view (f_n, ζ) and each pedestal's trust with its reasons; each bearing's measured \
dynamic stiffness against the fitted model; Bode and polar figures; with --diagnose the \
diagnosis (as `plinth diagnose RUN`); the command and version that made it. The page needs \
no network and no script; figures are inline SVG. docs/figures.md.")]
pub struct Args {
    /// Run directory (measurements.csv, bearings.csv; transducers.csv,
    /// truth.json when present).
    pub dir: PathBuf,
    /// The HTML file to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Also run the diagnosis (`plinth diagnose`) and include its verdict
    /// and figures.
    #[arg(long)]
    pub diagnose: bool,
    /// Identify (and diagnose) only the speeds from LO to HI Hz (ends
    /// included), as `plinth identify --speeds`.
    #[arg(long, allow_negative_numbers = true, value_name = "LO:HI", value_parser = crate::args::speed_band)]
    pub speeds: Option<crate::args::SpeedBand>,
    /// Pedestals on a base whose motion was not measured, as `plinth
    /// identify --unmeasured-base` (e.g. `left,right`).
    #[arg(long, value_name = "B1,B2[;B3,B4]")]
    pub unmeasured_base: Option<crate::identify::on_base::BaseGroups>,
    /// The transducers' units, rotation, 0° placement and style of the figures.
    #[command(flatten)]
    pub polar: PolarArgs,
    /// Replace an existing --out file.
    #[arg(long)]
    pub force: bool,
}

/// Everything the page shows, computed before it is written.
pub struct Contents<'a> {
    /// The run directory as given.
    pub dir: &'a Path,
    /// The run as read.
    pub run: &'a RunDir,
    /// Its identification.
    pub identification: &'a Identification,
    /// The transducers of `transducers.csv`, when the run has one.
    pub transducers: &'a [PlotTransducer],
    /// How the field figures are drawn.
    pub options: PlotOptions,
    /// With `--diagnose`: the outcome.
    pub diagnosis: Option<&'a crate::diagnose::Outcome>,
    /// The exact command line.
    pub command: String,
    /// The `plinth identify` command whose results the page shows.
    pub identify_command: String,
}

/// The `plinth identify` arguments of `args`: identify's defaults (as clap
/// parses `plinth identify RUN`) with the report's `--speeds` and
/// `--unmeasured-base`.
pub fn identify_args(args: &Args) -> Result<crate::identify::cli::Args> {
    use clap::{Args as _, FromArgMatches};
    let command = crate::identify::cli::Args::augment_args(clap::Command::new("identify"));
    let argv = [
        std::ffi::OsString::from("identify"),
        "--".into(),
        args.dir.clone().into_os_string(),
    ];
    let matches = command.try_get_matches_from(argv)?;
    let mut identify = crate::identify::cli::Args::from_arg_matches(&matches)?;
    identify.speeds = args.speeds;
    identify.unmeasured_base = args.unmeasured_base.clone();
    Ok(identify)
}

/// The `plinth identify` command line [`identify_args`] stands for.
pub fn identify_command(args: &Args) -> String {
    let mut argv = vec![
        "plinth".to_string(),
        "identify".into(),
        args.dir.display().to_string(),
    ];
    if let Some(b) = args.speeds {
        argv.extend(["--speeds".into(), format!("{}:{}", b.lo_hz, b.hi_hz)]);
    }
    if let Some(g) = &args.unmeasured_base {
        let groups: Vec<String> = g.0.iter().map(|names| names.join(",")).collect();
        argv.extend(["--unmeasured-base".into(), groups.join(";")]);
    }
    command_line(argv)
}

/// The command line as a shell would read it back (arguments with spaces or
/// quotes single-quoted).
pub fn command_line(args: impl IntoIterator<Item = String>) -> String {
    args.into_iter()
        .map(|a| {
            if !a.is_empty()
                && a.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "-_./:=,+@%".contains(c))
            {
                a
            } else {
                format!("'{}'", a.replace('\'', r"'\''"))
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Runs `plinth report`.
pub fn run(args: &Args) -> Result<()> {
    // --out is checked before anything is computed.
    crate::output::check_file("--out", &args.out, args.force)?;
    let (transducers, options) = crate::field::plot::run_figures(&args.dir, &args.polar)?;
    // What `plinth identify` shows: the band, the bases, the modal view.
    let (run, identification) = crate::identify::cli::identify_args(&identify_args(args)?)
        .with_context(|| format!("identifying {}", args.dir.display()))?;
    let outcome = if args.diagnose {
        let options = crate::diagnose::Options {
            progress: false,
            ..crate::diagnose::Options::default()
        };
        Some(
            crate::diagnose::diagnose(&run, &options)
                .with_context(|| format!("diagnosing {}", args.dir.display()))?,
        )
    } else {
        None
    };
    let contents = Contents {
        dir: &args.dir,
        run: &run,
        identification: &identification,
        transducers: &transducers,
        options,
        diagnosis: outcome.as_ref(),
        command: command_line(std::env::args()),
        identify_command: identify_command(args),
    };
    let html = page::render(&contents)?;
    crate::output::write_file("--out", &args.out, args.force, html.as_bytes())?;
    println!(
        "report of {} ({} pedestals, {} figures) -> {}",
        args.dir.display(),
        identification.pedestals.len(),
        html.matches("<svg").count(),
        args.out.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::command_line;

    #[test]
    fn command_is_quoted_for_a_shell() {
        let c = command_line(
            ["plinth", "report", "my run", "--out", "r.html", "it's"].map(String::from),
        );
        assert_eq!(c, r"plinth report 'my run' --out r.html 'it'\''s'");
    }
}
