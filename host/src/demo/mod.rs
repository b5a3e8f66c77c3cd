//! `plinth demo`: the whole chain on the bundled paper machine, in one
//! command, without hardware.
//!
//! 1. **Signals**: the damped Feng & Hahn machine (`examples/feng-hahn-1997-damped.toml`,
//!    bundled; or `--machine FILE`) is run down at a constant rate and its
//!    sensors sampled as the box's ADC would ([`crate::sim::signals`]):
//!    proximity probes and pedestal accelerometers, 1 mV noise, 16-bit ADC,
//!    a keyphasor.
//! 2. **Box**: the signals are replayed, over the real wire protocol and the
//!    `plinth stream` session ([`crate::stream`]), to the field box: by
//!    default the firmware's pipeline compiled for the host and run in
//!    process ([`inprocess`]); with `--qemu` the real firmware image under
//!    QEMU on a pseudo-terminal ([`qemu`]). The box extracts 1X phasors,
//!    computes bearing forces from its table and fits each pedestal
//!    recursively (RLS).
//! 3. **Run directory**: every byte the box sent is kept (`raw.bin`), and the
//!    run directory (formats.md) is re-derived from it, with the simulation's
//!    `truth.json` added.
//! 4. **Batch fits**: [`crate::identify`] on the run directory, the paper's OLS
//!    and the maximum-likelihood fit (`plinth identify`'s default).
//! 5. **Table and figures**: box RLS vs host OLS vs host ML vs truth with their
//!    differences ([`table`]), and the amplitude, phase and phase-difference
//!    figures, box-extracted phasors over the simulated truth, PNG and SVG
//!    ([`figures`]).
//!
//! Files (under `--out`, default `plinth-demo/`): `box/stream.toml` and
//! `box/bearings.csv` (the box's configuration: `plinth stream --config
//! OUT/box/stream.toml --out OUT/run --offline` rebuilds the run directory
//! from `raw.bin`), `run/` (the run directory, `raw.bin`,
//! `stream-report.json`), `figures/`, `demo-report.json`, and with
//! `--keep-signals` the signal set `signals/`.
//!
//! The host-only default replays a realistic run-down, 200 → 5 Hz at
//! 10 Hz/s (19.5 s of signals, 2000 revolutions, 1 M sample vectors of 8
//! channels at the box's 51.2 kHz; a few seconds in release), with seismic
//! displacement sensors on the pedestals ([`DEFAULT_SEISMIC`] says why). Under QEMU the firmware runs about 100×
//! slower than real time, so `--qemu` replays a short run-down through the
//! pedestal resonances (62 → 48 Hz at 35 Hz/s, 0.4 s) with one revolution
//! per phasor.
//!
//! Files: this one (the command and the chain), `box_config` (the box's
//! configuration and bearing table), `report` (`demo-report.json` and the
//! end-of-demo text), [`table`], [`figures`], [`inprocess`], [`qemu`].

pub mod figures;
pub mod inprocess;
pub mod qemu;
pub mod table;

mod box_config;
mod report;

pub use box_config::*;
pub use report::*;

