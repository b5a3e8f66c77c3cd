//! `plinth paper`: the structure of the tables and the accuracy the
//! reproduction of Feng & Hahn (1997) reaches on Plinth's reconstruction of
//! their machine. All numbers are deterministic (no noise: only digit
//! reduction of the simulated phasors), so the thresholds below sit at
//! measured values plus an honest margin; the measured values are in the
//! comments (`plinth paper`, `plinth paper --truncate`).

use plinth::paper::{
    reproduce, reproduce_with, worst_error, DampingCase, PaperOptions, Tables, DAMPED_MACHINE, KM,
    UNDAMPED_MACHINE,
};
use plinth::rundir::DigitsMode;
use plinth::sim::Machine;

fn machines() -> (Machine, Machine) {
    (
        Machine::from_toml_str(UNDAMPED_MACHINE, "feng-hahn-1997.toml").unwrap(),
        Machine::from_toml_str(DAMPED_MACHINE, "feng-hahn-1997-damped.toml").unwrap(),
    )
}

fn table1_worst(t: &Tables, digits: u32) -> f64 {
    t.table1
        .iter()
        .filter(|r| r.digits == digits && KM.contains(&r.param.as_str()))
        .map(|r| r.error_pct.abs())
        .fold(0.0, f64::max)
}

#[test]
fn json_has_the_documented_structure() {
    let paper = reproduce(&PaperOptions::default()).unwrap();
    let v = serde_json::to_value(&paper.tables).unwrap();
    assert_eq!(v["digits_mode"], "round", "rounding is the default");
    let t1 = v["table1"].as_array().unwrap();
    let t2 = v["table2"].as_array().unwrap();
    // 3 digit counts × 2 pedestals × (k_y, k_z, m).
    assert_eq!(t1.len(), 18);
    // Two damping cases × (R&I: 2 × 5 parameters; R+I, R, I: 2 × 3).
    assert_eq!(t2.len(), 2 * (10 + 3 * 6));
    for r in t1 {
        for k in [
            "digits",
            "digits_mode",
            "bearing",
            "param",
            "truth",
            "identified",
            "error_pct",
        ] {
            assert!(r.get(k).is_some(), "table1 row lacks {k}: {r}");
        }
        assert_eq!(r["digits_mode"], "round");
    }
    for r in t2 {
        for k in [
            "case",
            "damping_scale",
            "mode",
            "bearing",
            "param",
            "truth",
            "identified",
            "error_pct",
        ] {
            assert!(r.get(k).is_some(), "table2 row lacks {k}: {r}");
        }
    }
    for case in ["scan_damping", "heavy_damping"] {
        let modes: Vec<&str> = t2
            .iter()
            .filter(|r| r["case"] == case)
            .map(|r| r["mode"].as_str().unwrap())
            .collect();
        assert_eq!(modes.len(), 28, "{case}");
        for m in ["R&I", "R+I", "R", "I"] {
            assert!(modes.contains(&m), "{case} lacks {m}");
        }
    }
    // error_pct is what it says.
    for r in &paper.tables.table1 {
        let e = 100.0 * (r.identified - r.truth) / r.truth;
        assert!((e - r.error_pct).abs() < 1e-9);
    }
    for r in &paper.tables.table2 {
        let e = 100.0 * (r.identified - r.truth) / r.truth;
        assert!((e - r.error_pct).abs() < 1e-9);
    }
}

#[test]
fn table2_cases_state_their_damping() {
    let paper = reproduce(&PaperOptions::default()).unwrap();
    let cases = &paper.tables.table2_cases;
    assert_eq!(cases.len(), 2);
    let (scan, heavy) = (&cases[0], &cases[1]);
    assert_eq!(scan.case, DampingCase::ScanDamping);
    assert_eq!(scan.damping_scale, 1.0);
    // The scan's 70-100 N·s/m: ζ = c/(2·sqrt(k·m)) ≈ 0.18 %.
    let z = scan.mean_damping_ratio();
    assert!((0.0015..0.0021).contains(&z), "scan ζ = {z}");
    assert_eq!(heavy.case, DampingCase::HeavyDamping);
    // ×55 (2 significant digits) brings the mean ratio to 9.9 %.
    assert_eq!(heavy.damping_scale, 55.0);
    let z = heavy.mean_damping_ratio();
    assert!((z - 0.10).abs() < 0.002, "heavy ζ = {z}");
    // The rows' truth is the scaled machine's damping.
    for p in &heavy.pedestals {
        let s = scan
            .pedestals
            .iter()
            .find(|q| q.bearing == p.bearing)
            .unwrap();
        assert!((p.c_y - 55.0 * s.c_y).abs() < 1e-9 && (p.c_z - 55.0 * s.c_z).abs() < 1e-9);
        let row = paper
            .tables
            .table2
            .iter()
            .find(|r| r.case == heavy.case && r.bearing == p.bearing && r.param == "c_y")
            .unwrap();
        assert_eq!(row.truth, p.c_y);
        assert_eq!(row.damping_scale, 55.0);
    }
}

#[test]
fn table1_accuracy_follows_the_digits_rounded() {
    let paper = reproduce(&PaperOptions::default()).unwrap();
    let err = |d| table1_worst(&paper.tables, d);
    // 12 digits: exact to far below the data's precision.
    assert!(err(12) < 1e-6, "12 digits: {}%", err(12));
    // 3 digits (≤ 0.5 % input error): measured 0.12 %.
    assert!(err(3) < 0.3, "3 digits: {}%", err(3));
    // 2 digits rounded (the paper's "maximum error of 5 %"): the 1 % goal
    // for every k and m; measured 0.87 % (right k_z). The paper reached 2 %.
    assert!(err(2) < 1.0, "2 digits rounded, R&I: worst {}%", err(2));
}

