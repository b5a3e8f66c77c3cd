//! Issue 17, "a ± must mean what it says": where the errors-in-variables
//! rule withholds a pedestal's covariance (host/src/estimate/ml/eiv.rs,
//! `MIN_INFORMATION_SIGMAS`: what remains of the fit's information is too
//! close to its own noise, where the asymptotic F⁻¹ is short), identify
//! shows no ± at all (infinite, `null` in JSON, no covariance, no modal ±)
//! instead of F⁻¹'s. docs/trust.md, Session 44 (farate17).
//!
//! The run: `tests/data/lowsnr-null-train-1509` (ROSS unseen-train's B1, a
//! stiff pedestal read near its noise; scripts/make_lowsnr_null.py). Main
//! (76899fa) calls B1 `undetermined` there but prints k_y 1138 ± 41 MN/m
//! (truth 900: 5.8 of its ±), m 1070 ± 168 kg (truth 320: 4.5 ±) and
//! f_n,y 164 ± 10 Hz (truth 267: 10 ±), in text and JSON.

use plinth::identify::Identification;
use plinth::present::table::value_pm;
use plinth_tests::rundown::{identify_dir, pedestal};
use std::path::Path;

fn identify(name: &str) -> Identification {
    identify_dir(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("data")
            .join(name),
    )
}

/// The withheld ± is shown as unknown everywhere identify shows one: the
/// fit's standard errors (text and JSON), its covariance and its modal ±.
#[test]
fn a_withheld_covariance_shows_no_standard_error() {
    let id = identify("lowsnr-null-train-1509");
    let b1 = pedestal(&id, "B1");
    assert!(!b1.trusted, "B1 must stay untrusted: {:?}", b1.warnings);
    assert!(
        b1.warnings
            .iter()
            .any(|w| w.message.contains("standard errors are not known")),
        "{:?}",
        b1.warnings
    );
    let json = serde_json::to_value(b1).expect("JSON");
    for p in ["k_y", "k_z", "m", "c_y", "c_z"] {
        assert!(
            json["std_err"][p].is_null(),
            "std_err.{p} shown as {} (a ± that does not mean what it says)",
            json["std_err"][p]
        );
    }
    assert!(
        json.get("covariance").is_none(),
        "covariance: {}",
        json["covariance"]
    );
    for d in ["y", "z"] {
        assert!(json["modal"][d]["f_n_hz"].is_number(), "{}", json["modal"]);
        assert!(
            json["modal"][d]["f_n_std_err"].is_null() && json["modal"][d]["zeta_std_err"].is_null(),
            "modal {d}: {}",
            json["modal"][d]
        );
    }
    let text = value_pm(b1.pedestal.k_y, b1.std_err.k_y);
    assert!(text.ends_with("± ∞"), "k_y printed as {text}");
}

/// Control: a pedestal whose information is well above its noise keeps
/// its ± and covariance (the stored unseen-flex recording's B2, resonant in
/// its band; tests/data/ross-recording-flex-sign).
#[test]
fn a_well_read_pedestal_keeps_its_standard_errors() {
    let id = identify("ross-recording-flex-sign");
    let b2 = pedestal(&id, "B2");
    assert!(
        b2.std_err.theta().iter().all(|s| s.is_finite() && *s > 0.0),
        "{:?}",
        b2.std_err
    );
    assert!(b2.covariance.is_some());
    let json = serde_json::to_value(b2).expect("JSON");
    assert!(json["std_err"]["k_y"].is_number() && json["modal"]["y"]["f_n_std_err"].is_number());
}
