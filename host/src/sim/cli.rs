//! `plinth simulate`, `plinth signals`, `plinth predict`.

use super::budget;
use super::inject::EffectSet;
use super::machine::Machine;
use super::response::{Noise, UnbalanceSolver};
use crate::output::OutputDir;
use crate::progress::Ticker;
use crate::rundir::{DigitsMode, WriteOptions};
use anyhow::{bail, Context};
use std::path::PathBuf;

/// Command-line arguments of `plinth simulate`.
#[derive(clap::Args, Debug)]
pub struct SimulateArgs {
    /// Machine file (TOML, SI units; see the `plinth::sim::machine` docs).
    pub machine: PathBuf,
    /// Run directory to write: a new or empty directory; written in a hidden
    /// sibling and moved into place only when complete.
    #[arg(long)]
    pub out: PathBuf,
    /// Write into an --out that already holds files (files Plinth did not
    /// write there are kept, never replaced).
    #[arg(long)]
    pub force: bool,
    /// Speeds [Hz] as START:STOP:STEP (inclusive), or a comma-separated list.
    #[arg(long, default_value = "5:200:1")]
    pub speeds: String,
    /// Significant digits of the measured phasors (the paper used 12, 3, 2).
    #[arg(long)]
    pub digits: Option<u32>,
    /// Truncate to --digits instead of rounding (as the paper did).
    #[arg(long, requires = "digits")]
    pub truncate: bool,
    /// Complex Gaussian noise, RMS relative to each channel's RMS over speed.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::args::non_negative)]
    pub noise: Option<f64>,
    /// Seed of the noise (needs --noise).
    #[arg(
        long,
        allow_negative_numbers = true,
        default_value_t = 1,
        requires = "noise"
    )]
    pub seed: u64,
    /// Effect to inject: NAME[:BEARING][=SIZE] (repeatable; see `plinth::sim::inject`).
    #[arg(long = "effect")]
    pub effects: Vec<String>,
}

pub use super::predict::{predict, PredictArgs};
pub use super::signals::SignalsArgs;

/// `plinth signals` as the command line runs it: [`SignalsArgs`] plus the
/// output policy (the signal set is written through [`OutputDir`]).
#[derive(clap::Args, Debug)]
pub struct SignalsCommand {
    /// The signal options.
    #[command(flatten)]
    pub args: SignalsArgs,
    /// Write into an --out that already holds files (files Plinth did not
    /// write there are kept, never replaced).
    #[arg(long)]
    pub force: bool,
}

/// Runs `plinth signals`: the signal set is staged beside `--out` and moved
/// into place only when complete.
pub fn signals(command: SignalsCommand) -> anyhow::Result<()> {
    let SignalsCommand { args, force } = command;
    super::signals::signals(&args, force)
}

/// Parses a speed list: `START:STOP:STEP` (inclusive, to within STEP/1e6) or
/// `a,b,c` [Hz].
pub fn parse_speeds(text: &str) -> anyhow::Result<Vec<f64>> {
    let num = |s: &str| -> anyhow::Result<f64> {
        let v: f64 = s
            .trim()
            .parse()
            .with_context(|| format!("--speeds: {s:?} is not a number"))?;
        if !(v.is_finite() && v >= 0.0) {
            bail!("--speeds: {v} must be finite and >= 0 Hz");
        }
        if v > crate::args::MAX_SPEED_HZ {
            bail!(
                "--speeds: {v:e} Hz is above {:e} Hz (6 million rpm): a typo or rpm where Hz is meant?",
                crate::args::MAX_SPEED_HZ
            );
        }
        Ok(v)
    };
    let parts: Vec<&str> = text.split(':').collect();
    let speeds = match parts.as_slice() {
        [a, b, c] => {
            let (start, stop, step) = (num(a)?, num(b)?, num(c)?);
            if step <= 0.0 || stop < start {
                bail!("--speeds {text}: need STOP >= START and STEP > 0");
            }
            // Counted (saturating) and checked before anything is allocated.
            let n = ((stop - start) / step + 1e-6).floor() as u64;
            let n = n.saturating_add(1);
            budget::SPEEDS
                .check(&format!("--speeds {text}"), n)
                .map_err(anyhow::Error::msg)?;
            (0..n).map(|i| start + i as f64 * step).collect()
        }
        [_] => {
            let entries = text.split(',').count();
            budget::SPEEDS
                .check(
                    &format!("--speeds (a list of {entries} entries)"),
                    entries as u64,
                )
                .map_err(anyhow::Error::msg)?;
            text.split(',')
                .map(num)
                .collect::<anyhow::Result<Vec<_>>>()?
        }
        _ => bail!("--speeds {text}: use START:STOP:STEP or a comma-separated list"),
    };
    if speeds.is_empty() {
        bail!("--speeds {text}: no speeds");
    }
    // formats.md: the same (speed_hz, bearing) twice is an error, so a
    // repeated speed (listed twice, or a STEP below the doubles' spacing at
    // START) would give a run every reader refuses.
    let mut sorted = speeds.clone();
    sorted.sort_by(f64::total_cmp);
    if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
        bail!(
            "--speeds {text}: {} Hz comes twice (a run has one row per speed and bearing)",
            crate::rundir::format_number(w[0])
        );
    }
    Ok(speeds)
}

