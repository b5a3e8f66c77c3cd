//! `plinth extract RECORDING --channels CHANNELS.toml --bearings BEARINGS.csv
//! --out DIR`: 1X phasors from recorded waveforms (formats.md "Recorded
//! waveforms"), with the field box's own extractor.
//!
//! The recording (WAV or CSV, [`recording`]) is read a block at a time; the
//! keyphasor channel gives sub-sample edges ([`keyphasor`]); the shared
//! extractor turns every revolution into displacement phasors (seismic
//! channels converted with the revolution's kinematics, the run-down
//! correction applied), R of which are averaged into one phasor with its
//! noise ([`phasors`]) and moved from the window's mean to its middle
//! ([`window`]); each bearing's channels are resolved into y and z;
//! consecutive phasors whose speeds agree within `speed_resolution_hz`
//! (default 0.001 Hz: a dwell) are averaged into one row at their mean speed. The run
//! directory has the noise columns (`rel_y_sd`, ...: sqrt(E|n|²) of the
//! written phasor). Phasors outside the speeds the bearing table covers are
//! left out (with a warning); keyphasor faults are reported as the box
//! counts them.

pub mod channels;
pub mod edge_fit;
pub mod health;
pub mod keyphasor;
pub mod phasors;
pub mod recording;
pub mod wav;
pub mod window;

use crate::field::angle::resolve;
use crate::field::import::write_run;
use crate::field::slow_roll::SlowRollBand;
use crate::rundir::{read_bearings, Measurement, RunDir};
use anyhow::{bail, Result};
use channels::Channels;
use num_complex::Complex;
use phasors::{extract, Extraction};
use plinth_shared::extractor::FaultKind;
use recording::Recording;
use std::path::PathBuf;
use std::time::Instant;

/// Command-line arguments of `plinth extract`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The recording: WAV (8- to 32-bit integer PCM, 32- or 64-bit float) or CSV (`time_s`, then channels in volts).
    pub recording: PathBuf,
    /// Channel map, sensitivities and keyphasor (TOML, docs/formats.md "Recorded waveforms").
    #[arg(long)]
    pub channels: PathBuf,
    /// Bearing coefficients (`bearings.csv` layout).
    #[arg(long)]
    pub bearings: PathBuf,
    /// Run directory to write (refused if it exists and is not empty, unless --force).
    #[arg(long)]
    pub out: PathBuf,
    /// Subtract each bearing's mean `rel` vector between LO and HI Hz (slow roll).
    #[arg(long, value_name = "LO:HI")]
    pub slow_roll: Option<SlowRollBand>,
    /// Also draw Bode and polar plots into DIR/figures.
    #[arg(long)]
    pub plots: bool,
    /// No progress bar.
    #[arg(skip)]
    pub quiet: bool,
    /// Replace the files this command writes in an existing --out.
    #[arg(long)]
    pub force: bool,
}

/// One bearing's y/z phasors [m] (rel y, rel z, ped y, ped z) and their
/// noise sd [m] (NaN when unknown) from one output.
fn bearing_phasors(
    o: &phasors::Output,
    config: &Channels,
    sets: &[Vec<usize>; 2],
) -> ([Complex<f64>; 4], [f64; 4]) {
    let mut values = [Complex::new(0.0, 0.0); 4];
    let mut sds = [f64::NAN; 4];
    for (qi, set) in sets.iter().enumerate() {
        let angles: Vec<f64> = set
            .iter()
            .map(|&i| config.channels[i].placement.angle_deg)
            .collect();
        let q: Vec<Complex<f64>> = set
            .iter()
            .map(|&i| {
                Complex::new(
                    f64::from(o.displacement[i].re),
                    f64::from(o.displacement[i].im),
                )
            })
            .collect();
        let sd: Option<Vec<f64>> = set.iter().map(|&i| o.noise_sd[i]).collect();
        let (yz, noise) = resolve(&angles, &q, sd.as_deref());
        values[2 * qi] = yz[0];
        values[2 * qi + 1] = yz[1];
        if let Some(n) = noise {
            sds[2 * qi] = n[0];
            sds[2 * qi + 1] = n[1];
        }
    }
    (values, sds)
}

