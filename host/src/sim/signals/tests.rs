//! Unit tests of the signal model, format and synthesis.

use super::*;

#[test]
fn pulses_are_at_whole_revolutions() {
    let r = RunDown {
        start_hz: 200.0,
        end_hz: 5.0,
        rate_hz_per_s: 5.0,
    };
    for j in [0u64, 1, 10, 1000, r.revolutions()] {
        let t = r.pulse_time(j);
        assert!((r.angle_rad(t) / TAU - j as f64).abs() < 1e-9, "pulse {j}");
    }
    // Total revolutions: mean speed × duration = 102.5 Hz × 39 s.
    assert_eq!(r.revolutions(), 3997);
    assert!(r.pulse_time(r.revolutions()) <= r.duration_s());
}

#[test]
fn spline_is_exact_for_cubics_inside_and_has_derivatives() {
    // A natural spline reproduces a linear function exactly.
    let x: Vec<f64> = (0..20).map(|i| i as f64 * 0.5).collect();
    let y: Vec<C64> = x.iter().map(|&v| C64::new(2.0 * v + 1.0, -v)).collect();
    let s = ComplexSpline::new(x, y).unwrap();
    let (v, d, dd) = s.eval(3.3);
    assert!((v - C64::new(7.6, -3.3)).norm() < 1e-12);
    assert!((d - C64::new(2.0, -1.0)).norm() < 1e-12);
    assert!(dd.norm() < 1e-12);
    // A smooth function: error O(h⁴) away from the ends.
    let x: Vec<f64> = (0..200).map(|i| i as f64 * 0.05).collect();
    let y: Vec<C64> = x.iter().map(|&v| C64::from_polar(1.0, v)).collect();
    let s = ComplexSpline::new(x, y).unwrap();
    let (v, d, _) = s.eval(5.0123);
    assert!((v - C64::from_polar(1.0, 5.0123)).norm() < 1e-6);
    assert!((d - C64::i() * C64::from_polar(1.0, 5.0123)).norm() < 1e-4);
}

#[test]
fn adc_quantises_and_clips() {
    let adc = Adc::ad7606();
    assert_eq!(adc.quantise(0.0), (0, false));
    assert_eq!(adc.quantise(10.0 / 32768.0 * 3.4), (3, false));
    assert_eq!(adc.quantise(10.0), (32767, true));
    assert_eq!(adc.quantise(-10.0), (-32768, false));
    assert_eq!(adc.quantise(-11.0), (-32768, true));
    assert!(Adc::new(17, 10.0).is_err());
}

#[test]
fn rundown_parses_and_rejects() {
    let r = RunDown::parse("200:5:5").unwrap();
    assert_eq!(r.slope(), -5.0);
    assert_eq!(r.duration_s(), 39.0);
    assert!(RunDown::parse("200:5").is_err());
    assert!(RunDown::parse("200:0:5").is_err());
    assert!(RunDown::parse("200:5:-1").is_err());
    assert!(RunDown::parse("5:5:1").is_err());
}

/// A resonance's displacement x(f) = 1/(f₀² − f² + i·f·c) [m] and its
/// closed-form first and second derivatives in f.
fn resonance(f: f64) -> [C64; 3] {
    let (f0, c) = (50.0, 2.0);
    let d = C64::new(f0 * f0 - f * f, f * c);
    let dd = C64::new(-2.0 * f, c);
    let x = 1.0 / d;
    let x1 = -dd / (d * d);
    let x2 = 2.0 * dd * dd / (d * d * d) - C64::new(-2.0, 0.0) / (d * d);
    [x, x1, x2]
}

#[test]
fn the_error_of_a_derivative_channel_is_measured_against_closed_form_derivatives() {
    // A grid of 1 Hz over a resonance 2 Hz wide, a run-down of 5 Hz/s.
    let grid: Vec<f64> = (30..=70).map(f64::from).collect();
    let s = ComplexSpline::new(
        grid.clone(),
        grid.iter().map(|&f| resonance(f)[0]).collect(),
    )
    .unwrap();
    let omega_dot = TAU * 5.0;
    let checks: Vec<f64> = (0..400).map(|k| 31.0 + 38.0 * k as f64 / 400.0).collect();
    let d = 0.01;
    let points = || {
        checks.iter().map(move |&f| {
            (
                f,
                [resonance(f - d)[0], resonance(f)[0], resonance(f + d)[0]],
            )
        })
    };
    // Exact: closed-form derivatives.
    let exact = |kind| {
        let (mut err, mut peak) = (0.0f64, 0.0f64);
        for &f in &checks {
            let [x, x1, x2] = resonance(f);
            let w = TAU * f;
            let truth = sensed_phasor(kind, x, x1, x2, w, omega_dot);
            let (v, dv, d2v) = s.eval(f);
            err = err.max((sensed_phasor(kind, v, dv, d2v, w, omega_dot) - truth).norm());
            peak = peak.max(truth.norm());
        }
        err / peak
    };
    let run = (30.0, 70.0);
    let disp = written_error(
        SensorKind::Displacement,
        Some(&s),
        points(),
        d,
        omega_dot,
        run,
    );
    for kind in [SensorKind::Velocity, SensorKind::Acceleration] {
        let measured = written_error(kind, Some(&s), points(), d, omega_dot, run);
        let truth = exact(kind);
        assert!(
            (measured / truth - 1.0).abs() < 0.01,
            "{kind:?}: {measured} vs {truth}"
        );
        // Not the displacement's figure reported again.
        assert!(
            (measured / disp - 1.0).abs() > 1e-3,
            "{kind:?}: {measured} vs displacement {disp}"
        );
    }
}
