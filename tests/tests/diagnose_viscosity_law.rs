//! A bearing table written at the design viscosity while the oil's
//! viscosity follows the speed (session 48, helper thermvisc17): the
//! seventh unseen machine's `table-thermal` case (+29 % at 5 Hz, 0 at the
//! 50 Hz top speed on every journal), ROSS 2.3.0, seed 5402
//! (tests/data/thermal17/README.md), an independent path;
//! docs/diagnose-bearing-table.md, "Session 48 (thermvisc17)".
//!
//! On main at 49d143f diagnose named `bearing_coefficients` at B3 as a
//! constant clearance ratio (0.91 ± 0.01, the Sommerfeld number's mean
//! over the run taken for a clearance) and reported B3's pedestal with
//! k_y, k_z and m 9-13 % off, 6-10 of their ± (the constant correction
//! puts the scale W/c of the film at the clearance it assumed). With the
//! oil's viscosity law, significant against the constant correction, the
//! correction is the oil's: μ/μ_w about 1 at the top speed and 1.3 at the
//! bottom, and B3's values within 2 % and 3 ±.

use plinth::diagnose::diagnose;
use plinth::diagnose::report::Diagnosis;
use plinth_tests::unseen;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data");

#[test]
fn a_viscosity_following_the_speed_is_fitted_and_the_pedestal_is_right() {
    let (_, options) =
        unseen::machine_and_options(&format!("{DATA}/ross-unseen-7"), "unseen-seven.toml");
    let run = unseen::stored(&format!("{DATA}/thermal17"), "table-thermal-5402");
    let d: Diagnosis = diagnose(&run, &options).expect("diagnose").diagnosis;
    let text = d.to_text();
    println!("{text}");
    let step = d
        .steps
        .iter()
        .find(|s| s.effect == "bearing_coefficients" && s.bearing == "B3" && s.dropped.is_none())
        .expect("bearing_coefficients kept at B3");
    let param = |name: &str| {
        step.parameters
            .iter()
            .find(|p| p.name == name)
            .unwrap_or_else(|| panic!("{name} in {:?}", step.parameters))
    };
    // The truth: μ/μ_w = 1.3^(1 − (f/50)²): 1 at 50 Hz, 1.287 at 5 Hz.
    let top = param("viscosity_ratio_top");
    let bottom = param("viscosity_ratio_bottom");
    let at_bottom = 1.3f64.powf(1.0 - 0.01);
    assert!((top.value - 1.0).abs() <= 3.0 * top.std_err, "{top:?}");
    assert!(
        (bottom.value - at_bottom).abs() <= 3.0 * bottom.std_err,
        "{bottom:?}"
    );
    assert!(bottom.std_err > 0.0 && bottom.std_err < 0.1, "{bottom:?}");
    assert!(step.parameters.iter().all(|p| p.name != "clearance_ratio"));
    assert!(text.contains("oil viscosity ×"), "{text}");
    // B3's pedestal after the correction: k_y, k_z, m within 2 % and 3 ±.
    let truth = unseen::truth_of(&run, "B3");
    let after = d
        .pedestals_after
        .iter()
        .find(|p| p.bearing == "B3")
        .expect("B3 after");
    for (name, want) in [("k_y", truth.k_y), ("k_z", truth.k_z), ("m", truth.m)] {
        let v = after.values[name];
        let se = after.std_err[name];
        assert!((v / want - 1.0).abs() < 0.02, "B3 {name} {v} vs {want}");
        assert!(
            (v - want).abs() <= 3.0 * se,
            "B3 {name} {v} ± {se} vs {want}"
        );
    }
    let json = serde_json::to_value(&d).expect("json");
    assert!(json["steps"]
        .as_array()
        .is_some_and(|s| s.iter().any(|s| s["parameters"]
            .as_array()
            .is_some_and(|p| p.iter().any(|p| p["name"] == "viscosity_ratio_bottom")))));
}
