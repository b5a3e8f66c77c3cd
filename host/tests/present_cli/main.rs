//! What a person sees: the modal view in `identify`'s table and JSON, the
//! speed band, a closed stdout, `--quiet`, `import`'s rounding noise, and
//! documentation that stays inside the repository.

use plinth::identify::synthetic::SyntheticRun;
use plinth::rundir::{DigitsMode, RunDir, WriteOptions};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn plinth() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plinth"))
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("host/ has a parent")
        .to_path_buf()
}

/// A damped paper-like run with 4 significant digits and its truth.
fn run_dir() -> (tempfile::TempDir, RunDir) {
    let dir = tempfile::tempdir().unwrap();
    let run = SyntheticRun::paper_like(true, 80).build().unwrap();
    run.write_with(
        dir.path(),
        &WriteOptions {
            digits: Some(4),
            digits_mode: DigitsMode::Round,
        },
    )
    .unwrap();
    (dir, run)
}

fn json(args: &[&str]) -> serde_json::Value {
    let out = plinth().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// `identify --json` carries `modal` for every pedestal: f_n within 0.1 %
/// of √(k/m)/2π of the truth and within 3 of its standard errors, ζ within
/// 3 of its standard errors; the table shows the same numbers in Hz and rpm.
#[test]
fn identify_reports_natural_frequencies_and_damping_ratios() {
    let (dir, run) = run_dir();
    let d = dir.path().to_str().unwrap();
    let v = json(&["identify", d, "--json"]);
    let truth = run.truth.as_ref().unwrap();
    for p in v["pedestals"].as_array().unwrap() {
        let t = truth
            .pedestals
            .iter()
            .find(|t| t.bearing == p["bearing"].as_str().unwrap())
            .unwrap();
        for (dir, k, c) in [
            ("y", t.pedestal.k_y, t.pedestal.c_y),
            ("z", t.pedestal.k_z, t.pedestal.c_z),
        ] {
            let m = &p["modal"][dir];
            let f_true = (k / t.pedestal.m).sqrt() / std::f64::consts::TAU;
            let zeta_true = c / (2.0 * (k * t.pedestal.m).sqrt());
            let f = m["f_n_hz"].as_f64().unwrap();
            let f_se = m["f_n_std_err"].as_f64().unwrap();
            let z = m["zeta"].as_f64().unwrap();
            let z_se = m["zeta_std_err"].as_f64().unwrap();
            assert!((f / f_true - 1.0).abs() < 1e-3, "{dir}: {f} vs {f_true}");
            assert!(
                (f - f_true).abs() < 3.0 * f_se,
                "{dir}: {f} ± {f_se} vs {f_true}"
            );
            assert!(f_se > 0.0 && z_se > 0.0);
            assert!(
                (z - zeta_true).abs() < 3.0 * z_se,
                "{dir}: ζ {z} ± {z_se} vs {zeta_true}"
            );
        }
        assert_eq!(p["covariance"].as_array().map(Vec::len), Some(5));
    }
    let out = plinth().args(["identify", d]).output().unwrap();
    let table = String::from_utf8(out.stdout).unwrap();
    assert!(
        table.contains("f_n [rpm]") && table.contains("ζ [%]"),
        "{table}"
    );
    assert!(
        table.contains("left y") && table.contains("right z"),
        "{table}"
    );
}

/// `--speeds LO:HI` fits only that band; a band with no speed, or a bad
/// one, is an error naming the option.
#[test]
fn speed_band() {
    let (dir, _) = run_dir();
    let d = dir.path().to_str().unwrap();
    let v = json(&["identify", d, "--json", "--speeds", "20:120"]);
    for p in v["pedestals"].as_array().unwrap() {
        let r = &p["speed_range_hz"];
        assert!(
            r[0].as_f64().unwrap() >= 20.0 && r[1].as_f64().unwrap() <= 120.0,
            "{r}"
        );
    }
    for (band, says) in [("900:1000", "no measured speed"), ("120:20", "LO")] {
        let out = plinth()
            .args(["identify", d, "--speeds", band])
            .output()
            .unwrap();
        assert!(!out.status.success(), "{band}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--speeds") && err.contains(says), "{err}");
    }
}

