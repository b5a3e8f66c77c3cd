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

use crate::identify::{identify_run, mode_label, EquationMode, Model, Options, PedestalFit};
use crate::plots::{
    phase_lag_deg, Mark, PhaseStyle, PhasorFigure, PhasorPanel, PhasorSeries, PhasorView, Quantity,
    Rows, ScalarFigure, ScalarSeries,
};
use crate::rundir::{round_to_digits, DigitsMode, Measurement, RunDir};
use crate::sim::cli::parse_speeds;
use crate::sim::predict::{compare, predict_run, Comparison, IdentifiedPedestal};
use crate::sim::{unbalance_response, EffectSet, Machine};
use anyhow::{anyhow, Context, Result};
use num_complex::Complex;
use plinth_shared::phasor::omega_from_hz;
use serde::{Serialize, Serializer};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The undamped paper machine (Table 1), bundled.
pub const UNDAMPED_MACHINE: &str = include_str!("../../examples/feng-hahn-1997.toml");
/// The damped paper machine (Table 2), bundled.
pub const DAMPED_MACHINE: &str = include_str!("../../examples/feng-hahn-1997-damped.toml");

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
    #[arg(long, default_value_t = 0.10)]
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

/// `round` or `truncate`: the name of a digits mode in the tables.
pub fn digits_mode_name(mode: DigitsMode) -> &'static str {
    match mode {
        DigitsMode::Round => "round",
        DigitsMode::Truncate => "truncate",
    }
}

fn serialize_digits_mode<S: Serializer>(mode: &DigitsMode, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(digits_mode_name(*mode))
}

/// One row of Table 1.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table1Row {
    /// Significant digits of the measured phasors.
    pub digits: u32,
    /// How the phasors were reduced to `digits` (`round` or `truncate`).
    #[serde(serialize_with = "serialize_digits_mode")]
    pub digits_mode: DigitsMode,
    /// Bearing (pedestal) name.
    pub bearing: String,
    /// `k_y` [N/m], `k_z` [N/m] or `m` [kg].
    pub param: String,
    /// The machine's value.
    pub truth: f64,
    /// The identified value (the paper's OLS).
    pub identified: f64,
    /// 100·(identified − truth)/truth [%].
    pub error_pct: f64,
    /// The maximum-likelihood estimate of the same data and model
    /// (`plinth identify`'s default).
    pub ml: f64,
    /// 100·(ml − truth)/truth [%].
    pub ml_error_pct: f64,
}

/// Which pedestal damping a Table 2 row was computed with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DampingCase {
    /// The damped example as the scan reads it (70-100 N·s/m).
    ScanDamping,
    /// The same machine with the pedestal damping scaled to a damping ratio
    /// of about 10 %.
    HeavyDamping,
}

impl DampingCase {
    /// `scan_damping` or `heavy_damping`, as in the JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::ScanDamping => "scan_damping",
            Self::HeavyDamping => "heavy_damping",
        }
    }
}

/// One row of Table 2.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table2Row {
    /// The damping case.
    pub case: DampingCase,
    /// Factor [-] applied to the damped machine's c_y, c_z in this case (1
    /// for the scan's damping).
    pub damping_scale: f64,
    /// `R&I`, `R+I`, `R` or `I`.
    pub mode: String,
    /// Bearing (pedestal) name.
    pub bearing: String,
    /// `k_y`, `k_z` [N/m], `m` [kg], and for R&I `c_y`, `c_z` [N·s/m].
    pub param: String,
    /// The machine's value.
    pub truth: f64,
    /// The identified value (the paper's OLS).
    pub identified: f64,
    /// 100·(identified − truth)/truth [%].
    pub error_pct: f64,
    /// R&I only: the maximum-likelihood estimate of the same data and model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ml: Option<f64>,
    /// R&I only: 100·(ml − truth)/truth [%].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ml_error_pct: Option<f64>,
}