/// Turns an extraction into run-directory rows: each output moved to its
/// window's middle ([`window::mid_window`]); y/z resolved per bearing;
/// a dwell (consecutive phasors within `config.speed_resolution_hz` of the
/// first of them) averaged into one row at their mean speed, its noise sd
/// the sd of that mean. Rows without a noise estimate take the median of
/// the others of their bearing and column.
pub fn measurements(extraction: &Extraction, config: &Channels) -> Vec<Measurement> {
    let res = config.speed_resolution_hz;
    // Consecutive outputs within `res` of the group's first speed.
    let outputs = window::mid_window(&extraction.outputs, config.revolutions);
    let mut groups: Vec<Vec<&phasors::Output>> = Vec::new();
    for o in &outputs {
        match groups.last_mut() {
            Some(g) if (o.speed_hz - g[0].speed_hz).abs() <= res => g.push(o),
            _ => groups.push(vec![o]),
        }
    }
    let mut rows: Vec<Measurement> = Vec::new();
    for g in &groups {
        let n = g.len() as f64;
        let speed_hz = g.iter().map(|o| o.speed_hz).sum::<f64>() / n;
        for (name, sets) in &config.bearings {
            let mut sum = [Complex::new(0.0, 0.0); 4];
            let mut var = [0.0f64; 4];
            for o in g {
                let (v, sd) = bearing_phasors(o, config, sets);
                for k in 0..4 {
                    sum[k] += v[k];
                    var[k] += sd[k] * sd[k];
                }
            }
            let v = sum.map(|s| s / n);
            rows.push(Measurement {
                speed_hz,
                bearing: name.clone(),
                rel: [v[0], v[1]],
                ped: [v[2], v[3]],
                noise_sd: Some(var.map(|s| s.sqrt() / n)),
                written: None,
            });
        }
    }
    // Two groups at exactly the same speed (a run-up and a run-down meeting
    // there) would be the same (speed, bearing) twice: merge them.
    rows.sort_by(|a, b| {
        a.speed_hz
            .total_cmp(&b.speed_hz)
            .then(a.bearing.cmp(&b.bearing))
    });
    let mut merged: Vec<(Measurement, f64)> = Vec::new();
    for m in rows {
        match merged.last_mut() {
            Some((last, count)) if last.speed_hz == m.speed_hz && last.bearing == m.bearing => {
                let c = *count;
                for k in 0..2 {
                    last.rel[k] = (last.rel[k] * c + m.rel[k]) / (c + 1.0);
                    last.ped[k] = (last.ped[k] * c + m.ped[k]) / (c + 1.0);
                }
                if let (Some(a), Some(b)) = (&mut last.noise_sd, m.noise_sd) {
                    for k in 0..4 {
                        a[k] = ((a[k] * c).powi(2) + b[k] * b[k]).sqrt() / (c + 1.0);
                    }
                }
                *count += 1.0;
            }
            _ => merged.push((m, 1.0)),
        }
    }
    let mut rows: Vec<Measurement> = merged.into_iter().map(|(m, _)| m).collect();
    for (name, _) in &config.bearings {
        for k in 0..4 {
            let mut known: Vec<f64> = rows
                .iter()
                .filter(|m| &m.bearing == name)
                .filter_map(|m| m.noise_sd.map(|s| s[k]))
                .filter(|s| s.is_finite())
                .collect();
            known.sort_by(f64::total_cmp);
            // No phasor of this channel came with a noise estimate (too few
            // revolutions), or every revolution was identical (an exactly
            // periodic digital recording: scatter 0): there is no measured
            // scatter to write, and 0 would claim exact phasors. The rows
            // then have no noise columns, so the run has none and Plinth
            // estimates the noise from the data (formats.md).
            let median = if known.iter().all(|&s| s == 0.0) {
                None
            } else {
                known.get(known.len() / 2).copied()
            };
            for m in rows.iter_mut().filter(|m| &m.bearing == name) {
                match (median, &mut m.noise_sd) {
                    (Some(median), Some(s)) if !s[k].is_finite() || s[k] == 0.0 => s[k] = median,
                    (None, sd) => *sd = None,
                    _ => {}
                }
            }
        }
    }
    rows
}

