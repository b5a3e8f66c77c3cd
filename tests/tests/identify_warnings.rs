//! The identification warns instead of returning confident nonsense: too few
//! speeds, no pedestal resonance in range, collinear or ill-conditioned data,
//! non-finite input.

use plinth::estimate::Observation;
use plinth::identify::synthetic::{linspace, SyntheticRun};
use plinth::identify::{fit_pedestal, identify_run, pedestal_points, Options, WarningKind};
use plinth::rundir::RunDir;
use plinth_tests::rel_err;

fn run_with_speeds(speeds_hz: Vec<f64>) -> RunDir {
    let mut recipe = SyntheticRun::paper_like(true, 2);
    recipe.speeds_hz = speeds_hz;
    recipe.build().unwrap()
}

fn left_points(run: &RunDir) -> Vec<Observation> {
    pedestal_points(
        run.measurements.iter().filter(|m| m.bearing == "left"),
        &run.bearing_schedules()["left"],
    )
    .unwrap()
}

fn kinds(fit: &plinth::identify::PedestalFit) -> Vec<WarningKind> {
    fit.warnings.iter().map(|w| w.kind).collect()
}

#[test]
fn too_few_speeds() {
    // Two speeds: 8 equations for 5 unknowns solve exactly, but there is no
    // way to tell how good that is.
    let run = run_with_speeds(vec![30.0, 60.0]);
    let id = identify_run(&run, &Options::default()).unwrap();
    for p in &id.pedestals {
        assert!(p.has_warning(WarningKind::TooFewSpeeds), "{:?}", kinds(p));
        assert!(!p.trusted);
        assert_eq!(p.speeds, 2);
        let w = &p.warnings[0].message;
        assert!(w.contains("2 distinct speed"), "{w}");
    }
    // One speed, R only: 2 equations for 3 unknowns.
    let run = run_with_speeds(vec![40.0]);
    let fit = fit_pedestal(
        "left",
        &left_points(&run),
        &Options::with_mode(plinth::identify::EquationMode::Real),
    )
    .unwrap();
    assert!(fit.has_warning(WarningKind::TooFewSpeeds));
    assert!(!fit.trusted);
    assert!(fit.std_err.k_y.is_infinite() && fit.condition_number.is_infinite());
    // JSON writes the unbounded figures as null and reads them back.
    let text = serde_json::to_string(&fit).unwrap();
    assert!(text.contains("\"condition_number\":null"), "{text}");
    let back: plinth::identify::PedestalFit = serde_json::from_str(&text).unwrap();
    assert!(back.condition_number.is_infinite() && back.std_err.m.is_infinite());
}

#[test]
fn no_pedestal_resonance_in_range() {
    // All four pedestal resonances are at 35-42 Hz; measure 5-25 Hz only.
    let run = run_with_speeds(linspace(5.0, 25.0, 40));
    let id = identify_run(&run, &Options::default()).unwrap();
    for p in &id.pedestals {
        let w = p
            .warnings
            .iter()
            .find(|w| w.kind == WarningKind::NoResonance)
            .unwrap_or_else(|| panic!("{}: {:?}", p.bearing, kinds(p)));
        assert!(w.message.contains("between 5 and 25 Hz"), "{}", w.message);
    }
    // A range with the resonances gives no such warning.
    let run = run_with_speeds(linspace(20.0, 60.0, 40));
    let id = identify_run(&run, &Options::default()).unwrap();
    for p in &id.pedestals {
        assert!(!p.has_warning(WarningKind::NoResonance), "{:?}", p.warnings);
    }
    // Far above every resonance too.
    let run = run_with_speeds(linspace(100.0, 200.0, 40));
    let id = identify_run(&run, &Options::default()).unwrap();
    assert!(id.pedestals[0].has_warning(WarningKind::NoResonance));
}

#[test]
fn collinear_data_dead_sensor() {
    // A dead vertical pedestal sensor: ped_y = 0 at every speed, so nothing
    // determines k_y and c_y.
    let run = run_with_speeds(linspace(5.0, 200.0, 60));
    let mut points = left_points(&run);
    for p in &mut points {
        p.ped[0] = num_complex::Complex::new(0.0, 0.0);
    }
    let fit = fit_pedestal("left", &points, &Options::default()).unwrap();
    assert!(
        fit.has_warning(WarningKind::RankDeficient),
        "{:?}",
        kinds(&fit)
    );
    assert!(!fit.trusted);
    let w = fit
        .warnings
        .iter()
        .find(|w| w.kind == WarningKind::RankDeficient)
        .unwrap();
    assert!(
        w.message.contains("k_y") && w.message.contains("c_y"),
        "{}",
        w.message
    );
    assert!(!w.message.contains("k_z"), "{}", w.message);
    assert!(fit.condition_number.is_infinite());
    assert!(fit.std_err.k_z.is_infinite());
}

#[test]
fn collinear_data_narrow_speed_band() {
    // Speeds within 0.02 Hz of 50 Hz: Ω² is nearly constant, so the m
    // column (−Ω²X) is nearly a combination of the k_y and k_z columns.
    let run = run_with_speeds(linspace(50.0, 50.02, 30));
    let fit = fit_pedestal("left", &left_points(&run), &Options::default()).unwrap();
    assert!(
        fit.has_warning(WarningKind::IllConditioned),
        "{:?} {}",
        kinds(&fit),
        fit.condition_number
    );
    assert!(!fit.trusted);
    assert!(fit.condition_number > 1e3, "{}", fit.condition_number);
    let w = fit
        .warnings
        .iter()
        .find(|w| w.kind == WarningKind::IllConditioned)
        .unwrap();
    assert!(
        w.message.contains("k_y") && w.message.contains("m"),
        "{}",
        w.message
    );
    // The same pedestal over the whole run-down is well conditioned.
    let run = run_with_speeds(linspace(5.0, 200.0, 30));
    let fit = fit_pedestal("left", &left_points(&run), &Options::default()).unwrap();
    assert!(fit.condition_number < 100.0 && fit.trusted, "{fit:?}");
}

#[test]
fn non_finite_points_are_left_out_and_reported() {
    let run = run_with_speeds(linspace(5.0, 200.0, 50));
    let mut points = left_points(&run);
    // A non-finite force in z (its bearing stiffness).
    points[7].kstar[1][1].re = f64::NAN;
    points[9].ped[0].im = f64::INFINITY;
    let fit = fit_pedestal("left", &points, &Options::default()).unwrap();
    assert!(fit.has_warning(WarningKind::NonFiniteInput));
    assert!(fit.warnings[0].message.starts_with("2 speed(s)"));
    assert_eq!(fit.speeds, 48);
    assert!(fit.trusted);
    let t = &run.truth.unwrap().pedestals[0];
    assert!(
        rel_err(fit.pedestal.k_y, t.pedestal.k_y) < 1e-9
            && rel_err(fit.pedestal.m, t.pedestal.m) < 1e-9
    );
    // Nothing finite at all is an error, not a fit.
    for p in &mut points {
        p.speed_hz = f64::NAN;
    }
    assert!(fit_pedestal("left", &points, &Options::default()).is_err());
}
