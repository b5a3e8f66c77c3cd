//! Synthesis of a run-down's sampled channels from the machine's response,
//! with the interpolation error measured and bounded.

use super::*;
use crate::progress::Ticker;
use crate::sim::budget;
use crate::sim::response::UnbalanceSolver;

/// Everything `plinth signals` can be told.
#[derive(Clone, Debug, PartialEq)]
pub struct SignalOptions {
    /// The speed ramp.
    pub rundown: RunDown,
    /// Sample rate per channel [Hz].
    pub sample_rate_hz: f64,
    /// The converter.
    pub adc: Adc,
    /// Proximity probe sensitivity [V/m] (7.87 V/mm = 7870 V/m).
    pub probe_sensitivity: f64,
    /// Proximity probe gap voltage [V] (DC the vibration rides on).
    pub probe_gap_v: f64,
    /// Noise on the probe channels [V RMS].
    pub probe_noise_v: f64,
    /// Transducer type on the pedestals.
    pub seismic_kind: SensorKind,
    /// Seismic sensitivity [V/m, V/(m/s) or V/(m/s²) as the kind].
    pub seismic_sensitivity: f64,
    /// Noise on the seismic channels [V RMS].
    pub seismic_noise_v: f64,
    /// Speed grid step of the precomputed response [Hz].
    pub grid_step_hz: f64,
    /// Position of keyphasor pulse 0 in sample periods, in [0, 1).
    pub t0_sample_position: f64,
    /// Noise seed.
    pub seed: u64,
}

impl SignalOptions {
    /// Sample vectors (samples per channel) the set holds: every sample time
    /// within [−p0/fs, duration] of the run-down at the sample rate. The
    /// run-down, the rate [Hz] and the first pulse's position are checked
    /// first, so a command can size its output before any work.
    pub fn sample_count(&self) -> Result<u64, SignalsError> {
        self.rundown
            .validate()
            .map_err(|m| SignalsError::Request(format!("run-down: {m}")))?;
        let fs = self.sample_rate_hz;
        if !(fs.is_finite() && fs > 0.0) {
            return Err(SignalsError::Request(format!(
                "sample rate must be finite and > 0 Hz (got {fs})"
            )));
        }
        if !(0.0..1.0).contains(&self.t0_sample_position) {
            return Err(SignalsError::Request(format!(
                "t0 sample position must be in [0, 1) (got {})",
                self.t0_sample_position
            )));
        }
        // Saturating: a count beyond u64 is refused by the size checks.
        let samples = (self.rundown.duration_s() * fs + self.t0_sample_position).floor() as u64;
        Ok(samples.saturating_add(1))
    }
}

impl Default for SignalOptions {
    fn default() -> Self {
        Self {
            rundown: RunDown {
                start_hz: 200.0,
                end_hz: 5.0,
                rate_hz_per_s: 5.0,
            },
            sample_rate_hz: 51_200.0,
            adc: Adc::ad7606(),
            probe_sensitivity: 7870.0,
            probe_gap_v: -9.0,
            probe_noise_v: 1e-3,
            seismic_kind: SensorKind::Acceleration,
            seismic_sensitivity: default_seismic_sensitivity(SensorKind::Acceleration),
            seismic_noise_v: 1e-3,
            grid_step_hz: 0.01,
            t0_sample_position: 0.5,
            seed: 1,
        }
    }
}

/// Typical field sensitivity of a seismic sensor kind: 100 mV/g
/// accelerometer (0.0102 V/(m/s²)), 20 mV/(mm/s) velocity pick-up
/// (20 V/(m/s)), or a 7.87 V/mm displacement sensor.
pub fn default_seismic_sensitivity(kind: SensorKind) -> f64 {
    match kind {
        SensorKind::Acceleration => 0.1 / crate::sim::machine::STANDARD_GRAVITY,
        SensorKind::Velocity => 20.0,
        SensorKind::Displacement => 7870.0,
    }
}

