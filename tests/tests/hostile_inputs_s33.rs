//! Inputs found wanting by the session-33 hostile probe (docs/robustness-hostile.md):
//! a TOML or JSON file that is not UTF-8 failed with "stream did not contain
//! valid UTF-8" and no place, a `truth.json` saved with a byte-order mark
//! failed at "line 1 column 1", and a `truth.json` listing one bearing's
//! pedestal twice was taken silently (one of the two values compared).
//! The run and machine files come from the bundled example and the
//! simulator's run writer; each case edits one file as an editor would.

use plinth::rundir::RunDir;
use plinth::sim::machine::Machine;
use std::path::{Path, PathBuf};

/// The bundled damped paper machine.
fn example_machine() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/feng-hahn-1997-damped.toml")
}

/// A run directory of the example machine (5 to 200 Hz, exact phasors,
/// with its `truth.json`) in `dir`, as the simulator writes it.
fn run_in(dir: &Path) -> PathBuf {
    let machine = plinth_tests::rundown::machine("examples/feng-hahn-1997-damped.toml");
    let run = plinth_tests::rundown::run(&machine, None, None);
    assert!(run.truth.is_some());
    let path = dir.join("run");
    run.write(&path).unwrap();
    path
}

/// The line [1-based] of the second line of `text` that holds `needle`.
fn second_line_with(text: &str, needle: &str) -> usize {
    let mut lines = text.lines().enumerate().filter(|(_, l)| l.contains(needle));
    lines.nth(1).map(|(i, _)| i + 1).expect("two lines")
}

#[test]
fn a_truth_json_with_a_byte_order_mark_is_read_as_without() {
    let t = tempfile::tempdir().unwrap();
    let run = run_in(t.path());
    let plain = RunDir::read(&run).unwrap();
    let truth = run.join("truth.json");
    let mut bytes = vec![0xEF, 0xBB, 0xBF];
    bytes.extend(std::fs::read(&truth).unwrap());
    std::fs::write(&truth, bytes).unwrap();
    let with_bom = RunDir::read(&run).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(with_bom.truth, plain.truth);
}

#[test]
fn a_pedestal_listed_twice_in_truth_json_is_refused_at_the_second() {
    let t = tempfile::tempdir().unwrap();
    let run = run_in(t.path());
    let truth = run.join("truth.json");
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    let pedestals = json["pedestals"].as_array_mut().unwrap();
    let mut again = pedestals[0].clone();
    again["m"] = serde_json::json!(81.0);
    pedestals.push(again);
    let text = serde_json::to_string_pretty(&json).unwrap();
    std::fs::write(&truth, &text).unwrap();
    let second = second_line_with(&text, "\"bearing\": \"left\"");
    let e = RunDir::read(&run)
        .expect_err("a pedestal twice")
        .to_string();
    assert!(
        e.contains(&format!("truth.json:{second}:")) && e.contains("`left` is listed twice"),
        "{e}"
    );
}

#[test]
fn a_machine_file_in_latin_1_or_utf_16_is_named_with_its_place() {
    let t = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(example_machine()).unwrap();
    // The file saved in Latin-1 (its `·` and `µ` are single bytes there):
    // named at its first character outside ASCII.
    let (line, column, byte) = text
        .lines()
        .enumerate()
        .find_map(|(i, l)| {
            l.chars()
                .position(|c| !c.is_ascii())
                .map(|c| (i + 1, c + 1, l.chars().nth(c).unwrap() as u32))
        })
        .unwrap();
    let latin = t.path().join("latin.toml");
    let bytes: Vec<u8> = text.chars().map(|c| c as u32 as u8).collect();
    std::fs::write(&latin, bytes).unwrap();
    let e = Machine::from_toml_path(&latin)
        .expect_err("Latin-1")
        .to_string();
    assert!(
        e.contains(&format!(
            "line {line}, column {column}: byte 0x{byte:02X} is not UTF-8"
        )),
        "{e}"
    );

    // The same file saved as UTF-16 (Windows "Unicode").
    let utf16 = t.path().join("utf16.toml");
    let mut bytes = vec![0xFF, 0xFE];
    bytes.extend(text.encode_utf16().flat_map(u16::to_le_bytes));
    std::fs::write(&utf16, bytes).unwrap();
    let e = Machine::from_toml_path(&utf16)
        .expect_err("UTF-16")
        .to_string();
    assert!(e.contains("UTF-16") && e.contains("iconv"), "{e}");

    // With a UTF-8 byte-order mark it is the same machine.
    let bom = t.path().join("bom.toml");
    let mut bytes = vec![0xEF, 0xBB, 0xBF];
    bytes.extend(text.as_bytes());
    std::fs::write(&bom, bytes).unwrap();
    let plain = Machine::from_toml_path(example_machine()).unwrap();
    let read = Machine::from_toml_path(&bom).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(read.bearings.len(), plain.bearings.len());
}

