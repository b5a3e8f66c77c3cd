//! The end of a stream: the box's final recursive estimates beside the host's
//! batch fits of the whole run directory (the paper's OLS, the same
//! least-squares problem the box solves, and the maximum-likelihood fit
//! `plinth identify` makes by default), with their differences, and a JSON
//! record of the session (`stream-report.json`) for scripts and tests.

use crate::identify::{Identification, WarningKind};
use crate::present::{modal::PedestalModal, table};
use plinth_shared::protocol::{BoxHealth, EstimateFrame, LinkStats, PreviousReset, SampleClock};
use plinth_shared::regression::Parameter;
use serde::Serialize;

/// File name of the JSON session report inside the run directory.
pub const REPORT_FILE: &str = "stream-report.json";

/// The unit of a parameter's value.
pub fn unit(p: Parameter) -> &'static str {
    match p {
        Parameter::Ky | Parameter::Kz => "N/m",
        Parameter::M => "kg",
        Parameter::Cy | Parameter::Cz => "N·s/m",
    }
}

/// One parameter of one pedestal: the box's value, the host's OLS and ML
/// values, and the box's difference from OLS.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParameterComparison {
    /// Parameter name (formats.md).
    pub parameter: &'static str,
    /// Its unit.
    pub unit: &'static str,
    /// The box's final recursive estimate (`null` if it sent none).
    pub box_value: Option<f64>,
    /// Its standard error.
    pub box_std_err: Option<f64>,
    /// The batch least-squares value (the paper's OLS; `null` if the fit
    /// failed).
    pub batch_value: Option<f64>,
    /// Its standard error (OLS's own: equal, independent equation errors).
    pub batch_std_err: Option<f64>,
    /// The host's maximum-likelihood value (errors in variables, the noise
    /// model of the run directory: `plinth identify`'s default; `null` if
    /// the fit failed).
    pub ml_value: Option<f64>,
    /// Its standard error from the Fisher information (the Cramér–Rao bound
    /// at the estimate, scaled up by χ²/dof when the data scatter more than
    /// their noise says).
    pub ml_std_err: Option<f64>,
    /// box − batch, in the parameter's unit.
    pub difference: Option<f64>,
    /// (box − batch) / |batch| · 100 [%]; `null` where batch is 0.
    pub difference_percent: Option<f64>,
}