/// Synthesises the signal set of `machine` (with `effects`) and its truth run
/// directory (noise-free phasors on the speed grid).
pub fn synthesise(
    machine: &Machine,
    effects: &EffectSet,
    opts: &SignalOptions,
) -> Result<(SignalSet, RunDir), SignalsError> {
    let samples = opts.sample_count()?;
    let r = opts.rundown;
    let fs = opts.sample_rate_hz;
    let max_speed = r.start_hz.max(r.end_hz);
    if fs < 8.0 * max_speed {
        return Err(SignalsError::Request(format!(
            "sample rate {fs} Hz is below 8 samples per revolution at {max_speed} Hz"
        )));
    }
    let step = opts.grid_step_hz;
    if !(step.is_finite() && step > 0.0) {
        return Err(SignalsError::Request(format!(
            "grid step must be finite and > 0 Hz (got {step})"
        )));
    }
    for (what, v) in [
        ("probe sensitivity", opts.probe_sensitivity),
        ("seismic sensitivity", opts.seismic_sensitivity),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(SignalsError::Request(format!(
                "{what} must be finite and > 0 (got {v})"
            )));
        }
    }
    for (what, v) in [
        ("probe noise", opts.probe_noise_v),
        ("seismic noise", opts.seismic_noise_v),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(SignalsError::Request(format!(
                "{what} must be finite and >= 0 V (got {v})"
            )));
        }
    }
    if !opts.probe_gap_v.is_finite() {
        return Err(SignalsError::Request(
            "probe gap voltage must be finite".into(),
        ));
    }

    // Speed grid covering the run with 4 steps of margin each side.
    let lo = r.start_hz.min(r.end_hz);
    let hi = max_speed;
    let g0 = ((lo / step).floor() - 4.0).max(0.0) * step;
    let g0 = if g0 <= 0.0 { step.min(lo / 2.0) } else { g0 };
    let points = ((hi - g0) / step).ceil() + 5.0;
    if points > MAX_GRID_POINTS as f64 {
        return Err(SignalsError::Request(format!(
            "grid step {step} Hz needs {points:.3e} response solves over {g0}..{hi} Hz; at most {MAX_GRID_POINTS} are made: use a step of at least {:.3e} Hz",
            (hi - g0) / (MAX_GRID_POINTS as f64 - 5.0)
        )));
    }
    let n_grid = points as usize;
    // Memory before anything large is allocated (the check speeds are at
    // most one per grid interval plus CHECK_SPEEDS + 1).
    let needed = budget::signals_bytes(machine, samples, n_grid, n_grid + CHECK_SPEEDS + 1);
    budget::check_signals(
        &format!(
            "signals: {samples} samples × {} channels, {n_grid} grid speeds",
            machine.bearings.len() * 4
        ),
        needed,
        budget::available_bytes(),
    )
    .map_err(SignalsError::Request)?;
    // The sample file indexes i16 codes by a 64-bit count; beyond this a
    // run is a mistake, whatever the memory.
    if samples.saturating_mul(machine.bearings.len() as u64 * 4) > 2_000_000_000 {
        return Err(SignalsError::Request(format!(
            "{samples} samples × {} channels is too large",
            machine.bearings.len() * 4
        )));
    }
    let grid: Vec<f64> = (0..n_grid).map(|i| g0 + i as f64 * step).collect();
    let solver = UnbalanceSolver::new(machine, effects)?;
    let mut ticker = Ticker::new("signals: grid speeds", n_grid, true);
    let response = solver.run_with(&grid, false, &mut |done| ticker.tick(done));
    ticker.finish();
    let truth = response?.to_run_dir(None)?;
    let spline =
        PhasorSpline::from_measurements(&truth.measurements).map_err(SignalsError::Request)?;

    // Measure the interpolation error where the run is: at the midpoint of
    // every grid interval the run overlaps and at CHECK_SPEEDS speeds spread
    // over the run (a grid coarser than the run has no midpoint inside it).
    let mut checks: Vec<f64> = grid
        .windows(2)
        .filter(|w| w[1] >= lo && w[0] <= hi)
        .map(|w| 0.5 * (w[0] + w[1]))
        .collect();
    checks.extend((0..=CHECK_SPEEDS).map(|i| lo + (hi - lo) * i as f64 / CHECK_SPEEDS as f64));
    checks.sort_by(f64::total_cmp);
    checks.dedup();
    let check_rows = solver.run_with(&checks, false, &mut |_| {})?.measurements();

    // Velocity and acceleration channels are written from the model's
    // derivatives in speed (five-point differences at step d) through a
    // quintic Hermite interpolant, and measured at the check speeds against
    // the same differences there; the differences' own truncation error is
    // estimated by Richardson's rule from a second set at step 2d
    // (|D(2d) − D(d)|/15, d⁴ behaviour) and added.
    let omega_dot = TAU * r.slope();
    let nb = machine.bearings.len();
    let (hermites, at_checks) = if opts.seismic_kind == SensorKind::Displacement {
        (Vec::new(), None)
    } else {
        // Every stencil speed (down to f − 4d at the checks) stays ≥ 0.
        let d = difference_step(step).min(0.2 * grid[0]);
        let hermites = pedestal_derivatives(&solver, nb, &grid, d)?
            .into_iter()
            .map(|v| QuinticHermite::new(grid.clone(), v))
            .collect::<Result<Vec<_>, _>>()
            .map_err(SignalsError::Request)?;
        let fine = pedestal_derivatives(&solver, nb, &checks, d)?;
        let coarse = pedestal_derivatives(&solver, nb, &checks, 2.0 * d)?;
        (hermites, Some((fine, coarse)))
    };

    // Channels: per bearing rel_y, rel_z (probes), ped_y, ped_z (seismic).
    let mut channels = Vec::new();
    for (bi, b) in machine.bearings.iter().enumerate() {
        for q in ChannelQuantity::ALL {
            let probe = matches!(q, ChannelQuantity::RelY | ChannelQuantity::RelZ);
            let mut max_x: f64 = 0.0;
            for m in truth
                .measurements
                .iter()
                .chain(&check_rows)
                .filter(|m| m.bearing == b.name)
            {
                if m.speed_hz >= lo && m.speed_hz <= hi {
                    max_x = max_x.max(q.of(m).norm());
                }
            }
            let mut err: f64 = 0.0;
            for m in check_rows.iter().filter(|m| m.bearing == b.name) {
                if let Some(v) = spline.at(&b.name, q, m.speed_hz) {
                    err = err.max((v - q.of(m)).norm());
                }
            }
            let mut rel = if max_x > 0.0 { err / max_x } else { 0.0 };
            if let (Some((fine, coarse)), false) = (&at_checks, probe) {
                let idx = 2 * bi + usize::from(q == ChannelQuantity::PedZ);
                (err, rel) = written_error(
                    opts.seismic_kind,
                    &hermites[idx],
                    &checks,
                    (&fine[idx], &coarse[idx]),
                    omega_dot,
                    (lo, hi),
                );
            }
            channels.push(Channel {
                name: format!("{}_{}", b.name, q.name()),
                bearing: b.name.clone(),
                bearing_index: bi,
                quantity: q,
                kind: if probe {
                    SensorKind::Displacement
                } else {
                    opts.seismic_kind
                },
                sensitivity: if probe {
                    opts.probe_sensitivity
                } else {
                    opts.seismic_sensitivity
                },
                offset_v: if probe { opts.probe_gap_v } else { 0.0 },
                noise_v_rms: if probe {
                    opts.probe_noise_v
                } else {
                    opts.seismic_noise_v
                },
                clipped_samples: 0,
                signal_peak_v: 0.0,
                interpolation_error_m: err,
                interpolation_error_rel: rel,
            });
        }
    }
    if let Some(c) = channels.iter().find(|c| {
        c.interpolation_error_rel.is_nan() || c.interpolation_error_rel > MAX_INTERPOLATION_ERROR
    }) {
        return Err(SignalsError::Request(format!(
            "grid step {step} Hz cannot represent the response: channel {} is interpolated with an error of {:.2e} of its peak (measured at {} speeds over the run; at most {MAX_INTERPOLATION_ERROR} accepted): use a smaller --grid-step (the error falls as step⁴)",
            c.name,
            c.interpolation_error_rel,
            checks.len()
        )));
    }
    let n = channels.len();
    let chan_splines: Vec<&ComplexSpline> = channels
        .iter()
        .map(|c| {
            spline
                .get(&c.bearing, c.quantity)
                .ok_or_else(|| SignalsError::Request(format!("no response for channel {}", c.name)))
        })
        .collect::<Result<_, _>>()?;

    let mut rng = StdRng::seed_from_u64(opts.seed);
    let normal = Normal::new(0.0, 1.0)
        .map_err(|e| SignalsError::Request(format!("noise distribution: {e}")))?;
    // The interpolant each channel is written from: the Hermite one for
    // velocity and acceleration channels.
    let chan_hermites: Vec<Option<&QuinticHermite>> = channels
        .iter()
        .map(|c| {
            let pedestal = matches!(c.quantity, ChannelQuantity::PedY | ChannelQuantity::PedZ);
            let idx = 2 * c.bearing_index + usize::from(c.quantity == ChannelQuantity::PedZ);
            (pedestal && c.kind != SensorKind::Displacement)
                .then(|| hermites.get(idx))
                .flatten()
        })
        .collect();
    let mut codes = vec![0i16; samples as usize * n];
    for k in 0..samples as usize {
        let t = (k as f64 - opts.t0_sample_position) / fs;
        let f = r.speed_hz(t);
        let omega = TAU * f;
        let rot = C64::from_polar(1.0, r.angle_rad(t));
        for (ci, c) in channels.iter_mut().enumerate() {
            let xs = match chan_hermites[ci] {
                Some(h) => h.eval(f),
                None => {
                    let (x, dxdf, d2xdf2) = chan_splines[ci].eval(f);
                    [x, dxdf, d2xdf2]
                }
            };
            let phasor = sensed_phasor(c.kind, xs, omega, omega_dot);
            let value = (phasor * rot).re;
            let noise = if c.noise_v_rms > 0.0 {
                c.noise_v_rms * normal.sample(&mut rng)
            } else {
                0.0
            };
            c.signal_peak_v = c.signal_peak_v.max((c.sensitivity * value).abs());
            let volts = c.offset_v + c.sensitivity * value + noise;
            let (code, clipped) = opts.adc.quantise(volts);
            if clipped {
                c.clipped_samples += 1;
            }
            codes[k * n + ci] = code;
        }
    }

    let mut keyphasor = Vec::new();
    let pulses = r.revolutions();
    for j in 0..=pulses {
        let p = r.pulse_time(j) * fs + opts.t0_sample_position;
        if p < samples as f64 {
            keyphasor.push(p);
        }
    }
    let max_rel_error = channels
        .iter()
        .map(|c| c.interpolation_error_rel)
        .fold(0.0, f64::max);
    let header = SignalHeader {
        format: FORMAT_NAME.into(),
        version: FORMAT_VERSION,
        machine: machine.name.clone(),
        sample_rate_hz: fs,
        samples,
        adc: opts.adc,
        rundown: r,
        t0_sample_position: opts.t0_sample_position,
        keyphasor_pulses: keyphasor.len() as u64,
        channels,
        interpolation: Interpolation {
            method: InterpolationMethod::NaturalCubicSpline,
            grid_step_hz: step,
            max_rel_error,
        },
        seed: opts.seed,
        effects: truth
            .truth
            .as_ref()
            .map(|t| t.effects.clone())
            .unwrap_or_default(),
    };
    Ok((
        SignalSet {
            header,
            codes,
            keyphasor,
        },
        truth,
    ))
}

