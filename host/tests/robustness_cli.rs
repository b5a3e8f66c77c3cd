//! Issue 13 through the `plinth` binary itself: outputs that never destroy
//! input, a stream that always ends, options validated before use, and
//! messages that say what was found and what is expected.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[path = "../../tests/tests/stream_common/one_frame.rs"]
mod one_frame;
use one_frame::one_frame_log;

mod robustness_common;
use robustness_common::{
    example, long_machine, offline_rebuild, plinth, run_bounded, simulated_run, snapshot,
    stream_config, text,
};

/// A "measured" run directory: a simulation whose files were then written by
/// someone else (not in Plinth's manifest), plus the raw log of a field run.
fn measured_run(dir: &Path) {
    let o = plinth()
        .args(["simulate", "--speeds", "5:60:5", "--out"])
        .arg(dir)
        .arg(example())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    std::fs::remove_file(dir.join(plinth::output::MANIFEST_FILE)).unwrap();
    std::fs::write(dir.join("raw.bin"), b"\x00field bytes\x00").unwrap();
}

#[test]
fn simulate_never_replaces_a_measured_run() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("measured");
    measured_run(&run);
    let before = snapshot(&run);

    let o = plinth()
        .arg("simulate")
        .arg(example())
        .arg("--out")
        .arg(&run)
        .output()
        .unwrap();
    assert!(!o.status.success());
    let msg = text(&o);
    assert!(
        msg.contains("already holds a run directory") && msg.contains("--force"),
        "{msg}"
    );
    assert_eq!(snapshot(&run), before);

    // --force: measurements.csv is not Plinth's, so it is not replaced.
    let o = plinth()
        .arg("simulate")
        .arg(example())
        .arg("--force")
        .arg("--out")
        .arg(&run)
        .output()
        .unwrap();
    assert!(!o.status.success());
    let msg = text(&o);
    assert!(
        msg.contains(
            "bearings.csv (and measurements.csv) would be replaced, but Plinth did not write it"
        ),
        "{msg}"
    );
    assert_eq!(snapshot(&run), before);
    // Nothing left beside it either.
    let names: Vec<_> = std::fs::read_dir(t.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("measured")]);
}

#[test]
fn simulate_force_replaces_its_own_files_and_keeps_others() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("sim");
    let sim = |extra: &[&str]| {
        let o = plinth()
            .arg("simulate")
            .arg(example())
            .args(extra)
            .arg("--out")
            .arg(&run)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", text(&o));
    };
    sim(&["--speeds", "5:50:5"]);
    std::fs::write(run.join("notes.txt"), "commissioning notes").unwrap();
    let outside = t.path().join("outside.csv");
    std::fs::write(&outside, "not yours").unwrap();
    std::os::unix::fs::symlink(&outside, run.join("link.csv")).unwrap();
    sim(&["--speeds", "5:100:5", "--force"]);
    let after = snapshot(&run);
    assert_eq!(after["notes.txt"], b"commissioning notes");
    assert_eq!(std::fs::read(&outside).unwrap(), b"not yours");
    assert!(run
        .join("link.csv")
        .symlink_metadata()
        .unwrap()
        .file_type()
        .is_symlink());
    let rows = String::from_utf8(after["measurements.csv"].clone()).unwrap();
    assert_eq!(rows.lines().count(), 1 + 20 * 2, "the new run is in place");
}

#[test]
fn out_that_is_a_file_or_a_link_is_refused() {
    let t = tempfile::tempdir().unwrap();
    let file = t.path().join("file");
    std::fs::write(&file, "x").unwrap();
    let o = plinth()
        .arg("simulate")
        .arg(example())
        .arg("--out")
        .arg(&file)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(
        text(&o).contains("is a file, not a directory"),
        "{}",
        text(&o)
    );
    assert_eq!(std::fs::read(&file).unwrap(), b"x");

    let link = t.path().join("link");
    std::os::unix::fs::symlink(t.path(), &link).unwrap();
    let o = plinth()
        .arg("simulate")
        .arg(example())
        .arg("--out")
        .arg(&link)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(text(&o).contains("symbolic link"), "{}", text(&o));
}