use crate::identify::{identify_run, Options};
use crate::paper::DAMPED_MACHINE;
use crate::rundir::{RunDir, TRUTH_FILE};
use crate::sim::signals::{
    default_seismic_sensitivity, synthesise, write_truth, RunDown, SensorKind, SignalOptions,
};
use crate::sim::{EffectSet, Machine};
use crate::stream::config::{BearingTables, StreamConfig};
use crate::stream::port::{Backoff, Connector, SerialConnector};
use crate::stream::progress::Progress;
use crate::stream::rawlog::RAW_LOG_FILE;
use crate::stream::replay::{SignalSetReplay, JOURNAL_FILE};
use crate::stream::session::SessionOptions;
use anyhow::{anyhow, bail, Context, Result};
use plinth_firmware::ad7606::Range;
use plinth_firmware::config::TABLE_ROWS;
use plinth_firmware::device::SAMPLE_RATE_HZ;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Run-down of the host-only demo: 200 → 5 Hz at 10 Hz/s (19.5 s, 2000
/// revolutions).
pub const DEFAULT_RUNDOWN: RunDown = RunDown {
    start_hz: 200.0,
    end_hz: 5.0,
    rate_hz_per_s: 10.0,
};

/// Run-down of the QEMU demo: 62 → 48 Hz at 35 Hz/s (0.4 s of signals, 22
/// revolutions, through the bundled machine's pedestal resonances at
/// 50-58 Hz), short because QEMU runs the firmware about 100× slower than
/// real time (about a minute).
pub const QEMU_RUNDOWN: RunDown = RunDown {
    start_hz: 62.0,
    end_hz: 48.0,
    rate_hz_per_s: 35.0,
};

/// Revolutions per phasor of the host-only demo.
pub const DEFAULT_AVERAGING: u32 = 4;

/// Revolutions per phasor under QEMU (the short run has few revolutions).
pub const QEMU_AVERAGING: u32 = 1;

/// Seismic transducers of the demo: seismic displacement sensors
/// (7.87 V/mm). The pedestals move by fractions of a micrometre at low
/// speed, where a velocity pick-up's signal falls as Ω and an
/// accelerometer's as Ω²: with those, 1 mV of noise puts noise into the
/// regressors of eq. 4 (errors in variables) and biases k low (measured on
/// this machine at seed 1: velocity pick-ups ≤ 0.7 %, accelerometers up to
/// 2 %, 2-3 σ; try `--seismic velocity` or `acceleration`).
pub const DEFAULT_SEISMIC: SensorKind = SensorKind::Displacement;

/// Name of the bundled machine in messages.
pub const BUNDLED_MACHINE_NAME: &str = "examples/feng-hahn-1997-damped.toml";

/// Command-line arguments of `plinth demo`.
#[derive(clap::Args, Debug)]
#[command(
    long_about = "The whole chain on the bundled paper machine (Feng & Hahn 1997, damped pedestals), \
without hardware: simulated run-down signals -> field box (the firmware pipeline compiled for \
the host, or with --qemu the real firmware image under QEMU) over the wire protocol -> run \
directory -> batch fit -> table (box RLS vs batch fit vs truth) and figures (PNG and SVG).\n\n\
Host-only default: 200 -> 5 Hz at 10 Hz/s, 51.2 kHz, 8 channels. With --qemu a short run-down \
(62 -> 48 Hz at 35 Hz/s) is replayed, as QEMU runs the firmware about 100x slower than real time."
)]
pub struct Args {
    /// Output directory (created): box configuration, run directory, figures, report.
    #[arg(long, default_value = "plinth-demo")]
    pub out: PathBuf,
    /// Write into an existing --plots/--out directory that already holds
    /// files (files Plinth did not write there are kept, never replaced).
    #[arg(long)]
    pub force: bool,
    /// Run the real firmware image under qemu-system-arm (netduinoplus2) instead
    /// of the pipeline compiled for the host.
    #[arg(long)]
    pub qemu: bool,
    /// Firmware image for --qemu (default: target/thumbv7em-none-eabihf/release/plinth-firmware;
    /// build it with `cargo build -p plinth-firmware --target thumbv7em-none-eabihf --release`).
    #[arg(long, requires = "qemu")]
    pub elf: Option<PathBuf>,
    /// Run-down START:END:RATE [Hz:Hz:Hz/s] (default 200:5:10; with --qemu 62:48:35).
    #[arg(long)]
    pub rundown: Option<String>,
    /// Keyphasor revolutions averaged into one phasor, 1 to 65535 (default 4;
    /// with --qemu 1).
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..=65535))]
    pub averaging: Option<u32>,
    /// Machine file (TOML) instead of the bundled damped paper machine.
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// Seed of the sensor noise.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1)]
    pub seed: u64,
    /// Seismic transducers on the pedestals: displacement, velocity or
    /// acceleration (typical field sensitivities:
    /// 20 mV/(mm/s) velocity pick-ups, 100 mV/g accelerometers, 7.87 V/mm).
    #[arg(long, value_parser = crate::sim::signals::parse_sensor_kind, default_value = "displacement")]
    pub seismic: SensorKind,
    /// Also write the simulated signals to OUT/signals (`plinth signals` format,
    /// about 0.8 MB per second of run-down).
    #[arg(long)]
    pub keep_signals: bool,
    /// No progress on stderr.
    #[arg(skip)]
    pub quiet: bool,
}

/// Which field box the signals are replayed to.
#[derive(Clone, Debug, PartialEq)]
pub enum BoxTarget {
    /// The firmware's device and pipeline compiled for the host, in process.
    InProcess,
    /// The firmware image at this path under QEMU (netduinoplus2).
    Qemu(PathBuf),
}

impl BoxTarget {
    /// Short description for messages and the report.
    pub fn describe(&self) -> String {
        match self {
            BoxTarget::InProcess => "firmware pipeline compiled for the host (in process)".into(),
            BoxTarget::Qemu(p) => {
                format!("firmware image {} under QEMU netduinoplus2", p.display())
            }
        }
    }
}

