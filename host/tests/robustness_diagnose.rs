//! Issue 13: `diagnose` on data with a convention mistake says what its own
//! numbers say: a gap that grew is said to have risen, never to have fallen,
//! and the text report agrees with the JSON.

use std::path::Path;
use std::process::Command;

fn plinth() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plinth"))
}

/// Conjugates every phasor of `measurements.csv` (negates the `*_im`
/// columns by editing the text, independently of Plinth's own readers): the
/// phasor-convention mistake q(t) = Re{Q e^{−iΩt}}.
fn conjugate(run: &Path) {
    let path = run.join("measurements.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut out = vec![header.join(",")];
    for line in lines {
        let fields: Vec<String> = line
            .split(',')
            .zip(&header)
            .map(|(f, h)| {
                if h.ends_with("_im") {
                    match f.strip_prefix('-') {
                        Some(rest) => rest.to_string(),
                        None => format!("-{f}"),
                    }
                } else {
                    f.to_string()
                }
            })
            .collect();
        out.push(fields.join(","));
    }
    std::fs::write(&path, out.join("\n") + "\n").unwrap();
}

/// Runs `diagnose` with and without `--json` and checks the wording of the
/// verdict against gap_before and gap_after; returns (before, after, steps).
fn check_wording(run: &Path) -> (f64, f64, usize) {
    let o = plinth()
        .arg("diagnose")
        .arg(run)
        .arg("--json")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let json: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let before = json["gap_before"].as_f64().unwrap();
    let after = json["gap_after"].as_f64().unwrap();
    let steps = json["steps"].as_array().unwrap().len();
    let verdict = json["verdict"].as_str().unwrap().to_string();
    if steps > 0 {
        assert!(
            verdict.contains(&format!("from {before:.4} to {after:.4}")),
            "{verdict}"
        );
        if after > before {
            assert!(
                verdict.contains("ROSE") && !verdict.contains("fell"),
                "{verdict}"
            );
        } else if after < before {
            assert!(
                verdict.contains("fell") && !verdict.contains("ROSE"),
                "{verdict}"
            );
        }
    }
    let o = plinth().arg("diagnose").arg(run).output().unwrap();
    let report = String::from_utf8_lossy(&o.stdout);
    assert!(
        report.contains(&verdict),
        "text report lacks the verdict:\n{report}"
    );
    assert!(
        report.contains(&format!("Pedestal-level gap {before:.4}")),
        "{report}"
    );
    (before, after, steps)
}

#[test]
fn a_gap_that_rose_is_never_said_to_have_fallen() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    let machine =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/feng-hahn-1997-damped.toml");
    let o = plinth()
        .arg("simulate")
        .arg(&machine)
        .args(["--speeds", "5:200:2", "--noise", "0.01", "--out"])
        .arg(&run)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    conjugate(&run);
    let (before, after, steps) = check_wording(&run);
    // The conjugated data make diagnose add effects that do not help: the
    // case the wording must get right.
    assert!(steps > 0, "no effect added ({before} -> {after})");
}