/// The comparison for one pedestal.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PedestalComparison {
    /// Bearing name.
    pub bearing: String,
    /// Per parameter, in θ order.
    pub parameters: Vec<ParameterComparison>,
    /// Equations the box folded in (effective, with forgetting).
    pub box_equations: Option<f64>,
    /// The box's reduced χ² (whitened residuals: 1 when they are as large as
    /// the phasors' noise says).
    pub box_reduced_chi_square: Option<f64>,
    /// Equations the box scaled down (squares beyond f32) and rejected (not
    /// finite).
    pub box_guarded: Option<(u32, u32)>,
    /// The batch (OLS) fit is trusted (no warning says otherwise).
    pub batch_trusted: Option<bool>,
    /// The ML fit is trusted.
    pub ml_trusted: Option<bool>,
    /// The ML iteration failed (the values are then OLS's, as `plinth
    /// identify` reports them) or stopped before converging.
    pub ml_failed: Option<bool>,
    /// The ML fit's natural frequencies and damping ratios (formats.md `modal`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modal: Option<PedestalModal>,
}

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// Compares the box's last estimates with the host's batch fits (`batch`:
/// the paper's OLS; `ml`: the maximum-likelihood identification), per
/// configured bearing.
pub fn compare(
    bearings: &[String],
    estimates: Option<&EstimateFrame>,
    batch: Option<&Identification>,
    ml: Option<&Identification>,
) -> Vec<PedestalComparison> {
    bearings
        .iter()
        .enumerate()
        .map(|(index, name)| {
            let entry =
                estimates.and_then(|e| e.pedestals.iter().find(|p| p.bearing as usize == index));
            let fit = batch.and_then(|b| b.pedestal(name));
            let ml_fit = ml.and_then(|b| b.pedestal(name));
            let parameters = Parameter::ALL
                .iter()
                .map(|&p| {
                    let i = p as usize;
                    let box_value = entry.and_then(|e| finite(e.theta[i] as f64));
                    let batch_value = fit.and_then(|f| finite(f.pedestal.theta()[i]));
                    let difference = match (box_value, batch_value) {
                        (Some(a), Some(b)) => Some(a - b),
                        _ => None,
                    };
                    let difference_percent = match (difference, batch_value) {
                        (Some(d), Some(b)) if b != 0.0 => Some(100.0 * d / b.abs()),
                        _ => None,
                    };
                    ParameterComparison {
                        parameter: p.name(),
                        unit: unit(p),
                        box_value,
                        box_std_err: entry.and_then(|e| finite(e.std_err[i] as f64)),
                        batch_value,
                        batch_std_err: fit.and_then(|f| finite(f.std_err.theta()[i])),
                        ml_value: ml_fit.and_then(|f| finite(f.pedestal.theta()[i])),
                        ml_std_err: ml_fit.and_then(|f| finite(f.std_err.theta()[i])),
                        difference,
                        difference_percent,
                    }
                })
                .collect();
            PedestalComparison {
                bearing: name.clone(),
                parameters,
                box_equations: entry.map(|e| e.equations as f64),
                box_reduced_chi_square: entry.and_then(|e| finite(e.reduced_chi_square as f64)),
                box_guarded: entry.map(|e| (e.rescaled, e.rejected)),
                batch_trusted: fit.map(|f| f.trusted),
                ml_trusted: ml_fit.map(|f| f.trusted),
                ml_failed: ml_fit.map(|f| f.has_warning(WarningKind::MlFailed)),
                modal: ml_fit.and_then(|f| f.modal),
            }
        })
        .collect()
}

/// The estimators shown side by side for one parameter, in column order:
/// (name, value, standard error). The one place where a column is added.
pub fn estimators(p: &ParameterComparison) -> Vec<(&'static str, Option<f64>, Option<f64>)> {
    vec![
        ("box RLS", p.box_value, p.box_std_err),
        ("host OLS", p.batch_value, p.batch_std_err),
        ("host ML", p.ml_value, p.ml_std_err),
    ]
}

