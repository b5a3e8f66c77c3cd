//! Batch identification (`plinth identify`) against data that satisfy the
//! paper's pedestal model exactly, rounded like field data, and with the
//! paper's damped pedestals (Table 1 and Table 2).

use plinth::identify::{
    identify_run, mode_label, EquationMode, Identification, Model, Options, Parameter,
};
use plinth::rundir::RunDir;
use plinth_tests::{paper_like_run, rel_err};

const MODES: [EquationMode; 4] = [
    EquationMode::RealAndImag,
    EquationMode::RealPlusImag,
    EquationMode::Real,
    EquationMode::Imag,
];

/// Largest relative error of k_y, k_z, m over both pedestals.
fn worst_k_m_error(id: &Identification, run: &RunDir) -> f64 {
    let truth = run.truth.as_ref().expect("truth.json");
    let mut worst: f64 = 0.0;
    for t in &truth.pedestals {
        let p = id.pedestal(&t.bearing).expect("pedestal identified");
        for (a, b) in [
            (p.pedestal.k_y, t.pedestal.k_y),
            (p.pedestal.k_z, t.pedestal.k_z),
            (p.pedestal.m, t.pedestal.m),
        ] {
            worst = worst.max(rel_err(a, b));
        }
    }
    worst
}

#[test]
fn exact_data_give_every_parameter_to_1e_9() {
    let run = paper_like_run(100, 1.0, None);
    let truth = run.truth.clone().unwrap();
    let id = identify_run(&run, &Options::default()).unwrap();
    assert_eq!(id.model, ["k_y", "k_z", "m", "c_y", "c_z"]);
    assert_eq!(id.equations, "r-and-i");
    assert_eq!(id.pedestals.len(), 2);
    for t in &truth.pedestals {
        let p = id.pedestal(&t.bearing).unwrap();
        let want = [
            t.pedestal.k_y,
            t.pedestal.k_z,
            t.pedestal.m,
            t.pedestal.c_y,
            t.pedestal.c_z,
        ];
        for param in Parameter::ALL {
            let got = p.pedestal.get(param);
            let want = want[param as usize];
            assert!(
                rel_err(got, want) < 1e-9,
                "{} {}: {got} vs {want}",
                t.bearing,
                param.name()
            );
        }
        assert!(p.trusted, "{:?}", p.warnings);
        assert!(p.warnings.is_empty(), "{:?}", p.warnings);
        assert_eq!(p.speeds, 100);
        assert_eq!(p.equations, 400);
        assert!(p.residual_rms < 1e-9, "{}", p.residual_rms);
        assert!(p.condition_number > 1.0 && p.condition_number < 100.0);
        // Standard errors are of the size of the rounding of the inputs.
        assert!(p.std_err.k_y < 1e-9 * t.pedestal.k_y && p.std_err.m < 1e-9 * t.pedestal.m);
    }
    // The speeds span every pedestal resonance: 5 to 200 Hz.
    assert_eq!(id.pedestals[0].speed_range_hz, [5.0, 200.0]);
}

#[test]
fn exact_undamped_data_give_zero_damping() {
    let run = paper_like_run(100, 0.0, None);
    let id = identify_run(&run, &Options::default()).unwrap();
    for p in &id.pedestals {
        assert!(
            p.pedestal.c_y.abs() < 1e-6 && p.pedestal.c_z.abs() < 1e-6,
            "{p:?}"
        );
        // Damping consistent with zero is reported, not hidden...
        assert!(p.has_warning(plinth::identify::WarningKind::DampingNotResolved));
        // ...but does not make k and m untrustworthy.
        assert!(p.trusted);
    }
    // Every equation mode is exact without damping (the paper's point).
    for mode in MODES {
        let id = identify_run(&run, &Options::with_mode(mode)).unwrap();
        assert!(worst_k_m_error(&id, &run) < 1e-9, "{}", mode_label(mode));
    }
}

#[test]
fn table_1_two_digit_undamped_data_within_2_percent() {
    let run = paper_like_run(100, 0.0, Some(2));
    let options = Options {
        model: Some(Model::UNDAMPED),
        ..Options::default()
    };
    let id = identify_run(&run, &options).unwrap();
    let worst = worst_k_m_error(&id, &run);
    assert!(worst <= 0.02, "worst k/m error {worst}");
    // Rounding errors are real: the fit is not exact, and says so.
    assert!(worst > 1e-4);
    for p in &id.pedestals {
        assert!(p.trusted, "{:?}", p.warnings);
        assert!(p.residual_rms > 0.0);
        // The truth lies within a few standard errors (errors-in-variables
        // bias makes this loose, hence 10).
        let t = run.truth.as_ref().unwrap();
        let t = t.pedestals.iter().find(|t| t.bearing == p.bearing).unwrap();
        assert!(
            (p.pedestal.k_y - t.pedestal.k_y).abs() < 10.0 * p.std_err.k_y,
            "{p:?}"
        );
    }
    // 3 digits are better than 2.
    let run3 = paper_like_run(100, 0.0, Some(3));
    let id3 = identify_run(&run3, &options).unwrap();
    assert!(worst_k_m_error(&id3, &run3) < worst);
}

