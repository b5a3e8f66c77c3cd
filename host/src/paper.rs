//! `plinth paper`: reproduces the numerical experiment of Feng & Hahn (1997)
//! on Plinth's reconstruction of their machine (`examples/feng-hahn-1997.toml`
//! and its damped twin, bundled into the binary; see their comments for what
//! is the paper's and what is ours).
//!
//! - **Table 1** (no pedestal damping): the unbalance response at the speeds
//!   (default 5-200 Hz every 1 Hz) is *truncated* to 12, 3 and 2 significant
//!   digits, as the paper did, and k_y, k_z, m of both pedestals are
//!   identified with all four equations of eq. 4 (R&I) and the undamped model
//!   (c fixed at 0, as in the paper's Table 1).
//! - **Table 2** (damped pedestals, 2 digits): the four ways of using eq. 4 —
//!   R&I (all equations, the full model k_y, k_z, m, c_y, c_z), R+I, R and I
//!   (the undamped model, as the paper's Table 2 lists only k and m for them).
//! - **Figures** (with `--plots DIR`, PNG and SVG): response amplitudes and
//!   phase lags at the measurement points (Figs. 3-4 undamped, 7-8 damped:
//!   rotor relative to pedestal and absolute pedestal, Ly/Lz/Ry/Rz), the phase
//!   lag of each pedestal's response behind the force transmitted to it
//!   (Figs. 5, 9), and the 2-digit measured rotor response against the one
//!   re-predicted with the 2-digit identified pedestals (Fig. 6).
//!
//! Errors are 100·(identified − truth)/truth [%]. The bearing coefficients are
//! known exactly (they are the paper's "assumed known" bearing properties);
//! only the measured phasors are truncated.

use crate::identify::{identify_run, mode_label, EquationMode, Model, Options, PedestalFit};
use crate::plots::{
    phase_lag_deg, Mark, PhaseStyle, PhasorFigure, PhasorPanel, PhasorSeries, PhasorView, Quantity,
    Rows, ScalarFigure, ScalarSeries,
};
use crate::rundir::{significant_digits, DigitsMode, Measurement, RunDir};
use crate::sim::cli::parse_speeds;
use crate::sim::predict::{compare, predict_run, Comparison, IdentifiedPedestal};
use crate::sim::{unbalance_response, EffectSet, Machine};
use anyhow::{anyhow, Context, Result};
use num_complex::Complex;
use plinth_shared::phasor::omega_from_hz;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The undamped paper machine (Table 1), bundled.
pub const UNDAMPED_MACHINE: &str = include_str!("../../examples/feng-hahn-1997.toml");
/// The damped paper machine (Table 2), bundled.
pub const DAMPED_MACHINE: &str = include_str!("../../examples/feng-hahn-1997-damped.toml");

/// Command-line arguments of `plinth paper`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Print the tables as JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Write the figures (PNG and SVG) into this directory.
    #[arg(long)]
    pub plots: Option<PathBuf>,
    /// Measurement speeds [Hz]: START:STOP:STEP (inclusive) or a list.
    #[arg(long, default_value = "5:200:1")]
    pub speeds: String,
    /// Undamped machine file instead of the bundled examples/feng-hahn-1997.toml.
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// Damped machine file instead of the bundled examples/feng-hahn-1997-damped.toml.
    #[arg(long)]
    pub damped_machine: Option<PathBuf>,
    /// Round to the digits instead of truncating (the paper truncated).
    #[arg(long)]
    pub round: bool,
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
    /// Truncate (the paper) or round.
    pub digits_mode: DigitsMode,
}

impl Default for PaperOptions {
    fn default() -> Self {
        Self {
            speeds_hz: (5..=200).map(f64::from).collect(),
            table1_digits: vec![12, 3, 2],
            table2_digits: 2,
            digits_mode: DigitsMode::Truncate,
        }
    }
}

/// One row of Table 1.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table1Row {
    /// Significant digits of the measured phasors.
    pub digits: u32,
    /// Bearing (pedestal) name.
    pub bearing: String,
    /// `k_y` [N/m], `k_z` [N/m] or `m` [kg].
    pub param: String,
    /// The machine's value.
    pub truth: f64,
    /// The identified value.
    pub identified: f64,
    /// 100·(identified − truth)/truth [%].
    pub error_pct: f64,
}

