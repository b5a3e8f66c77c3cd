//! `plinth compare RUN_A RUN_B`: two runs of the same machine identified
//! and each pedestal's values tested for agreement
//! (docs/trust-lack-of-fit.md, session 49).
//!
//! The test one run cannot make: in a run-down time and speed are tied, so
//! a support whose stiffness drifts over the run (a hot end cooling) reads
//! as a mass term, with a perfect fit ([`crate::identify::conditional::drift`]).
//! A second run whose time runs the other way in speed (a run-up after the
//! run-down) is biased the other way, and one at another temperature is
//! offset: the same pedestal from the two disagreeing beyond their ± says
//! the support was not the same in both, and that neither run's values
//! are to be trusted alone. A command of its own, not an option of
//! `identify`: its result is a verdict on a pair (text, JSON and exit code
//! of their own), and each run is identified exactly as `plinth identify
//! DIR` does (its defaults: one definition of an identification).

pub mod agreement;

use crate::identify::Identification;
use agreement::Agreement;
use anyhow::Context;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Command-line arguments of `plinth compare`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Identifies RUN_A and RUN_B as `plinth identify DIR` does (its defaults), then tests each \
pedestal's values from the two runs for agreement: χ² of the difference with both runs' \
covariances (the ± as printed, every widening included), each pedestal at 1 %/(number of \
pedestals), so that two runs of the same support are flagged in at most 1 % of pairs. \
Meant for a run-down and a run-up of the same machine, or two run-downs at different \
temperatures: a support whose stiffness drifts over a run cannot be seen in that run alone \
(identify's \"Conditional on\"), and runs whose time runs the other way in speed are biased \
the other way. The two runs must measure the same bearings. Exit code 2 when a pedestal \
disagrees (everything is printed first), 1 on errors.")]
pub struct Args {
    /// The first run directory (measurements.csv, bearings.csv).
    pub run_a: PathBuf,
    /// The second run directory, of the same machine.
    pub run_b: PathBuf,
    /// Print the comparison as JSON (docs/formats.md) instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `plinth identify`'s arguments, for its defaults.
#[derive(clap::Parser)]
struct IdentifyDefaults {
    #[command(flatten)]
    args: crate::identify::cli::Args,
}

/// What `plinth compare --json` prints.
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    /// The two run directories, as given.
    pub runs: [String; 2],
    /// The chance per pair of runs of the same support that some pedestal
    /// is said to disagree [-].
    pub family_false_alarm: f64,
    /// Per bearing (run A's order), the verdict.
    pub pedestals: Vec<Agreement>,
    /// The two identifications, as `plinth identify --json` gives their
    /// pedestals and noise.
    pub identifications: [Identification; 2],
}

impl Comparison {
    /// The pedestals that disagree.
    pub fn disagreeing(&self) -> impl Iterator<Item = &Agreement> {
        self.pedestals.iter().filter(|p| !p.agree)
    }
}

/// Identifies one run as `plinth identify DIR` does.
fn identify(dir: &Path) -> anyhow::Result<Identification> {
    use clap::Parser;
    let parsed = IdentifyDefaults::try_parse_from([
        std::ffi::OsStr::new("identify"),
        std::ffi::OsStr::new("--"),
        dir.as_os_str(),
    ])
    .map_err(|e| anyhow::anyhow!("{}: {e}", dir.display()))?;
    let (_, identification) = crate::identify::cli::identify_args(&parsed.args)?;
    Ok(identification)
}

/// Both runs identified and compared (module docs); errors name the run.
pub fn comparison(run_a: &Path, run_b: &Path) -> anyhow::Result<Comparison> {
    let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    };
    if same(run_a, run_b) {
        anyhow::bail!(
            "{} is given twice: compare needs two runs of the machine (a run-down and a run-up, or two temperatures)",
            run_a.display()
        );
    }
    let a = identify(run_a).with_context(|| format!("run A ({})", run_a.display()))?;
    let b = identify(run_b).with_context(|| format!("run B ({})", run_b.display()))?;
    let names = |i: &Identification| -> Vec<String> {
        let mut v: Vec<String> = i.pedestals.iter().map(|p| p.bearing.clone()).collect();
        v.sort();
        v
    };
    if names(&a) != names(&b) {
        anyhow::bail!(
            "{} measures bearings {} and {} measures {}: the runs are not of the same machine (or not of the same sensors); compare needs the same bearings in both",
            run_a.join(crate::rundir::MEASUREMENTS_FILE).display(),
            names(&a).join(", "),
            run_b.join(crate::rundir::MEASUREMENTS_FILE).display(),
            names(&b).join(", ")
        );
    }
    let alpha = agreement::FAMILY_FALSE_ALARM / a.pedestals.len().max(1) as f64;
    let pedestals = a
        .pedestals
        .iter()
        .filter_map(|pa| {
            let pb = b.pedestal(&pa.bearing)?;
            Some(agreement::compare(pa, pb, alpha))
        })
        .collect();
    Ok(Comparison {
        runs: [run_a.display().to_string(), run_b.display().to_string()],
        family_false_alarm: agreement::FAMILY_FALSE_ALARM,
        pedestals,
        identifications: [a, b],
    })
}

/// The comparison as text: per pedestal the values of both runs, the
/// difference in % and in combined ±, then the verdict.
pub fn text(c: &Comparison) -> String {
    let mut out = format!(
        "A = {}\nB = {}\neach pedestal tested at {:.2} % (χ² of B − A with both runs' ±; at most {:.0} % of pairs of runs of the same support flagged)\n",
        c.runs[0],
        c.runs[1],
        100.0 * c.pedestals.first().map_or(f64::NAN, |p| p.alpha),
        100.0 * c.family_false_alarm
    );
    for p in &c.pedestals {
        out.push_str(&format!(
            "\n{}{}\n",
            p.bearing,
            match p.trusted {
                [true, true] => String::new(),
                [a, b] => format!(
                    " (identify does not trust run {}'s fit: its ± excludes model error)",
                    if !a && !b {
                        "A's nor B"
                    } else if !a {
                        "A"
                    } else {
                        "B"
                    }
                ),
            }
        ));
        out.push_str("         run A                    run B                    B − A\n");
        for q in &p.parameters {
            out.push_str(&format!(
                "  {:<4} {:>11.5e} ± {:<9.2e} {:>11.5e} ± {:<9.2e} {:+7.2} % ({:+.1} ±)\n",
                q.name,
                q.a[0],
                q.a[1],
                q.b[0],
                q.b[1],
                100.0 * q.difference_relative,
                q.z
            ));
        }
        out.push_str(&format!(
            "  {}{}\n",
            if p.agree { "" } else { "DISAGREE: " },
            p.message
        ));
    }
    out
}

/// Runs `plinth compare`: text (or JSON) on stdout; a disagreement is
/// returned after printing as [`crate::identify::physical::NotPhysical`]
/// (exit code 2, as identify's for a result that must not be used).
pub fn run(args: &Args) -> anyhow::Result<()> {
    let c = comparison(&args.run_a, &args.run_b)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&c)?);
    } else {
        print!("{}", text(&c));
    }
    let lines: Vec<String> = c
        .disagreeing()
        .map(|p| {
            format!(
                "pedestal `{}`: the two runs disagree beyond their ± (above): neither run's values are to be trusted alone",
                p.bearing
            )
        })
        .collect();
    if lines.is_empty() {
        Ok(())
    } else {
        Err(crate::identify::physical::NotPhysical(lines).into())
    }
}
