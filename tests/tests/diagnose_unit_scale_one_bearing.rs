//! A unit mistake on one bearing's transducers (session 40,
//! docs/robustness-hostile.md "Session 40 (partialunit17)"): one bearing's `rel` s times their true
//! value identify that pedestal s times its own (exactly what a bearing
//! table s times too stiff gives there), so `plinth identify` cannot tell;
//! the machine file can where the rotor's response depends on that
//! bearing. The stored run is ROSS 2.3.0's clean run of unseen-five
//! (seed 1, tests/data/ross-unseen-5/clean-n3) with B2's `rel_y` and `rel_z`
//! × 2 (probes' 0-peak read as peak-to-peak), made by
//! `python3 scripts/unit_scale_run.py tests/data/ross-unseen-5/clean-n3
//! tests/data/ross-unseen-5/clean-n3-b2-rel-x2 2 rel B2`.

use plinth::diagnose::report::Diagnosis;
use plinth_tests::rundown::identify;
use plinth_tests::unseen::{self, untrusted};

/// The JSON `unit_scale` of a diagnosis: (kind, bearing, factor).
fn unit_scale(d: &Diagnosis) -> Option<(String, String, f64)> {
    let v = serde_json::to_value(d).expect("diagnosis as JSON");
    let u = v.get("unit_scale")?;
    Some((
        u.get("kind")?.as_str()?.to_string(),
        u.get("bearing")?.as_str()?.to_string(),
        u.get("factor")?.as_f64()?,
    ))
}

/// unseen-five, B2's probes × 2: identify trusts B2 at twice its k, m, c;
/// on main (fd6fbae) diagnose --machine trusted it too (machine-level gap
/// 1.88 against a limit of 2.03 that cannot judge: the pedestal twice too
/// stiff widens its own floor), confidently wrong. Now the check finds
/// that B2's `rel` divided by about 2 passes it while the readings as they
/// are fail the same yardstick: untrusted, the bearing, kind and factor
/// named.
#[test]
fn one_bearings_probes_at_twice_their_value_are_named_at_that_bearing() {
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-5");
    let run = unseen::stored(data, "clean-n3-b2-rel-x2");
    let id = identify(&run);
    assert!(untrusted(&id).is_empty(), "identify cannot tell");
    let d = unseen::diagnosis_with_machine_check(data, "unseen-five.toml", &run);
    assert!(!d.trusted, "{}", d.to_text());
    let (kind, bearing, s) =
        unit_scale(&d).unwrap_or_else(|| panic!("no unit_scale: {}", d.to_text()));
    assert_eq!((kind.as_str(), bearing.as_str()), ("rel", "B2"));
    assert!((s / 2.0 - 1.0).abs() < 0.05, "factor {s} against 2");
    assert!(
        d.trust_reasons
            .iter()
            .any(|r| r.contains("the `rel` transducers of B2") && r.contains("×2 (0-peak")),
        "{:?}",
        d.trust_reasons
    );
}