/// One row of Table 2.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table2Row {
    /// `R&I`, `R+I`, `R` or `I`.
    pub mode: String,
    /// Bearing (pedestal) name.
    pub bearing: String,
    /// `k_y`, `k_z` [N/m], `m` [kg], and for R&I `c_y`, `c_z` [N·s/m].
    pub param: String,
    /// The machine's value.
    pub truth: f64,
    /// The identified value.
    pub identified: f64,
    /// 100·(identified − truth)/truth [%].
    pub error_pct: f64,
}

/// Both tables.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Tables {
    /// Table 1 rows: digits × bearing × (k_y, k_z, m).
    pub table1: Vec<Table1Row>,
    /// Table 2 rows: mode × bearing × parameters.
    pub table2: Vec<Table2Row>,
}

/// Everything the reproduction computed.
#[derive(Clone, Debug)]
pub struct Paper {
    /// The tables.
    pub tables: Tables,
    /// Undamped run, full precision.
    pub undamped: RunDir,
    /// Damped run, full precision.
    pub damped: RunDir,
    /// Undamped run at the smallest Table 1 digit count (Fig. 6 "measured").
    pub undamped_truncated: RunDir,
    /// Rows re-predicted with the pedestals identified from it (Fig. 6).
    pub repredicted: Vec<Measurement>,
    /// How far the re-prediction is from the truncated "measurement".
    pub reprediction: Comparison,
    /// Smallest Table 1 digit count (the Fig. 6 case).
    pub fig6_digits: u32,
}

/// Reads a machine from a file, or the bundled text.
fn load_machine(path: Option<&Path>, bundled: &str, name: &str) -> Result<Machine> {
    Ok(match path {
        Some(p) => Machine::from_toml_path(p)?,
        None => Machine::from_toml_str(bundled, name)?,
    })
}

/// The measured phasors of `run` reduced to `digits` significant digits.
pub fn reduce_digits(run: &RunDir, digits: u32, mode: DigitsMode) -> RunDir {
    let r = |c: Complex<f64>| {
        Complex::new(
            significant_digits(c.re, digits, mode),
            significant_digits(c.im, digits, mode),
        )
    };
    let mut out = run.clone();
    for m in &mut out.measurements {
        m.rel = [r(m.rel[0]), r(m.rel[1])];
        m.ped = [r(m.ped[0]), r(m.ped[1])];
    }
    out
}

fn simulate(machine: &Machine, speeds: &[f64]) -> Result<RunDir> {
    let response = unbalance_response(machine, speeds, &EffectSet::none())
        .with_context(|| format!("simulating {}", machine.name))?;
    Ok(response.to_run_dir(None)?)
}

fn truth_of(run: &RunDir, bearing: &str) -> Result<crate::rundir::PedestalTruth> {
    run.truth
        .as_ref()
        .and_then(|t| t.pedestals.iter().find(|p| p.bearing == bearing))
        .cloned()
        .ok_or_else(|| anyhow!("the simulation has no pedestal truth for {bearing:?}"))
}

fn param_value(p: &crate::rundir::PedestalTruth, name: &str) -> f64 {
    match name {
        "k_y" => p.k_y,
        "k_z" => p.k_z,
        "m" => p.m,
        "c_y" => p.c_y,
        _ => p.c_z,
    }
}

fn fit_value(f: &PedestalFit, name: &str) -> f64 {
    match name {
        "k_y" => f.k_y,
        "k_z" => f.k_z,
        "m" => f.m,
        "c_y" => f.c_y,
        _ => f.c_z,
    }
}

fn error_pct(identified: f64, truth: f64) -> f64 {
    100.0 * (identified - truth) / truth
}