#[test]
fn killing_simulate_mid_run_leaves_the_previous_run_byte_identical() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    simulated_run(&run, "5:50:5");
    let before = snapshot(&run);
    let machine = long_machine(t.path(), 12_000);
    for delay_ms in [150u64, 600] {
        let mut child = plinth()
            .arg("simulate")
            .arg(&machine)
            .args(["--speeds", "5:200:0.5", "--force", "--out"])
            .arg(&run)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(delay_ms));
        let finished = child.try_wait().unwrap().is_some();
        assert!(!finished, "the simulation ended before it was killed");
        child.kill().unwrap(); // SIGKILL
        child.wait().unwrap();
        assert_eq!(snapshot(&run), before, "killed after {delay_ms} ms");
    }
}

#[test]
fn numeric_options_are_validated_before_use() {
    let t = tempfile::tempdir().unwrap();
    let config = t.path().join("stream.toml");
    std::fs::write(&config, "bearings = \"b.csv\"\n").unwrap();
    for (flag, value) in [
        ("--duration", "-1"),
        ("--duration", "nan"),
        ("--duration", "1e30"),
        ("--reconnect-timeout", "1e30"),
        ("--reconnect-timeout", "inf"),
        ("--handshake-timeout", "-0.5"),
        ("--window", "0"),
    ] {
        let o = plinth()
            .args(["stream", "--port", "/dev/null", "--out"])
            .arg(t.path().join("out"))
            .arg("--config")
            .arg(&config)
            .arg(format!("{flag}={value}"))
            .output()
            .unwrap();
        let msg = text(&o);
        assert_eq!(o.status.code(), Some(2), "{flag}={value}: {msg}");
        assert!(msg.contains(flag) && !msg.contains("panicked"), "{msg}");
    }
    for value in ["-0.1", "nan", "x"] {
        let o = plinth()
            .arg("simulate")
            .arg(example())
            .arg(format!("--noise={value}"))
            .arg("--out")
            .arg(t.path().join("n"))
            .output()
            .unwrap();
        let msg = text(&o);
        assert_eq!(o.status.code(), Some(2), "{msg}");
        assert!(msg.contains("--noise") && !msg.contains("speeds:"), "{msg}");
    }
    // Contradictory flags are refused, not ignored.
    let o = plinth()
        .args(["stream", "--offline", "--port", "/dev/null", "--out", "o"])
        .arg("--config")
        .arg(&config)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let o = plinth()
        .arg("simulate")
        .arg(example())
        .args(["--truncate", "--out", "o"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(!t.path().join("out").exists() && !t.path().join("n").exists());
}

#[test]
fn a_silent_port_ends_the_stream_with_a_clear_error_and_changes_nothing() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    measured_run(&run);
    let config = stream_config(&run);
    let before = snapshot(&run);
    // A pseudo-terminal nobody answers on (a wrong adapter, no firmware).
    let (_master, port) = plinth::stream::port::pseudo_terminal().unwrap();
    for quiet in [false, true] {
        let mut cmd = plinth();
        cmd.args(["stream", "--port", &port, "--handshake-timeout", "1"])
            .args(["--reconnect-timeout", "2", "--duration", "3", "--config"])
            .arg(&config)
            .arg("--out")
            .arg(&run);
        if quiet {
            cmd.arg("--quiet");
        }
        let started = Instant::now();
        let o = run_bounded(&mut cmd, Duration::from_secs(30));
        let msg = text(&o);
        assert!(!o.status.success(), "{msg}");
        assert!(
            msg.contains(&format!("no answer from the box on serial port {port}"))
                && msg.contains("is it the box's port, is the firmware running?"),
            "{msg}"
        );
        assert!(started.elapsed() < Duration::from_secs(10), "{msg}");
        assert_eq!(snapshot(&run), before);
        assert!(!plinth::stream::staging_dir(&run).exists());
    }
}

#[test]
fn offline_rebuild_of_an_empty_log_is_refused_and_changes_nothing() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    measured_run(&run);
    let config = stream_config(&run);
    std::fs::write(run.join("raw.bin"), b"").unwrap();
    let before = snapshot(&run);
    let o = offline_rebuild(&config, &run);
    let msg = text(&o);
    assert!(!o.status.success(), "{msg}");
    assert!(
        msg.contains("raw.bin is empty (0 bytes") && msg.contains("no run to rebuild"),
        "{msg}"
    );
    assert_eq!(snapshot(&run), before);
    assert!(!plinth::stream::staging_dir(&run).exists());
}

