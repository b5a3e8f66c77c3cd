//! The field box's f32 recursive least squares (plinth_shared::rls) against
//! the host's f64 batch fit, on the same run-down after one pass.

use num_complex::Complex;
use plinth::estimate::Observation;
use plinth::identify::{fit_pedestal, pedestal_points, Options, Parameter};
use plinth::rundir::RunDir;
use plinth_shared::phasor::omega_from_hz;
use plinth_shared::rls::PedestalRls;
use plinth_tests::{paper_like_run, rel_err};

fn points(run: &RunDir, bearing: &str) -> Vec<Observation> {
    let schedules = run.bearing_schedules();
    pedestal_points(
        run.measurements.iter().filter(|m| m.bearing == bearing),
        &schedules[bearing],
    )
    .unwrap()
}

fn c32(c: Complex<f64>) -> Complex<f32> {
    Complex::new(c.re as f32, c.im as f32)
}

/// Feeds every speed once, in run-down order (highest speed first).
fn rls_pass(points: &[Observation]) -> [f64; 5] {
    let mut rls = PedestalRls::<f32>::default();
    let mut order: Vec<&Observation> = points.iter().collect();
    order.sort_by(|a, b| b.speed_hz.total_cmp(&a.speed_hz));
    for p in order {
        let accepted = rls.update(
            omega_from_hz(p.speed_hz as f32),
            &p.ped.map(c32),
            &p.force().map(c32),
        );
        assert_eq!(accepted, 4);
    }
    rls.estimate().unwrap().theta.map(f64::from)
}

#[test]
fn f32_rls_agrees_with_the_f64_batch_fit_on_exact_data() {
    let run = paper_like_run(100, 1.0, None);
    for bearing in ["left", "right"] {
        let pts = points(&run, bearing);
        let batch = fit_pedestal(bearing, &pts, &Options::default()).unwrap();
        let rls = rls_pass(&pts);
        for p in Parameter::ALL {
            let (a, b) = (rls[p as usize], batch.pedestal.get(p));
            assert!(rel_err(a, b) < 1e-3, "{bearing} {}: {a} vs {b}", p.name());
        }
    }
}

#[test]
fn f32_rls_agrees_with_the_f64_batch_fit_on_two_digit_data() {
    // Rounded data: the least-squares solution is not the truth, so this
    // compares the two solvers, not each with the truth.
    let run = paper_like_run(100, 50.0, Some(2));
    for bearing in ["left", "right"] {
        let pts = points(&run, bearing);
        let batch = fit_pedestal(bearing, &pts, &Options::default()).unwrap();
        let rls = rls_pass(&pts);
        for p in Parameter::ALL {
            let (a, b) = (rls[p as usize], batch.pedestal.get(p));
            assert!(rel_err(a, b) < 1e-3, "{bearing} {}: {a} vs {b}", p.name());
        }
    }
}