/// Everything a demo run needs.
#[derive(Clone, Debug)]
pub struct DemoOptions {
    /// The machine (the bundled damped paper machine by default).
    pub machine: Machine,
    /// The speed ramp.
    pub rundown: RunDown,
    /// Keyphasor revolutions per phasor.
    pub averaging: u32,
    /// Noise seed.
    pub seed: u64,
    /// Seismic transducers on the pedestals (at their typical sensitivity).
    pub seismic: SensorKind,
    /// Output directory.
    pub out: PathBuf,
    /// The box.
    pub target: BoxTarget,
    /// Write the signal set to `out/signals`.
    pub keep_signals: bool,
    /// Progress on stderr.
    pub progress: bool,
}

impl DemoOptions {
    /// The host-only demo of the bundled machine with the default run-down,
    /// writing into `out`.
    pub fn bundled(out: impl Into<PathBuf>) -> Result<Self> {
        Ok(Self {
            machine: bundled_machine()?,
            rundown: DEFAULT_RUNDOWN,
            averaging: DEFAULT_AVERAGING,
            seed: 1,
            seismic: DEFAULT_SEISMIC,
            out: out.into(),
            target: BoxTarget::InProcess,
            keep_signals: false,
            progress: false,
        })
    }
}

/// The bundled damped paper machine.
pub fn bundled_machine() -> Result<Machine> {
    Machine::from_toml_str(DAMPED_MACHINE, BUNDLED_MACHINE_NAME)
        .with_context(|| format!("the bundled machine {BUNDLED_MACHINE_NAME}"))
}

/// Runs `plinth demo`.
pub fn run(args: &Args) -> Result<()> {
    let started = Instant::now();
    let target = if args.qemu {
        BoxTarget::Qemu(qemu::find_image(args.elf.as_deref())?)
    } else {
        BoxTarget::InProcess
    };
    let rundown = match &args.rundown {
        Some(text) => RunDown::parse(text)?,
        None if args.qemu => QEMU_RUNDOWN,
        None => DEFAULT_RUNDOWN,
    };
    let averaging = args.averaging.unwrap_or(if args.qemu {
        QEMU_AVERAGING
    } else {
        DEFAULT_AVERAGING
    });
    let machine = match &args.machine {
        Some(p) => Machine::from_toml_path(p)?,
        None => bundled_machine()?,
    };
    let staged = crate::output::OutputDir::create(&args.out, args.force)?;
    let opts = DemoOptions {
        machine,
        rundown,
        averaging,
        seed: args.seed,
        seismic: args.seismic,
        out: staged.path().to_path_buf(),
        target,
        keep_signals: args.keep_signals,
        progress: !args.quiet,
    };
    let outcome = demo(&opts)?;
    staged.commit()?;
    print!(
        "{}",
        summary(&outcome).replace(
            &opts.out.display().to_string(),
            &args.out.display().to_string()
        )
    );
    println!(
        "elapsed {:.1} s (signals {:.1} s, box {:.1} s, fit {:.1} s, figures {:.1} s)",
        started.elapsed().as_secs_f64(),
        outcome.report.timings.signals_s,
        outcome.report.timings.stream_s,
        outcome.report.timings.fit_s,
        outcome.report.timings.figures_s
    );
    Ok(())
}

/// Writes a progress note on stderr when enabled.
fn note(on: bool, text: &str) {
    if on {
        eprintln!("{text}");
    }
}