/// [`synthesise`] and write the signal set with its truth to `dir`.
pub fn synthesise_to(
    machine: &Machine,
    effects: &EffectSet,
    opts: &SignalOptions,
    dir: &Path,
) -> Result<SignalSet, SignalsError> {
    let (set, truth) = synthesise(machine, effects, opts)?;
    set.write(dir)?;
    write_truth(dir, &truth)?;
    Ok(set)
}

/// Largest error of what a velocity or acceleration channel is written from
/// (the `hermite` interpolant, sensed as `kind`) at the check speeds
/// `checks` [Hz], against the model's five-point differences there at steps
/// d and 2d (`fine`, `coarse`), plus the differences' own truncation error
/// |D(2d) − D(d)|/15: (largest displacement error [m], largest sensed error
/// relative to the channel's largest |sensed phasor| over the run's speeds
/// `run` [Hz]).
pub(super) fn written_error(
    kind: SensorKind,
    hermite: &QuinticHermite,
    checks: &[f64],
    (fine, coarse): (&[[C64; 3]], &[[C64; 3]]),
    omega_dot: f64,
    run: (f64, f64),
) -> (f64, f64) {
    let (mut err_m, mut err, mut peak) = (0.0f64, 0.0f64, 0.0f64);
    for ((&f, x), x2) in checks.iter().zip(fine).zip(coarse) {
        let omega = TAU * f;
        let truth = sensed_phasor(kind, *x, omega, omega_dot);
        let rough = sensed_phasor(kind, *x2, omega, omega_dot);
        let w = hermite.eval(f);
        err_m = err_m.max((w[0] - x[0]).norm());
        let e = (sensed_phasor(kind, w, omega, omega_dot) - truth).norm()
            + (rough - truth).norm() / 15.0;
        err = err.max(e);
        if f >= run.0 && f <= run.1 {
            peak = peak.max(truth.norm());
        }
    }
    (err_m, if peak > 0.0 { err / peak } else { 0.0 })
}
