//! Issue 13, the rest: inputs that are not regular files never block,
//! leftovers of killed commands are cleared by the next one, `signals`
//! validates every number and its memory before allocating, contradictory
//! flags are refused, and operating-system errors are printed once.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod robustness_common;
use robustness_common::{example, long_machine, plinth, run_bounded, simulated_run, text};

fn mkfifo(path: &Path) {
    let _ = std::fs::remove_file(path);
    let status = Command::new("mkfifo").arg(path).status().unwrap();
    assert!(status.success(), "mkfifo {}", path.display());
}

fn simulate(out: &Path) {
    simulated_run(out, "5:60:5");
}

/// Expects a prompt refusal naming `file` as not a regular file.
fn refused_as_not_a_file(cmd: &mut Command, file: &str) {
    let o = run_bounded(cmd, Duration::from_secs(30));
    let msg = text(&o);
    assert!(!o.status.success(), "{file}: {msg}");
    assert!(
        msg.contains(file) && msg.contains("not a regular file"),
        "{file}: {msg}"
    );
    assert!(!msg.contains("panicked"), "{msg}");
}

#[test]
fn fifos_where_files_are_expected_are_refused_without_blocking() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    simulate(&run);

    // truth.json and bearings.csv of a run directory.
    for name in ["truth.json", "bearings.csv"] {
        let copy = t.path().join(format!("run-{name}"));
        std::fs::create_dir(&copy).unwrap();
        for f in ["measurements.csv", "bearings.csv", "truth.json"] {
            std::fs::copy(run.join(f), copy.join(f)).unwrap();
        }
        mkfifo(&copy.join(name));
        refused_as_not_a_file(plinth().arg("identify").arg(&copy), name);
    }

    // A machine file, to simulate, signals and predict.
    let machine = t.path().join("machine.toml");
    mkfifo(&machine);
    refused_as_not_a_file(
        plinth()
            .arg("simulate")
            .arg(&machine)
            .arg("--out")
            .arg(t.path().join("o1")),
        "machine.toml",
    );
    refused_as_not_a_file(
        plinth()
            .arg("signals")
            .arg(&machine)
            .arg("--out")
            .arg(t.path().join("o2")),
        "machine.toml",
    );

    // predict's identification JSON.
    let ident = t.path().join("ident.json");
    mkfifo(&ident);
    refused_as_not_a_file(
        plinth()
            .arg("predict")
            .arg(example())
            .arg("--pedestals")
            .arg(&ident)
            .arg("--against")
            .arg(&run),
        "ident.json",
    );

    // stream's configuration (offline rebuild: no port needed).
    let config = t.path().join("stream.toml");
    mkfifo(&config);
    refused_as_not_a_file(
        plinth()
            .args(["stream", "--offline", "--config"])
            .arg(&config)
            .arg("--out")
            .arg(t.path().join("o3")),
        "stream.toml",
    );
    // base.csv of a run directory (identify).
    let copy = t.path().join("run-base");
    std::fs::create_dir(&copy).unwrap();
    for f in ["measurements.csv", "bearings.csv"] {
        std::fs::copy(run.join(f), copy.join(f)).unwrap();
    }
    mkfifo(&copy.join("base.csv"));
    refused_as_not_a_file(plinth().arg("identify").arg(&copy), "base.csv");

    // import's table and layout, extract's recording and channels file.
    let field = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures/field");
    let tables = field.join("tables");
    let fifo_table = t.path().join("table.csv");
    let fifo_layout = t.path().join("layout.toml");
    mkfifo(&fifo_table);
    mkfifo(&fifo_layout);
    for (table, layout, name) in [
        (
            fifo_table.clone(),
            tables.join("arbitrary_angles.toml"),
            "table.csv",
        ),
        (
            tables.join("arbitrary_angles.csv"),
            fifo_layout.clone(),
            "layout.toml",
        ),
    ] {
        refused_as_not_a_file(
            plinth()
                .arg("import")
                .arg(&table)
                .arg("--layout")
                .arg(&layout)
                .arg("--bearings")
                .arg(field.join("sim/bearings.csv"))
                .arg("--out")
                .arg(t.path().join("o4")),
            name,
        );
    }
    let fifo_rec = t.path().join("rec.wav");
    let fifo_channels = t.path().join("channels.toml");
    mkfifo(&fifo_rec);
    mkfifo(&fifo_channels);
    let wav = field.join("wav");
    for (rec, channels, name) in [
        (fifo_rec.clone(), wav.join("channels.toml"), "rec.wav"),
        (
            wav.join("rec_int16.wav"),
            fifo_channels.clone(),
            "channels.toml",
        ),
    ] {
        refused_as_not_a_file(
            plinth()
                .arg("extract")
                .arg(&rec)
                .arg("--channels")
                .arg(&channels)
                .arg("--bearings")
                .arg(wav.join("bearings.csv"))
                .arg("--out")
                .arg(t.path().join("o5")),
            name,
        );
    }
    for o in ["o1", "o2", "o3", "o4", "o5"] {
        assert!(!t.path().join(o).exists(), "{o} was created");
    }
}

