//! `plinth paper`: the structure of the tables and the accuracy the
//! reproduction of Feng & Hahn (1997) reaches on Plinth's reconstruction of
//! their machine. All numbers are deterministic (no noise: only digit
//! reduction of the simulated phasors).

use plinth::paper::{
    reproduce, reproduce_with, PaperOptions, Table2Row, DAMPED_MACHINE, UNDAMPED_MACHINE,
};
use plinth::rundir::DigitsMode;
use plinth::sim::Machine;

fn machines() -> (Machine, Machine) {
    (
        Machine::from_toml_str(UNDAMPED_MACHINE, "feng-hahn-1997.toml").unwrap(),
        Machine::from_toml_str(DAMPED_MACHINE, "feng-hahn-1997-damped.toml").unwrap(),
    )
}

fn max_abs_error<'a>(rows: impl Iterator<Item = (&'a str, f64)>, params: &[&str]) -> f64 {
    rows.filter(|(p, _)| params.contains(p))
        .map(|(_, e)| e.abs())
        .fold(0.0, f64::max)
}

#[test]
fn json_has_the_documented_structure() {
    let paper = reproduce(&PaperOptions::default()).unwrap();
    let v = serde_json::to_value(&paper.tables).unwrap();
    let t1 = v["table1"].as_array().unwrap();
    let t2 = v["table2"].as_array().unwrap();
    // 3 digit counts × 2 pedestals × (k_y, k_z, m).
    assert_eq!(t1.len(), 18);
    // R&I: 2 × 5 parameters; R+I, R, I: 2 × 3.
    assert_eq!(t2.len(), 10 + 3 * 6);
    for r in t1 {
        for k in [
            "digits",
            "bearing",
            "param",
            "truth",
            "identified",
            "error_pct",
        ] {
            assert!(r.get(k).is_some(), "table1 row lacks {k}: {r}");
        }
    }
    for r in t2 {
        for k in [
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
    let modes: Vec<&str> = t2.iter().map(|r| r["mode"].as_str().unwrap()).collect();
    for m in ["R&I", "R+I", "R", "I"] {
        assert!(modes.contains(&m));
    }
    // error_pct is what it says.
    for r in &paper.tables.table1 {
        let e = 100.0 * (r.identified - r.truth) / r.truth;
        assert!((e - r.error_pct).abs() < 1e-9);
    }
}

#[test]
fn table1_accuracy_follows_the_digits() {
    let paper = reproduce(&PaperOptions::default()).unwrap();
    let err = |d: u32| {
        max_abs_error(
            paper
                .tables
                .table1
                .iter()
                .filter(|r| r.digits == d)
                .map(|r| (r.param.as_str(), r.error_pct)),
            &["k_y", "k_z", "m"],
        )
    };
    // 12 digits: exact to far below the data's precision.
    assert!(err(12) < 1e-6, "12 digits: {}%", err(12));
    // 3 digits (≤ 1 % input error): measured 0.26 %.
    assert!(err(3) < 0.5, "3 digits: {}%", err(3));
    // 2 digits *truncated* as the paper did (input error up to 10 %, one-sided):
    // the paper reached 2 %, this machine 2.2 %; the truncation bias of the
    // errors-in-variables regression does not average out with more speeds.
    assert!(err(2) < 3.0, "2 digits truncated: {}%", err(2));
}

#[test]
fn two_digits_rounded_meet_the_one_percent_goal() {
    // The paper's "maximum error of 5 %" at 2 digits is rounding (truncation
    // can be off by 10 %): with rounded data every k and m is within 1 %.
    let (u, d) = machines();
    let opts = PaperOptions {
        digits_mode: DigitsMode::Round,
        ..PaperOptions::default()
    };
    let paper = reproduce_with(&u, &d, &opts).unwrap();
    let worst = max_abs_error(
        paper
            .tables
            .table1
            .iter()
            .filter(|r| r.digits == 2)
            .map(|r| (r.param.as_str(), r.error_pct)),
        &["k_y", "k_z", "m"],
    );
    assert!(worst < 1.0, "2 digits rounded, R&I: worst {worst}%");
}

fn mode_error(rows: &[Table2Row], mode: &str, params: &[&str]) -> f64 {
    max_abs_error(
        rows.iter()
            .filter(|r| r.mode == mode)
            .map(|r| (r.param.as_str(), r.error_pct)),
        params,
    )
}

#[test]
fn table2_only_r_and_i_is_right_with_real_damping() {
    // The bundled damped machine has c = 70-100 N·s/m as the scan reads:
    // ζ ≈ 0.2 %, a damping force Ωc/k ≈ 0.3 % of the spring force at the
    // pedestal resonance, far below 2-digit precision, so no method sees it.
    // With 100× that damping (7-10 kN·s/m, ζ ≈ 10 %) the paper's finding
    // appears: R&I right (and c with it), R+I, R and I clearly wrong.
    let (u, mut d) = machines();
    for name in d.bearing_names() {
        let mut p = d.pedestal(&name).unwrap().unwrap();
        p.c_y *= 100.0;
        p.c_z *= 100.0;
        d.set_pedestal(&name, Some(p)).unwrap();
    }
    let opts = PaperOptions {
        digits_mode: DigitsMode::Round,
        ..PaperOptions::default()
    };
    let paper = reproduce_with(&u, &d, &opts).unwrap();
    let t2 = &paper.tables.table2;
    let km = ["k_y", "k_z", "m"];
    let ri = mode_error(t2, "R&I", &km);
    let ri_c = mode_error(t2, "R&I", &["c_y", "c_z"]);
    assert!(ri < 2.0, "R&I k, m: worst {ri}%");
    assert!(ri_c < 5.0, "R&I c: worst {ri_c}%");
    for mode in ["R+I", "R", "I"] {
        let e = mode_error(t2, mode, &km);
        assert!(
            e > 10.0,
            "{mode} should be clearly wrong, worst error only {e}%"
        );
    }
}

#[test]
fn table2_on_the_bundled_machine_gets_k_and_m() {
    let paper = reproduce(&PaperOptions::default()).unwrap();
    let e = mode_error(&paper.tables.table2, "R&I", &["k_y", "k_z", "m"]);
    assert!(
        e < 3.0,
        "R&I k, m on the bundled damped machine: worst {e}%"
    );
}
