//! What commands write and print: `import` leaves the noise to identify
//! (no noise columns), and no command names its hidden staging directory.

use super::{json, plinth, repo, run_dir, succeeded};

/// `import` writes no noise columns: the table's rounding is only a floor
/// under the sensors' own noise, and columns are taken as the whole noise
/// (docs/formats.md, "Noise columns"). identify estimates the noise from the
/// data and trusts the bundled field example's clean pedestals.
#[test]
fn import_leaves_the_noise_to_identify() {
    let field = repo().join("examples/field");
    let out_dir = tempfile::tempdir().unwrap();
    let run = out_dir.path().join("run");
    succeeded(
        plinth()
            .arg("import")
            .arg(field.join("vector-table.csv"))
            .arg("--layout")
            .arg(field.join("layout.toml"))
            .arg("--bearings")
            .arg(field.join("bearings.csv"))
            .arg("--out")
            .arg(&run)
            .output()
            .unwrap(),
    );
    let text = std::fs::read_to_string(run.join("measurements.csv")).unwrap();
    assert!(!text.lines().next().unwrap().contains("_sd"), "{text}");
    let v = json(&["identify", run.to_str().unwrap(), "--json"]);
    for (_, n) in v["noise"].as_object().unwrap() {
        assert_ne!(n["source"], "columns", "{n}");
    }
    for p in v["pedestals"].as_array().unwrap() {
        assert_eq!(p["trusted"], true, "{p}");
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