#[test]
fn table1_two_digits_truncated_as_the_paper_wrote() {
    // Truncation is off by up to 10 % and always towards zero: the bias of the
    // errors-in-variables regression does not average out with more speeds.
    // Measured 2.16 % (right k_y); the paper reached 2 %.
    let (u, d) = machines();
    let opts = PaperOptions {
        digits_mode: DigitsMode::Truncate,
        ..PaperOptions::default()
    };
    let paper = reproduce_with(&u, &d, &opts).unwrap();
    assert_eq!(paper.tables.digits_mode, DigitsMode::Truncate);
    let v = serde_json::to_value(&paper.tables).unwrap();
    assert_eq!(v["digits_mode"], "truncate");
    assert_eq!(v["table1"][0]["digits_mode"], "truncate");
    let worst = table1_worst(&paper.tables, 2);
    assert!(worst < 3.0, "2 digits truncated, R&I: worst {worst}%");
    // Truncating is worse than rounding on the same data (0.87 % rounded).
    let rounded = table1_worst(&reproduce(&PaperOptions::default()).unwrap().tables, 2);
    assert!(worst > rounded, "truncated {worst}% vs rounded {rounded}%");
}

#[test]
fn table2_scan_damping_is_below_two_digit_resolution() {
    // The bundled damped machine has c = 70-100 N·s/m as the scan reads:
    // ζ ≈ 0.18 %, a damping force 2ζ ≈ 0.36 % of the spring force at a
    // pedestal resonance. R&I still gets k and m (measured 0.67 %), but
    // leaving c out costs R+I, R and I only 0.16-0.18 % on full-precision
    // data, below the 2-digit noise, so the paper's contrast cannot appear.
    let paper = reproduce(&PaperOptions::default()).unwrap();
    let t = &paper.tables;
    let case = DampingCase::ScanDamping;
    let ri = worst_error(&t.table2, case, "R&I", &KM);
    assert!(ri < 1.0, "R&I k, m with the scan's damping: worst {ri}%");
    let exact = &t.table2_cases[0].full_precision_worst_km_pct;
    assert!(exact["R&I"] < 1e-6, "R&I on exact data: {}%", exact["R&I"]);
    for mode in ["R+I", "R", "I"] {
        // Not zero (the damping is there) but far below 2-digit noise.
        assert!(
            (0.05..0.3).contains(&exact[mode]),
            "{mode} on exact data: {}%",
            exact[mode]
        );
        let e = worst_error(&t.table2, case, mode, &KM);
        assert!(e < 1.5, "{mode} k, m with the scan's damping: worst {e}%");
    }
}

#[test]
fn table2_heavy_damping_only_r_and_i_is_right() {
    // With the damping ×55 (ζ ≈ 10 %) the paper's finding appears. Measured
    // (2 digits, rounded): R&I k, m worst 1.93 % (right k_z), c worst 3.1 %;
    // R+I 11.3 %, R 20.4 %, I 10.9 %. The R&I figure is rounding noise that
    // moves with the exact damping (0.5-1.9 % for scales 28-110), so the
    // bound is 2.5 %; the other modes' errors are the method's own (13.2,
    // 19.3, 12.3 % on full-precision data), at least 5.6× R&I's.
    let paper = reproduce(&PaperOptions::default()).unwrap();
    let t = &paper.tables;
    let case = DampingCase::HeavyDamping;
    let ri = worst_error(&t.table2, case, "R&I", &KM);
    let ri_c = worst_error(&t.table2, case, "R&I", &["c_y", "c_z"]);
    assert!(ri < 2.5, "R&I k, m: worst {ri}%");
    assert!(ri_c < 6.0, "R&I c: worst {ri_c}%");
    let exact = &t.table2_cases[1].full_precision_worst_km_pct;
    assert!(exact["R&I"] < 1e-6, "R&I on exact data: {}%", exact["R&I"]);
    for mode in ["R+I", "R", "I"] {
        let e = worst_error(&t.table2, case, mode, &KM);
        assert!(
            e > 2.5 * ri,
            "{mode} should be clearly wrong: worst {e}% vs R&I {ri}%"
        );
        assert!(exact[mode] > 10.0, "{mode} on exact data: {}%", exact[mode]);
    }
}

#[test]
fn heavy_damping_follows_the_requested_ratio() {
    let (u, d) = machines();
    let opts = PaperOptions {
        heavy_damping_ratio: 0.2,
        speeds_hz: (5..=200).step_by(5).map(f64::from).collect(),
        ..PaperOptions::default()
    };
    let paper = reproduce_with(&u, &d, &opts).unwrap();
    let heavy = &paper.tables.table2_cases[1];
    assert_eq!(heavy.damping_scale, 110.0);
    assert!((heavy.mean_damping_ratio() - 0.2).abs() < 0.003);
    // Bad ratios and an undamped "damped" machine are named errors.
    for bad in [0.0, -0.1, 1.5, f64::NAN] {
        let opts = PaperOptions {
            heavy_damping_ratio: bad,
            ..opts.clone()
        };
        let e = reproduce_with(&u, &d, &opts).unwrap_err().to_string();
        assert!(e.contains("heavy-damping ratio"), "{bad}: {e}");
    }
    let e = reproduce_with(&u, &u, &opts).unwrap_err().to_string();
    assert!(e.contains("no positive pedestal damping"), "{e}");
}
