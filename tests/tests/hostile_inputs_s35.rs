//! Inputs found wanting by the session-34 and session-35 hostile probes
//! (docs/robustness-hostile.md): an output directory given by `--plots`
//! was refused as `--out`, a pedestal stiffness of 1e300 N/m was said to be
//! "no stiffness", and `--speeds 5:200:0.001` (or a fine mesh at many
//! speeds) ran without any time budget. The runs come from the simulator;
//! each case edits the bundled example machine as an editor would.

use plinth::sim::cli::{parse_speeds, simulate, SimulateArgs};
use plinth::sim::machine::Machine;
use plinth::sim::{unbalance_response, EffectSet};
use std::path::Path;

/// The bundled damped paper machine's text.
fn example_machine() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/feng-hahn-1997-damped.toml");
    std::fs::read_to_string(path).unwrap()
}

/// `plinth paper` arguments at 40 speeds, figures into `plots`.
fn paper_args(plots: &Path, speeds: &str) -> plinth::paper::Args {
    plinth::paper::Args {
        json: true,
        plots: Some(plots.to_path_buf()),
        force: false,
        speeds: speeds.into(),
        machine: None,
        damped_machine: None,
        truncate: false,
        heavy_damping_ratio: 0.10,
    }
}

#[test]
fn a_plots_directory_that_cannot_be_used_is_named_by_its_option() {
    let t = tempfile::tempdir().unwrap();
    let file = t.path().join("afile");
    std::fs::write(&file, "mine").unwrap();
    // paper --plots: refused before the paper is computed, as --plots.
    let e = plinth::paper::run(&paper_args(&file, "5:200:5"))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(&format!("--plots {}: is a file", file.display())) && !e.contains("--out"),
        "{e}"
    );
    // identify --plots (the figures of an identification): the same.
    let machine = Machine::from_toml_str(&example_machine(), "m.toml").unwrap();
    let speeds: Vec<f64> = (1..=40).map(|i| 5.0 * f64::from(i)).collect();
    let run = unbalance_response(&machine, &speeds, &EffectSet::none())
        .unwrap()
        .to_run_dir(None)
        .unwrap();
    let identification =
        plinth::identify::identify_run(&run, &plinth::identify::Options::default()).unwrap();
    let e = plinth::report::fitted::write_identify_plots(
        &file,
        &run,
        &identification,
        plinth::plots::Style::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with(&format!("--plots {}: is a file", file.display())) && !e.contains("--out"),
        "{e}"
    );
    // --out stays --out; nothing was written anywhere.
    let e = plinth::output::OutputDir::create(&file, false)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("--out "), "{e}");
    assert_eq!(std::fs::read(&file).unwrap(), b"mine");
    assert_eq!(std::fs::read_dir(t.path()).unwrap().count(), 1);
}

#[test]
fn a_pedestal_stiffness_too_large_to_compute_with_is_named_as_such() {
    let text = example_machine();
    for (to, key) in [
        ("k_y = 1e300", "k_y = 1e300 N/m"),
        ("k_y = 2e154", "k_y = 2e154 N/m"),
    ] {
        let edited = text.replacen("k_y = 10.0e6", to, 1);
        let machine = Machine::from_toml_str(&edited, "m.toml").unwrap();
        let e = unbalance_response(&machine, &[5.0, 50.0], &EffectSet::none())
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("cannot be solved in double precision")
                && e.contains("bearings[0] (name = \"left\")")
                && e.contains(key)
                && !e.contains("no stiffness")
                && !e.contains("singular"),
            "{to}: {e}"
        );
    }
}

