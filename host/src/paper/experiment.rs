//! The paper's numerical experiment: simulate the machines, reduce the
//! phasors to digits, identify with the paper's equation variants (and the
//! maximum-likelihood column), re-predict with the identified pedestals and
//! locate the re-prediction gap.

use super::*;
use crate::estimate::Pedestal;
use crate::identify::{identify_run, mode_label, EquationMode, Model, Options, Parameter};
use crate::rundir::{round_to_digits, DigitsMode, Measurement, RunDir};
use crate::sim::predict::{compare, predict_run, Comparison, IdentifiedPedestal};
use crate::sim::{unbalance_response, EffectSet, Machine};
use anyhow::{anyhow, Context, Result};
use num_complex::Complex;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

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
pub(super) fn load_machine(path: Option<&Path>, bundled: &str, name: &str) -> Result<Machine> {
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

pub(super) fn simulate(machine: &Machine, speeds: &[f64]) -> Result<RunDir> {
    let response = unbalance_response(machine, speeds, &EffectSet::none())
        .with_context(|| format!("simulating {}", machine.name))?;
    Ok(response.to_run_dir(None)?)
}

pub(super) fn truth_of(run: &RunDir, bearing: &str) -> Result<Pedestal> {
    run.truth
        .as_ref()
        .and_then(|t| t.pedestals.iter().find(|p| p.bearing == bearing))
        .map(|p| p.pedestal)
        .ok_or_else(|| anyhow!("the simulation has no pedestal truth for {bearing:?}"))
}

/// The parameter `name` (formats.md: `k_y`, `k_z`, `m`, `c_y`, `c_z`) of
/// `p`; NaN for any other name.
pub(super) fn param_value(p: &Pedestal, name: &str) -> f64 {
    Parameter::from_name(name).map_or(f64::NAN, |q| p.get(q))
}

/// The noise model's reading of how the paper's digits were reduced.
pub(super) fn quantisation_of(mode: DigitsMode) -> crate::estimate::noise::Quantisation {
    match mode {
        DigitsMode::Round => crate::estimate::noise::Quantisation::Rounding,
        DigitsMode::Truncate => crate::estimate::noise::Quantisation::Truncation,
    }
}

pub(super) fn error_pct(identified: f64, truth: f64) -> f64 {
    100.0 * (identified - truth) / truth
}

/// The pedestal damping of `machine` (every bearing with a pedestal).
pub(super) fn case_damping(machine: &Machine) -> Result<Vec<CaseDamping>> {
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
pub(super) fn scale_damping(machine: &Machine, scale: f64) -> Result<Machine> {
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
pub(super) fn heavy_damping_scale(machine: &Machine, target: f64) -> Result<f64> {
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
pub(super) fn table2_rows(
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
                let (t, v) = (param_value(&truth, name), param_value(&fit.pedestal, name));
                let ml = ml_fit.map(|f| param_value(&f.pedestal, name));
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
                let (t, v) = (
                    param_value(&truth, param),
                    param_value(&fit.pedestal, param),
                );
                let ml = ml_id
                    .pedestal(b)
                    .map_or(f64::NAN, |f| param_value(&f.pedestal, param));
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
            pedestal: fit.pedestal,
            std_err: None,
            trusted: None,
        };
        // The identification's own check (a negative mass from too few
        // speeds) is named as this step's too.
        p.params()
            .and_then(|params| Ok(machine.set_pedestal(&p.bearing, Some(params))?))
            .with_context(|| {
                format!(
                    "Fig. 6: re-predicting the {}-digit undamped run with the pedestal {:?} identified from it",
                    fig6_digits, p.bearing
                )
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
pub(super) const GAP_HALF_WIDTH_HZ: f64 = 2.0;

/// Runs the reproduction on the bundled machines.
pub fn reproduce(opts: &PaperOptions) -> Result<Paper> {
    let u = load_machine(None, UNDAMPED_MACHINE, "examples/feng-hahn-1997.toml")?;
    let d = load_machine(None, DAMPED_MACHINE, "examples/feng-hahn-1997-damped.toml")?;
    reproduce_with(&u, &d, opts)
}