/// The pedestal damping of one Table 2 case, one entry per pedestal.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CaseDamping {
    /// Bearing (pedestal) name.
    pub bearing: String,
    /// Vertical damping [N·s/m].
    pub c_y: f64,
    /// Horizontal damping [N·s/m].
    pub c_z: f64,
    /// Vertical damping ratio c_y/(2·sqrt(k_y·m)) of the pedestal alone [-].
    pub damping_ratio_y: f64,
    /// Horizontal damping ratio c_z/(2·sqrt(k_z·m)) of the pedestal alone [-].
    pub damping_ratio_z: f64,
}

/// One Table 2 case: which damping and how much.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table2Case {
    /// The case.
    pub case: DampingCase,
    /// Factor [-] applied to the damped machine's c_y, c_z.
    pub damping_scale: f64,
    /// The resulting damping of every pedestal.
    pub pedestals: Vec<CaseDamping>,
    /// Worst |error| in k_y, k_z, m [%] of each mode identified from the
    /// same run at full precision (no digit reduction): the error of the
    /// method itself, which the 2-digit rows add rounding noise to. R&I is
    /// exact there; R+I, R and I carry the error of leaving c out of eq. 4.
    pub full_precision_worst_km_pct: BTreeMap<String, f64>,
}

impl Table2Case {
    /// Mean damping ratio over every pedestal and direction [-].
    pub fn mean_damping_ratio(&self) -> f64 {
        let n = (2 * self.pedestals.len()).max(1) as f64;
        self.pedestals
            .iter()
            .map(|p| p.damping_ratio_y + p.damping_ratio_z)
            .sum::<f64>()
            / n
    }
}

/// Both tables.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Tables {
    /// How the phasors were reduced to digits in both tables.
    #[serde(serialize_with = "serialize_digits_mode")]
    pub digits_mode: DigitsMode,
    /// Table 1 rows: digits × bearing × (k_y, k_z, m).
    pub table1: Vec<Table1Row>,
    /// Digits of Table 2's phasors.
    pub table2_digits: u32,
    /// Table 2's damping cases, in the order of the rows.
    pub table2_cases: Vec<Table2Case>,
    /// Table 2 rows: case × mode × bearing × parameters.
    pub table2: Vec<Table2Row>,
}

/// A speed band where the Fig. 6 re-prediction gap concentrates.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GapBand {
    /// Speed of the largest gap in the band [Hz].
    pub speed_hz: f64,
    /// Lowest speed of the band [Hz].
    pub from_hz: f64,
    /// Highest speed of the band [Hz].
    pub to_hz: f64,
    /// Share of the total squared gap Σ|P − M|² inside the band [-].
    pub share: f64,
}

/// Where the Fig. 6 re-prediction gap lives.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GapLocation {
    /// The bands carrying most of the squared gap, largest first.
    pub bands: Vec<GapBand>,
    /// RMS |P − M| over RMS |M| outside the bands [-].
    pub rms_rel_outside: f64,
}

