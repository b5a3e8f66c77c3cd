//! The `plinth identify` binary itself: table, JSON, options and errors.

use plinth::identify::synthetic::SyntheticRun;
use plinth::identify::Identification;
use plinth::rundir::{DigitsMode, WriteOptions};
use std::process::Command;

fn plinth() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plinth"))
}

fn run_dir(digits: Option<u32>) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let run = SyntheticRun::paper_like(true, 60).build().unwrap();
    run.write_with(
        dir.path(),
        &WriteOptions {
            digits,
            digits_mode: DigitsMode::Round,
        },
    )
    .unwrap();
    dir
}

#[test]
fn table_and_json() {
    let dir = run_dir(Some(3));
    let out = plinth().arg("identify").arg(dir.path()).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let table = String::from_utf8(out.stdout).unwrap();
    assert!(
        table.starts_with(
            "estimator maximum likelihood (errors in variables), equations R&I, model k_y,k_z,m,c_y,c_z"
        ),
        "{table}"
    );
    assert!(
        table.contains("k_y [MN/m]") && table.contains("  truth"),
        "{table}"
    );
    assert!(!table.contains("UNTRUSTED"), "{table}");

    let out = plinth()
        .args([
            "identify",
            "--json",
            "--estimator",
            "ols",
            "--equations",
            "real",
            "--model",
            "k_y,k_z,m",
        ])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let id: Identification = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(id.model, ["k_y", "k_z", "m"]);
    assert_eq!(id.equations, "real");
    assert_eq!(id.pedestals.len(), 2);
    assert_eq!(id.pedestals[0].fixed, ["c_y", "c_z"]);
    assert!((id.pedestals[0].pedestal.k_y - 1.0e7).abs() < 0.01 * 1.0e7);
}

#[test]
fn warnings_go_to_stderr_and_untrusted_fits_are_marked() {
    let dir = tempfile::tempdir().unwrap();
    let mut recipe = SyntheticRun::paper_like(true, 2);
    recipe.speeds_hz = vec![40.0, 80.0];
    recipe.build().unwrap().write(dir.path()).unwrap();
    let out = plinth().arg("identify").arg(dir.path()).output().unwrap();
    assert!(out.status.success());
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains("warning: pedestal `left`: only 2 distinct speed"),
        "{stderr}"
    );
    let table = String::from_utf8(out.stdout).unwrap();
    assert!(table.contains("UNTRUSTED"), "{table}");
}

#[test]
fn errors_name_the_file_line_and_column() {
    let dir = run_dir(None);
    let path = dir.path().join("measurements.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let broken = text.replacen(",left,", ",left,x", 1);
    std::fs::write(&path, broken).unwrap();
    let out = plinth().arg("identify").arg(dir.path()).output().unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains("measurements.csv:2:3: column `rel_y_re`"),
        "{stderr}"
    );

    let out = plinth()
        .args(["identify", "--model", "k_y,q"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains("unknown pedestal parameter `q`"),
        "{stderr}"
    );
}
