//! The modal view: f_n and ζ with their standard errors in `identify`'s
//! JSON and table and under `diagnose`'s tables, and the speed band
//! (`--speeds LO:HI`) of both.

use super::{json, plinth, run_dir, succeeded};

/// `identify --json` carries `modal` for every pedestal: f_n within 0.1 %
/// of √(k/m)/2π of the truth and within 3 of its standard errors, ζ within
/// 3 of its standard errors; the table shows the same numbers in Hz and rpm.
#[test]
fn identify_reports_natural_frequencies_and_damping_ratios() {
    let (dir, run) = run_dir();
    let d = dir.path().to_str().unwrap();
    let v = json(&["identify", d, "--json"]);
    let truth = run.truth.as_ref().unwrap();
    for p in v["pedestals"].as_array().unwrap() {
        let t = truth
            .pedestals
            .iter()
            .find(|t| t.bearing == p["bearing"].as_str().unwrap())
            .unwrap();
        for (dir, k, c) in [
            ("y", t.pedestal.k_y, t.pedestal.c_y),
            ("z", t.pedestal.k_z, t.pedestal.c_z),
        ] {
            let m = &p["modal"][dir];
            let f_true = (k / t.pedestal.m).sqrt() / std::f64::consts::TAU;
            let zeta_true = c / (2.0 * (k * t.pedestal.m).sqrt());
            let f = m["f_n_hz"].as_f64().unwrap();
            let f_se = m["f_n_std_err"].as_f64().unwrap();
            let z = m["zeta"].as_f64().unwrap();
            let z_se = m["zeta_std_err"].as_f64().unwrap();
            assert!((f / f_true - 1.0).abs() < 1e-3, "{dir}: {f} vs {f_true}");
            assert!(
                (f - f_true).abs() < 3.0 * f_se,
                "{dir}: {f} ± {f_se} vs {f_true}"
            );
            assert!(f_se > 0.0 && z_se > 0.0);
            assert!(
                (z - zeta_true).abs() < 3.0 * z_se,
                "{dir}: ζ {z} ± {z_se} vs {zeta_true}"
            );
        }
        assert_eq!(p["covariance"].as_array().map(Vec::len), Some(5));
    }
    let out = plinth().args(["identify", d]).output().unwrap();
    let table = String::from_utf8(out.stdout).unwrap();
    assert!(
        table.contains("f_n [rpm]") && table.contains("ζ [%]"),
        "{table}"
    );
    assert!(
        table.contains("left y") && table.contains("right z"),
        "{table}"
    );
}

/// `--speeds LO:HI` fits only that band; a band with no speed, or a bad
/// one, is an error naming the option.
#[test]
fn speed_band() {
    let (dir, _) = run_dir();
    let d = dir.path().to_str().unwrap();
    let v = json(&["identify", d, "--json", "--speeds", "20:120"]);
    for p in v["pedestals"].as_array().unwrap() {
        let r = &p["speed_range_hz"];
        assert!(
            r[0].as_f64().unwrap() >= 20.0 && r[1].as_f64().unwrap() <= 120.0,
            "{r}"
        );
    }
    for (band, says) in [("900:1000", "no measured speed"), ("120:20", "LO")] {
        let out = plinth()
            .args(["identify", d, "--speeds", band])
            .output()
            .unwrap();
        assert!(!out.status.success(), "{band}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--speeds") && err.contains(says), "{err}");
    }
}

/// One row of a modal table (see [`modal_blocks`]).
type ModalRow = (String, f64, f64, f64, f64);

/// The rows of the modal table: (pedestal and direction, f_n [Hz], its
/// standard error, ζ [%], its standard error), for each `natural frequency`
/// block of `text` in order.
fn modal_blocks(text: &str) -> Vec<Vec<ModalRow>> {
    let mut blocks = Vec::new();
    let mut lines = text.lines();
    while let Some(l) = lines.next() {
        if !l.starts_with("natural frequency f_n") {
            continue;
        }
        assert!(lines.next().unwrap().starts_with("pedestal"), "{text}");
        let mut rows = Vec::new();
        for l in lines.by_ref() {
            if l.trim().is_empty() || l.starts_with("≈0") || l.starts_with("± -") {
                break;
            }
            if l.starts_with("  ") {
                continue; // truth
            }
            let cells: Vec<&str> = l.split("  ").filter(|c| !c.trim().is_empty()).collect();
            let pm = |c: &str| -> (f64, f64) {
                let (v, s) = c
                    .split_once(" ± ")
                    .unwrap_or_else(|| panic!("{c:?} in {l}"));
                let s = s.split_whitespace().next().unwrap();
                (v.trim().parse().unwrap(), s.parse().unwrap_or(f64::NAN))
            };
            let (f, fs) = pm(cells[1]);
            let (z, zs) = pm(cells[3]);
            rows.push((cells[0].trim().to_string(), f, fs, z, zs));
        }
        blocks.push(rows);
    }
    blocks
}