/// Everything the reproduction computed.
#[derive(Clone, Debug)]
pub struct Paper {
    /// The tables.
    pub tables: Tables,
    /// Undamped run, full precision.
    pub undamped: RunDir,
    /// Damped run with the scan's damping, full precision.
    pub damped: RunDir,
    /// Damped run with the heavy damping of Table 2 case (b), full precision.
    pub heavily_damped: RunDir,
    /// Undamped run at the smallest Table 1 digit count (Fig. 6 "measured").
    pub undamped_truncated: RunDir,
    /// Rows re-predicted with the pedestals identified from it (Fig. 6).
    pub repredicted: Vec<Measurement>,
    /// How far the re-prediction is from the reduced "measurement".
    pub reprediction: Comparison,
    /// Where that gap concentrates.
    pub reprediction_gap: GapLocation,
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
            round_to_digits(c.re, digits, mode),
            round_to_digits(c.im, digits, mode),
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

/// The noise model's reading of how the paper's digits were reduced.
fn quantisation_of(mode: DigitsMode) -> crate::estimate::noise::Quantisation {
    match mode {
        DigitsMode::Round => crate::estimate::noise::Quantisation::Rounding,
        DigitsMode::Truncate => crate::estimate::noise::Quantisation::Truncation,
    }
}

fn error_pct(identified: f64, truth: f64) -> f64 {
    100.0 * (identified - truth) / truth
}

/// The pedestal damping of `machine` (every bearing with a pedestal).
fn case_damping(machine: &Machine) -> Result<Vec<CaseDamping>> {
    let mut out = Vec::new();
    for b in machine.bearing_names() {
        if let Some(p) = machine.pedestal(&b)? {
            out.push(CaseDamping {
                bearing: b,
                c_y: p.c_y,
                c_z: p.c_z,
                damping_ratio_y: p.c_y / (2.0 * (p.k_y * p.m).sqrt()),
                damping_ratio_z: p.c_z / (2.0 * (p.k_z * p.m).sqrt()),
            });
        }
    }
    Ok(out)
}

/// `machine` with every pedestal's c_y, c_z multiplied by `scale`.
fn scale_damping(machine: &Machine, scale: f64) -> Result<Machine> {
    let mut out = machine.clone();
    out.name = format!("{} (pedestal damping ×{scale})", machine.name);
    for b in machine.bearing_names() {
        if let Some(mut p) = machine.pedestal(&b)? {
            p.c_y *= scale;
            p.c_z *= scale;
            out.set_pedestal(&b, Some(p))
                .with_context(|| format!("scaling the damping of pedestal {b:?} by {scale}"))?;
        }
    }
    Ok(out)
}

/// The factor (2 significant digits) that brings the mean pedestal damping
/// ratio of `machine` to `target` [-].
fn heavy_damping_scale(machine: &Machine, target: f64) -> Result<f64> {
    if !(target.is_finite() && target > 0.0 && target < 1.0) {
        return Err(anyhow!(
            "the heavy-damping ratio must be in (0, 1), got {target}"
        ));
    }
    let case = Table2Case {
        case: DampingCase::ScanDamping,
        damping_scale: 1.0,
        pedestals: case_damping(machine)?,
        full_precision_worst_km_pct: BTreeMap::new(),
    };
    let mean = case.mean_damping_ratio();
    if !(mean.is_finite() && mean > 0.0) {
        return Err(anyhow!(
            "the damped machine {:?} has no positive pedestal damping (mean damping ratio {mean}): \
             Table 2's heavy-damping case scales it",
            machine.name
        ));
    }
    Ok(round_to_digits(target / mean, 2, DigitsMode::Round))
}

/// Table 2's rows for one damping case: the four modes of eq. 4 on `damped`
/// reduced to `digits`.
///
/// `digits: None` keeps full precision (the method's own error).
fn table2_rows(
    damped: &RunDir,
    bearings: &[String],
    digits: Option<u32>,
    digits_mode: DigitsMode,
    case: DampingCase,
    damping_scale: f64,
) -> Result<Vec<Table2Row>> {
    let mut rows = Vec::new();
    let run = match digits {
        Some(d) => reduce_digits(damped, d, digits_mode),
        None => damped.clone(),
    };
    let digits_text = digits.map_or("full-precision".to_string(), |d| format!("{d}-digit"));
    for mode in [
        EquationMode::RealAndImag,
        EquationMode::RealPlusImag,
        EquationMode::Real,
        EquationMode::Imag,
    ] {
        let options = Options {
            quantisation: quantisation_of(digits_mode),
            ..Options::with_mode(mode).ols()
        };
        let model = options.model();
        let ml_id = if mode == EquationMode::RealAndImag {
            let ml_options = Options {
                estimator: crate::identify::Estimator::Ml,
                ..options
            };
            Some(identify_run(&run, &ml_options).with_context(|| {
                format!(
                    "identifying the {digits_text} damped run ({}) by maximum likelihood",
                    case.name()
                )
            })?)
        } else {
            None
        };
        let id = identify_run(&run, &options).with_context(|| {
            format!(
                "identifying the {digits_text} damped run ({}) with {}",
                case.name(),
                mode_label(mode)
            )
        })?;
        for b in bearings {
            let fit = id
                .pedestal(b)
                .ok_or_else(|| anyhow!("no fit for pedestal {b:?} ({})", case.name()))?;
            let truth = truth_of(damped, b)?;
            let ml_fit = ml_id.as_ref().and_then(|id| id.pedestal(b));
            for param in model.parameters() {
                let name = param.name();
                let (t, v) = (param_value(&truth, name), fit_value(fit, name));
                let ml = ml_fit.map(|f| fit_value(f, name));
                rows.push(Table2Row {
                    case,
                    damping_scale,
                    mode: mode_label(mode).into(),
                    bearing: b.clone(),
                    param: name.into(),
                    truth: t,
                    identified: v,
                    error_pct: error_pct(v, t),
                    ml,
                    ml_error_pct: ml.map(|m| error_pct(m, t)),
                });
            }
        }
    }
    Ok(rows)
}

/// Where the squared gap Σ|P − M|² (every channel, every bearing) between
/// `predicted` and `measured` concentrates: greedily, the speed of the
/// largest remaining gap and every speed within `half_width_hz` of it, until
/// `cover` of the total is claimed or `max_bands` bands are found.
pub fn locate_gap(
    predicted: &[Measurement],
    measured: &[Measurement],
    half_width_hz: f64,
    max_bands: usize,
    cover: f64,
) -> Result<GapLocation> {
    let key = |m: &Measurement| (m.bearing.clone(), m.speed_hz.to_bits());
    let pred: BTreeMap<(String, u64), &Measurement> =
        predicted.iter().map(|m| (key(m), m)).collect();
    // speed bits → (Σ|P − M|², Σ|M|²)
    let mut per_speed: BTreeMap<u64, (f64, f64, f64)> = BTreeMap::new();
    for m in measured {
        let p = pred.get(&key(m)).ok_or_else(|| {
            anyhow!(
                "no prediction for bearing {:?} at {} Hz",
                m.bearing,
                m.speed_hz
            )
        })?;
        let e = per_speed
            .entry(m.speed_hz.to_bits())
            .or_insert((m.speed_hz, 0.0, 0.0));
        for (mv, pv) in m.rel.iter().chain(&m.ped).zip(p.rel.iter().chain(&p.ped)) {
            if mv.re.is_finite() && mv.im.is_finite() {
                e.1 += (pv - mv).norm_sqr();
                e.2 += mv.norm_sqr();
            }
        }
    }
    let speeds: Vec<(f64, f64, f64)> = per_speed.into_values().collect();
    let total: f64 = speeds.iter().map(|s| s.1).sum();
    let mut claimed = vec![false; speeds.len()];
    let mut bands = Vec::new();
    let mut covered = 0.0;
    while bands.len() < max_bands && total > 0.0 && covered < cover * total {
        let Some((i, _)) = speeds
            .iter()
            .enumerate()
            .filter(|(i, _)| !claimed[*i])
            .max_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
        else {
            break;
        };
        let centre = speeds[i].0;
        let (mut sum, mut lo, mut hi) = (0.0, centre, centre);
        for (j, s) in speeds.iter().enumerate() {
            if !claimed[j] && (s.0 - centre).abs() <= half_width_hz {
                claimed[j] = true;
                sum += s.1;
                lo = lo.min(s.0);
                hi = hi.max(s.0);
            }
        }
        covered += sum;
        bands.push(GapBand {
            speed_hz: centre,
            from_hz: lo,
            to_hz: hi,
            share: sum / total,
        });
    }
    let (d2, m2) = speeds
        .iter()
        .zip(&claimed)
        .filter(|(_, c)| !**c)
        .fold((0.0, 0.0), |(d, m), (s, _)| (d + s.1, m + s.2));
    Ok(GapLocation {
        bands,
        rms_rel_outside: if m2 > 0.0 { (d2 / m2).sqrt() } else { 0.0 },
    })
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
    let heavy_scale = heavy_damping_scale(damped_machine, opts.heavy_damping_ratio)?;
    let heavy_machine = scale_damping(damped_machine, heavy_scale)?;
    let undamped = simulate(undamped_machine, &opts.speeds_hz)?;
    let damped = simulate(damped_machine, &opts.speeds_hz)?;
    let heavily_damped = simulate(&heavy_machine, &opts.speeds_hz)?;
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
            quantisation: quantisation_of(opts.digits_mode),
            ..Options::with_mode(EquationMode::RealAndImag).ols()
        };
        let id = identify_run(&run, &options)
            .with_context(|| format!("identifying the {digits}-digit undamped run"))?;
        let ml_id = identify_run(
            &run,
            &Options {
                estimator: crate::identify::Estimator::Ml,
                ..options
            },
        )
        .with_context(|| {
            format!("identifying the {digits}-digit undamped run by maximum likelihood")
        })?;
        for b in &bearings {
            let fit = id
                .pedestal(b)
                .ok_or_else(|| anyhow!("no fit for pedestal {b:?}"))?;
            let truth = truth_of(&undamped, b)?;
            for param in ["k_y", "k_z", "m"] {
                let (t, v) = (param_value(&truth, param), fit_value(fit, param));
                let ml = ml_id.pedestal(b).map_or(f64::NAN, |f| fit_value(f, param));
                table1.push(Table1Row {
                    digits,
                    digits_mode: opts.digits_mode,
                    bearing: b.clone(),
                    param: param.into(),
                    truth: t,
                    identified: v,
                    error_pct: error_pct(v, t),
                    ml,
                    ml_error_pct: error_pct(ml, t),
                });
            }
        }
        if digits == fig6_digits && fig6.is_none() {
            fig6 = Some((run, id));
        }
    }

    let cases = [
        (DampingCase::ScanDamping, 1.0, damped_machine, &damped),
        (
            DampingCase::HeavyDamping,
            heavy_scale,
            &heavy_machine,
            &heavily_damped,
        ),
    ];
    let mut table2 = Vec::new();
    let mut table2_cases = Vec::new();
    for (case, scale, machine, run) in cases {
        let exact = table2_rows(run, &bearings, None, opts.digits_mode, case, scale)?;
        let full_precision_worst_km_pct = ["R&I", "R+I", "R", "I"]
            .into_iter()
            .map(|m| (m.to_string(), worst_error(&exact, case, m, &KM)))
            .collect();
        table2_cases.push(Table2Case {
            case,
            damping_scale: scale,
            pedestals: case_damping(machine)?,
            full_precision_worst_km_pct,
        });
        table2.extend(table2_rows(
            run,
            &bearings,
            Some(opts.table2_digits),
            opts.digits_mode,
            case,
            scale,
        )?);
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
            std_err: Default::default(),
        };
        machine
            .set_pedestal(&p.bearing, Some(p.params()?))
            .with_context(|| {
                format!("re-predicting with the identified pedestal {:?}", p.bearing)
            })?;
    }
    let repredicted = predict_run(&machine, &EffectSet::none(), &undamped_truncated)?;
    let reprediction = compare(&repredicted, &undamped_truncated.measurements)?;
    let reprediction_gap = locate_gap(
        &repredicted,
        &undamped_truncated.measurements,
        GAP_HALF_WIDTH_HZ,
        3,
        0.95,
    )?;
    Ok(Paper {
        tables: Tables {
            digits_mode: opts.digits_mode,
            table1,
            table2_digits: opts.table2_digits,
            table2_cases,
            table2,
        },
        undamped,
        damped,
        heavily_damped,
        undamped_truncated,
        repredicted,
        reprediction,
        reprediction_gap,
        fig6_digits,
    })
}

