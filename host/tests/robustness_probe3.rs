//! Defects found by the third bad-input probe (scripts/probe-inputs-3.sh):
//! a bearing coefficient or a phasor beyond any machine's taken by every
//! run reader (it failed later as an overflow in the fit, or not at all in
//! `plot`), `accuracy --noise` below a double's rounding failing with a
//! message that did not name the option, and a keyphasor with two pulses
//! per revolution blamed on the sample rate alone.

use std::path::Path;

mod robustness_common;
use robustness_common::{edited_wav, example, field, plinth_quiet, simulated_run, text};

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
        ("bearings.csv", 5, 9, "-2e17", "column 10 (`czz`)"),
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

/// A "rigid" support written as a bearing of 1e16 N/m (a test machine's
/// idealisation) is simulated and its run read back: the bounds leave room.
#[test]
fn a_rigid_support_of_1e16_n_per_m_is_read_back() {
    let t = tempfile::tempdir().unwrap();
    let text_of = std::fs::read_to_string(example()).unwrap();
    let film = "oil_film = { diameter = 0.1, length = 0.0254, clearance = 40.0e-6, viscosity = 0.0069, load = \"weight\" }";
    assert!(text_of.contains(film));
    let rigid = text_of.replace(
        film,
        "coefficients = [ { speed_hz = 0.0, kyy = 1e16, kzz = 1e16, cyy = 1e6, czz = 1e6 } ]",
    );
    let machine = t.path().join("rigid.toml");
    std::fs::write(&machine, rigid).unwrap();
    let run = t.path().join("run");
    let o = plinth_quiet()
        .arg("simulate")
        .arg(&machine)
        .args(["--speeds", "5:60:5", "--out"])
        .arg(&run)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let o = plinth_quiet()
        .arg("plot")
        .arg(&run)
        .arg("--out")
        .arg(t.path().join("plots"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
}

#[test]
fn a_keyphasor_with_two_pulses_per_revolution_is_named_as_a_possible_cause() {
    let t = tempfile::tempdir().unwrap();
    // The keyphasor's codes (channel 8 of 9, 24-bit): each notch copied 20
    // samples later, a second mark on the shaft.
    let bytes = std::fs::read(field("recording.wav")).unwrap();
    let data = bytes.windows(4).position(|w| w == b"data").unwrap() + 8;
    let kp: Vec<i32> = bytes[data..]
        .chunks_exact(3)
        .skip(8)
        .step_by(9)
        .map(|s| i32::from_le_bytes([0, s[0], s[1], s[2]]) >> 8)
        .collect();
    let low = *kp.iter().min().unwrap();
    let high = *kp.iter().max().unwrap();
    let mid = (low + high) / 2;
    let doubled = edited_wav(t.path(), "doubled.wav", |frame, c, v| {
        if c == 8 && frame >= 20 && kp[frame - 20] < mid {
            low
        } else {
            v
        }
    });
    let o = plinth_quiet()
        .arg("extract")
        .arg(&doubled)
        .arg("--channels")
        .arg(field("channels.toml"))
        .arg("--bearings")
        .arg(field("bearings.csv"))
        .arg("--out")
        .arg(t.path().join("out"))
        .output()
        .unwrap();
    let msg = text(&o);
    assert!(!o.status.success(), "{msg}");
    assert!(
        msg.contains("doubled.wav") && msg.contains("more than one pulse per revolution"),
        "{msg}"
    );
    assert!(!t.path().join("out").exists());
}