/// The paper's damped pedestals (c = 70-100 N·s/m, ζ ≈ 0.1%), 2 digits.
///
/// What happens, honestly: R&I recovers k and m within 2%. On exact data,
/// R, I and R+I with the undamped model (their default) are biased, but only
/// by 0.1-0.2%: at this little damping the bias is far below the 2-digit
/// rounding error, so on 2-digit data they are *not* clearly worse than R&I
/// (this test does not claim they are). The 2-digit data do not resolve the
/// damping itself with the paper's OLS (standard error ≈ value), and the fit
/// says so; the maximum-likelihood default does (`estimation_noise.rs`). The
/// contrast of the paper's Table 2 needs more damping: see the next test.
#[test]
fn table_2_paper_damping_two_digits() {
    let run = paper_like_run(100, 1.0, Some(2));
    let id = identify_run(&run, &Options::default().ols()).unwrap();
    let worst = worst_k_m_error(&id, &run);
    assert!(worst <= 0.02, "R&I worst k/m error {worst}");
    for p in &id.pedestals {
        assert!(p.trusted, "{:?}", p.warnings);
    }
    assert!(id
        .pedestals
        .iter()
        .any(|p| p.has_warning(plinth::identify::WarningKind::DampingNotResolved)));

    let exact = paper_like_run(100, 1.0, None);
    let exact_ri = worst_k_m_error(&identify_run(&exact, &Options::default()).unwrap(), &exact);
    assert!(exact_ri < 1e-9);
    for mode in &MODES[1..] {
        let bias = worst_k_m_error(
            &identify_run(&exact, &Options::with_mode(*mode)).unwrap(),
            &exact,
        );
        assert!(
            bias > 5e-4 && bias < 5e-3,
            "{}: bias {bias}",
            mode_label(*mode)
        );
    }
}

/// Table 2's contrast with damping that matters (c = 3.5-5 kN·s/m, ζ ≈ 3-4%):
/// on 2-digit data R&I recovers k and m within 2% and the damping within
/// 10%; R, I and R+I (undamped model, as the paper used them) are off by
/// several times more.
#[test]
fn table_2_contrast_with_heavier_damping() {
    let run = paper_like_run(100, 50.0, Some(2));
    let truth = run.truth.clone().unwrap();
    let id = identify_run(&run, &Options::default()).unwrap();
    let ri = worst_k_m_error(&id, &run);
    assert!(ri <= 0.02, "R&I worst k/m error {ri}");
    for t in &truth.pedestals {
        let p = id.pedestal(&t.bearing).unwrap();
        assert!(p.trusted, "{:?}", p.warnings);
        assert!(
            rel_err(p.pedestal.c_y, t.pedestal.c_y) < 0.1,
            "{} c_y {}",
            t.bearing,
            p.pedestal.c_y
        );
        assert!(
            rel_err(p.pedestal.c_z, t.pedestal.c_z) < 0.1,
            "{} c_z {}",
            t.bearing,
            p.pedestal.c_z
        );
    }
    for mode in &MODES[1..] {
        let other = worst_k_m_error(
            &identify_run(&run, &Options::with_mode(*mode)).unwrap(),
            &run,
        );
        assert!(
            other > 0.02 && other > 2.5 * ri,
            "{}: {other} vs R&I {ri}",
            mode_label(*mode)
        );
    }
}

#[test]
fn k_and_m_do_not_depend_on_whether_c_is_estimated() {
    // Eq. 5-7 of the paper: on undamped (3-digit) data, estimating c_y, c_z
    // or fixing them at zero gives the same k and m.
    let run = paper_like_run(100, 0.0, Some(3));
    let full = identify_run(&run, &Options::default()).unwrap();
    let undamped = identify_run(
        &run,
        &Options {
            model: Some(Model::UNDAMPED),
            ..Options::default()
        },
    )
    .unwrap();
    for (a, b) in full.pedestals.iter().zip(&undamped.pedestals) {
        for p in [Parameter::Ky, Parameter::Kz, Parameter::M] {
            assert!(
                rel_err(a.pedestal.get(p), b.pedestal.get(p)) < 2e-3,
                "{}",
                p.name()
            );
        }
        assert_eq!(b.fixed, ["c_y", "c_z"]);
        assert_eq!((b.pedestal.c_y, b.pedestal.c_z), (0.0, 0.0));
        assert_eq!((b.std_err.c_y, b.std_err.c_z), (0.0, 0.0));
    }
}

#[test]
fn json_output_has_the_formats_md_keys_and_round_trips() {
    let run = paper_like_run(40, 1.0, Some(3));
    let options = Options {
        model: Some(Model::UNDAMPED),
        ..Options::default()
    };
    let id = identify_run(&run, &options).unwrap();
    let text = serde_json::to_string(&id).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["model"], serde_json::json!(["k_y", "k_z", "m"]));
    let p = &v["pedestals"][0];
    assert_eq!(p["bearing"], "left");
    for key in [
        "k_y",
        "k_z",
        "m",
        "c_y",
        "c_z",
        "residual_rms",
        "condition_number",
    ] {
        assert!(p[key].is_number(), "{key}: {}", p[key]);
    }
    for key in ["k_y", "k_z", "m", "c_y", "c_z"] {
        assert!(p["std_err"][key].is_number(), "std_err.{key}");
    }
    assert_eq!(p["c_y"], 0.0);
    assert_eq!(p["std_err"]["c_z"], 0.0);
    assert_eq!(p["fixed"], serde_json::json!(["c_y", "c_z"]));
    assert!(p["warnings"].is_array());
    assert_eq!(p["trusted"], true);
    let back: Identification = serde_json::from_str(&text).unwrap();
    assert_eq!(back, id);
}

#[test]
fn table_marks_values_units_and_truth() {
    let run = paper_like_run(50, 1.0, Some(2));
    let id = identify_run(&run, &Options::default()).unwrap();
    let table = plinth::identify::cli::table(&id, run.truth.as_ref());
    assert!(table.contains("k_y [MN/m]"), "{table}");
    assert!(table.contains("m [kg]"));
    assert!(table.contains("c_y [N·s/m]"));
    assert!(table.contains("  truth  10.0000"), "{table}");
    assert!(table.contains("  error"));
    assert!(!table.contains("UNTRUSTED"));
}
