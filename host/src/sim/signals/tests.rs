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