/// Names beside `dir` that start with `.NAME.`.
fn leftovers(dir: &Path) -> Vec<String> {
    let name = dir.file_name().unwrap().to_string_lossy().into_owned();
    let mut v: Vec<String> = std::fs::read_dir(dir.parent().unwrap())
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(&format!(".{name}.")))
        .collect();
    v.sort();
    v
}

/// The id of a process that has ended.
fn dead_pid() -> u32 {
    let mut c = Command::new("true").spawn().unwrap();
    let pid = c.id();
    c.wait().unwrap();
    pid
}

#[test]
fn leftovers_of_a_killed_simulate_are_cleared_by_the_next_command() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    simulate(&run);
    let machine = long_machine(t.path(), 12_000);
    let mut child = plinth()
        .arg("simulate")
        .arg(&machine)
        .args(["--speeds", "5:200:0.5", "--force", "--out"])
        .arg(&run)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let killed = child.id();
    // Wait until its staging directory exists, then SIGKILL it.
    let staging = format!(".run.plinth-partial-{killed}");
    let start = Instant::now();
    while !t.path().join(&staging).exists() {
        assert!(start.elapsed() < Duration::from_secs(20), "no staging dir");
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(Duration::from_millis(100));
    assert!(child.try_wait().unwrap().is_none(), "ended before the kill");
    child.kill().unwrap();
    child.wait().unwrap();
    // Its staging directory and its lock file (released by the kernel).
    assert_eq!(
        leftovers(&run),
        vec![".run.plinth-lock".to_string(), staging.clone()]
    );

    // Not Plinth's (no manifest mark) or of a running process: kept.
    let foreign = t.path().join(format!(".run.plinth-partial-{}", dead_pid()));
    std::fs::create_dir(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
    let running = t
        .path()
        .join(format!(".run.plinth-partial-{}", std::process::id()));
    std::fs::create_dir(&running).unwrap();
    std::fs::write(running.join(".plinth-written"), "").unwrap();

    let o = plinth()
        .arg("simulate")
        .arg(example())
        .args(["--speeds", "5:60:5", "--force", "--out"])
        .arg(&run)
        .output()
        .unwrap();
    let msg = text(&o);
    assert!(o.status.success(), "{msg}");
    assert!(
        msg.contains(&staging) && msg.contains("interrupted") && msg.contains(&killed.to_string()),
        "{msg}"
    );
    assert!(!t.path().join(&staging).exists());
    assert!(!t.path().join(".run.plinth-lock").exists());
    assert!(foreign.join("notes.txt").exists() && running.exists());
}

#[test]
fn a_run_moved_aside_by_a_killed_commit_is_moved_back() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    simulate(&run);
    let before = std::fs::read(run.join("measurements.csv")).unwrap();
    // As a commit killed between its two renames leaves it.
    let aside = t.path().join(format!(".run.plinth-old-{}", dead_pid()));
    std::fs::rename(&run, &aside).unwrap();
    let o = plinth()
        .arg("simulate")
        .arg(example())
        .args(["--speeds", "5:60:5", "--out"])
        .arg(&run)
        .output()
        .unwrap();
    let msg = text(&o);
    // Restored, and then (no --force) not overwritten.
    assert!(msg.contains("restored"), "{msg}");
    assert!(!o.status.success() && msg.contains("--force"), "{msg}");
    assert_eq!(std::fs::read(run.join("measurements.csv")).unwrap(), before);
    assert!(!aside.exists());
}

