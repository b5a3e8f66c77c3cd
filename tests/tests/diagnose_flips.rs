//! `plinth diagnose` runs identify's keyphasor-flip tests before it fits
//! anything: the flipped speeds are listed (`flipped_speeds_hz`, text and
//! JSON), left out of the noise, the fits and the gap, and the diagnosis
//! concludes on the rest. Faults are made in the data here (negation), the
//! data by the simulator, independently of the tests.

use plinth::diagnose::{diagnose, Options};
use plinth::rundir::RunDir;
use plinth_tests::rundown::{machine, run};

/// `r` with every channel of `bearing` negated at the speeds `flipped` [Hz].
fn flip(r: &mut RunDir, bearing: &str, flipped: &[f64]) {
    for row in &mut r.measurements {
        if row.bearing == bearing && flipped.contains(&row.speed_hz) {
            for z in row.rel.iter_mut().chain(row.ped.iter_mut()) {
                *z = -*z;
            }
        }
    }
}

#[test]
fn flipped_speeds_are_left_out_listed_and_the_rest_is_trusted() {
    // Two adjacent flips next to `mid`'s pedestal resonance (found against
    // the other bearings), one far away (found in speed), 1 % noise.
    let m = machine("tests/machines/three-bearing-tabulated.toml");
    let mut r = run(&m, Some((0.01, 3)), Some(6));
    let flipped = [40.0, 42.5, 120.0];
    flip(&mut r, "mid", &flipped);
    let out = diagnose(&r, &Options::default()).expect("diagnose");
    let d = &out.diagnosis;
    let text = d.to_text();
    println!("{text}");
    assert_eq!(d.flipped_speeds_hz.len(), 1, "{:?}", d.flipped_speeds_hz);
    assert_eq!(d.flipped_speeds_hz["mid"], flipped);
    assert!(d.effects_added.is_empty(), "named {:?}", d.effects_added);
    assert!(d.trusted, "{:?}", d.trust_reasons);
    assert!(
        text.contains("KEYPHASOR FLIP at mid") && text.contains("40, 42.5, 120 Hz"),
        "{text}"
    );
    // Left out of the fits: no point of `mid` at those speeds.
    let b = out.prep.bearing_index("mid").expect("mid");
    for (j, s) in out.prep.speeds_hz.iter().enumerate() {
        assert_eq!(
            out.prep.points[b][j].is_none(),
            flipped.contains(s),
            "{s} Hz"
        );
    }
    let json = serde_json::to_value(d).expect("json");
    assert_eq!(json["flipped_speeds_hz"]["mid"][2].as_f64(), Some(120.0));
}

#[test]
fn every_bearing_flipped_is_left_out_at_every_bearing_with_the_note() {
    let m = machine("tests/machines/three-bearing-tabulated.toml");
    let mut r = run(&m, Some((0.01, 5)), Some(6));
    let flipped = [120.0, 150.0];
    for bearing in ["drive", "mid", "outboard"] {
        flip(&mut r, bearing, &flipped);
    }
    let out = diagnose(&r, &Options::default()).expect("diagnose");
    let d = &out.diagnosis;
    let text = d.to_text();
    println!("{text}");
    for bearing in ["drive", "mid", "outboard"] {
        assert_eq!(
            d.flipped_speeds_hz.get(bearing).map(Vec::as_slice),
            Some(&flipped[..]),
            "{bearing}"
        );
    }
    assert!(
        text.contains("every bearing is flipped at 120, 150 Hz"),
        "{text}"
    );
    assert!(d.effects_added.is_empty(), "named {:?}", d.effects_added);
    assert!(d.trusted, "{:?}", d.trust_reasons);
    assert!(!out.prep.speeds_hz.contains(&120.0));
}

#[test]
fn a_clean_run_lists_no_flip() {
    let m = machine("tests/machines/three-bearing-tabulated.toml");
    for seed in [3, 5] {
        let d = diagnose(&run(&m, Some((0.01, seed)), Some(6)), &Options::default())
            .expect("diagnose")
            .diagnosis;
        assert!(d.flipped_speeds_hz.is_empty(), "{:?}", d.flipped_speeds_hz);
        let json = serde_json::to_value(&d).expect("json");
        assert!(json["flipped_speeds_hz"]
            .as_object()
            .is_some_and(|m| m.is_empty()));
    }
}
