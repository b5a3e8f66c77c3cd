//! Issue 20, session 20: the classes the fresh probe (scripts/probe-inputs-2.sh)
//! found, one test each: a thousands separator that shifts a table row, phases
//! in radians, too few speeds, another run's truth.json, a noise column of
//! zeros, option values that never reached their checks (negative numbers,
//! `--effect`), absurd speeds, a seismic channel below its noise, an `--out`
//! whose parents are missing, and numbers printed in full in messages.

mod robustness_common;
use robustness_common::{example, field, plinth, simulated_run, text};
use std::path::Path;
use std::process::Output;

/// A copy of the field example's import inputs in `dir`.
fn field_inputs(dir: &Path) {
    for f in ["vector-table.csv", "layout.toml", "bearings.csv"] {
        std::fs::copy(field(f), dir.join(f)).unwrap();
    }
}

fn import(dir: &Path, out: &str) -> Output {
    plinth()
        .arg("--quiet")
        .arg("import")
        .arg(dir.join("vector-table.csv"))
        .arg("--layout")
        .arg(dir.join("layout.toml"))
        .arg("--bearings")
        .arg(dir.join("bearings.csv"))
        .arg("--out")
        .arg(dir.join(out))
        .output()
        .unwrap()
}

/// The table's rows as fields (no quotes in the example).
fn table_rows(dir: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(dir.join("vector-table.csv"))
        .unwrap()
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

fn write_table(dir: &Path, rows: &[Vec<String>]) {
    let text: String = rows.iter().map(|r| r.join(",") + "\n").collect();
    std::fs::write(dir.join("vector-table.csv"), text).unwrap();
}

fn error_line(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr)
        .lines()
        .rfind(|l| l.starts_with("error:"))
        .unwrap_or("")
        .to_string()
}

#[test]
fn a_thousands_separator_that_shifts_a_row_is_refused_and_empty_trailing_columns_are_not() {
    let d = tempfile::tempdir().unwrap();
    field_inputs(d.path());
    let clean = import(d.path(), "clean");
    assert!(clean.status.success(), "{}", text(&clean));
    // Spreadsheet trailing empty columns on the data rows: the same run.
    let mut rows = table_rows(d.path());
    for r in rows.iter_mut().skip(1) {
        r.extend(["".to_string(), "".to_string()]);
    }
    write_table(d.path(), &rows);
    let trailing = import(d.path(), "trailing");
    assert!(trailing.status.success(), "{}", text(&trailing));
    assert_eq!(
        std::fs::read(d.path().join("clean/measurements.csv")).unwrap(),
        std::fs::read(d.path().join("trailing/measurements.csv")).unwrap()
    );
    // `1,234` unquoted in an amplitude of line 6: every later column shifts.
    let mut rows = table_rows(d.path());
    let width = rows[0].len();
    rows[5].truncate(width);
    rows[5][4] = "1,234".into();
    write_table(d.path(), &rows);
    let o = import(d.path(), "shifted");
    assert!(!o.status.success(), "{}", text(&o));
    let e = error_line(&o);
    assert!(
        e.contains("vector-table.csv:6:") && e.contains("thousands separator"),
        "{e}"
    );
    assert!(!d.path().join("shifted").exists());
}

#[test]
fn phases_in_radians_are_named_and_the_degrees_of_the_example_are_not() {
    let d = tempfile::tempdir().unwrap();
    field_inputs(d.path());
    let clean = import(d.path(), "clean");
    assert!(clean.status.success(), "{}", text(&clean));
    assert!(!text(&clean).contains("radians"), "{}", text(&clean));
    let mut rows = table_rows(d.path());
    let phase_columns: Vec<usize> = (0..rows[0].len())
        .filter(|&j| rows[0][j].contains("Phase"))
        .collect();
    for r in rows.iter_mut().skip(1) {
        for &j in &phase_columns {
            let deg: f64 = r[j].parse().unwrap();
            r[j] = format!("{:.4}", deg.to_radians());
        }
    }
    write_table(d.path(), &rows);
    let o = import(d.path(), "radians");
    let t = text(&o);
    assert!(
        t.contains("warning:") && t.contains("radians") && t.contains("vector-table.csv"),
        "{t}"
    );
}

