//! `plinth signals`: the signal-set files round-trip, the samples carry the
//! truth phasors (recovered here by an angle-domain Fourier coefficient, an
//! extraction independent of the firmware's), and bad files are rejected
//! with the file and place named.

use num_complex::Complex;
use plinth::sim::signals::{
    read_truth, synthesise, synthesise_to, ChannelQuantity, PhasorSpline, RunDown, SensorKind,
    SignalOptions, SignalSet, KEYPHASOR_FILE, SAMPLES_FILE,
};
use plinth::sim::{EffectSet, Machine};
use std::f64::consts::TAU;

fn machine() -> Machine {
    Machine::from_toml_str(plinth::paper::DAMPED_MACHINE, "feng-hahn-1997-damped.toml").unwrap()
}

/// A short run-down through the pedestal resonances, no noise.
fn options(kind: SensorKind) -> SignalOptions {
    SignalOptions {
        rundown: RunDown {
            start_hz: 80.0,
            end_hz: 70.0,
            rate_hz_per_s: 20.0,
        },
        probe_noise_v: 0.0,
        seismic_noise_v: 0.0,
        seismic_kind: kind,
        seismic_sensitivity: plinth::sim::signals::default_seismic_sensitivity(kind),
        ..SignalOptions::default()
    }
}

/// Angle-domain 1X coefficient of channel `n` over revolution j (between
/// pulses j and j+1), in the transducer's unit, with the exact shaft angle.
fn revolution_phasor(set: &SignalSet, n: usize, j: usize) -> (f64, Complex<f64>) {
    let h = &set.header;
    let ch = &h.channels[n];
    let r = h.rundown;
    let (p0, p1) = (set.keyphasor[j], set.keyphasor[j + 1]);
    let mut sum = Complex::new(0.0, 0.0);
    let k0 = p0.ceil() as usize;
    let k1 = p1.floor() as usize;
    for k in k0..=k1 {
        let t = set.time_s(k);
        let theta = r.angle_rad(t);
        let dtheta = TAU * r.speed_hz(t) / h.sample_rate_hz;
        // Trapezoid weights with the fractional ends at the pulses.
        let w = if k == k0 {
            0.5 + (k0 as f64 - p0)
        } else if k == k1 {
            0.5 + (p1 - k1 as f64)
        } else {
            1.0
        };
        let x = (set.volts(k, n) - ch.offset_v) / ch.sensitivity;
        sum += Complex::from_polar(1.0, -theta) * (x * w * dtheta);
    }
    let speed = h.sample_rate_hz / (p1 - p0);
    (speed, sum / std::f64::consts::PI)
}

#[test]
fn samples_carry_the_truth_phasors() {
    for kind in [SensorKind::Acceleration, SensorKind::Velocity] {
        let (set, truth) = synthesise(&machine(), &EffectSet::none(), &options(kind)).unwrap();
        let spline = PhasorSpline::from_measurements(&truth.measurements).unwrap();
        assert_eq!(set.channels(), 8);
        let mut worst: f64 = 0.0;
        for j in [2usize, 10, 20, 35] {
            for (n, ch) in set.header.channels.iter().enumerate() {
                let (speed, q) = revolution_phasor(&set, n, j);
                let omega = TAU * speed;
                let x = match ch.kind {
                    SensorKind::Displacement => q,
                    SensorKind::Velocity => q / (Complex::i() * omega),
                    SensorKind::Acceleration => q / (-omega * omega),
                };
                let want = spline.at(&ch.bearing, ch.quantity, speed).unwrap();
                // One ADC step in metres, and the channel's size over the run.
                let lsb_m = set.header.adc.volts_per_code / ch.sensitivity
                    * match ch.kind {
                        SensorKind::Displacement => 1.0,
                        SensorKind::Velocity => 1.0 / omega,
                        SensorKind::Acceleration => 1.0 / (omega * omega),
                    };
                let err = (x - want).norm();
                // Quantisation averages over ~700 samples per revolution; the
                // run-down (20 Hz/s) changes X by ~0.4 % per revolution near
                // the resonances, which the revolution mean absorbs to O(ΔX²).
                let tol = 0.02 * want.norm() + 0.2 * lsb_m;
                assert!(
                    err < tol,
                    "{kind:?} {} rev {j} at {speed:.3} Hz: {x} vs {want} (|err| {err:.3e} m > {tol:.3e})",
                    ch.name
                );
                worst = worst.max(err / want.norm().max(1e-12));
            }
        }
        assert!(worst.is_finite());
    }
}