/// `diagnose` shows its pedestals through identify's printer: the same
/// columns and units, and under each table f_n (Hz, rpm) and ζ (%) with ±
/// from the diagnosis fit's covariance. On a simulated run the f_n are
/// within 0.1 % and 3 standard errors of the truth, ζ within 3 standard
/// errors, and the ± are of the size identify reports (same data, an
/// estimator within a factor of a few of the bound).
#[test]
fn diagnose_prints_the_modal_view_like_identify() {
    let (dir, run) = run_dir();
    let d = dir.path().to_str().unwrap();
    let out = succeeded(plinth().args(["diagnose", d]).output().unwrap());
    let text = String::from_utf8(out.stdout).unwrap();
    let header = "bearing  k_y [MN/m]";
    assert_eq!(text.matches(header).count(), 2, "{text}");
    let blocks = modal_blocks(&text);
    assert_eq!(blocks.len(), 2, "base and final model: {text}");
    let identified =
        String::from_utf8(plinth().args(["identify", d]).output().unwrap().stdout).unwrap();
    let reference = &modal_blocks(&identified)[0];
    let truth = run.truth.as_ref().unwrap();
    for rows in &blocks {
        assert_eq!(rows.len(), 4, "{text}");
        for ((name, f, fs, z, zs), (name_i, f_i, fs_i, _, zs_i)) in rows.iter().zip(reference) {
            assert_eq!(name, name_i);
            let (bearing, dir) = name.split_once(' ').unwrap();
            let t = truth
                .pedestals
                .iter()
                .find(|t| t.bearing == bearing)
                .unwrap();
            let (k, c) = if dir == "y" {
                (t.pedestal.k_y, t.pedestal.c_y)
            } else {
                (t.pedestal.k_z, t.pedestal.c_z)
            };
            let f_true = (k / t.pedestal.m).sqrt() / std::f64::consts::TAU;
            let z_true = 100.0 * c / (2.0 * (k * t.pedestal.m).sqrt());
            assert!(
                fs.is_finite() && *fs > 0.0 && zs.is_finite() && *zs > 0.0,
                "{text}"
            );
            assert!((f / f_true - 1.0).abs() < 1e-3, "{name}: {f} vs {f_true}");
            assert!(
                (f - f_true).abs() < 3.0 * fs,
                "{name}: {f} ± {fs} vs {f_true}"
            );
            assert!(
                (z - z_true).abs() < 3.0 * zs,
                "{name}: ζ {z} ± {zs} vs {z_true}"
            );
            // The same fit in both printers, so close values and ± of one size.
            assert!(
                (f - f_i).abs() < 3.0 * fs.max(*fs_i),
                "{name}: {f} vs {f_i}"
            );
            for (a, b) in [(fs, fs_i), (zs, zs_i)] {
                assert!(
                    a / b > 0.2 && a / b < 5.0,
                    "{name}: ± {a} vs identify's {b}"
                );
            }
        }
    }
}

/// `diagnose --speeds LO:HI` diagnoses only that band (every place where
/// the disagreement lives is inside it), and a band with no speed is an
/// error naming the option, as for `identify`.
#[test]
fn diagnose_fits_a_speed_band() {
    let (dir, _) = run_dir();
    let d = dir.path().to_str().unwrap();
    let whole = json(&["diagnose", d, "--json"]);
    let band = json(&["diagnose", d, "--json", "--speeds", "30:90"]);
    assert_ne!(whole["gap_before"], band["gap_before"]);
    let peaks: Vec<f64> = band["where_before"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["peak_hz"].as_f64().unwrap())
        .collect();
    assert!(!peaks.is_empty());
    assert!(peaks.iter().all(|p| (30.0..=90.0).contains(p)), "{peaks:?}");
    let out = plinth()
        .args(["diagnose", d, "--speeds", "900:1000"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--speeds") && err.contains("no measured speed"),
        "{err}"
    );
}
