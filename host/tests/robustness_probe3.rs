//! Defects found by the third bad-input probe (scripts/probe-inputs-3.sh):
//! a bearing coefficient or a phasor beyond any machine's taken by every
//! run reader (it failed later as an overflow in the fit, or not at all in
//! `plot`), and `accuracy --noise` below a double's rounding failing with a
//! message that did not name the option.

use std::path::Path;

mod robustness_common;
use robustness_common::{example, plinth_quiet, simulated_run, text};

/// Writes `value` into field `column` (0-based) of data line `line`
/// (1-based, the header is line 1) of `path`, editing the text.
fn set_field(path: &Path, line: usize, column: usize, value: &str) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut fields: Vec<&str> = lines[line - 1].split(',').collect();
    fields[column] = value;
    lines[line - 1] = fields.join(",");
    std::fs::write(path, lines.join("\n") + "\n").unwrap();
}

#[test]
fn absurd_coefficients_and_phasors_are_refused_at_their_line_and_column() {
    let t = tempfile::tempdir().unwrap();
    let clean = t.path().join("clean");
    simulated_run(&clean, "5:60:5");
    // (file, line, 0-based column, value, what the message names)
    let cases = [
        (
            "bearings.csv",
            2,
            2,
            "1.7976931348623157e308",
            "column 3 (`kyy`)",
        ),
        ("bearings.csv", 5, 9, "-2e11", "column 10 (`czz`)"),
        ("measurements.csv", 7, 6, "1e300", "column 7 (`ped_y_re`)"),
    ];
    for (k, (file, line, column, value, named)) in cases.iter().enumerate() {
        let run = t.path().join(format!("run{k}"));
        std::fs::create_dir(&run).unwrap();
        for f in ["measurements.csv", "bearings.csv", "truth.json"] {
            std::fs::copy(clean.join(f), run.join(f)).unwrap();
        }
        set_field(&run.join(file), *line, *column, value);
        for cmd in ["identify", "plot", "report", "diagnose"] {
            let mut c = plinth_quiet();
            c.arg(cmd).arg(&run);
            if cmd == "plot" || cmd == "report" {
                c.arg("--out").arg(t.path().join(format!("out-{k}-{cmd}")));
            }
            let o = c.output().unwrap();
            let msg = text(&o);
            assert!(!o.status.success(), "{cmd} {file} {value}: {msg}");
            assert!(
                msg.contains(&format!("{file}:{line}:")) && msg.contains(named),
                "{cmd} {file} {value}: {msg}"
            );
            assert!(!msg.contains("panicked"), "{msg}");
        }
    }
    // The clean run's numbers pass (the bounds' false alarms on it: none).
    let o = plinth_quiet().arg("identify").arg(&clean).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
}

#[test]
fn accuracy_noise_below_a_doubles_rounding_names_the_option() {
    for v in ["4.9e-324", "1e-300", "1e-17"] {
        let o = plinth_quiet()
            .arg("accuracy")
            .arg(example())
            .args(["--draws", "2", "--speeds", "5:60:5", "--noise", v])
            .output()
            .unwrap();
        let msg = text(&o);
        assert!(!o.status.success(), "{v}: {msg}");
        assert!(
            msg.contains("--noise") && msg.contains("rounding"),
            "{v}: {msg}"
        );
    }
    let o = plinth_quiet()
        .arg("accuracy")
        .arg(example())
        .args(["--draws", "2", "--speeds", "5:60:5", "--noise", "1e-6"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
}