/// The comparison as a text table for the terminal: every estimator's
/// value ± standard error, then box − host OLS.
pub fn render(comparisons: &[PedestalComparison]) -> String {
    let mut s = String::new();
    for c in comparisons {
        s.push_str(&format!(
            "pedestal {}: box RLS ({} equations{}{}) vs host fits{}\n",
            c.bearing,
            c.box_equations
                .map_or("no".to_string(), |n| format!("{n:.0}")),
            c.box_reduced_chi_square
                .map_or(String::new(), |x| format!(", reduced χ² {x:.2}")),
            match c.box_guarded {
                Some((r, j)) if r + j > 0 => {
                    format!(", {r} equations rescaled and {j} rejected by the overflow guard")
                }
                _ => String::new(),
            },
            [
                (c.batch_trusted == Some(false))
                    .then_some(" (host OLS NOT trusted: see `plinth identify --estimator ols`)"),
                (c.ml_trusted == Some(false))
                    .then_some(" (host ML NOT trusted: see `plinth identify`)"),
                (c.ml_failed == Some(true))
                    .then_some(" (host ML did not converge: see `plinth identify`)"),
            ]
            .into_iter()
            .flatten()
            .collect::<String>()
        ));
        let names: Vec<&str> = c
            .parameters
            .first()
            .map(|p| estimators(p).iter().map(|e| e.0).collect())
            .unwrap_or_default();
        // Units, order and notation of the shared printer (present::table).
        let mut rows: Vec<Vec<String>> = Vec::new();
        let mut header = vec![String::new(), "unit".to_string()];
        header.extend(names.iter().map(|n| format!("{n} ± σ")));
        header.extend(["box − OLS".to_string(), "%".to_string()]);
        rows.push(header);
        for p in &c.parameters {
            let (unit, k) = table::unit(p.parameter);
            let mut row = vec![p.parameter.to_string(), unit.to_string()];
            for (_, v, e) in estimators(p) {
                row.push(match (v, e) {
                    (Some(v), Some(e)) => table::value_pm(v * k, e * k),
                    (Some(v), None) => table::sig(v * k, 6),
                    _ => "—".into(),
                });
            }
            row.push(p.difference.map_or("—".into(), |d| table::sig(d * k, 3)));
            row.push(
                p.difference_percent
                    .map_or("—".to_string(), |v| format!("{v:+.3}")),
            );
            rows.push(row);
        }
        let widths: Vec<usize> = (0..rows[0].len())
            .map(|i| rows.iter().map(|r| r[i].chars().count()).max().unwrap_or(0))
            .collect();
        for r in &rows {
            let mut line = String::from("  ");
            for (i, cell) in r.iter().enumerate() {
                let pad = " ".repeat(widths[i] - cell.chars().count());
                if i < 2 {
                    line.push_str(&format!("{cell}{pad}  "));
                } else {
                    line.push_str(&format!("{pad}{cell}  "));
                }
            }
            s.push_str(line.trim_end());
            s.push('\n');
        }
        if let Some(m) = c.modal {
            let row = table::PedestalRow {
                bearing: c.bearing.clone(),
                modal: Some(m),
                ..table::PedestalRow::default()
            };
            s.push_str("  host ML, ");
            s.push_str(&table::render_modal(&[row]));
        }
    }
    s
}

/// Link health as reported at the end.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LinkSummary {
    /// Frames accepted.
    pub frames_ok: u32,
    /// Frames missing by sequence number.
    pub sequence_gaps: u32,
    /// CRC failures (line corruption).
    pub crc_failures: u32,
    /// Invalid COBS.
    pub cobs_failures: u32,
    /// Good CRC but undecodable (protocol mismatch).
    pub decode_failures: u32,
    /// Longer than any frame.
    pub oversize: u32,
    /// Times frame sync was regained after failures.
    pub resyncs: u32,
    /// Repeated frames dropped.
    pub duplicates: u32,
    /// Sequence restarts (new box sessions).
    pub restarts: u32,
}

impl From<LinkStats> for LinkSummary {
    fn from(s: LinkStats) -> Self {
        Self {
            frames_ok: s.frames_ok,
            sequence_gaps: s.sequence_gaps,
            crc_failures: s.crc_failures,
            cobs_failures: s.cobs_failures,
            decode_failures: s.decode_failures,
            oversize: s.oversize,
            resyncs: s.resyncs,
            duplicates: s.duplicates,
            restarts: s.restarts,
        }
    }
}

/// One line of link counters for the terminal.
pub fn render_link(label: &str, s: &LinkSummary) -> String {
    format!(
        "{label}: {} frames, {} lost (sequence gaps), {} CRC failures, {} COBS failures, {} undecodable, {} oversize, {} resyncs, {} duplicates, {} restarts",
        s.frames_ok,
        s.sequence_gaps,
        s.crc_failures,
        s.cobs_failures,
        s.decode_failures,
        s.oversize,
        s.resyncs,
        s.duplicates,
        s.restarts
    )
}

