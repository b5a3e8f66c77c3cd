//! Inputs found wanting by the session-34 hostile probe (docs/robustness-hostile.md, "Session 34"):
//! a machine file with a subnormal pedestal mass (1e-310 kg) was accepted,
//! a `truth.json` key Plinth does not read (`k_yy` beside `k_y`, `efects`)
//! or an effect name it does not know (`probe_runnout`) was dropped without
//! a word, and a raw log that filled the disk said "cannot append N bytes"
//! without saying that part of them was lost. The runs come from the
//! simulator's run writer and the stored ROSS runs; each case edits one file
//! as an editor would.

use plinth::rundir::truth_keys::unread;
use plinth::rundir::{RunDir, Truth};
use plinth::sim::machine::Machine;
use std::path::{Path, PathBuf};

/// The bundled damped paper machine's text.
fn example_machine() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/feng-hahn-1997-damped.toml");
    std::fs::read_to_string(path).unwrap()
}

/// The notes on `text` read as a `truth.json`.
fn notes(text: &str) -> Vec<String> {
    let truth: Truth = serde_json::from_str(text).unwrap();
    unread(text, &truth)
}

#[test]
fn a_subnormal_pedestal_value_in_a_machine_file_is_refused_at_its_key() {
    let text = example_machine();
    for (from, to, key, why) in [
        ("m = 80.0", "m = 1e-310", "bearings[0].pedestal.m", "> 0"),
        (
            "k_y = 10.0e6",
            "k_y = 4.9e-324",
            "bearings[0].pedestal.k_y",
            "> 0",
        ),
        (
            "c_y = 100.0",
            "c_y = 1e-320",
            "bearings[0].pedestal.c_y",
            ">= 0",
        ),
    ] {
        assert!(text.contains(from), "{from}");
        let edited = text.replacen(from, to, 1);
        let e = Machine::from_toml_str(&edited, "m.toml")
            .map(|_| ())
            .expect_err(to)
            .to_string();
        assert!(
            e.contains(&format!("m.toml: {key}: must be a finite number {why}"))
                && e.contains("subnormal"),
            "{to}: {e}"
        );
    }
    // The smallest normal number and zero damping stay valid inputs.
    let edited =
        text.replacen("m = 80.0", "m = 2.3e-308", 1)
            .replacen("c_y = 100.0", "c_y = 0.0", 1);
    Machine::from_toml_str(&edited, "m.toml").unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn truth_keys_and_effect_names_plinth_does_not_read_are_named_at_their_place() {
    // The example machine's run (5 to 200 Hz) as the simulator writes it.
    let t = tempfile::tempdir().unwrap();
    let machine = plinth_tests::rundown::machine("examples/feng-hahn-1997-damped.toml");
    let run = t.path().join("run");
    plinth_tests::rundown::run(&machine, None, None)
        .write(&run)
        .unwrap();
    let path = run.join("truth.json");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(notes(&text).is_empty(), "{:?}", notes(&text));
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["pedestals"][1]["k_yy"] = serde_json::json!(2.0e7);
    json["efects"] = serde_json::json!(["sensor_delay"]);
    json["effects"] = serde_json::json!(["probe_runnout"]);
    json["source"] = serde_json::json!("a hand edit");
    let edited = serde_json::to_string_pretty(&json).unwrap();
    std::fs::write(&path, &edited).unwrap();
    // Still read (formats.md lets a format grow), with a note per key or name.
    let read = RunDir::read(&run).unwrap_or_else(|e| panic!("{e}"));
    let n = unread(&edited, read.truth.as_ref().unwrap());
    assert_eq!(n.len(), 3, "{n:?}");
    let line_of = |needle: &str| {
        edited
            .lines()
            .position(|l| l.contains(needle))
            .map(|i| i + 1)
            .unwrap()
    };
    let has =
        |prefix: String, rest: &str| n.iter().any(|m| m.starts_with(&prefix) && m.contains(rest));
    assert!(
        has(
            format!("{}:", line_of("\"k_yy\"")),
            "key `k_yy` (pedestals[1].k_yy)"
        ),
        "{n:?}"
    );
    assert!(
        has(
            format!("{}:", line_of("\"efects\"")),
            "key `efects` (efects)"
        ),
        "{n:?}"
    );
    assert!(
        has(
            format!("{}:", line_of("\"probe_runnout\"")),
            "effects[0] `probe_runnout` is not an effect"
        ),
        "{n:?}"
    );
}

/// Every `truth.json` under `dir`, at any depth.
fn truths_under(dir: &Path, found: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            truths_under(&path, found);
        } else if path.file_name().is_some_and(|n| n == "truth.json") {
            found.push(path);
        }
    }
}

#[test]
fn stored_runs_carrying_a_source_key_have_no_note() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut found = Vec::new();
    for dir in ["data", "reference", "../examples"] {
        truths_under(&root.join(dir), &mut found);
    }
    assert!(found.len() >= 50, "only {} stored truths", found.len());
    let mut sources = 0;
    for path in &found {
        let text = std::fs::read_to_string(path).unwrap();
        sources += usize::from(text.contains("\"source\""));
        assert!(
            notes(&text).is_empty(),
            "{}: {:?}",
            path.display(),
            notes(&text)
        );
    }
    assert!(sources >= 4, "{sources} truths carry `source`");
}

#[cfg(target_os = "linux")]
#[test]
fn a_raw_log_on_a_full_disk_says_how_many_bytes_were_lost() {
    let full = Path::new("/dev/full");
    if !full.exists() {
        return;
    }
    let mut log = plinth::stream::rawlog::RawLog::open(full).unwrap();
    let e = format!(
        "{:#}",
        log.append(&[1, 2, 3, 4, 5]).expect_err("a full disk")
    );
    assert!(
        e.contains("cannot append 5 bytes to the raw log /dev/full at byte 0 (0 of them written, the last 5 lost)"),
        "{e}"
    );
}