#[test]
fn a_speed_list_beyond_the_budget_is_refused_before_any_work() {
    let e = parse_speeds("5:200:0.001").unwrap_err().to_string();
    assert!(
        e.starts_with("--speeds 5:200:0.001: 195001 speeds asked, above the limit of 100000")
            && e.contains("PLINTH_MAX_SPEEDS=195001"),
        "{e}"
    );
    // The largest run the docs measure (20 001 speeds) is accepted.
    assert_eq!(parse_speeds("5:205:0.01").unwrap().len(), 20_001);
    // paper: refused before any work (main ran for minutes past 1.6 GB).
    // No stopwatch: both machines are given a pedestal stiffness the
    // solver cannot compute with (k_y = 1e300, refused at the first solve),
    // so a budget checked after any solve would report the overflow instead.
    let t = tempfile::tempdir().unwrap();
    let unsolvable = t.path().join("unsolvable.toml");
    std::fs::write(
        &unsolvable,
        example_machine().replacen("k_y = 10.0e6", "k_y = 1e300", 1),
    )
    .unwrap();
    let plots = t.path().join("plots");
    let mut args = paper_args(&plots, "5:200:0.001");
    args.machine = Some(unsolvable.clone());
    args.damped_machine = Some(unsolvable.clone());
    let e = plinth::paper::run(&args).unwrap_err().to_string();
    assert!(
        e.contains("195001 speeds asked") && !e.contains("double precision"),
        "{e}"
    );
    // The same machines at 40 speeds do reach the solver (so the refusal
    // above is the budget's, not the machine file's).
    let mut args = paper_args(&plots, "5:200:5");
    args.machine = Some(unsolvable.clone());
    args.damped_machine = Some(unsolvable);
    let e = format!("{:#}", plinth::paper::run(&args).unwrap_err());
    assert!(e.contains("cannot be solved in double precision"), "{e}");
    // A fine mesh at many speeds: nodes × speeds beyond the budget, refused
    // before the solve (the same unsolvable pedestal) and before --out is
    // made.
    let machine = t.path().join("fine.toml");
    std::fs::write(
        &machine,
        example_machine()
            .replacen("elements = 10", "elements = 60000", 1)
            .replacen("k_y = 10.0e6", "k_y = 1e300", 1),
    )
    .unwrap();
    let out = t.path().join("run");
    let e = simulate(&SimulateArgs {
        machine: machine.clone(),
        out: out.clone(),
        force: false,
        speeds: "5:200:0.1".into(),
        digits: None,
        truncate: false,
        noise: None,
        seed: 1,
        effects: Vec::new(),
    })
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("shaft node x speed solves asked, above the limit of 100000000")
            && e.contains("PLINTH_MAX_NODE_SPEEDS=")
            && !e.contains("double precision"),
        "{e}"
    );
    assert!(!out.exists());
}

/// `plinth report RUN --out OUT --force` with the default figures.
fn report_args(run: &Path, out: &Path) -> plinth::report::Args {
    plinth::report::Args {
        dir: run.to_path_buf(),
        out: out.to_path_buf(),
        diagnose: false,
        speeds: None,
        unmeasured_base: None,
        polar: plinth::field::plot::PolarArgs {
            layout: None,
            channels: None,
            rotation: None,
            zero_at_transducer: false,
            style: plinth::plots::StyleArgs {
                speed_unit: Default::default(),
                log_amplitude: false,
            },
        },
        force: true,
    }
}

#[test]
fn a_report_is_never_written_over_a_fifo_a_link_or_a_device() {
    let t = tempfile::tempdir().unwrap();
    let machine = Machine::from_toml_str(&example_machine(), "m.toml").unwrap();
    let speeds: Vec<f64> = (1..=40).map(|i| 5.0 * f64::from(i)).collect();
    let run = t.path().join("run");
    unbalance_response(&machine, &speeds, &EffectSet::none())
        .unwrap()
        .to_run_dir(None)
        .unwrap()
        .write(&run)
        .unwrap();
    // A FIFO (main replaced it with the page, as it replaced /dev/full).
    let fifo = t.path().join("r.html");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    let e = plinth::report::run(&report_args(&run, &fifo))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(&format!("--out {}: is not a regular file", fifo.display())),
        "{e}"
    );
    use std::os::unix::fs::FileTypeExt;
    assert!(fifo.symlink_metadata().unwrap().file_type().is_fifo());
    // A symbolic link to a file: neither followed nor replaced.
    let kept = t.path().join("kept.txt");
    std::fs::write(&kept, "mine").unwrap();
    let link = t.path().join("link.html");
    std::os::unix::fs::symlink(&kept, &link).unwrap();
    let e = plinth::report::run(&report_args(&run, &link))
        .unwrap_err()
        .to_string();
    assert!(e.contains("is a symbolic link"), "{e}");
    assert!(link.symlink_metadata().unwrap().file_type().is_symlink());
    assert_eq!(std::fs::read(&kept).unwrap(), b"mine");
    // A regular file with --force is replaced whole.
    let page = t.path().join("page.html");
    std::fs::write(&page, "old").unwrap();
    plinth::report::run(&report_args(&run, &page)).unwrap();
    assert!(std::fs::read_to_string(&page)
        .unwrap()
        .starts_with("<!DOCTYPE html>"));
}
