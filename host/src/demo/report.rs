//! What a demo produced: `demo-report.json` (timings, the comparison table,
//! warnings, files) and the end-of-demo text.

use super::*;
use crate::identify::Identification;
use crate::rundir::Truth;
use crate::sim::signals::RunDown;
use crate::stream::report::StreamReport;
use serde::Serialize;
use std::path::{Path, PathBuf};
use table::ComparisonRow;

/// Wall-clock time of each stage [s].
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Timings {
    /// Response and time-signal synthesis.
    pub signals_s: f64,
    /// Streaming to the box (replay, phasors, RLS) and re-deriving the run directory.
    pub stream_s: f64,
    /// Batch fit and table.
    pub fit_s: f64,
    /// Figures.
    pub figures_s: f64,
    /// Everything.
    pub total_s: f64,
}

/// `demo-report.json`: what was run, what came out, where it was written.
#[derive(Clone, Debug, Serialize)]
pub struct DemoReport {
    /// Machine name.
    pub machine: String,
    /// The box the signals went to.
    pub target: String,
    /// The speed ramp.
    pub rundown: RunDown,
    /// Duration of the run-down [s].
    pub duration_s: f64,
    /// Keyphasor revolutions in the run-down.
    pub revolutions: u64,
    /// Sample rate per channel [Hz].
    pub sample_rate_hz: f64,
    /// Sample vectors replayed.
    pub sample_vectors: usize,
    /// Channels per sample vector.
    pub channels: usize,
    /// Revolutions per phasor.
    pub averaging: u32,
    /// Noise seed.
    pub seed: u64,
    /// Rows of the box's bearing table per bearing.
    pub bearing_table_rows: usize,
    /// Largest relative error of the box's (linearly interpolated) bearing
    /// table against the exact coefficients over the run.
    pub bearing_table_max_rel_error: f64,
    /// Phasor frames the box sent.
    pub phasor_frames: usize,
    /// Rows of measurements.csv.
    pub measurement_rows: usize,
    /// Box RLS vs host OLS vs host ML vs truth, per pedestal and parameter.
    pub table: Vec<ComparisonRow>,
    /// Warnings of the host fits, per estimator and pedestal.
    pub warnings: Vec<String>,
    /// Wall-clock times.
    pub timings: Timings,
    /// Every file written (besides the run directory's own).
    pub files: Vec<PathBuf>,
}

/// What a demo run produced.
#[derive(Clone, Debug)]
pub struct DemoOutcome {
    /// The run directory (`out/run`).
    pub run_dir: PathBuf,
    /// The figures directory (`out/figures`).
    pub figures_dir: PathBuf,
    /// The report (also in `out/demo-report.json`).
    pub report: DemoReport,
    /// The stream's own report (also in `out/run/stream-report.json`).
    pub stream: StreamReport,
    /// The batch fit of the run directory (the paper's OLS).
    pub identification: Identification,
    /// The maximum-likelihood fit of the run directory (`plinth identify`'s
    /// default).
    pub ml: Identification,
    /// The machine's pedestals.
    pub truth: Truth,
}

/// File name of the demo report inside the output directory.
pub const REPORT_FILE: &str = "demo-report.json";

/// The end-of-demo text: what ran, the table, the warnings, the files.
pub fn summary(o: &DemoOutcome) -> String {
    let r = &o.report;
    let mut s = String::new();
    s.push_str(&format!(
        "\nplinth demo: {} run down {} → {} Hz at {} Hz/s ({:.2} s, {} revolutions), {} sample vectors × {} channels at {} Hz\n",
        r.machine,
        r.rundown.start_hz,
        r.rundown.end_hz,
        r.rundown.rate_hz_per_s,
        r.duration_s,
        r.revolutions,
        r.sample_vectors,
        r.channels,
        r.sample_rate_hz
    ));
    s.push_str(&format!("box: {}\n", r.target));
    s.push_str(&format!(
        "     bearing table {} rows per bearing (linear interpolation within {:.2e} of the exact coefficients), {} revolution(s) per phasor\n",
        r.bearing_table_rows, r.bearing_table_max_rel_error, r.averaging
    ));
    s.push_str(&crate::stream::report::render_link(
        "link",
        &o.stream.link_raw_log,
    ));
    s.push('\n');
    s.push_str(&format!(
        "{} phasor frames -> {} measurement rows ({} dropped)\n\n",
        r.phasor_frames,
        r.measurement_rows,
        o.stream.dropped_rows.len()
    ));
    s.push_str(&table::render(&r.table, &o.identification, &o.ml));
    for w in &r.warnings {
        s.push_str(&format!("warning: {w}\n"));
    }
    s.push_str(&format!(
        "\nwritten to {}:\n",
        o.run_dir
            .parent()
            .map_or(o.run_dir.clone(), Path::to_path_buf)
            .display()
    ));
    s.push_str(&format!(
        "  {}  run directory (measurements.csv, bearings.csv, truth.json, raw.bin, stream-report.json): try `plinth identify {}`\n",
        o.run_dir.display(),
        o.run_dir.display()
    ));
    s.push_str(&format!(
        "  {}  amplitudes, phases, phase_difference (.png and .svg)\n",
        o.figures_dir.display()
    ));
    for f in &r.files {
        if !f.starts_with(&o.figures_dir) {
            s.push_str(&format!("  {}\n", f.display()));
        }
    }
    s
}
