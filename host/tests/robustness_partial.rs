//! Issue 20, the last silent inputs: a `truth.json` that lacks a measured
//! bearing is said (text, JSON, a warning naming the file) instead of being
//! taken silently, and `diagnose --machine` says that it replaces the
//! machine file's base under the measured pedestals.

use std::path::{Path, PathBuf};

mod robustness_common;
use robustness_common::{example, plinth_quiet, simulated_run, text};

/// Drops the pedestal of `bearing` from `run/truth.json` (through
/// serde_json's own value, not Plinth's reader).
fn drop_truth_of(run: &Path, bearing: &str) {
    let path = run.join("truth.json");
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let pedestals = json["pedestals"].as_array_mut().unwrap();
    let before = pedestals.len();
    pedestals.retain(|p| p["bearing"] != bearing);
    assert_eq!(pedestals.len(), before - 1, "no pedestal {bearing}");
    std::fs::write(&path, serde_json::to_string_pretty(&json).unwrap()).unwrap();
}

/// The lines of `table` from the row of `bearing` to the next blank line.
fn block<'a>(table: &'a str, bearing: &str) -> Vec<&'a str> {
    table
        .lines()
        .skip_while(|l| !l.trim_start().starts_with(bearing))
        .take_while(|l| !l.trim().is_empty())
        .collect()
}

#[test]
fn a_truth_without_a_measured_bearing_says_which_in_text_and_json() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    simulated_run(&run, "5:60:5");

    // The whole truth: no warning, no key, a truth row under each pedestal.
    let o = plinth_quiet().arg("identify").arg(&run).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let stdout = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(!String::from_utf8_lossy(&o.stderr).contains("truth"));
    for b in ["left", "right"] {
        let rows = block(&stdout, b);
        assert!(
            rows.iter()
                .any(|l| l.trim_start().starts_with("truth") && !l.contains("none")),
            "{b}:\n{stdout}"
        );
    }
    let o = plinth_quiet()
        .arg("identify")
        .arg(&run)
        .arg("--json")
        .output()
        .unwrap();
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(json.get("bearings_without_truth").is_none(), "{json}");

    // Truth for `left` only: accepted, and `right` named everywhere.
    drop_truth_of(&run, "right");
    let o = plinth_quiet().arg("identify").arg(&run).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let stdout = String::from_utf8_lossy(&o.stdout).to_string();
    let stderr = String::from_utf8_lossy(&o.stderr).to_string();
    // The truth warning names `right` only (other warnings, e.g. a delay
    // not excluded at a pedestal whose true damping is zero, may name
    // `left` on their own lines).
    let truth_lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains("truth.json"))
        .collect();
    assert!(
        !truth_lines.is_empty()
            && truth_lines
                .iter()
                .all(|l| l.contains("`right`") && !l.contains("`left`")),
        "{stderr}"
    );
    let right = block(&stdout, "right");
    assert!(
        right
            .iter()
            .any(|l| l.trim_start().starts_with("truth") && l.contains("none")),
        "{stdout}"
    );
    assert!(
        !right.iter().any(|l| l.trim_start().starts_with("error")),
        "{stdout}"
    );
    let left = block(&stdout, "left");
    assert!(
        left.iter().any(|l| l.trim_start().starts_with("error")),
        "{stdout}"
    );

    let o = plinth_quiet()
        .arg("identify")
        .arg(&run)
        .arg("--json")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        json["bearings_without_truth"],
        serde_json::json!(["right"]),
        "{json}"
    );
    assert_eq!(json["pedestals"].as_array().unwrap().len(), 2);

    // Truth naming a bearing the run lacks stays an error.
    let path = run.join("truth.json");
    let edited = std::fs::read_to_string(&path)
        .unwrap()
        .replace("\"left\"", "\"middle\"");
    std::fs::write(&path, edited).unwrap();
    let o = plinth_quiet().arg("identify").arg(&run).output().unwrap();
    assert!(!o.status.success());
    assert!(text(&o).contains("`middle`"), "{}", text(&o));
}

/// `plinth simulate MACHINE --speeds SPEEDS --noise 0.005 --out DIR`.
fn simulate(machine: &Path, out: &Path) {
    let o = plinth_quiet()
        .arg("simulate")
        .arg(machine)
        .args(["--speeds", "5:60:2.5", "--noise", "0.005", "--out"])
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
}

fn skid() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/two-pedestals-on-skid.toml")
}

/// `plinth diagnose RUN --machine MACHINE` (`--json` when `json`), quiet.
fn diagnose_machine(run: &Path, machine: &Path, json: bool) -> std::process::Output {
    let mut c = plinth_quiet();
    c.arg("diagnose").arg(run).arg("--machine").arg(machine);
    if json {
        c.arg("--json");
    }
    c.output().unwrap()
}

#[test]
fn diagnose_machine_says_it_replaces_the_files_base() {
    let t = tempfile::tempdir().unwrap();
    // The skid machine's run, checked against its own file: both pedestals
    // stand on `skid` there.
    let run = t.path().join("skid");
    simulate(&skid(), &run);
    let o = diagnose_machine(&run, &skid(), true);
    assert!(o.status.success(), "{}", text(&o));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let verdict = json["verdict"].as_str().unwrap();
    assert!(
        verdict.contains("replaces the machine file's base `skid` under `left`, `right`"),
        "{verdict}"
    );
    let o = diagnose_machine(&run, &skid(), false);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains(verdict),
        "the text report lacks the verdict:\n{}",
        text(&o)
    );

    // A machine file on rigid ground: nothing replaced, nothing said.
    let run = t.path().join("rigid");
    simulate(&example(), &run);
    let o = diagnose_machine(&run, &example(), true);
    assert!(o.status.success(), "{}", text(&o));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let verdict = json["verdict"].as_str().unwrap();
    assert!(!verdict.contains("replaces"), "{verdict}");
    assert!(json["machine_gap_after"].as_f64().is_some(), "{json}");
}