#[test]
fn offline_rebuild_with_the_runs_own_config_keeps_it() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    simulated_run(&run, "5:60:5");
    let config = stream_config(&run);
    std::fs::write(run.join("raw.bin"), one_frame_log(30.0, 2)).unwrap();
    let config_before = std::fs::read(&config).unwrap();
    let o = offline_rebuild(&config, &run);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(std::fs::read(&config).unwrap(), config_before);
    assert!(!config_before.is_empty());
    assert!(run.join("stream-report.json").is_file());
    // The simulation's stale truth.json went with the rest of its output.
    assert!(!run.join("truth.json").exists());
}

#[test]
fn identify_refuses_a_fifo_and_names_spreadsheet_layouts() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    simulated_run(&run, "5:60:5");
    let m = run.join("measurements.csv");
    let good = std::fs::read_to_string(&m).unwrap();

    // European Excel: `;` and decimal commas.
    let euro: String = good
        .lines()
        .map(|l| l.replace(',', ";").replace('.', ","))
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(&m, euro).unwrap();
    let o = plinth().arg("identify").arg(&run).output().unwrap();
    let msg = text(&o);
    assert!(
        msg.contains("measurements.csv:1: the header")
            && msg.contains("separated by `;` with decimal commas"),
        "{msg}"
    );
    // UTF-16 with a byte-order mark.
    let utf16: Vec<u8> = [0xFF, 0xFE]
        .into_iter()
        .chain(good.encode_utf16().flat_map(u16::to_le_bytes))
        .collect();
    std::fs::write(&m, utf16).unwrap();
    let msg = text(&plinth().arg("identify").arg(&run).output().unwrap());
    assert!(
        msg.contains("UTF-16") && msg.contains("expected UTF-8"),
        "{msg}"
    );
    // A UTF-8 byte-order mark (Excel's "CSV UTF-8") is read.
    std::fs::write(&m, format!("\u{feff}{good}")).unwrap();
    let o = plinth().arg("identify").arg(&run).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));

    // A FIFO in place of measurements.csv: refused at once, not read.
    std::fs::remove_file(&m).unwrap();
    let status = Command::new("mkfifo").arg(&m).status().unwrap();
    assert!(status.success());
    let o = run_bounded(plinth().arg("identify").arg(&run), Duration::from_secs(20));
    let msg = text(&o);
    assert!(!o.status.success());
    assert!(msg.contains("not a regular file"), "{msg}");
}

#[test]
fn operating_system_errors_are_printed_once() {
    let o = plinth()
        .args(["identify", "/nonexistent/plinth-run"])
        .output()
        .unwrap();
    let msg = text(&o);
    assert!(!o.status.success());
    // Named once, in the CLI's form (`DIR: no such run directory`), with
    // the operating system's text at most once.
    assert!(
        msg.matches("No such file or directory").count() <= 1,
        "{msg}"
    );
    assert_eq!(msg.matches("/nonexistent/plinth-run").count(), 1, "{msg}");
    assert!(msg.contains("no such run directory"), "{msg}");
}

#[test]
fn predict_takes_damping_consistent_with_zero_as_zero() {
    let t = tempfile::tempdir().unwrap();
    let run = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/run-paper-2digits");
    let o = plinth()
        .arg("identify")
        .arg(&run)
        .args(["--json", "--estimator", "ols"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let id = t.path().join("id.json");
    std::fs::write(&id, &o.stdout).unwrap();
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let negative = json["pedestals"]
        .as_array()
        .unwrap()
        .iter()
        .any(|p| p["c_y"].as_f64() < Some(0.0) || p["c_z"].as_f64() < Some(0.0));
    assert!(
        negative,
        "the bundled example has a negative damping within its error"
    );
    let o = plinth()
        .arg("predict")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/feng-hahn-1997-damped.toml"))
        .arg("--pedestals")
        .arg(&id)
        .arg("--against")
        .arg(&run)
        .output()
        .unwrap();
    let msg = text(&o);
    assert!(o.status.success(), "{msg}");
    assert!(
        msg.contains("is consistent with zero: re-predicted with c_"),
        "{msg}"
    );
}