/// Runs `plinth extract`.
pub fn run(args: &Args) -> Result<()> {
    let config = Channels::read(&args.channels)?;
    let bearings = read_bearings(&args.bearings)?;
    let mut recording = Recording::open(&args.recording, config.full_scale_v)?;
    // A bar over the frames (WAV), a spinner over them (CSV: count unknown).
    let bar = crate::progress::bar("", recording.frames, !args.quiet);
    bar.set_message(format!("extracting {}", args.recording.display()));
    let started = Instant::now();
    let csv = recording.frames.is_none();
    let extraction = extract(&mut recording, &config, |frames| bar.set_position(frames))?;
    bar.finish_and_clear();
    let elapsed = started.elapsed().as_secs_f64();
    if csv {
        let measured = recording.measured_rate_hz();
        if (measured / extraction.sample_rate_hz - 1.0).abs() > 1e-4 {
            eprintln!(
                "warning: {}: the sample rate over the whole file is {measured:.6} Hz, but {:.6} Hz over its start (used): speeds are off by {:.3} %",
                args.recording.display(),
                extraction.sample_rate_hz,
                100.0 * (measured / extraction.sample_rate_hz - 1.0)
            );
        }
    }
    report_faults(&extraction);
    if let Some((first, last)) = extraction.keyphasor_span {
        if let Some(w) =
            health::keyphasor_coverage(first, last, extraction.frames, extraction.sample_rate_hz)
        {
            eprintln!("warning: {}: {w}", args.recording.display());
        }
    }
    if extraction.outputs.is_empty() {
        bail!(
            "{}: {} keyphasor edges but no phasor: the extractor needs 3 edges to lock and {} revolutions per phasor, with no fault in between",
            args.recording.display(),
            extraction.edges,
            config.revolutions
        );
    }
    let mut rows = measurements(&extraction, &config);
    // Keep what the bearing table covers.
    let schedules = RunDir {
        measurements: Vec::new(),
        bearings: bearings.clone(),
        truth: None,
    }
    .bearing_schedules();
    for (b, _) in &config.bearings {
        if !schedules.contains_key(b) {
            bail!(
                "{}: bearing `{b}` has no rows in {}",
                args.channels.display(),
                args.bearings.display()
            );
        }
    }
    let before = rows.len();
    rows.retain(|m| {
        schedules
            .get(&m.bearing)
            .is_some_and(|s| s.at(m.speed_hz).is_ok())
    });
    if rows.len() < before {
        eprintln!(
            "warning: {} of {before} rows are at speeds outside the range {} lists and were left out (coefficients are not extrapolated; if the machine ran inside that range, every speed is scaled: is the recording's sample rate the one it was sampled at?)",
            before - rows.len(),
            args.bearings.display()
        );
    }
    if rows.is_empty() {
        bail!(
            "no phasor lies in the speed range of {}",
            args.bearings.display()
        );
    }
    let n_rows = rows.len();
    let placements: Vec<_> = config
        .channels
        .iter()
        .map(|c| c.placement.clone())
        .collect();
    write_run(
        &args.out,
        args.force,
        rows,
        bearings,
        args.slow_roll,
        args.plots
            .then(|| crate::field::plot::FieldFigures::from_channels(&config)),
        &placements,
    )?;
    let fit = &extraction.edge_fit;
    println!(
        "keyphasor: edge timing jitter {:.3}° of shaft angle (sd, {:.4} samples at {:.1} samples per revolution), {}",
        fit.jitter_deg(),
        fit.jitter_samples,
        fit.median_period,
        if fit.smoothed {
            format!(
                "smoothed over ±{} edges to {:.3}°",
                edge_fit::HALF_WINDOW,
                fit.jitter_deg() * fit.leverage.sqrt()
            )
        } else {
            format!("edges used as timed (below {} sample)", edge_fit::SMOOTH_ABOVE)
        }
    );
    if let Some(w) = jitter_warning(&extraction, config.revolutions) {
        eprintln!("warning: {}: {w}", args.recording.display());
    }
    let per_channel = extraction.frames as f64 / elapsed.max(1e-9);
    println!(
        "{} ({}, {} channels at {} Hz, {:.1} s): {} keyphasor edges, {} phasors, {} rows -> {}",
        args.recording.display(),
        recording.format,
        recording.channels,
        extraction.sample_rate_hz,
        extraction.frames as f64 / extraction.sample_rate_hz,
        extraction.edges,
        extraction.outputs.len(),
        n_rows,
        args.out.display()
    );
    println!(
        "throughput: {:.3e} samples/s per channel ({:.0}x real time) in {elapsed:.2} s",
        per_channel,
        per_channel / extraction.sample_rate_hz
    );
    Ok(())
}

