//! Issue 20, item 3 through the command line: counts read from a file are
//! checked against the memory budget before what they imply is allocated.
//! `PLINTH_MEMORY_MB` lowers the budget, so small files stand for large
//! ones: a table or run directory with more rows than the budget holds is
//! refused at its first extra line, naming the file and the figures, and
//! nothing is written.

mod robustness_common;
use robustness_common::{example, field, plinth, simulated_run, text};

#[test]
fn a_table_with_more_rows_than_the_budget_holds_is_refused_at_its_first_extra_line() {
    let t = tempfile::tempdir().unwrap();
    // The example table's first row, at 1200 distinct speeds.
    let example = std::fs::read_to_string(field("vector-table.csv")).unwrap();
    let mut lines = example.lines();
    let header = lines.next().unwrap();
    let first: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut table = format!("{header}\n");
    for i in 0..1200 {
        let mut row = first.clone();
        let sample = (i + 1).to_string();
        let rpm = format!("{:.1}", 4500.0 - 2.5 * f64::from(i));
        row[0] = &sample;
        row[1] = &rpm;
        table.push_str(&row.join(","));
        table.push('\n');
    }
    let path = t.path().join("long-table.csv");
    std::fs::write(&path, table).unwrap();
    let out = t.path().join("out");
    let o = plinth()
        .env("PLINTH_MEMORY_MB", "1")
        .arg("import")
        .arg(&path)
        .arg("--layout")
        .arg(field("layout.toml"))
        .arg("--bearings")
        .arg(field("bearings.csv"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let msg = text(&o);
    assert!(!o.status.success(), "{msg}");
    assert!(
        msg.contains("long-table.csv")
            && msg.contains("line 1025: more than 1024 lines")
            && msg.contains("1 MB available")
            && msg.contains("PLINTH_MEMORY_MB"),
        "{msg}"
    );
    assert!(!msg.contains("panicked"), "{msg}");
    assert!(!out.exists(), "{msg}");
}

#[test]
fn a_run_directory_with_more_rows_than_the_budget_holds_is_refused_naming_its_file() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    simulated_run(&run, "5:200:0.1");
    let o = plinth()
        .env("PLINTH_MEMORY_MB", "1")
        .arg("identify")
        .arg(&run)
        .output()
        .unwrap();
    let msg = text(&o);
    assert!(!o.status.success(), "{msg}");
    assert!(
        msg.contains(".csv") && msg.contains("line 1025: more than 1024 lines"),
        "{msg}"
    );
    assert!(!msg.contains("panicked"), "{msg}");
}

#[test]
fn an_unreadable_memory_budget_is_named_and_not_used() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    let o = plinth()
        .env("PLINTH_MEMORY_MB", "lots")
        .arg("simulate")
        .arg(example())
        .args(["--speeds", "5:60:5", "--out"])
        .arg(&run)
        .output()
        .unwrap();
    let msg = text(&o);
    assert!(o.status.success(), "{msg}");
    assert_eq!(
        msg.matches(
            "warning: PLINTH_MEMORY_MB: `lots` is not a whole number of MiB >= 1; not used"
        )
        .count(),
        1,
        "{msg}"
    );
}

#[test]
fn a_signal_set_its_disk_cannot_hold_is_refused_before_any_work() {
    // 195 000 s of run-down at 10 MHz: 1.95e12 samples × 8 channels × 2
    // bytes = 31 TB of `samples.i16` alone, more than any test disk holds.
    // The free space is checked before the memory budget and before the
    // staging directory is made (session 37: only the memory budget
    // refused it, naming no disk; a set that fits memory but not the disk
    // was written until the disk was full).
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("sig");
    let o = plinth()
        .arg("signals")
        .arg(example())
        .args(["--rundown", "200:5:0.001", "--rate", "1e7", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let msg = text(&o);
    assert!(!o.status.success(), "{msg}");
    assert!(
        msg.contains(&format!("--out {}: would need at least ", out.display()))
            && msg.contains("bytes free")
            && msg.contains("nothing was written"),
        "{msg}"
    );
    assert!(!msg.contains("panicked"), "{msg}");
    let left: Vec<_> = std::fs::read_dir(t.path()).unwrap().collect();
    assert!(left.is_empty(), "{left:?}");
}
