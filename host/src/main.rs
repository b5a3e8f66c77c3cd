//! `plinth`: the laptop side of Plinth.
use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "plinth",
    version,
    about = "Identify bearing-pedestal mass, stiffness and damping from run-down vibration data (Feng & Hahn 1997)"
)]
struct Cli {
    /// No progress display on stderr (warnings and errors are still printed).
    #[arg(long, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Identification of every pedestal in a run directory (maximum likelihood or the paper's least squares).
    Identify(plinth::identify::cli::Args),
    /// Unbalance response of a machine file, written as a run directory.
    Simulate(plinth::sim::cli::SimulateArgs),
    /// Sampled sensor signals of a run-down, for the field box.
    Signals(plinth::sim::cli::SignalsCommand),
    /// Re-predict a machine with identified pedestals and compare with a run.
    Predict(plinth::sim::cli::PredictArgs),
    /// Two runs of one machine (a run-down and a run-up, two temperatures): each pedestal's values tested for agreement.
    Compare(plinth::compare::Args),
    /// Reproduce Feng & Hahn (1997): Tables 1 and 2 and the figures.
    Paper(plinth::paper::Args),
    /// Stream from the field box over a serial port.
    Stream(plinth::stream::Args),
    /// The whole chain on the bundled paper machine.
    Demo(plinth::demo::Args),
    /// Find, name and fix what the pedestal model is missing.
    Diagnose(plinth::diagnose::Args),
    /// Import a 1X vector table (amplitude and phase per transducer) as a run directory.
    Import(plinth::field::import::Args),
    /// Extract 1X phasors from a recorded run-down (WAV or CSV) into a run directory.
    Extract(plinth::extract::Args),
    /// Bode and polar plots of a run directory.
    Plot(plinth::field::plot::Args),
    /// Monte-Carlo of OLS and ML against the Cramér–Rao bound on a simulated machine.
    Accuracy(plinth::accuracy::Args),
    /// One self-contained HTML report of a run: data, identification, figures.
    Report(plinth::report::Args),
}

fn main() -> ExitCode {
    plinth::pipe::exit_quietly_on_closed_stdout();
    plinth::output::refuse_writes_past_the_size_limit();
    let cli = Cli::parse();
    plinth::progress::set_quiet(cli.quiet);
    let quiet = cli.quiet;
    let result = match cli.command {
        Command::Identify(a) => plinth::identify::cli::run(&a),
        Command::Simulate(a) => plinth::sim::cli::simulate(&a),
        Command::Signals(a) => plinth::sim::cli::signals(a),
        Command::Predict(a) => plinth::sim::cli::predict(&a),
        Command::Compare(a) => plinth::compare::run(&a),
        Command::Paper(a) => plinth::paper::run(&a),
        Command::Stream(mut a) => {
            a.quiet |= quiet;
            plinth::stream::run(&a)
        }
        Command::Demo(mut a) => {
            a.quiet |= quiet;
            plinth::demo::run(&a)
        }
        Command::Diagnose(a) => plinth::diagnose::run(&a),
        Command::Import(a) => plinth::field::import::run(&a),
        Command::Extract(mut a) => {
            a.quiet |= quiet;
            plinth::extract::run(&a)
        }
        Command::Plot(a) => plinth::field::plot::run(&a),
        Command::Accuracy(a) => plinth::accuracy::run(&a),
        Command::Report(a) => plinth::report::run(&a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // `plinth identify --json | head -1`: the reader has what it wanted.
        Err(e) if plinth::pipe::is_closed_stdout(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", plinth::error_text(&e));
            ExitCode::from(plinth::identify::physical::exit_code(&e))
        }
    }
}