/// Runs the whole reproduction on two machines.
pub fn reproduce_with(
    undamped_machine: &Machine,
    damped_machine: &Machine,
    opts: &PaperOptions,
) -> Result<Paper> {
    if opts.table1_digits.is_empty() {
        return Err(anyhow!("Table 1 needs at least one digit count"));
    }
    let undamped = simulate(undamped_machine, &opts.speeds_hz)?;
    let damped = simulate(damped_machine, &opts.speeds_hz)?;
    let bearings: Vec<String> = undamped
        .measured_bearings()
        .iter()
        .map(|s| s.to_string())
        .collect();

    let mut table1 = Vec::new();
    let fig6_digits = *opts.table1_digits.iter().min().unwrap_or(&2);
    let mut fig6 = None;
    for &digits in &opts.table1_digits {
        let run = reduce_digits(&undamped, digits, opts.digits_mode);
        let options = Options {
            model: Some(Model::UNDAMPED),
            ..Options::with_mode(EquationMode::RealAndImag)
        };
        let id = identify_run(&run, &options)
            .with_context(|| format!("identifying the {digits}-digit undamped run"))?;
        for b in &bearings {
            let fit = id
                .pedestal(b)
                .ok_or_else(|| anyhow!("no fit for pedestal {b:?}"))?;
            let truth = truth_of(&undamped, b)?;
            for param in ["k_y", "k_z", "m"] {
                let (t, v) = (param_value(&truth, param), fit_value(fit, param));
                table1.push(Table1Row {
                    digits,
                    bearing: b.clone(),
                    param: param.into(),
                    truth: t,
                    identified: v,
                    error_pct: error_pct(v, t),
                });
            }
        }
        if digits == fig6_digits && fig6.is_none() {
            fig6 = Some((run, id));
        }
    }

    let mut table2 = Vec::new();
    let damped_run = reduce_digits(&damped, opts.table2_digits, opts.digits_mode);
    for mode in [
        EquationMode::RealAndImag,
        EquationMode::RealPlusImag,
        EquationMode::Real,
        EquationMode::Imag,
    ] {
        let options = Options::with_mode(mode);
        let model = options.model();
        let id = identify_run(&damped_run, &options).with_context(|| {
            format!(
                "identifying the {}-digit damped run with {}",
                opts.table2_digits,
                mode_label(mode)
            )
        })?;
        for b in &bearings {
            let fit = id
                .pedestal(b)
                .ok_or_else(|| anyhow!("no fit for pedestal {b:?}"))?;
            let truth = truth_of(&damped, b)?;
            for param in model.parameters() {
                let name = param.name();
                let (t, v) = (param_value(&truth, name), fit_value(fit, name));
                table2.push(Table2Row {
                    mode: mode_label(mode).into(),
                    bearing: b.clone(),
                    param: name.into(),
                    truth: t,
                    identified: v,
                    error_pct: error_pct(v, t),
                });
            }
        }
    }

    let (undamped_truncated, id) = fig6.ok_or_else(|| anyhow!("no Table 1 case for Fig. 6"))?;
    let mut machine = undamped_machine.clone();
    for fit in &id.pedestals {
        let p = IdentifiedPedestal {
            bearing: fit.bearing.clone(),
            k_y: Some(fit.k_y),
            k_z: Some(fit.k_z),
            m: Some(fit.m),
            c_y: Some(fit.c_y),
            c_z: Some(fit.c_z),
        };
        machine
            .set_pedestal(&p.bearing, Some(p.params()?))
            .with_context(|| {
                format!("re-predicting with the identified pedestal {:?}", p.bearing)
            })?;
    }
    let repredicted = predict_run(&machine, &EffectSet::none(), &undamped_truncated)?;
    let reprediction = compare(&repredicted, &undamped_truncated.measurements)?;
    Ok(Paper {
        tables: Tables { table1, table2 },
        undamped,
        damped,
        undamped_truncated,
        repredicted,
        reprediction,
        fig6_digits,
    })
}

/// Runs the reproduction on the bundled machines.
pub fn reproduce(opts: &PaperOptions) -> Result<Paper> {
    let u = load_machine(None, UNDAMPED_MACHINE, "examples/feng-hahn-1997.toml")?;
    let d = load_machine(None, DAMPED_MACHINE, "examples/feng-hahn-1997-damped.toml")?;
    reproduce_with(&u, &d, opts)
}

/// Short label of a bearing for legends: `left` → `L`, `right` → `R`,
/// anything else as is.
fn short(bearing: &str) -> String {
    match bearing {
        "left" => "L".into(),
        "right" => "R".into(),
        b => format!("{b} "),
    }
}

/// (speed [Hz], phasor [m]) points of one channel.
type SpeedPhasors = Vec<(f64, Complex<f64>)>;