/// A warning when the keyphasor's raw edge jitter would have been the
/// larger part of some phasor's error (|phasor| × jitter [rad] / √R above
/// its noise sd, the sd including the smoothed edges' remaining part): the
/// keyphasor's transition is then likely shorter than a sample, and the
/// phases rest on the smoothing of its edges.
fn jitter_warning(e: &Extraction, revolutions: u16) -> Option<String> {
    let fit = &e.edge_fit;
    let mut worst = 0.0f64;
    for o in &e.outputs {
        let raw = std::f64::consts::TAU * fit.jitter_samples * o.speed_hz
            / e.sample_rate_hz
            / f64::from(revolutions.max(1)).sqrt();
        for (d, sd) in o.displacement.iter().zip(&o.noise_sd) {
            if let Some(sd) = sd.filter(|s| *s > 0.0) {
                let q = f64::from(d.re).hypot(f64::from(d.im));
                worst = worst.max(q * raw / sd);
            }
        }
    }
    (fit.smoothed && worst > 1.0).then(|| {
        format!(
            "the keyphasor's edge times jitter by {:.2}° of shaft angle (sd) around a smooth shaft speed: its transition is probably shorter than a sample (a square pulse, a sharp notch), so each edge is timed only to within ±0.5 sample; unsmoothed, this jitter would be up to {worst:.1}× a phasor's noise. The edges were smoothed over ±{} revolutions and the noise columns count what remains ({:.2}°); a keyphasor edge spanning 2 or more samples avoids it",
            fit.jitter_deg(),
            edge_fit::HALF_WINDOW,
            fit.jitter_deg() * fit.leverage.sqrt()
        )
    })
}

/// Prints the keyphasor faults the way the box counts them.
fn report_faults(e: &Extraction) {
    if e.faults.is_empty() {
        return;
    }
    let count = |kinds: &[FaultKind]| e.faults.iter().filter(|f| kinds.contains(&f.kind)).count();
    let missing = count(&[FaultKind::MissingPulse, FaultKind::Timeout]);
    let extra = count(&[FaultKind::ExtraPulse, FaultKind::IrregularPulses]);
    let non_finite = count(&[FaultKind::NonFinite]);
    let times: Vec<String> = e
        .faults
        .iter()
        .take(10)
        .map(|f| {
            format!(
                "{:?} at {:.3} s",
                f.kind,
                f.sample as f64 / e.sample_rate_hz
            )
        })
        .collect();
    eprintln!(
        "warning: keyphasor: {missing} missing pulse(s), {extra} extra pulse(s), {non_finite} non-finite revolution(s); the revolutions around each were dropped ({}{})",
        times.join(", "),
        if e.faults.len() > 10 { ", ..." } else { "" }
    );
}
