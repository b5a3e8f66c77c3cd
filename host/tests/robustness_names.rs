//! Issue 20, item 1: names are never paths. Hostile bearing names in a run
//! directory, an import layout or transducers.csv are refused where they
//! are read (file, line, column or key named), and every figure file stays
//! directly inside `--out`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn plinth() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plinth"))
}

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures/field")
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Every path under `root` (relative), files and directories.
fn tree(root: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            out.push(p.strip_prefix(root).unwrap().display().to_string());
            if e.file_type().unwrap().is_dir() {
                stack.push(p);
            }
        }
    }
    out.sort();
    out
}

/// A copy of the fixture run with bearing `left` renamed to `name` in both tables.
fn renamed_run(dir: &Path, name: &str) -> PathBuf {
    let run = dir.join("run");
    std::fs::create_dir_all(&run).unwrap();
    for f in ["measurements.csv", "bearings.csv"] {
        let t = std::fs::read_to_string(fixtures().join("sim").join(f)).unwrap();
        std::fs::write(run.join(f), t.replace(",left,", &format!(",{name},"))).unwrap();
    }
    run
}

#[test]
fn hostile_bearing_names_in_a_run_are_refused_and_nothing_is_written() {
    let t = tempfile::tempdir().unwrap();
    for (i, name) in ["../../../x", "DE/NDE", "..", "a\\b"].iter().enumerate() {
        let case = t.path().join(format!("c{i}"));
        let run = renamed_run(&case, name);
        let out = case.join("figs");
        let o = plinth()
            .arg("plot")
            .arg(&run)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let msg = text(&o);
        assert!(!o.status.success(), "{name}: {msg}");
        assert!(
            msg.contains("measurements.csv:2:") && msg.contains("bearing"),
            "{name}: {msg}"
        );
        assert!(!msg.contains("panicked"), "{msg}");
        assert!(!out.exists(), "{name}: --out was written");
        assert_eq!(
            tree(&case),
            ["run", "run/bearings.csv", "run/measurements.csv"]
        );
        let o = plinth().arg("identify").arg(&run).output().unwrap();
        assert!(
            !o.status.success() && text(&o).contains("bearing"),
            "{}",
            text(&o)
        );
    }
}

#[test]
fn names_with_spaces_and_dots_give_figures_inside_out_only() {
    let t = tempfile::tempdir().unwrap();
    let run = renamed_run(t.path(), "Brg. 2 (DE)");
    let out = t.path().join("figs");
    let o = plinth()
        .arg("plot")
        .arg(&run)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let files = tree(&out);
    assert!(files.iter().all(|f| !f.contains('/')), "{files:?}");
    assert!(
        files
            .iter()
            .any(|f| f.starts_with("bode_Brg.%202%20%28DE%29_rel")),
        "{files:?}"
    );
    assert_eq!(
        tree(t.path())
            .iter()
            .filter(|f| !f.starts_with("run") && !f.starts_with("figs"))
            .count(),
        0
    );
}

#[test]
fn hostile_names_in_a_layout_or_transducers_csv_are_refused_with_their_key() {
    let t = tempfile::tempdir().unwrap();
    let tables = fixtures().join("tables");
    let layout = std::fs::read_to_string(tables.join("arbitrary_angles.toml")).unwrap();
    let bad = t.path().join("layout.toml");
    std::fs::write(
        &bad,
        layout.replace("bearing = \"left\"", "bearing = \"../../left\""),
    )
    .unwrap();
    let out = t.path().join("imported");
    let o = plinth()
        .arg("import")
        .arg(tables.join("arbitrary_angles.csv"))
        .arg("--layout")
        .arg(&bad)
        .arg("--bearings")
        .arg(fixtures().join("sim/bearings.csv"))
        .arg("--out")
        .arg(&out)
        .arg("--plots")
        .output()
        .unwrap();
    let msg = text(&o);
    assert!(!o.status.success(), "{msg}");
    assert!(
        msg.contains("transducer[0].bearing") && msg.contains("path separator"),
        "{msg}"
    );
    assert!(!out.exists());

    // transducers.csv of a run: read by `plot`.
    let run = renamed_run(t.path(), "left");
    std::fs::write(
        run.join("transducers.csv"),
        "bearing,quantity,angle_deg\nleft,rel,45\n../../../x,rel,135\n",
    )
    .unwrap();
    let figs = t.path().join("figs");
    let o = plinth()
        .arg("plot")
        .arg(&run)
        .arg("--out")
        .arg(&figs)
        .output()
        .unwrap();
    let msg = text(&o);
    assert!(!o.status.success(), "{msg}");
    assert!(msg.contains("transducers.csv:3:1"), "{msg}");
    assert!(!figs.exists() && !t.path().join("x.png").exists());
}