/// Runs `plinth simulate`.
pub fn simulate(args: &SimulateArgs) -> anyhow::Result<()> {
    let machine = Machine::from_toml_path(&args.machine)?;
    let speeds = parse_speeds(&args.speeds)?;
    budget::check_solves(&format!("--speeds {}", args.speeds), &machine, speeds.len())
        .map_err(anyhow::Error::msg)?;
    // The run written has one row per speed and bearing: within the rows
    // every reader takes, or it could never be read back.
    let bearings = machine.bearings.len();
    budget::ROWS
        .check(
            &format!("--speeds {} on {bearings} bearings", args.speeds),
            (speeds.len() as u64).saturating_mul(bearings as u64),
        )
        .map_err(anyhow::Error::msg)?;
    // The least the run's two tables take [bytes]: every row holds at least
    // a one-character speed, the bearing's name and eight one-character
    // numbers with their commas and line end, in measurements.csv and in
    // bearings.csv. A disk with less free is refused before any work.
    let least = machine
        .bearings
        .iter()
        .map(|b| 2 * (19 + b.name.len() as u64))
        .sum::<u64>()
        .saturating_mul(speeds.len() as u64);
    crate::output::check_room("--out", &args.out, least)?;
    let out = OutputDir::create(&args.out, args.force)?;
    let effects = EffectSet::from_options(&args.effects).map_err(anyhow::Error::msg)?;
    if let Some(d) = args.digits {
        if d == 0 {
            bail!("--digits must be at least 1");
        }
    }
    let needed = budget::simulate_bytes(&machine, speeds.len());
    budget::check(
        &format!(
            "simulating {} shaft elements at {} speeds",
            machine.elements.len(),
            speeds.len()
        ),
        needed,
        budget::available_bytes(),
    )
    .map_err(anyhow::Error::msg)?;
    let mut ticker = Ticker::new("simulate: speeds", speeds.len(), true);
    let response = UnbalanceSolver::new(&machine, &effects)
        .and_then(|s| s.run_with(&speeds, false, &mut |done| ticker.tick(done)))
        .with_context(|| format!("simulating {}", args.machine.display()))?;
    ticker.finish();
    let noise = args.noise.map(|fraction| Noise {
        fraction,
        seed: args.seed,
    });
    let run = response.to_run_dir(noise)?;
    let options = WriteOptions {
        digits: args.digits,
        digits_mode: if args.truncate {
            DigitsMode::Truncate
        } else {
            DigitsMode::Round
        },
    };
    run.write_with(out.path(), &options)
        .with_context(|| format!("writing {}", args.out.display()))?;
    if response.table_differs() {
        write_true_bearings(out.path(), &response.true_bearing_rows())?;
    }
    if !machine.bases.is_empty() {
        let bases: Vec<(String, Vec<String>)> = super::base::truth(&machine)
            .into_iter()
            .map(|b| (b.name, b.bearings))
            .collect();
        crate::base_csv::write(out.path(), &crate::base_csv::rows_of(&response, &bases))?;
    }
    out.commit()?;
    println!(
        "{}: {} speeds x {} bearings -> {}",
        machine.name,
        speeds.len(),
        machine.bearings.len(),
        args.out.display()
    );
    Ok(())
}

/// File of the bearing coefficients as simulated, written beside
/// `bearings.csv` when the effect `bearing_coefficients` makes them differ.
pub const TRUE_BEARINGS_FILE: &str = "bearings_true.csv";

/// Writes `rows` as `dir/bearings_true.csv` (the `bearings.csv` columns,
/// full round-trip precision).
fn write_true_bearings(
    dir: &std::path::Path,
    rows: &[crate::rundir::BearingRow],
) -> anyhow::Result<()> {
    let path = dir.join(TRUE_BEARINGS_FILE);
    let mut w =
        csv::Writer::from_path(&path).with_context(|| format!("writing {}", path.display()))?;
    w.write_record(crate::rundir::BEARING_COLUMNS)?;
    for r in rows {
        let (k, c) = (r.coefficients.k, r.coefficients.c);
        let mut record = vec![crate::rundir::format_number(r.speed_hz), r.bearing.clone()];
        for v in [
            k[0][0], k[0][1], k[1][0], k[1][1], c[0][0], c[0][1], c[1][0], c[1][1],
        ] {
            record.push(crate::rundir::format_number(v));
        }
        w.write_record(&record)?;
    }
    w.flush()
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_ranges_are_inclusive() {
        let s = parse_speeds("5:200:1").unwrap();
        assert_eq!(s.len(), 196);
        assert_eq!(*s.last().unwrap(), 200.0);
        assert_eq!(parse_speeds("1.5, 2").unwrap(), vec![1.5, 2.0]);
        assert!(parse_speeds("5:1:1").is_err());
        assert!(parse_speeds("a:b").is_err());
        let twice = |t: &str| parse_speeds(t).unwrap_err().to_string();
        assert!(twice("5,10,5.0").contains("5 Hz comes twice"));
        // A STEP below the doubles' spacing at START (1.5e-11 at 65536):
        // 20 000 speeds, within the limit, many of them equal.
        assert!(twice("65536:65536.0000001:5e-12").contains("comes twice"));
        // 2 000 000 such speeds are beyond budget::SPEEDS before that.
        assert!(twice("65536:65536.00001:5e-12").contains("above the limit of"));
        assert_eq!(parse_speeds("10,5").unwrap(), vec![10.0, 5.0]);
    }
}