#[test]
fn signals_validates_numbers_and_memory_before_allocating() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("sig");
    for (flag, value) in [
        ("--rate", "-1"),
        ("--rate", "nan"),
        ("--grid-step", "0"),
        ("--grid-step", "inf"),
        ("--probe-gap", "nan"),
        ("--probe-v-per-mm", "0"),
        ("--probe-noise-mv", "-1"),
        ("--seismic-noise-mv", "1e999"),
        ("--seismic-sensitivity", "-3"),
        ("--adc-bits", "20"),
        ("--adc-range", "0"),
    ] {
        let o = plinth()
            .arg("signals")
            .arg(example())
            .arg("--out")
            .arg(&out)
            .arg(format!("{flag}={value}"))
            .output()
            .unwrap();
        let msg = text(&o);
        assert_eq!(o.status.code(), Some(2), "{flag}={value}: {msg}");
        assert!(msg.contains(flag) && !msg.contains("panicked"), "{msg}");
    }
    // A grid step too fine to solve: refused at once with the step that works.
    let o = run_bounded(
        plinth()
            .arg("signals")
            .arg(example())
            .args(["--grid-step", "1e-9", "--out"])
            .arg(&out),
        Duration::from_secs(20),
    );
    let msg = text(&o);
    assert!(!o.status.success(), "{msg}");
    assert!(
        msg.contains("response solves") && msg.contains("use a step of at least"),
        "{msg}"
    );
    // A grid step too coarse for the response: refused with the measured
    // error, not written with a "largest error 0".
    let o = run_bounded(
        plinth()
            .arg("signals")
            .arg(example())
            .args(["--grid-step", "100", "--rundown", "60:20:20", "--out"])
            .arg(&out),
        Duration::from_secs(60),
    );
    let msg = text(&o);
    assert!(!o.status.success(), "{msg}");
    assert!(msg.contains("cannot represent the response"), "{msg}");
    // A run longer than the memory (the budget lowered to 64 MB, so the
    // 160 MB of samples fits any test disk: a set no disk holds is refused
    // for its disk first, robustness_memory.rs): refused with the figure.
    let o = run_bounded(
        plinth()
            .env("PLINTH_MEMORY_MB", "64")
            .arg("signals")
            .arg(example())
            .args(["--rundown", "200:5:1", "--out"])
            .arg(&out),
        Duration::from_secs(20),
    );
    let msg = text(&o);
    assert!(!o.status.success(), "{msg}");
    assert!(
        msg.contains("MB of memory") && msg.contains("MB available"),
        "{msg}"
    );
    assert!(!out.exists());
}