/// A reader that closes the pipe early (`| head -1`) ends the command
/// quietly with exit code 0, as ripgrep does; nothing on stderr.
#[test]
fn closed_stdout_ends_quietly() {
    let (dir, _) = run_dir();
    let mut child = plinth()
        .args(["identify", dir.path().to_str().unwrap(), "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Close our end of stdout before the child writes its JSON.
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(
        !err.contains("panicked") && !err.contains("Broken pipe"),
        "{err}"
    );
}

/// `--quiet` is global: accepted before and after the command.
#[test]
fn quiet_is_global() {
    let (dir, _) = run_dir();
    let d = dir.path().to_str().unwrap();
    for args in [
        vec!["--quiet", "identify", d],
        vec!["identify", d, "--quiet"],
    ] {
        let out = plinth().args(&args).output().unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// `import` writes the noise of the table's own rounding as noise columns,
/// and identify uses them (`"source": "columns"`).
#[test]
fn import_keeps_the_tables_precision() {
    let field = repo().join("examples/field");
    let out_dir = tempfile::tempdir().unwrap();
    let run = out_dir.path().join("run");
    let status = plinth()
        .arg("import")
        .arg(field.join("vector-table.csv"))
        .arg("--layout")
        .arg(field.join("layout.toml"))
        .arg("--bearings")
        .arg(field.join("bearings.csv"))
        .arg("--out")
        .arg(&run)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let text = std::fs::read_to_string(run.join("measurements.csv")).unwrap();
    assert!(text.lines().next().unwrap().contains("rel_y_sd"), "{text}");
    let v = json(&["identify", run.to_str().unwrap(), "--json"]);
    for (_, n) in v["noise"].as_object().unwrap() {
        assert_eq!(n["source"], "columns", "{n}");
    }
}

/// Every `--help` that names the data contract names the file in the
/// repository (docs/formats.md), which exists.
#[test]
fn help_texts_point_inside_the_repository() {
    assert!(repo().join("docs/formats.md").is_file());
    let commands = [
        "identify", "simulate", "signals", "predict", "paper", "stream", "demo", "diagnose",
        "import", "extract", "plot", "accuracy",
    ];
    for c in commands {
        let out = plinth().args([c, "--help"]).output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        for (i, _) in text.match_indices("formats.md") {
            assert!(
                text[..i].ends_with("docs/"),
                "plinth {c} --help names formats.md outside docs/: {text}"
            );
        }
        assert!(!text.contains(&["/work", "/shared"].concat()), "{c}");
    }
}

/// Every relative link in README.md and docs/*.md resolves to a file in
/// the repository, and no file of the repository refers to documents
/// outside it.
#[test]
fn documentation_links_resolve_and_stay_inside() {
    let root = repo();
    let mut pages = vec![
        root.join("README.md"),
        root.join("examples/field/README.md"),
    ];
    for e in std::fs::read_dir(root.join("docs")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "md") {
            pages.push(p);
        }
    }
    let mut broken = Vec::new();
    for page in &pages {
        let text = std::fs::read_to_string(page).unwrap();
        let mut rest = text.as_str();
        while let Some(i) = rest.find("](") {
            rest = &rest[i + 2..];
            let Some(end) = rest.find(')') else { break };
            let target = &rest[..end];
            rest = &rest[end..];
            if target.starts_with("http")
                || target.starts_with('#')
                || target.starts_with("mailto:")
            {
                continue;
            }
            let path = target.split('#').next().unwrap_or(target);
            let resolved = page.parent().unwrap().join(path);
            if !resolved.exists() {
                broken.push(format!("{}: {target}", page.display()));
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));

    let outside = ["/work", "/shared"].concat();
    let mut mentions = Vec::new();
    let mut stack = vec![root.clone()];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().to_string();
            if name.starts_with('.') || name.starts_with("target") {
                continue;
            }
            if p.is_dir() {
                stack.push(p);
            } else if let Ok(bytes) = std::fs::read(&p) {
                if bytes
                    .windows(outside.len())
                    .any(|w| w == outside.as_bytes())
                {
                    mentions.push(p.display().to_string());
                }
            }
        }
    }
    assert!(mentions.is_empty(), "files naming {outside}: {mentions:?}");
}

/// One row of a modal table (see [`modal_blocks`]).
type ModalRow = (String, f64, f64, f64, f64);

/// The rows of the modal table: (pedestal and direction, f_n [Hz], its
/// standard error, ζ [%], its standard error), for each `natural frequency`
/// block of `text` in order.
fn modal_blocks(text: &str) -> Vec<Vec<ModalRow>> {
    let mut blocks = Vec::new();
    let mut lines = text.lines();
    while let Some(l) = lines.next() {
        if !l.starts_with("natural frequency f_n") {
            continue;
        }
        assert!(lines.next().unwrap().starts_with("pedestal"), "{text}");
        let mut rows = Vec::new();
        for l in lines.by_ref() {
            if l.trim().is_empty() || l.starts_with("≈0") || l.starts_with("± -") {
                break;
            }
            if l.starts_with("  ") {
                continue; // truth
            }
            let cells: Vec<&str> = l.split("  ").filter(|c| !c.trim().is_empty()).collect();
            let pm = |c: &str| -> (f64, f64) {
                let (v, s) = c
                    .split_once(" ± ")
                    .unwrap_or_else(|| panic!("{c:?} in {l}"));
                let s = s.split_whitespace().next().unwrap();
                (v.trim().parse().unwrap(), s.parse().unwrap_or(f64::NAN))
            };
            let (f, fs) = pm(cells[1]);
            let (z, zs) = pm(cells[3]);
            rows.push((cells[0].trim().to_string(), f, fs, z, zs));
        }
        blocks.push(rows);
    }
    blocks
}

/// `diagnose` shows its pedestals through identify's printer: the same
/// columns and units, and under each table f_n (Hz, rpm) and ζ (%) with ±
/// from the diagnosis fit's covariance. On a simulated run the f_n are
/// within 0.1 % and 3 standard errors of the truth, ζ within 3 standard
/// errors, and the ± are of the size identify reports (same data, an
/// estimator within a factor of a few of the bound).
#[test]
fn diagnose_prints_the_modal_view_like_identify() {
    let (dir, run) = run_dir();
    let d = dir.path().to_str().unwrap();
    let out = plinth().args(["diagnose", d]).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let header = "bearing  k_y [MN/m]";
    assert_eq!(text.matches(header).count(), 2, "{text}");
    let blocks = modal_blocks(&text);
    assert_eq!(blocks.len(), 2, "base and final model: {text}");
    let identified =
        String::from_utf8(plinth().args(["identify", d]).output().unwrap().stdout).unwrap();
    let reference = &modal_blocks(&identified)[0];
    let truth = run.truth.as_ref().unwrap();
    for rows in &blocks {
        assert_eq!(rows.len(), 4, "{text}");
        for ((name, f, fs, z, zs), (name_i, f_i, fs_i, _, zs_i)) in rows.iter().zip(reference) {
            assert_eq!(name, name_i);
            let (bearing, dir) = name.split_once(' ').unwrap();
            let t = truth
                .pedestals
                .iter()
                .find(|t| t.bearing == bearing)
                .unwrap();
            let (k, c) = if dir == "y" {
                (t.pedestal.k_y, t.pedestal.c_y)
            } else {
                (t.pedestal.k_z, t.pedestal.c_z)
            };
            let f_true = (k / t.pedestal.m).sqrt() / std::f64::consts::TAU;
            let z_true = 100.0 * c / (2.0 * (k * t.pedestal.m).sqrt());
            assert!(
                fs.is_finite() && *fs > 0.0 && zs.is_finite() && *zs > 0.0,
                "{text}"
            );
            assert!((f / f_true - 1.0).abs() < 1e-3, "{name}: {f} vs {f_true}");
            assert!(
                (f - f_true).abs() < 3.0 * fs,
                "{name}: {f} ± {fs} vs {f_true}"
            );
            assert!(
                (z - z_true).abs() < 3.0 * zs,
                "{name}: ζ {z} ± {zs} vs {z_true}"
            );
            // The same fit in both printers, so close values and ± of one size.
            assert!(
                (f - f_i).abs() < 3.0 * fs.max(*fs_i),
                "{name}: {f} vs {f_i}"
            );
            for (a, b) in [(fs, fs_i), (zs, zs_i)] {
                assert!(
                    a / b > 0.2 && a / b < 5.0,
                    "{name}: ± {a} vs identify's {b}"
                );
            }
        }
    }
}

/// `diagnose --speeds LO:HI` diagnoses only that band (every place where
/// the disagreement lives is inside it), and a band with no speed is an
/// error naming the option, as for `identify`.
#[test]
fn diagnose_fits_a_speed_band() {
    let (dir, _) = run_dir();
    let d = dir.path().to_str().unwrap();
    let whole = json(&["diagnose", d, "--json"]);
    let band = json(&["diagnose", d, "--json", "--speeds", "30:90"]);
    assert_ne!(whole["gap_before"], band["gap_before"]);
    let peaks: Vec<f64> = band["where_before"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["peak_hz"].as_f64().unwrap())
        .collect();
    assert!(!peaks.is_empty());
    assert!(peaks.iter().all(|p| (30.0..=90.0).contains(p)), "{peaks:?}");
    let out = plinth()
        .args(["diagnose", d, "--speeds", "900:1000"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--speeds") && err.contains("no measured speed"),
        "{err}"
    );
}

/// Runs `plinth ARGS` with its stderr on a fresh pseudo-terminal (openpty),
/// stdout discarded, progress shown at once, and returns what the terminal
/// showed; `None` when no pseudo-terminal can be opened. (util-linux
/// `script` loses the session when its stdin is not a terminal.)
fn on_a_terminal(args: &[&str]) -> Option<String> {
    use std::io::Read;
    use std::os::fd::{FromRawFd, OwnedFd};
    let (mut master, mut slave) = (-1, -1);
    // SAFETY: openpty writes two new descriptors, owned from here on.
    let opened = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            std::ptr::null_mut(),
            std::ptr::null(),
            std::ptr::null(),
        )
    };
    if opened != 0 {
        return None;
    }
    // SAFETY: both descriptors were just opened by openpty and are not shared.
    let (master, slave) = unsafe { (OwnedFd::from_raw_fd(master), OwnedFd::from_raw_fd(slave)) };
    let mut terminal = std::fs::File::from(master);
    // Read while the command runs, so that a full pty buffer never blocks it;
    // the read ends with EIO once the last slave descriptor is closed.
    let reader = std::thread::spawn(move || {
        let mut shown = Vec::new();
        let mut chunk = [0u8; 4096];
        while let Ok(n) = terminal.read(&mut chunk) {
            if n == 0 {
                break;
            }
            shown.extend_from_slice(&chunk[..n]);
        }
        shown
    });
    let status = Command::new(env!("CARGO_BIN_EXE_plinth"))
        .args(args)
        .env("PLINTH_PROGRESS_AFTER_MS", "0")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::from(slave))
        .status()
        .unwrap();
    let shown = String::from_utf8_lossy(&reader.join().unwrap()).to_string();
    assert!(status.success(), "{args:?}: {shown}");
    Some(shown)
}