/// Half-width of a speed band of the Fig. 6 gap [Hz].
const GAP_HALF_WIDTH_HZ: f64 = 2.0;

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
    let case_label = |case: DampingCase| {
        paper
            .tables
            .table2_cases
            .iter()
            .find(|c| c.case == case)
            .map(|c| {
                format!(
                    "c ≠ 0: scan's c ×{}, ζ ≈ {:.2} %",
                    c.damping_scale,
                    100.0 * c.mean_damping_ratio()
                )
            })
            .unwrap_or_else(|| "c ≠ 0".into())
    };
    let (scan_label, heavy_label) = (
        case_label(DampingCase::ScanDamping),
        case_label(DampingCase::HeavyDamping),
    );
    let cases = [
        (&paper.undamped, "c = 0", ["fig3", "fig4", "fig5"], ""),
        (
            &paper.damped,
            scan_label.as_str(),
            ["fig7", "fig8", "fig9"],
            "",
        ),
        (
            &paper.heavily_damped,
            heavy_label.as_str(),
            ["fig7", "fig8", "fig9"],
            "_heavy_damping",
        ),
    ];
    for (run, case, [amp, phase, diff], suffix) in cases {
        let fig = PhasorFigure {
            title: format!("Response amplitudes at the measurement points ({case})"),
            quantity: Quantity::DisplacementMicrons,
            view: PhasorView::Engineer(PhaseStyle::Wrapped),
            rows: Rows::First,
            panels: response_panels(run),
        };
        files.extend(fig.write(&dir.join(format!("{amp}_amplitudes{suffix}")))?);
        let fig = PhasorFigure {
            title: format!("Response phase lags at the measurement points ({case})"),
            rows: Rows::Second,
            ..fig
        };
        files.extend(fig.write(&dir.join(format!("{phase}_phases{suffix}")))?);
        let fig = ScalarFigure {
            title: format!("Phase lag of pedestal response behind transmitted force ({case})"),
            y_label: "Phase difference [deg]".into(),
            y_range: Some((-30.0, 210.0)),
            y_tick_step: Some(30.0),
            series: phase_difference_series(run)?,
        };
        files.extend(fig.write(&dir.join(format!("{diff}_phase_difference{suffix}")))?);
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
            "Rotor response, y: measured ({} digits) vs re-predicted; {}",
            paper.fig6_digits,
            gap_caption(paper)
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

/// Short text of the Fig. 6 gap: "gap RMS 44 %, max 65 %, mostly at 27, 45 Hz".
fn gap_caption(paper: &Paper) -> String {
    let o = &paper.reprediction.overall;
    let mut s = format!(
        "gap RMS {:.0} %, max {:.0} %",
        o.rms_rel * 100.0,
        o.max_rel * 100.0
    );
    let bands = &paper.reprediction_gap.bands;
    if !bands.is_empty() {
        let share: f64 = bands.iter().map(|b| b.share).sum();
        let mut at: Vec<f64> = bands.iter().map(|b| b.speed_hz).collect();
        at.sort_by(f64::total_cmp);
        let at: Vec<String> = at.iter().map(|f| f.to_string()).collect();
        // Floor: never print 100 % for 99.9 %.
        s += &format!(
            ", {:.0} % of it within {GAP_HALF_WIDTH_HZ} Hz of {} Hz",
            (share * 100.0).floor(),
            at.join(", ")
        );
    }
    s
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

/// The stiffness and mass parameters, k_y, k_z, m.
pub const KM: [&str; 3] = ["k_y", "k_z", "m"];

/// Worst |error_pct| [%] of the `rows` of one case and mode over `params`.
pub fn worst_error(rows: &[Table2Row], case: DampingCase, mode: &str, params: &[&str]) -> f64 {
    rows.iter()
        .filter(|r| r.case == case && r.mode == mode && params.contains(&r.param.as_str()))
        .map(|r| r.error_pct.abs())
        .fold(0.0, f64::max)
}

/// The two lines that say what a Table 2 case shows, with its numbers.
fn case_explanation(case: &Table2Case) -> [String; 2] {
    let zeta = case.mean_damping_ratio();
    let exact = |m: &str| {
        case.full_precision_worst_km_pct
            .get(m)
            .copied()
            .unwrap_or(f64::NAN)
    };
    match case.case {
        DampingCase::ScanDamping => [
            format!(
                "  The scan's damping is below what 2-digit data resolve: at a pedestal resonance its force is only \
                 2ζ ≈ {:.2} % of the spring force;",
                200.0 * zeta
            ),
            format!(
                "  leaving c out (R+I, R, I) costs only {:.2}, {:.2}, {:.2} % in k, m on full-precision data, less than \
                 the 2-digit noise: no contrast, and R&I's c is noise.",
                exact("R+I"),
                exact("R"),
                exact("I")
            ),
        ],
        DampingCase::HeavyDamping => [
            format!(
                "  With real damping (ζ ≈ {:.0} %, the smooth phase of the paper's Fig. 9) only R&I is right, as the paper \
                 found: R&I gets k, m and c;",
                100.0 * zeta
            ),
            format!(
                "  R+I, R and I leave c out of eq. 4 and miss k or m by up to {:.1}, {:.1}, {:.1} % even on full-precision data.",
                exact("R+I"),
                exact("R"),
                exact("I")
            ),
        ],
    }
}

/// Both tables as text, laid out like the paper's.
pub fn tables_text(t: &Tables) -> String {
    let mode = digits_mode_name(t.digits_mode);
    let mut s = String::new();
    s += &format!(
        "Table 1: identified pedestal parameters (c = 0), R&I, model k_y, k_z, m; digits: {mode}\n"
    );
    s += &format!(
        "  digits {} (the paper's \"maximum error of 5 %\" at 2 digits; --truncate for the literal \"truncated\")\n",
        match t.digits_mode {
            DigitsMode::Round => "rounded",
            DigitsMode::Truncate => "truncated",
        }
    );
    s += "  identified: the paper's least squares; ML: maximum likelihood, errors in variables (plinth identify's default)\n";
    s += &format!(
        "{:<10} {:<6} {:<5} {:>12} {:>12} {:>10} {:>12} {:>10}\n",
        "digits", "ped", "param", "truth", "identified", "error [%]", "ML", "error [%]"
    );
    for r in &t.table1 {
        let (u, k) = unit_of(&r.param);
        s += &format!(
            "{:<10} {:<6} {:<5} {:>12} {:>12} {:>10.3} {:>12} {:>10.3}  {u}\n",
            format!("{} {}", r.digits, digits_mode_name(r.digits_mode)),
            r.bearing,
            r.param,
            fmt_value(r.truth, k),
            fmt_value(r.identified, k),
            r.error_pct,
            fmt_value(r.ml, k),
            r.ml_error_pct
        );
    }
    s += &format!(
        "\nTable 2: identified pedestal parameters (c ≠ 0, {} digits, {mode}) by use of eq. 4\n",
        t.table2_digits
    );
    s += "  R&I: all equations independently (model k_y, k_z, m, c_y, c_z)\n";
    s += "  R+I: real- and imaginary-part equations added; R: real parts only; I: imaginary parts only (model k_y, k_z, m)\n";
    for (label, case) in ["(a)", "(b)"].iter().zip(&t.table2_cases) {
        let c: Vec<String> = case
            .pedestals
            .iter()
            .map(|p| format!("{} c_y {:.0}, c_z {:.0}", p.bearing, p.c_y, p.c_z))
            .collect();
        s += &format!(
            "\nCase {label} {}: pedestal damping ×{} of the damped example ({} N·s/m; mean damping ratio {:.2} %)\n",
            case.case.name(),
            case.damping_scale,
            c.join("; "),
            100.0 * case.mean_damping_ratio()
        );
        for line in case_explanation(case) {
            s += &line;
            s += "\n";
        }
        s += &format!(
            "{:<10} {:<6} {:<5} {:>12} {:>12} {:>10} {:>12} {:>10}\n",
            "mode", "ped", "param", "truth", "identified", "error [%]", "ML", "error [%]"
        );
        for r in t.table2.iter().filter(|r| r.case == case.case) {
            let (u, k) = unit_of(&r.param);
            let (ml, ml_err) = match (r.ml, r.ml_error_pct) {
                (Some(v), Some(e)) => (fmt_value(v, k), format!("{e:.3}")),
                _ => (String::new(), String::new()),
            };
            s += &format!(
                "{:<10} {:<6} {:<5} {:>12} {:>12} {:>10.3} {:>12} {:>10}  {u}\n",
                r.mode,
                r.bearing,
                r.param,
                fmt_value(r.truth, k),
                fmt_value(r.identified, k),
                r.error_pct,
                ml,
                ml_err
            );
        }
        let w = |m: &str| worst_error(&t.table2, case.case, m, &KM);
        s += &format!(
            "  worst |error| in k, m: R&I {:.2} %, R+I {:.2} %, R {:.2} %, I {:.2} %; in c (R&I): {:.1} %\n",
            w("R&I"),
            w("R+I"),
            w("R"),
            w("I"),
            worst_error(&t.table2, case.case, "R&I", &["c_y", "c_z"])
        );
    }
    s
}

/// The Fig. 6 re-prediction gap as text (max, RMS, where it concentrates).
pub fn reprediction_text(paper: &Paper) -> String {
    let o = &paper.reprediction.overall;
    let g = &paper.reprediction_gap;
    let mut s = format!(
        "Fig. 6: re-predicted with the {d}-digit identified pedestals vs the {d}-digit measurement \
         (every channel, both pedestals): max |dX| {:.3} um = {:.1} % of the largest |X|, RMS {:.1} %\n",
        o.max_abs_m * 1e6,
        o.max_rel * 100.0,
        o.rms_rel * 100.0,
        d = paper.fig6_digits,
    );
    if !g.bands.is_empty() {
        let bands: Vec<String> = g
            .bands
            .iter()
            .map(|b| {
                format!(
                    "{:.0} % at {}-{} Hz (peak {} Hz)",
                    b.share * 100.0,
                    b.from_hz,
                    b.to_hz,
                    b.speed_hz
                )
            })
            .collect();
        s += &format!(
            "  the squared gap concentrates in narrow bands: {}; elsewhere the RMS gap is {:.1} %\n",
            bands.join(", "),
            g.rms_rel_outside * 100.0
        );
        s += "  (nearly undamped resonances of the rotor on its pedestals in the undamped machine: a small error in k or m shifts them)\n";
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
        digits_mode: if args.truncate {
            DigitsMode::Truncate
        } else {
            DigitsMode::Round
        },
        heavy_damping_ratio: args.heavy_damping_ratio,
        ..PaperOptions::default()
    };
    let paper = reproduce_with(&undamped, &damped, &opts)?;
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
    if let Some(dir) = &args.plots {
        let staged = crate::output::OutputDir::create(dir, args.force)?;
        let files = write_figures(&paper, staged.path())?;
        staged.commit()?;
        if !args.json {
            text += &format!(
                "{} figure files written to {}\n",
                files.len(),
                dir.display()
            );
        }
    }
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