#[test]
fn a_speed_listed_twice_is_refused_before_a_run_no_reader_takes_is_written() {
    // `simulate --speeds 5,5,10` wrote two rows per bearing at 5 Hz, which
    // every reader then refused ("duplicate row for speed 5 Hz"); `accuracy`
    // counted the speed twice. The option is refused, naming the speed.
    // (A STEP below the doubles' spacing at 65536, 1.5e-11: 20 001 speeds,
    // inside the speeds budget of session 35, so the repeat is what is named.)
    for list in ["5,5,10", "10,5,5.0", "65536:65536.0000001:5e-12"] {
        let e = plinth::sim::cli::parse_speeds(list)
            .expect_err(list)
            .to_string();
        assert!(
            e.starts_with("--speeds ") && e.contains("Hz comes twice"),
            "{e}"
        );
    }
    assert_eq!(
        plinth::sim::cli::parse_speeds("10,5").unwrap(),
        vec![10.0, 5.0]
    );
}

#[test]
fn an_identification_listing_a_pedestal_twice_is_refused_by_predict() {
    // Two identifications pasted into one file: `predict` applied the
    // last `left` without a word (on the example, k_y doubled: the rms
    // difference from the run went from 25 % to 102 %). Placed at the second `"bearing": "left"`, not at the
    // noise section's `"left"` key.
    let t = tempfile::tempdir().unwrap();
    let path = t.path().join("id.json");
    let one = serde_json::json!({"bearing": "left", "k_y": 1e7, "k_z": 8e6, "m": 80.0,
                                 "c_y": 100.0, "c_z": 90.0, "trusted": true});
    let mut other = one.clone();
    other["k_y"] = serde_json::json!(2e7);
    let file = serde_json::json!({"noise": {"left": {"sd": 1e-9}}, "pedestals": [one, other]});
    let text = serde_json::to_string_pretty(&file).unwrap();
    std::fs::write(&path, &text).unwrap();
    let second = second_line_with(&text, "\"bearing\": \"left\"");
    let e = plinth::sim::predict::read_identified(&path)
        .expect_err("a pedestal twice")
        .to_string();
    assert!(
        e.contains(&format!("id.json:{second}:")) && e.contains("\"left\" is listed twice"),
        "{e}"
    );
}

#[test]
fn a_header_of_a_hundred_thousand_columns_is_checked_in_one_pass() {
    // Unknown columns are allowed (formats.md: new optional columns), so a
    // header of 100 000 of them is read; its duplicate check compared every
    // column with every earlier one (5e9 comparisons: 68 s for `identify`
    // with main's binary, 0.13 s now; measured, not asserted: no timed
    // tests). A duplicate at the end is still named at its column.
    let t = tempfile::tempdir().unwrap();
    let run = run_in(t.path());
    let path = run.join("measurements.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let n = 100_000;
    let mut lines = text.lines();
    let mut header = lines.next().unwrap().to_string();
    for i in 0..n {
        header.push_str(&format!(",x{i}"));
    }
    header.push_str(",x7");
    let cells = ",1".repeat(n + 1);
    let mut out = header + "\n";
    for l in lines {
        out.push_str(l);
        out.push_str(&cells);
        out.push('\n');
    }
    std::fs::write(&path, out).unwrap();
    let e = RunDir::read(&run).expect_err("x7 twice").to_string();
    assert!(
        e.contains(&format!(":1:{}", 10 + n + 1)) && e.contains("x7") && e.contains("twice"),
        "{e}"
    );
}
