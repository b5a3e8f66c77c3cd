//! `plinth identify` and `plinth diagnose` report a bad input in the CLI's
//! one form: `error: WHERE: what is wrong`, WHERE a file with line and column,
//! a run directory, or a flag; the path once, no "reading …" prefix, no
//! operating-system text for a directory that is missing or is a file, and
//! exit code 1.

use plinth::identify::synthetic::SyntheticRun;
use plinth::rundir::{DigitsMode, WriteOptions};
use std::path::Path;
use std::process::Command;

fn run_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    SyntheticRun::paper_like(true, 30)
        .build()
        .unwrap()
        .write_with(
            dir.path(),
            &WriteOptions {
                digits: Some(4),
                digits_mode: DigitsMode::Round,
            },
        )
        .unwrap();
    dir
}

/// Runs `plinth COMMAND ARGS…`; returns the exit code and the `error:` line(s).
fn error_of(command: &str, args: &[&std::ffi::OsStr]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_plinth"))
        .arg(command)
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    let error = stderr
        .lines()
        .skip_while(|l| !l.starts_with("error:"))
        .collect::<Vec<_>>()
        .join("\n");
    (out.status.code().unwrap_or(-1), error)
}

fn both(args: &[&std::ffi::OsStr], check: impl Fn(&str)) {
    for command in ["identify", "diagnose"] {
        let (code, error) = error_of(command, args);
        assert_eq!(code, 1, "{command}: {error}");
        assert!(
            !error.contains("reading ") && !error.contains("identifying "),
            "{command}: {error}"
        );
        check(&error);
    }
}

fn replace_line(file: &Path, line: usize, f: impl Fn(&str) -> String) {
    let text = std::fs::read_to_string(file).unwrap();
    let lines: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(i, l)| if i + 1 == line { f(l) } else { l.to_string() })
        .collect();
    std::fs::write(file, lines.join("\n") + "\n").unwrap();
}

#[test]
fn a_missing_directory_or_a_file_is_named_without_os_text() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no-such-run");
    let m = missing.display().to_string();
    both(&[missing.as_os_str()], |e| {
        assert_eq!(e, format!("error: {m}: no such run directory"));
    });
    let run = run_dir();
    let file = run.path().join("measurements.csv");
    let f = file.display().to_string();
    both(&[file.as_os_str()], |e| {
        assert!(
            e.starts_with(&format!("error: {f}: not a directory")) && !e.contains("os error"),
            "{e}"
        );
    });
}

#[test]
fn a_bad_number_is_located_by_file_line_and_column_once() {
    let run = run_dir();
    let file = run.path().join("measurements.csv");
    replace_line(&file, 4, |l| {
        let mut cells: Vec<&str> = l.split(',').collect();
        cells[2] = "1.2.3";
        cells.join(",")
    });
    let f = file.display().to_string();
    both(&[run.path().as_os_str()], |e| {
        assert!(e.starts_with(&format!("error: {f}:4:3: ")), "{e}");
        assert!(e.contains("`1.2.3` is not a number"), "{e}");
        assert_eq!(e.matches(&f).count(), 1, "the path once: {e}");
    });
    // A bad bearing coefficient, the same way.
    let run = run_dir();
    let file = run.path().join("bearings.csv");
    replace_line(&file, 3, |l| {
        let mut cells: Vec<&str> = l.split(',').collect();
        cells[2] = "xx";
        cells.join(",")
    });
    let f = file.display().to_string();
    both(&[run.path().as_os_str()], |e| {
        assert!(e.starts_with(&format!("error: {f}:3:3: ")), "{e}");
        assert_eq!(e.matches(&f).count(), 1, "the path once: {e}");
    });
}

#[test]
fn a_bearing_without_coefficients_names_both_files() {
    let run = run_dir();
    let file = run.path().join("bearings.csv");
    let text = std::fs::read_to_string(&file).unwrap();
    let kept: Vec<&str> = text.lines().filter(|l| !l.contains(",right,")).collect();
    std::fs::write(&file, kept.join("\n") + "\n").unwrap();
    // The reader finds it first, at the first row of that bearing.
    let m = run.path().join("measurements.csv").display().to_string();
    let f = file.display().to_string();
    both(&[run.path().as_os_str()], |e| {
        assert!(e.starts_with(&format!("error: {m}:")), "{e}");
        assert!(e.contains("`right`") && e.contains(&f), "{e}");
    });
}

#[test]
fn diagnose_names_the_machine_flag() {
    let run = run_dir();
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "x = \n").unwrap();
    let b = bad.display().to_string();
    let (code, e) = error_of(
        "diagnose",
        &[
            run.path().as_os_str(),
            "--machine".as_ref(),
            bad.as_os_str(),
        ],
    );
    assert_eq!(code, 1, "{e}");
    assert!(e.starts_with(&format!("error: {b}")), "{e}");
    assert_eq!(e.matches(&b).count(), 1, "the path once: {e}");
    let missing = dir.path().join("none.toml");
    let (_, e) = error_of(
        "diagnose",
        &[
            run.path().as_os_str(),
            "--machine".as_ref(),
            missing.as_os_str(),
        ],
    );
    assert_eq!(e.matches("os error").count(), 1, "{e}");
    assert_eq!(e.matches(&missing.display().to_string()).count(), 1, "{e}");
}