/// Series of one quantity per (bearing, direction): `Ly`, `Lz`, `Ry`, `Rz`,
/// each with its direction index (0 = y, 1 = z).
fn channel_series(
    rows: &[Measurement],
    ped: bool,
    mark: Mark,
    suffix: &str,
) -> Vec<(usize, PhasorSeries)> {
    let mut by: BTreeMap<(usize, String, usize), SpeedPhasors> = BTreeMap::new();
    let mut order: Vec<String> = Vec::new();
    for m in rows {
        if !order.contains(&m.bearing) {
            order.push(m.bearing.clone());
        }
        let bi = order.iter().position(|b| *b == m.bearing).unwrap_or(0);
        let v = if ped { m.ped } else { m.rel };
        for (d, x) in v.iter().enumerate() {
            by.entry((bi, m.bearing.clone(), d))
                .or_default()
                .push((m.speed_hz, *x));
        }
    }
    by.into_iter()
        .map(|((_, b, d), points)| {
            (
                d,
                PhasorSeries {
                    name: format!("{}{}{suffix}", short(&b), if d == 0 { "y" } else { "z" }),
                    points,
                    mark,
                },
            )
        })
        .collect()
}

/// Phase lag of each pedestal's response behind the force transmitted to it
/// [deg] per (bearing, direction).
fn phase_difference_series(run: &RunDir) -> Result<Vec<ScalarSeries>> {
    let schedules = run.bearing_schedules();
    let mut by: BTreeMap<(String, usize), Vec<(f64, f64)>> = BTreeMap::new();
    for m in &run.measurements {
        let s = schedules
            .get(&m.bearing)
            .ok_or_else(|| anyhow!("no bearing coefficients for {:?}", m.bearing))?;
        let k = s.at(m.speed_hz).map_err(|e| anyhow!("{e}"))?;
        let f = k.force(omega_from_hz(m.speed_hz), &m.rel);
        for (d, (x, fd)) in m.ped.iter().zip(f).enumerate() {
            by.entry((m.bearing.clone(), d))
                .or_default()
                .push((m.speed_hz, phase_lag_deg(*x, fd)));
        }
    }
    Ok(by
        .into_iter()
        .map(|((b, d), points)| ScalarSeries {
            name: format!("{}{}", short(&b), if d == 0 { "y" } else { "z" }),
            points,
            mark: Mark::Line,
        })
        .collect())
}

fn response_panels(run: &RunDir) -> Vec<PhasorPanel> {
    vec![
        PhasorPanel {
            title: "Rotor relative to pedestal".into(),
            series: channel_series(&run.measurements, false, Mark::Line, "")
                .into_iter()
                .map(|(_, s)| s)
                .collect(),
        },
        PhasorPanel {
            title: "Pedestal (absolute)".into(),
            series: channel_series(&run.measurements, true, Mark::Line, "")
                .into_iter()
                .map(|(_, s)| s)
                .collect(),
        },
    ]
}

/// Keeps about `n` evenly spaced points of a series (markers stay legible).
fn thin(points: Vec<(f64, Complex<f64>)>, n: usize) -> Vec<(f64, Complex<f64>)> {
    let step = points.len().div_ceil(n.max(1)).max(1);
    points.into_iter().step_by(step).collect()
}

