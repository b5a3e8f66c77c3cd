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

/// A resonance x(f) = 1/(f₀² − f² + i·f·c) [m] at f₀ = 45 Hz with a
/// half-width of ≈ c/2 = 0.15 Hz (a natural cubic spline on a 0.01 Hz grid
/// puts 4e-4 of the peak into a 20 Hz/s acceleration channel, as on the
/// damped paper machine's 45.1 Hz mode: 2.6e-4), and
/// its closed-form first and second derivatives in f.
fn resonance(f: f64) -> [C64; 3] {
    let (f0, c) = (45.0, 0.3);
    let d = C64::new(f0 * f0 - f * f, f * c);
    let dd = C64::new(-2.0 * f, c);
    let x = 1.0 / d;
    [
        x,
        -dd / (d * d),
        2.0 * dd * dd / (d * d * d) + 2.0 / (d * d),
    ]
}

#[test]
fn quintic_hermite_is_exact_for_quintics() {
    let p = |x: f64| {
        let c = [
            C64::new(1.0, -2.0),
            C64::new(0.5, 0.3),
            C64::new(-0.2, 0.1),
            C64::new(0.05, -0.4),
            C64::new(0.01, 0.02),
            C64::new(-0.003, 0.001),
        ];
        let mut v = [C64::new(0.0, 0.0); 3];
        for (k, ck) in c.iter().enumerate() {
            let k = k as i32;
            v[0] += ck * x.powi(k);
            if k >= 1 {
                v[1] += ck * (f64::from(k) * x.powi(k - 1));
            }
            if k >= 2 {
                v[2] += ck * (f64::from(k * (k - 1)) * x.powi(k - 2));
            }
        }
        v
    };
    let x: Vec<f64> = vec![0.0, 0.7, 1.5, 3.0, 3.2];
    let h = QuinticHermite::new(x.clone(), x.iter().map(|&v| p(v)).collect()).unwrap();
    for t in [0.0, 0.3, 0.7, 1.1, 2.9, 3.1, 3.2] {
        let (got, want) = (h.eval(t), p(t));
        for k in 0..3 {
            assert!(
                (got[k] - want[k]).norm() < 1e-10,
                "x {t} d{k}: {got:?} vs {want:?}"
            );
        }
    }
    assert!(QuinticHermite::new(vec![1.0, 1.0], vec![p(1.0); 2]).is_err());
}

#[test]
fn five_point_differences_and_their_error_estimate_match_closed_form() {
    let d = difference_step(0.01);
    assert_eq!(d, 1e-3);
    let at = |f: f64, d: f64| {
        five_point(
            [-2.0, -1.0, 0.0, 1.0, 2.0].map(|k| resonance(f + k * d)[0]),
            d,
        )
    };
    for f in [44.5, 44.95, 45.0, 45.03, 45.1, 46.0] {
        let exact = resonance(f);
        let fine = at(f, d);
        for k in 1..3 {
            let err = (fine[k] - exact[k]).norm();
            assert!(err < 2e-5 * exact[k].norm(), "f {f} d{k}: {err:e}");
        }
        // Richardson's estimate |D(2h) − D(h)|/15 is the error's size where
        // truncation (h⁴) dominates the rounding: at h = 5e-3 Hz.
        let h = 5e-3;
        let (fine, coarse) = (at(f, h), at(f, 2.0 * h));
        for k in 1..3 {
            let err = (fine[k] - exact[k]).norm();
            let estimate = (coarse[k] - fine[k]).norm() / 15.0;
            assert!(
                (estimate / err - 1.0).abs() < 0.1,
                "f {f} d{k}: error {err:e}, estimate {estimate:e}"
            );
        }
    }
}

#[test]
fn acceleration_is_written_within_its_measured_error_where_the_spline_was_not() {
    // A 0.01 Hz grid over the resonance, a 20 Hz/s run-down (the case
    // signals_roundtrip's grid-step test makes at < 1e-5 of the peak).
    let step = 0.01;
    let grid: Vec<f64> = (0..=1000).map(|k| 40.0 + k as f64 * step).collect();
    let checks: Vec<f64> = grid.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
    let omega_dot = -TAU * 20.0;
    let d = difference_step(step);
    let diff = |fs: &[f64], d: f64| -> Vec<[C64; 3]> {
        fs.iter()
            .map(|&f| {
                five_point(
                    [-2.0, -1.0, 0.0, 1.0, 2.0].map(|k| resonance(f + k * d)[0]),
                    d,
                )
            })
            .collect()
    };
    let hermite = QuinticHermite::new(grid.clone(), diff(&grid, d)).unwrap();
    let (fine, coarse) = (diff(&checks, d), diff(&checks, 2.0 * d));
    let kind = SensorKind::Acceleration;
    let (_, reported) = written_error(
        kind,
        &hermite,
        &checks,
        (&fine, &coarse),
        omega_dot,
        (40.0, 50.0),
    );
    // The true error of what is written, against closed-form derivatives.
    let true_error = |eval: &dyn Fn(f64) -> [C64; 3]| {
        let (mut e, mut peak) = (0.0f64, 0.0f64);
        for &f in &checks {
            let w = TAU * f;
            let truth = sensed_phasor(kind, resonance(f), w, omega_dot);
            e = e.max((sensed_phasor(kind, eval(f), w, omega_dot) - truth).norm());
            peak = peak.max(truth.norm());
        }
        e / peak
    };
    let written = true_error(&|f| hermite.eval(f));
    assert!(written < 2e-6, "{written:e}");
    assert!(
        reported >= 0.5 * written && reported < 1e-5,
        "reported {reported:e}, true {written:e}"
    );
    // The natural cubic spline's second derivative (what was written
    // before) errs far beyond that.
    let spline = ComplexSpline::new(
        grid.clone(),
        grid.iter().map(|&f| resonance(f)[0]).collect(),
    )
    .unwrap();
    let spline_eval = |f: f64| {
        let (x, a, b) = spline.eval(f);
        [x, a, b]
    };
    let old = true_error(&spline_eval);
    assert!(old > 1e-4, "{old:e}");
    assert!(
        reported < 0.05 * old,
        "reported {reported:e}, spline {old:e}"
    );
}