/// Runs the whole chain (see the module documentation).
pub fn demo(opts: &DemoOptions) -> Result<DemoOutcome> {
    let started = Instant::now();
    let mut timings = Timings::default();
    let r = opts.rundown;
    r.validate().map_err(|m| anyhow!("run-down: {m}"))?;
    if opts.averaging == 0 {
        bail!("averaging must be at least 1 revolution per phasor");
    }
    let out = &opts.out;
    std::fs::create_dir_all(out)
        .with_context(|| format!("cannot create the output directory {}", out.display()))?;
    let box_dir = out.join("box");
    let run_dir = out.join("run");
    let figures_dir = out.join("figures");
    let signals_dir = out.join("signals");

    // 1. Signals.
    note(
        opts.progress,
        &format!(
            "[1/5] simulating {}: run-down {} → {} Hz at {} Hz/s ({:.2} s, {} revolutions), {} Hz sampling",
            opts.machine.name,
            r.start_hz,
            r.end_hz,
            r.rate_hz_per_s,
            r.duration_s(),
            r.revolutions(),
            SAMPLE_RATE_HZ
        ),
    );
    let t = Instant::now();
    let signal_opts = SignalOptions {
        rundown: r,
        sample_rate_hz: SAMPLE_RATE_HZ as f64,
        seed: opts.seed,
        seismic_kind: opts.seismic,
        seismic_sensitivity: default_seismic_sensitivity(opts.seismic),
        ..SignalOptions::default()
    };
    let (set, truth_run) = synthesise(&opts.machine, &EffectSet::none(), &signal_opts)
        .context("synthesising the run-down signals")?;
    let truth = truth_run
        .truth
        .clone()
        .ok_or_else(|| anyhow!("the simulation produced no truth"))?;
    if truth.pedestals.is_empty() {
        bail!(
            "machine {}: no bearing stands on a pedestal, so there is nothing to identify",
            opts.machine.name
        );
    }
    if opts.keep_signals {
        set.write(&signals_dir)
            .and_then(|()| write_truth(&signals_dir, &truth_run))
            .with_context(|| format!("writing the signals to {}", signals_dir.display()))?;
    }
    timings.signals_s = t.elapsed().as_secs_f64();
    note(
        opts.progress,
        &format!(
            "      {} sample vectors × {} channels in {:.1} s",
            set.len(),
            set.channels(),
            timings.signals_s
        ),
    );

    // 2. The box's configuration: channels as synthesised, and a bearing
    // table that fits the box.
    let (lo, hi) = (r.start_hz.min(r.end_hz), r.start_hz.max(r.end_hz));
    let (table_rows, table_error) = box_bearing_table(&truth_run.bearings, lo, hi, TABLE_ROWS)?;
    let per_bearing = table_rows.len() / truth.pedestals.len().max(1);
    let config = write_box_config(&box_dir, &set, &table_rows, opts.averaging)?;
    let tables = config.load_bearing_tables()?;

    // 3. Stream to the box.
    prepare_run_dir(&run_dir)?;
    let replay = SignalSetReplay::new(set, &config)?;
    let t = Instant::now();
    note(
        opts.progress,
        &format!("[2/5] streaming to the {}", opts.target.describe()),
    );
    let progress = if opts.progress {
        Progress::stderr()
    } else {
        Progress::hidden()
    };
    let signals_path = if opts.keep_signals {
        signals_dir.clone()
    } else {
        PathBuf::from(format!("(in memory: {})", opts.machine.name))
    };
    let outcome = match &opts.target {
        BoxTarget::InProcess => {
            let mut connector =
                inprocess::InProcessConnector::new(Range::PlusMinus10V.volts_per_code());
            stream_to(
                &mut connector,
                &run_dir,
                &config,
                &tables,
                &signals_path,
                &replay,
                SessionOptions::default(),
                progress,
            )?
        }
        BoxTarget::Qemu(image) => {
            let guard = qemu::Qemu::start(image)?;
            note(
                opts.progress,
                &format!(
                    "      QEMU started; the box's USART is on {} (QEMU runs the firmware ~100× slower than real time)",
                    guard.pty
                ),
            );
            let mut connector = SerialConnector::new(&guard.pty, 115_200);
            let options = SessionOptions {
                backoff: Backoff {
                    give_up: Duration::from_secs(10),
                    ..Backoff::default()
                },
                ..SessionOptions::default()
            };
            let o = stream_to(
                &mut connector,
                &run_dir,
                &config,
                &tables,
                &signals_path,
                &replay,
                options,
                progress,
            );
            drop(guard);
            o?
        }
    };
    let stream_report = crate::stream::finish(&run_dir, &config, &tables, Some(&outcome))?;
    if !outcome.completed {
        bail!(
            "the stream to the box did not complete: {}",
            outcome.error.as_deref().unwrap_or("no reason given")
        );
    }
    timings.stream_s = t.elapsed().as_secs_f64();
    note(
        opts.progress,
        &format!(
            "      {} phasor frames → {} measurement rows in {:.1} s",
            stream_report.phasor_frames, stream_report.measurement_rows, timings.stream_s
        ),
    );

    // 4. The run directory with its truth, read back as `plinth identify`
    // would, and the batch fit.
    note(
        opts.progress,
        "[3/5] batch fits (OLS and maximum likelihood) of the run directory",
    );
    let t = Instant::now();
    let truth_path = run_dir.join(TRUTH_FILE);
    let text = serde_json::to_string_pretty(&truth).context("encoding truth.json")?;
    std::fs::write(&truth_path, text + "\n")
        .with_context(|| format!("cannot write {}", truth_path.display()))?;
    let measured = RunDir::read(&run_dir)?;
    // The paper's OLS: the same least-squares problem the box's RLS solves;
    // and the maximum-likelihood fit `plinth identify` makes by default.
    let identification = identify_run(&measured, &Options::default().ols())
        .with_context(|| format!("identifying {} (OLS)", run_dir.display()))?;
    let ml = identify_run(&measured, &Options::default())
        .with_context(|| format!("identifying {} (ML)", run_dir.display()))?;
    let mut warnings = Vec::new();
    for (name, id) in [("host OLS", &identification), ("host ML", &ml)] {
        for p in &id.pedestals {
            for w in &p.warnings {
                warnings.push(format!("{name}, pedestal `{}`: {}", p.bearing, w.message));
            }
        }
    }
    let rows = table::rows(&stream_report.pedestals, &truth);
    timings.fit_s = t.elapsed().as_secs_f64();

    // 5. Figures.
    note(
        opts.progress,
        // `out` is the hidden staging directory until the end: name the
        // place the figures will be, not where they are being drawn.
        "[4/5] figures (figures/ of the output directory)",
    );
    let t = Instant::now();
    let truth_in_range = RunDir {
        measurements: truth_run
            .measurements
            .iter()
            .filter(|m| m.speed_hz >= lo && m.speed_hz <= hi)
            .cloned()
            .collect(),
        bearings: truth_run.bearings.clone(),
        truth: None,
    };
    let mut files = figures::write_figures(&measured, &truth_in_range, &figures_dir)?;
    timings.figures_s = t.elapsed().as_secs_f64();

    files.push(box_dir.join("stream.toml"));
    files.push(box_dir.join("bearings.csv"));
    if opts.keep_signals {
        files.push(signals_dir.clone());
    }
    let report_path = out.join(REPORT_FILE);
    files.push(report_path.clone());
    timings.total_s = started.elapsed().as_secs_f64();
    let report = DemoReport {
        machine: opts.machine.name.clone(),
        target: opts.target.describe(),
        rundown: r,
        duration_s: r.duration_s(),
        revolutions: r.revolutions(),
        sample_rate_hz: SAMPLE_RATE_HZ as f64,
        sample_vectors: replay.set().len(),
        channels: replay.set().channels(),
        averaging: opts.averaging,
        seed: opts.seed,
        bearing_table_rows: per_bearing,
        bearing_table_max_rel_error: table_error,
        phasor_frames: stream_report.phasor_frames,
        measurement_rows: stream_report.measurement_rows,
        table: rows,
        warnings,
        timings,
        files,
    };
    note(
        opts.progress,
        &format!(
            "[5/5] report ({} of the output directory)",
            report_path
                .strip_prefix(out)
                .unwrap_or(&report_path)
                .display()
        ),
    );
    let text = serde_json::to_string_pretty(&report).context("encoding the demo report")?;
    std::fs::write(&report_path, text + "\n")
        .with_context(|| format!("cannot write {}", report_path.display()))?;
    Ok(DemoOutcome {
        run_dir,
        figures_dir,
        report,
        stream: stream_report,
        identification,
        ml,
        truth,
    })
}