/// Writes every figure into `dir`; returns the files written.
pub fn write_figures(paper: &Paper, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let cases = [
        (&paper.undamped, "c = 0", ["fig3", "fig4", "fig5"]),
        (&paper.damped, "c ≠ 0", ["fig7", "fig8", "fig9"]),
    ];
    for (run, case, [amp, phase, diff]) in cases {
        let fig = PhasorFigure {
            title: format!("Response amplitudes at the measurement points ({case})"),
            quantity: Quantity::DisplacementMicrons,
            view: PhasorView::Engineer(PhaseStyle::Wrapped),
            rows: Rows::First,
            panels: response_panels(run),
        };
        files.extend(fig.write(&dir.join(format!("{amp}_amplitudes")))?);
        let fig = PhasorFigure {
            title: format!("Response phase lags at the measurement points ({case})"),
            rows: Rows::Second,
            ..fig
        };
        files.extend(fig.write(&dir.join(format!("{phase}_phases")))?);
        let fig = ScalarFigure {
            title: format!("Phase lag of pedestal response behind transmitted force ({case})"),
            y_label: "Phase difference [deg]".into(),
            y_range: Some((-30.0, 210.0)),
            y_tick_step: Some(30.0),
            series: phase_difference_series(run)?,
        };
        files.extend(fig.write(&dir.join(format!("{diff}_phase_difference")))?);
    }

    let mut series = Vec::new();
    let measured = channel_series(
        &paper.undamped_truncated.measurements,
        false,
        Mark::Markers,
        " measured",
    );
    let predicted = channel_series(&paper.repredicted, false, Mark::Line, " predicted");
    for ((d, m), (_, p)) in measured.into_iter().zip(predicted) {
        if d == 0 {
            series.push(PhasorSeries {
                points: thin(m.points, 40),
                ..m
            });
            series.push(p);
        }
    }
    let fig = PhasorFigure {
        title: format!(
            "Rotor response, vertical: measured ({} digits) vs predicted with identified pedestals",
            paper.fig6_digits
        ),
        quantity: Quantity::DisplacementMicrons,
        view: PhasorView::Engineer(PhaseStyle::Wrapped),
        rows: Rows::Both,
        panels: vec![PhasorPanel {
            title: "Rotor relative to pedestal, y".into(),
            series,
        }],
    };
    files.extend(fig.write(&dir.join("fig6_measured_vs_predicted"))?);
    Ok(files)
}

/// Significant-figure text of a value in a unit (e.g. MN/m).
fn fmt_value(v: f64, scale: f64) -> String {
    format!("{:.4}", v * scale)
}

fn unit_of(param: &str) -> (&'static str, f64) {
    match param {
        "k_y" | "k_z" => ("MN/m", 1e-6),
        "m" => ("kg", 1.0),
        _ => ("N·s/m", 1.0),
    }
}

/// Both tables as text, laid out like the paper's.
pub fn tables_text(t: &Tables) -> String {
    let mut s = String::new();
    s += "Table 1: identified pedestal parameters (c = 0), R&I, model k_y, k_z, m\n";
    s += &format!(
        "{:<10} {:<6} {:<5} {:>12} {:>12} {:>10}\n",
        "digits", "ped", "param", "truth", "identified", "error [%]"
    );
    for r in &t.table1 {
        let (u, k) = unit_of(&r.param);
        s += &format!(
            "{:<10} {:<6} {:<5} {:>12} {:>12} {:>10.3}  {u}\n",
            r.digits,
            r.bearing,
            r.param,
            fmt_value(r.truth, k),
            fmt_value(r.identified, k),
            r.error_pct
        );
    }
    s += "\nTable 2: identified pedestal parameters (c ≠ 0, 2 digits) by use of eq. 4\n";
    s += "  R&I: all equations independently (model k_y, k_z, m, c_y, c_z)\n";
    s += "  R+I: real- and imaginary-part equations added; R: real parts only; I: imaginary parts only (model k_y, k_z, m)\n";
    s += &format!(
        "{:<10} {:<6} {:<5} {:>12} {:>12} {:>10}\n",
        "mode", "ped", "param", "truth", "identified", "error [%]"
    );
    for r in &t.table2 {
        let (u, k) = unit_of(&r.param);
        s += &format!(
            "{:<10} {:<6} {:<5} {:>12} {:>12} {:>10.3}  {u}\n",
            r.mode,
            r.bearing,
            r.param,
            fmt_value(r.truth, k),
            fmt_value(r.identified, k),
            r.error_pct
        );
    }
    s
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
        digits_mode: if args.round {
            DigitsMode::Round
        } else {
            DigitsMode::Truncate
        },
        ..PaperOptions::default()
    };
    let paper = reproduce_with(&undamped, &damped, &opts)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&paper.tables)?);
    } else {
        print!("{}", tables_text(&paper.tables));
        let o = &paper.reprediction.overall;
        println!(
            "\nFig. 6: re-predicted with the {}-digit identified pedestals vs the {}-digit measurement: \
             max |dX| {:.3} um ({:.2} % of the largest), RMS {:.2} %",
            paper.fig6_digits,
            paper.fig6_digits,
            o.max_abs_m * 1e6,
            o.max_rel * 100.0,
            o.rms_rel * 100.0
        );
    }
    if let Some(dir) = &args.plots {
        let files = write_figures(&paper, dir)?;
        if !args.json {
            println!("{} figure files written to {}", files.len(), dir.display());
        }
    }
    Ok(())
}