#[test]
fn identify_and_accuracy_need_two_speeds_and_say_so() {
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("run");
    simulated_run(&run, "10:30:10");
    let m = run.join("measurements.csv");
    let text_m = std::fs::read_to_string(&m).unwrap();
    let kept: String = text_m
        .lines()
        .filter(|l| l.starts_with("speed_hz") || l.starts_with("20,"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&m, kept).unwrap();
    let o = plinth()
        .args(["--quiet", "identify"])
        .arg(&run)
        .output()
        .unwrap();
    assert!(!o.status.success(), "{}", text(&o));
    let e = error_line(&o);
    assert!(
        e.contains("measurements.csv") && e.contains("only 1 speed") && e.contains("at least 2"),
        "{e}"
    );
    for speeds in ["5:5:1", "5"] {
        let o = plinth()
            .args(["--quiet", "accuracy"])
            .arg(example())
            .args(["--draws", "2", "--speeds", speeds])
            .output()
            .unwrap();
        assert!(!o.status.success(), "{speeds}: {}", text(&o));
        let e = error_line(&o);
        assert!(e.contains("--speeds") && e.contains("at least 2"), "{e}");
        assert!(o.stdout.is_empty(), "no table printed: {}", text(&o));
    }
}

#[test]
fn a_truth_naming_another_bearing_and_a_noise_column_of_zeros_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("run");
    simulated_run(&run, "10:40:5");
    let identify = || {
        plinth()
            .args(["--quiet", "identify"])
            .arg(&run)
            .output()
            .unwrap()
    };
    assert!(identify().status.success());
    let truth = run.join("truth.json");
    let original = std::fs::read_to_string(&truth).unwrap();
    std::fs::write(&truth, original.replace("\"left\"", "\"LEFT\"")).unwrap();
    let o = identify();
    assert!(!o.status.success(), "{}", text(&o));
    let e = error_line(&o);
    assert!(
        e.contains("truth.json:") && e.contains("`LEFT`") && e.contains("`left`"),
        "{e}"
    );
    std::fs::write(&truth, &original).unwrap();
    // Noise columns, one of them 0 on every row.
    let m = run.join("measurements.csv");
    let rows: String = std::fs::read_to_string(&m)
        .unwrap()
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 0 {
                format!("{l},rel_y_sd,rel_z_sd,ped_y_sd,ped_z_sd\n")
            } else {
                format!("{l},1e-9,0,1e-9,1e-9\n")
            }
        })
        .collect();
    std::fs::write(&m, rows).unwrap();
    let o = identify();
    assert!(!o.status.success(), "{}", text(&o));
    let e = error_line(&o);
    assert!(
        e.contains("measurements.csv:2:") && e.contains("`rel_z_sd` is 0 on every row"),
        "{e}"
    );
}

#[test]
fn option_values_reach_their_checks_and_errors_name_the_option() {
    let cases: [(&[&str], &str); 6] = [
        (
            &["paper", "--heavy-damping-ratio", "-1"],
            "--heavy-damping-ratio",
        ),
        (
            &["paper", "--heavy-damping-ratio", "1e9"],
            "--heavy-damping-ratio",
        ),
        (
            &["identify", "run", "--max-condition", "-1"],
            "--max-condition",
        ),
        (&["demo", "--averaging", "4294967295"], "--averaging"),
        (
            &["signals", "M", "--out", "o", "--effect", "nosuch"],
            "--effect",
        ),
        (
            &["simulate", "M", "--out", "o", "--speeds", "1e308:1e308:1"],
            "--speeds",
        ),
    ];
    let d = tempfile::tempdir().unwrap();
    for (args, option) in cases {
        let args: Vec<String> = args
            .iter()
            .map(|a| match *a {
                "M" => example().display().to_string(),
                other => other.to_string(),
            })
            .collect();
        let o = plinth()
            .arg("--quiet")
            .args(&args)
            .current_dir(d.path())
            .output()
            .unwrap();
        assert!(!o.status.success(), "{args:?}: {}", text(&o));
        let all = String::from_utf8_lossy(&o.stderr).to_string();
        assert!(all.contains(option), "{args:?}: {all}");
        assert!(
            !all.contains("unexpected argument"),
            "{args:?}: a value taken for an option: {all}"
        );
        assert!(all.len() < 600, "{args:?}: {all}");
    }
    assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 0);
}

#[test]
fn absurd_speeds_are_refused_and_numbers_in_messages_stay_short() {
    let d = tempfile::tempdir().unwrap();
    for (cmd, value) in [("--speeds", "1e9:2e9:1e8"), ("--rundown", "1e9:5:5")] {
        let sub = if cmd == "--speeds" {
            "simulate"
        } else {
            "signals"
        };
        let o = plinth()
            .args(["--quiet", sub])
            .arg(example())
            .arg("--out")
            .arg(d.path().join("o"))
            .args([cmd, value])
            .output()
            .unwrap();
        assert!(!o.status.success(), "{}", text(&o));
        let e = error_line(&o);
        assert!(e.contains(cmd) && e.contains("6 million rpm"), "{e}");
    }
    // A table speed of 1e-300 rpm: refused at its line, the number short.
    field_inputs(d.path());
    let mut rows = table_rows(d.path());
    rows[7][1] = "1e-300".into();
    write_table(d.path(), &rows);
    let o = import(d.path(), "out");
    assert!(!o.status.success(), "{}", text(&o));
    let e = error_line(&o);
    assert!(e.contains("vector-table.csv:8:2:") && e.len() < 400, "{e}");
}

#[test]
fn a_seismic_channel_below_its_noise_is_named_and_the_default_set_is_not() {
    let d = tempfile::tempdir().unwrap();
    let signals = |out: &str, extra: &[&str]| {
        plinth()
            .args(["--quiet", "signals"])
            .arg(example())
            .args(["--rundown", "60:55:5", "--out"])
            .arg(d.path().join(out))
            .args(extra)
            .output()
            .unwrap()
    };
    let plain = signals("plain", &[]);
    assert!(plain.status.success(), "{}", text(&plain));
    assert!(!text(&plain).contains("noise only"), "{}", text(&plain));
    let faint = signals("faint", &["--seismic-sensitivity", "1e-9"]);
    let t = text(&faint);
    assert!(
        t.contains("warning: left_ped_y") && t.contains("noise only"),
        "{t}"
    );
}

#[test]
fn an_out_whose_parents_are_missing_is_created() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("site/2025-05-03/run");
    let o = plinth()
        .args(["--quiet", "simulate"])
        .arg(example())
        .args(["--speeds", "10:20:5", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    assert!(out.join("measurements.csv").is_file());
}