#[test]
fn files_round_trip_and_keyphasor_is_at_whole_revolutions() {
    let dir = tempfile::tempdir().unwrap();
    let set = synthesise_to(
        &machine(),
        &EffectSet::none(),
        &options(SensorKind::Acceleration),
        dir.path(),
    )
    .unwrap();
    let back = SignalSet::read(dir.path()).unwrap();
    assert_eq!(back.header, set.header);
    assert_eq!(back.codes, set.codes);
    assert_eq!(back.keyphasor.len(), set.keyphasor.len());
    for (a, b) in back.keyphasor.iter().zip(&set.keyphasor) {
        assert!((a - b).abs() <= 1e-9 * a.abs().max(1.0));
    }
    let r = set.header.rundown;
    for (j, p) in set.keyphasor.iter().enumerate() {
        let t = (p - set.header.t0_sample_position) / set.header.sample_rate_hz;
        assert!((r.angle_rad(t) / TAU - j as f64).abs() < 1e-6, "pulse {j}");
    }
    // 0.5 s at ~75 Hz: 37 whole revolutions plus pulse 0.
    assert_eq!(set.keyphasor.len(), 38);
    let truth = read_truth(dir.path()).unwrap();
    assert!(truth.truth.is_some());
    assert_eq!(truth.measurements.len() % 2, 0);
    // The interpolation error was measured and is far below one ADC step
    // relative to these signals.
    assert!(
        set.header.interpolation.max_rel_error < 1e-4,
        "{}",
        set.header.interpolation.max_rel_error
    );
    assert!(set.header.channels.iter().all(|c| c.clipped_samples == 0));
    assert!(set
        .header
        .channels
        .iter()
        .any(|c| c.quantity == ChannelQuantity::PedZ));
}

#[test]
fn bad_files_are_rejected_with_file_and_place() {
    let dir = tempfile::tempdir().unwrap();
    synthesise_to(
        &machine(),
        &EffectSet::none(),
        &options(SensorKind::Velocity),
        dir.path(),
    )
    .unwrap();
    // Truncated samples: the file and the byte offset are named.
    let sp = dir.path().join(SAMPLES_FILE);
    let bytes = std::fs::read(&sp).unwrap();
    std::fs::write(&sp, &bytes[..bytes.len() - 3]).unwrap();
    let e = SignalSet::read(dir.path()).unwrap_err().to_string();
    assert!(e.contains(SAMPLES_FILE) && e.contains("byte offset"), "{e}");
    std::fs::write(&sp, &bytes).unwrap();
    // A keyphasor row out of order: the line is named.
    let kp = dir.path().join(KEYPHASOR_FILE);
    let text = std::fs::read_to_string(&kp).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    lines.swap(3, 4);
    std::fs::write(&kp, lines.join("\n")).unwrap();
    let e = SignalSet::read(dir.path()).unwrap_err().to_string();
    assert!(e.contains(KEYPHASOR_FILE) && e.contains(":4:"), "{e}");
    std::fs::write(&kp, &text).unwrap();
    // A future version.
    let hp = dir.path().join("signals.json");
    let h = std::fs::read_to_string(&hp).unwrap();
    std::fs::write(&hp, h.replace("\"version\": 1", "\"version\": 2")).unwrap();
    let e = SignalSet::read(dir.path()).unwrap_err().to_string();
    assert!(e.contains("version"), "{e}");
    std::fs::write(&hp, &h).unwrap();
    assert!(SignalSet::read(dir.path()).is_ok());
}

#[test]
fn a_probe_near_full_scale_clips_and_says_so() {
    let opts = SignalOptions {
        probe_gap_v: -10.0,
        ..options(SensorKind::Acceleration)
    };
    let (set, _) = synthesise(&machine(), &EffectSet::none(), &opts).unwrap();
    let probes: Vec<_> = set
        .header
        .channels
        .iter()
        .filter(|c| c.kind == SensorKind::Displacement)
        .collect();
    assert!(probes.iter().all(|c| c.clipped_samples > 0));
    assert!(set.codes.contains(&i16::MIN));
}

/// Issue 13: a grid step the response cannot be represented on is refused
/// with the measured error (100 Hz over a 40-60 Hz run had reported "0.00e0"
/// and written signals off by 18×), and one that would need billions of
/// solves is refused before allocating them.
#[test]
fn grid_steps_that_cannot_represent_the_response_are_refused() {
    let run = |step: f64| {
        let mut o = options(SensorKind::Acceleration);
        o.rundown = RunDown {
            start_hz: 60.0,
            end_hz: 40.0,
            rate_hz_per_s: 20.0,
        };
        o.grid_step_hz = step;
        synthesise(&machine(), &EffectSet::none(), &o).map(|(set, _)| set)
    };
    for step in [100.0, 5.0] {
        let e = run(step).expect_err("coarse grid").to_string();
        assert!(
            e.contains("cannot represent the response") && e.contains("of its peak"),
            "{e}"
        );
    }
    let e = run(1e-9).expect_err("fine grid").to_string();
    assert!(
        e.contains("response solves") && e.contains("at most 200000"),
        "{e}"
    );
    let set = run(0.01).unwrap();
    let err = set.header.interpolation.max_rel_error;
    assert!(err > 0.0 && err < 1e-5, "{err}");
}
