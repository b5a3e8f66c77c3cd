//! Issue 17, "a ± must mean what it says": where `plinth identify`'s
//! errors-in-variables rule withholds a pedestal's standard errors
//! (host/src/estimate/ml/eiv.rs, `MIN_INFORMATION_SIGMAS`; identify shows
//! `± ∞`, `null` in JSON: tests/tests/identify_withheld_std_err.rs),
//! `plinth diagnose` shows none either, by the same test
//! (`plinth::identify::std_err_withheld` of its base fit): not in the base
//! model's pedestals, the final model's, nor their modal view.
//! docs/trust.md, Session 45 (before17).
//!
//! The run: `tests/data/lowsnr-null-train-1509` (ROSS unseen-train's B1, a
//! stiff pedestal read near its noise; scripts/make_lowsnr_null.py; truth
//! k_y 900 MN/m, m 320 kg). Main (52c0f7c) printed its own short ± there:
//! base model B1 k_y 1138 ± 30 MN/m (7.9 of its ± off the truth), m 1070 ±
//! 116 kg (6.5 ±), f_n,y 164 ± 10 Hz; final model k_y 1130 ± 229, f_n,y
//! 163 ± 10 Hz.

use plinth::diagnose::{cli::modal_views, diagnose, Options};
use plinth::rundir::RunDir;
use std::path::Path;

/// No ± of B1 anywhere diagnose reports one: text, JSON and modal view, of
/// the base and the final model.
#[test]
fn diagnose_shows_no_standard_error_where_identify_withholds_it() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lowsnr-null-train-1509");
    let run = RunDir::read(&dir).expect("stored run");
    let out = diagnose(&run, &Options::default()).expect("diagnose");
    let d = &out.diagnosis;
    let json = serde_json::to_value(d).expect("JSON");
    for list in ["pedestals_before", "pedestals_after"] {
        let b1 = json[list]
            .as_array()
            .and_then(|l| l.iter().find(|p| p["bearing"] == "B1"))
            .unwrap_or_else(|| panic!("{list} has no B1: {}", json[list]));
        for p in ["k_y", "k_z", "m"] {
            assert!(b1[p].is_number(), "{list}.{p}: {}", b1[p]);
            assert!(
                b1["std_err"][p].is_null(),
                "{list} B1 std_err.{p} shown as {} (a ± that does not mean what it says)",
                b1["std_err"][p]
            );
        }
    }
    let modal = modal_views(&out);
    for (which, views) in [("base", &modal.before), ("final", &modal.after)] {
        let b1 = views.get("B1").expect("modal view of B1");
        for (dir, m) in [("y", b1.y), ("z", b1.z)] {
            assert!(m.f_n_hz.is_finite(), "{which} {dir}: f_n {}", m.f_n_hz);
            assert!(
                m.f_n_std_err.is_nan() && m.zeta_std_err.is_nan(),
                "{which} model B1 {dir}: f_n ± {} Hz, ζ ± {} shown",
                m.f_n_std_err,
                m.zeta_std_err
            );
        }
    }
    let text = d.to_text_with(&modal);
    assert!(text.contains("± ∞"), "{text}");
    assert!(text.contains("standard errors are not known"), "{text}");
}