/// Streams the replay to the box behind `connector` into `run_dir`.
#[allow(clippy::too_many_arguments)]
fn stream_to(
    connector: &mut dyn Connector,
    run_dir: &Path,
    config: &StreamConfig,
    tables: &BearingTables,
    signals_path: &Path,
    replay: &SignalSetReplay,
    options: SessionOptions,
    progress: Progress,
) -> Result<crate::stream::session::SessionOutcome> {
    crate::stream::stream(
        connector,
        run_dir,
        config,
        tables,
        Some((signals_path, replay)),
        options,
        progress,
    )
    .with_context(|| format!("streaming to the {}", connector.describe()))
}

/// Makes `dir` ready for a fresh stream: the raw log is append-only and the
/// replay journal resumes an earlier replay, so both are removed (a demo
/// always starts over); everything else is rewritten.
fn prepare_run_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create the run directory {}", dir.display()))?;
    for name in [
        RAW_LOG_FILE.to_string(),
        JOURNAL_FILE.to_string(),
        format!("{JOURNAL_FILE}.tmp"),
        TRUTH_FILE.to_string(),
    ] {
        let p = dir.join(name);
        match std::fs::remove_file(&p) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(e).with_context(|| format!("cannot remove {}", p.display())),
        }
    }
    Ok(())
}