#[test]
fn contradictory_flags_are_refused() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    simulate(&run);
    // paper: --force says how to write into --plots, which is not given.
    let o = plinth().args(["paper", "--force"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("--plots"), "{}", text(&o));
    // identify: --compare-ols compares ML with OLS.
    let o = plinth()
        .arg("identify")
        .arg(&run)
        .args(["--estimator", "ols", "--compare-ols"])
        .output()
        .unwrap();
    let msg = text(&o);
    assert!(!o.status.success(), "{msg}");
    assert!(
        msg.contains("--compare-ols") && msg.contains("--estimator ols"),
        "{msg}"
    );
    // diagnose: --force without --plots; simulate: --seed without --noise.
    let o = plinth()
        .arg("diagnose")
        .arg(&run)
        .arg("--force")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("--plots"), "{}", text(&o));
    let o = plinth()
        .args([
            "simulate",
            example().to_str().unwrap(),
            "--seed",
            "3",
            "--out",
        ])
        .arg(t.path().join("seeded"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("--noise"), "{}", text(&o));
    assert!(!t.path().join("seeded").exists());
    // demo: --elf without --qemu; stream: --duration with --replay.
    let o = plinth()
        .args(["demo", "--elf", "x.elf", "--out"])
        .arg(t.path().join("d"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let o = plinth()
        .args([
            "stream",
            "--replay",
            "x",
            "--duration",
            "1",
            "--config",
            "c",
            "--out",
        ])
        .arg(t.path().join("s"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(!t.path().join("d").exists() && !t.path().join("s").exists());
}

#[test]
fn operating_system_errors_are_printed_once_by_every_reader() {
    let t = tempfile::tempdir().unwrap();
    let missing = t.path().join("missing.toml");
    for args in [vec!["simulate".to_string()], vec!["signals".to_string()]] {
        let o = plinth()
            .args(&args)
            .arg(&missing)
            .arg("--out")
            .arg(t.path().join("o"))
            .output()
            .unwrap();
        let msg = text(&o);
        assert!(!o.status.success(), "{msg}");
        assert_eq!(
            msg.matches("No such file or directory").count(),
            1,
            "{args:?}: {msg}"
        );
        assert!(msg.contains("missing.toml"), "{msg}");
    }
    let o = plinth()
        .arg("predict")
        .arg(example())
        .arg("--pedestals")
        .arg(t.path().join("none.json"))
        .arg("--against")
        .arg(t.path().join("none"))
        .output()
        .unwrap();
    let msg = text(&o);
    assert!(!o.status.success(), "{msg}");
    assert_eq!(msg.matches("No such file or directory").count(), 1, "{msg}");
}

#[test]
fn flags_and_base_files_that_would_be_ignored_are_refused() {
    let t = tempfile::tempdir().unwrap();
    let run = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures/field/sim");
    for extra in [&["--estimator", "ols"][..], &["--model", "k_y,k_z,m"][..]] {
        let o = plinth()
            .arg("identify")
            .arg(&run)
            .args(["--unmeasured-base", "left,right"])
            .args(extra)
            .output()
            .unwrap();
        let msg = text(&o);
        assert!(
            !o.status.success() && msg.contains("--unmeasured-base"),
            "{msg}"
        );
    }
    // A run with base.csv: --unmeasured-base refused; a base on a bearing
    // the run does not have, or a header without rows, refused.
    let copy = t.path().join("run");
    std::fs::create_dir(&copy).unwrap();
    for f in ["measurements.csv", "bearings.csv"] {
        std::fs::copy(run.join(f), copy.join(f)).unwrap();
    }
    let head = "speed_hz,base,bearings,y_re,y_im,z_re,z_im\n";
    std::fs::write(
        copy.join("base.csv"),
        format!("{head}5,skid,left;right,1e-7,0,0,1e-7\n"),
    )
    .unwrap();
    let o = plinth()
        .arg("identify")
        .arg(&copy)
        .args(["--unmeasured-base", "left,right"])
        .output()
        .unwrap();
    assert!(
        !o.status.success() && text(&o).contains("base.csv holds the measured base"),
        "{}",
        text(&o)
    );
    for (rows, what) in [
        ("", "no data rows"),
        (
            "5,skid,left;B9,1e-7,0,0,1e-7\n",
            "base.csv:2:3: base `skid`: bearing `B9` is not in measurements.csv",
        ),
        ("5,skid,left,right,1e-7,0,0,1e-7\n", "separate the bearings"),
    ] {
        std::fs::write(copy.join("base.csv"), format!("{head}{rows}")).unwrap();
        let o = plinth().arg("identify").arg(&copy).output().unwrap();
        let msg = text(&o);
        assert!(
            !o.status.success() && msg.contains("base.csv") && msg.contains(what),
            "{msg}"
        );
    }
}

#[test]
fn a_row_deleted_from_bearings_csv_is_named_where_it_is_interpolated() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    simulate(&run);
    let path = run.join("bearings.csv");
    let table = std::fs::read_to_string(&path).unwrap();
    // Delete the 25 Hz row of bearing `left` (formats.md then interpolates
    // between 20 and 30 Hz: allowed, but said).
    let is_gone = |l: &str| {
        let mut f = l.split(',');
        f.next().and_then(|s| s.parse::<f64>().ok()) == Some(25.0) && f.next() == Some("left")
    };
    let kept: Vec<&str> = table.lines().filter(|l| !is_gone(l)).collect();
    assert_eq!(kept.len() + 1, table.lines().count());
    std::fs::write(&path, kept.join("\n") + "\n").unwrap();
    let o = plinth().arg("identify").arg(&run).output().unwrap();
    let msg = text(&o);
    assert!(
        msg.contains("warning: ")
            && msg.contains(
                "bearings.csv: bearing `left`: no row at 1 of its 12 measurement speeds (25 Hz)"
            ),
        "{msg}"
    );
    // The untouched bearing, and an untouched run, say nothing of it.
    assert!(!msg.contains("bearing `right`: no row"), "{msg}");
    let clean = t.path().join("clean");
    simulate(&clean);
    let o = plinth().arg("identify").arg(&clean).output().unwrap();
    assert!(!text(&o).contains("no row at"), "{}", text(&o));
}