/// `stream-report.json`: everything a script needs to judge a stream.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StreamReport {
    /// The session ran to its end.
    pub completed: bool,
    /// Why not.
    pub error: Option<String>,
    /// Counters of this host process's receive link.
    pub link_this_process: Option<LinkSummary>,
    /// Counters from decoding the whole raw log (every host process).
    pub link_raw_log: LinkSummary,
    /// The box's own receive counters (frames from the host), last reported.
    pub link_box: Option<LinkSummary>,
    /// Bytes in the raw log.
    pub raw_log_bytes: u64,
    /// Times this process reopened the link.
    pub reconnects: u64,
    /// Phasor frames in the raw log.
    pub phasor_frames: usize,
    /// Rows of measurements.csv.
    pub measurement_rows: usize,
    /// Rows merged (same bearing and speed).
    pub merged_rows: usize,
    /// Rows dropped, and why.
    pub dropped_rows: Vec<String>,
    /// Replay blocks acknowledged and in total.
    pub replay_blocks: Option<(usize, usize)>,
    /// Replay blocks sent again after a loss.
    pub resent_blocks: u64,
    /// Box sessions in the raw log (each `Hello` restarts the box's
    /// estimator, so its final estimates cover only the last session's data
    /// while the batch fit covers all of them).
    pub box_sessions: u32,
    /// Box vs host OLS vs host ML per pedestal.
    pub pedestals: Vec<PedestalComparison>,
    /// Why the batch (OLS) fit could not run, if it could not.
    pub batch_error: Option<String>,
    /// Why the host ML fit could not run, if it could not.
    pub ml_error: Option<String>,
    /// The box's health as last reported (sample clock, previous reset,
    /// acquisition faults).
    pub box_health: Option<BoxHealth>,
}

/// One line of the box's health: sample clock, previous reset, and every
/// acquisition fault counter.
pub fn render_health(h: &BoxHealth) -> String {
    let clock = match h.sample_clock {
        SampleClock::Crystal => "crystal",
        SampleClock::RcOscillator => "RC oscillator (crystal failed; rate ±1 %)",
        SampleClock::RcOscillatorNoPll => "RC oscillator without PLL (cannot sample)",
        SampleClock::Emulated => "emulated",
    };
    let reset = match h.previous_reset {
        PreviousReset::Normal => "normal",
        PreviousReset::Panic => "PANIC",
        PreviousReset::HardFault => "HARD FAULT",
        PreviousReset::Watchdog => "WATCHDOG",
    };
    format!(
        "box health: sample clock {clock}; previous reset {reset}{}; restarts {}, slips {}, late reads {}, stalls {}, SPI errors {}, DMA errors {}, lost keyphasor captures {}",
        if h.sampling_refused { "; SAMPLING REFUSED" } else { "" },
        h.restarts,
        h.slips,
        h.late_reads,
        h.stalls,
        h.spi_errors,
        h.dma_errors,
        h.lost_captures
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use plinth_shared::protocol::PedestalEstimateEntry;

    #[test]
    fn differences_are_box_minus_batch_in_units_and_percent() {
        let mut e = EstimateFrame {
            revolution: 10,
            pedestals: Default::default(),
        };
        e.pedestals
            .push(PedestalEstimateEntry {
                bearing: 0,
                theta: [1.01e7, 2.0e7, 100.0, 50.0, 0.0],
                std_err: [1e4, 1e4, 0.1, f32::NAN, 1.0],
                equations: 40.0,
                reduced_chi_square: 1.1,
                rescaled: 0,
                rejected: 2,
            })
            .unwrap();
        let c = compare(
            &["left".to_string(), "right".to_string()],
            Some(&e),
            None,
            None,
        );
        assert_eq!(c.len(), 2);
        assert_eq!(c[0].parameters[0].box_value, Some(1.01e7));
        assert_eq!(c[0].parameters[3].box_std_err, None);
        assert_eq!(c[0].parameters[0].difference, None);
        assert!(c[1].parameters.iter().all(|p| p.box_value.is_none()));
        let text = render(&c);
        assert!(text.contains("pedestal left") && text.contains("k_y") && text.contains("N·s/m"));
        assert!(text.contains("box RLS") && text.contains("host OLS") && text.contains("host ML"));
        assert!(c[0].parameters[0].ml_value.is_none());
        assert!(text.contains("reduced χ² 1.10") && text.contains("2 rejected"));
    }
}