/// Progress is drawn on a terminal, for `identify` and `diagnose` too, and
/// never with `--quiet` or when stderr is not a terminal.
#[test]
fn progress_only_on_a_terminal_and_silenced_by_quiet() {
    let (dir, _) = run_dir();
    let d = dir.path().to_str().unwrap();
    for (command, label) in [
        ("identify", "identify: read, fit, bases"),
        ("diagnose", "diagnose: fits"),
    ] {
        let Some(shown) = on_a_terminal(&[command, d]) else {
            assert!(
                std::env::var_os("CI").is_none(),
                "no pseudo-terminal (openpty failed)"
            );
            eprintln!("SKIPPED: no pseudo-terminal (openpty failed)");
            return;
        };
        assert!(shown.contains(label), "{command}: {shown:?}");
        let quiet = on_a_terminal(&["--quiet", command, d]).unwrap();
        assert!(!quiet.contains(label), "{command} --quiet: {quiet:?}");
        let piped = plinth()
            .args([command, d])
            .env("PLINTH_PROGRESS_AFTER_MS", "0")
            .output()
            .unwrap();
        assert!(!String::from_utf8_lossy(&piped.stderr).contains(label));
    }
}

/// No command names its hidden staging directory (`.NAME.plinth-partial-PID`)
/// in what it prints: every path a person reads is the final one. Each
/// command that writes an output runs here once, small, and its stdout and
/// stderr are searched for the staging names.
#[test]
fn no_command_prints_a_staging_path() {
    let tmp = tempfile::tempdir().unwrap();
    let t = |name: &str| tmp.path().join(name).to_str().unwrap().to_string();
    let r = |rel: &str| repo().join(rel).to_str().unwrap().to_string();
    let (run, _) = run_dir();
    let run = run.path().to_str().unwrap().to_string();
    let paper = r("examples/feng-hahn-1997.toml");
    let runs: Vec<Vec<String>> = vec![
        vec![
            "simulate".into(),
            paper.clone(),
            "--speeds".into(),
            "5:50:5".into(),
            "--out".into(),
            t("sim"),
        ],
        vec![
            "signals".into(),
            paper.clone(),
            "--rundown".into(),
            "30:20:20".into(),
            "--rate".into(),
            "2048".into(),
            "--out".into(),
            t("signals"),
        ],
        vec![
            "import".into(),
            r("examples/field/vector-table.csv"),
            "--layout".into(),
            r("examples/field/layout.toml"),
            "--bearings".into(),
            r("examples/field/bearings.csv"),
            "--plots".into(),
            "--out".into(),
            t("imported"),
        ],
        vec![
            "extract".into(),
            r("examples/field/recording.wav"),
            "--channels".into(),
            r("examples/field/channels.toml"),
            "--bearings".into(),
            r("examples/field/bearings.csv"),
            "--out".into(),
            t("extracted"),
        ],
        vec![
            "identify".into(),
            run.clone(),
            "--plots".into(),
            t("identify-figures"),
        ],
        vec![
            "diagnose".into(),
            run.clone(),
            "--plots".into(),
            t("diagnose-figures"),
        ],
        vec!["plot".into(), run.clone(), "--out".into(), t("plots")],
        vec![
            "report".into(),
            run.clone(),
            "--out".into(),
            t("report.html"),
        ],
        vec!["paper".into(), "--plots".into(), t("paper")],
        vec![
            "demo".into(),
            "--rundown".into(),
            "60:40:20".into(),
            "--out".into(),
            t("demo"),
        ],
    ];
    for args in &runs {
        let out = plinth().args(args).output().unwrap();
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(out.status.success(), "{args:?}: {text}");
        assert!(
            !text.contains("plinth-partial") && !text.contains("plinth-old"),
            "{}: prints a staging path:\n{text}",
            args[0]
        );
        // Whatever it names as written is the final path.
        let target = args.last().unwrap();
        if text.contains(tmp.path().to_str().unwrap()) {
            assert!(text.contains(target.as_str()), "{}: {text}", args[0]);
        }
    }
}

/// `diagnose` on pedestals on an unmeasured skid (the simulator's base
/// element): the foundation candidate's parametric bootstrap, its slowest
/// step, shows its replicates done out of the total on a terminal.
#[test]
fn diagnose_progress_counts_the_bootstrap_replicates() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("skid");
    let made = plinth()
        .args([
            "simulate",
            repo()
                .join("examples/two-pedestals-on-skid.toml")
                .to_str()
                .unwrap(),
        ])
        .args([
            "--speeds",
            "5:120:2",
            "--noise",
            "0.005",
            "--out",
            run.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    std::fs::remove_file(run.join("base.csv")).unwrap();
    let Some(shown) = on_a_terminal(&["diagnose", run.to_str().unwrap()]) else {
        assert!(
            std::env::var_os("CI").is_none(),
            "no pseudo-terminal (openpty failed)"
        );
        eprintln!("SKIPPED: no pseudo-terminal (openpty failed)");
        return;
    };
    let label = "diagnose: foundation bootstrap replicates";
    let total = format!("/{}", plinth::diagnose::foundation::REPLICATES);
    assert!(
        shown
            .lines()
            .any(|l| l.contains(label) && l.contains(&total))
            || shown.split(label).skip(1).any(|after| after
                .split('(')
                .next()
                .unwrap_or("")
                .contains(&total)),
        "{shown:?}"
    );
}
