//! The field's reading of the figures, through the CLI: rotation from the
//! layout on `import --plots`, pick-ups in their own units, resolved y/z and
//! transducers in separate panels, `plot` with rpm, log amplitude and 0° at
//! the transducer, and `identify --plots` writing one measured-vs-fitted
//! figure per bearing.

use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Runs `plinth ARGS`, its output whatever the exit status.
fn run_plinth(args: &[&std::ffi::OsStr]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_plinth"))
        .args(args)
        .output()
        .unwrap()
}

/// Runs `plinth ARGS` expecting success; returns stdout.
fn plinth(args: &[&std::ffi::OsStr]) -> String {
    let out = run_plinth(args);
    assert!(
        out.status.success(),
        "plinth {:?} failed: {}",
        args,
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).to_string()
}

/// Runs `plinth ARGS` expecting a failure; returns stderr.
fn plinth_fails(args: &[&std::ffi::OsStr]) -> String {
    let out = run_plinth(args);
    assert!(!out.status.success(), "plinth {args:?} succeeded");
    String::from_utf8_lossy(&out.stderr).to_string()
}

/// `plinth import` of the table fixture in mils with phase lead and
/// `rotation = "cw"` into `out` (with `--plots` when `plots`); returns its
/// layout.
fn import_cw(out: &Path, plots: bool) -> PathBuf {
    let t = repo().join("tests/fixtures/field/tables");
    let table = t.join("mil_lead_cw.csv");
    let layout = t.join("mil_lead_cw.toml");
    let bearings = repo().join("tests/fixtures/field/sim/bearings.csv");
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "import".as_ref(),
        table.as_os_str(),
        "--layout".as_ref(),
        layout.as_os_str(),
        "--bearings".as_ref(),
        bearings.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ];
    if plots {
        args.push("--plots".as_ref());
    }
    plinth(&args);
    layout
}

fn svgs(dir: &Path, prefix: &str) -> Vec<(String, String)> {
    let mut v: Vec<(String, String)> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().to_string();
            (name.starts_with(prefix) && name.ends_with(".svg"))
                .then(|| (name, std::fs::read_to_string(e.path()).unwrap()))
        })
        .collect();
    v.sort();
    v
}

#[test]
fn import_plots_follow_the_layout_rotation_and_units() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    import_cw(&out, true);
    let figs = out.join("figures");
    // The layout says rotation = "cw" (seen from the driver): every polar
    // plot is drawn so, none against CCW rotation.
    let polars = svgs(&figs, "polar_");
    assert!(polars.len() >= 8, "{} polar plots", polars.len());
    for (name, text) in &polars {
        assert!(text.contains("lag against CW rotation"), "{name}");
    }
    // Proximity probes in mils as the layout gives them; the pedestal
    // pick-ups (`g rms`) in g pk, in a panel of their own beside the
    // resolved y/z (µm pk-pk).
    let bode_rel = std::fs::read_to_string(figs.join("bode_left_rel.svg")).unwrap();
    assert!(bode_rel.contains("mil pk-pk") && bode_rel.contains("µm pk-pk"));
    let bode_ped = std::fs::read_to_string(figs.join("bode_left_ped.svg")).unwrap();
    assert!(bode_ped.contains("resolved y, z") && bode_ped.contains("transducers"));
    assert!(bode_ped.contains("[g pk]"), "pedestal pick-ups in g");
    // Start and end of the run are marked on every polar plot.
    for (name, text) in &polars {
        assert!(text.contains("start ") && text.contains("end "), "{name}");
    }
}

#[test]
fn plot_options_and_identify_plots() {
    let tmp = tempfile::tempdir().unwrap();
    let run = repo().join("examples/run-paper-2digits");
    let out = tmp.path().join("figs");
    plinth(&[
        "plot".as_ref(),
        run.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--speed-unit".as_ref(),
        "rpm".as_ref(),
        "--log-amplitude".as_ref(),
        "--zero-at-transducer".as_ref(),
        "--rotation".as_ref(),
        "cw".as_ref(),
    ]);
    let bode = std::fs::read_to_string(out.join("bode_left_rel.svg")).unwrap();
    assert!(bode.contains("Rotor speed [rpm]"));
    let polar = std::fs::read_to_string(out.join("polar_left_rel_z.svg")).unwrap();
    assert!(polar.contains("0° at the transducer") && polar.contains("CW rotation"));
    assert!(polar.contains(" rpm"), "speed labels in rpm");

    let plots = tmp.path().join("fit");
    plinth(&[
        "identify".as_ref(),
        run.as_os_str(),
        "--plots".as_ref(),
        plots.as_os_str(),
    ]);
    for b in ["left", "right"] {
        let svg = std::fs::read_to_string(plots.join(format!("stiffness_{b}.svg"))).unwrap();
        assert!(svg.contains("Re F/X") && svg.contains("Im F/X") && svg.contains("Residual"));
        assert!(svg.contains(&format!("Pedestal {b}")));
        assert!(plots.join(format!("stiffness_{b}.png")).is_file());
    }
}

/// `plot` on a run directory: `transducers.csv` says where each transducer
/// sat but not its unit, so the pick-ups are drawn in µm pk-pk; with the
/// layout the run was imported with they are drawn in its units (the
/// bundled example's velocity pick-ups in mm/s pk) and the polar plots with
/// its rotation (`--rotation` still wins); a layout of another machine is
/// refused, naming the transducer and the file.
#[test]
fn plot_takes_units_and_rotation_from_the_layout() {
    let tmp = tempfile::tempdir().unwrap();
    let ex = repo().join("examples/field");
    let run = tmp.path().join("run");
    plinth(&[
        "import".as_ref(),
        ex.join("vector-table.csv").as_os_str(),
        "--layout".as_ref(),
        ex.join("layout.toml").as_os_str(),
        "--bearings".as_ref(),
        ex.join("bearings.csv").as_os_str(),
        "--out".as_ref(),
        run.as_os_str(),
    ]);
    let bode_ped = |figs: &Path| std::fs::read_to_string(figs.join("bode_left_ped.svg")).unwrap();
    let plain = tmp.path().join("plain");
    plinth(&[
        "plot".as_ref(),
        run.as_os_str(),
        "--out".as_ref(),
        plain.as_os_str(),
    ]);
    assert!(!bode_ped(&plain).contains("mm/s pk"));
    let native = tmp.path().join("native");
    let layout = ex.join("layout.toml");
    plinth(&[
        "plot".as_ref(),
        run.as_os_str(),
        "--out".as_ref(),
        native.as_os_str(),
        "--layout".as_ref(),
        layout.as_os_str(),
    ]);
    assert!(
        bode_ped(&native).contains("[mm/s pk]"),
        "velocity pick-ups in mm/s pk"
    );
    let polar = std::fs::read_to_string(native.join("polar_left_ped_0deg.svg")).unwrap();
    assert!(
        polar.contains("mm/s pk"),
        "polar of a velocity pick-up in its unit"
    );

    // Rotation: the mil/lead fixture's layout says cw.
    let cw_run = tmp.path().join("cw-run");
    let cw_layout = import_cw(&cw_run, false);
    for (extra, says) in [
        (vec![], "lag against CW rotation"),
        (vec!["--rotation", "ccw"], "lag against CCW rotation"),
    ] {
        let figs = tmp.path().join(format!("cw{}", extra.len()));
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "plot".as_ref(),
            cw_run.as_os_str(),
            "--out".as_ref(),
            figs.as_os_str(),
            "--layout".as_ref(),
            cw_layout.as_os_str(),
        ];
        args.extend(extra.iter().map(|a| std::ffi::OsStr::new(*a)));
        plinth(&args);
        for (name, text) in svgs(&figs, "polar_") {
            assert!(text.contains(says), "{name}: {extra:?}");
        }
        let rel = std::fs::read_to_string(figs.join("bode_left_rel.svg")).unwrap();
        assert!(
            rel.contains("mil pk-pk"),
            "probes in mils as the layout says"
        );
    }

    // Another machine's layout does not describe this run.
    let err = plinth_fails(&[
        "plot".as_ref(),
        run.as_os_str(),
        "--out".as_ref(),
        tmp.path().join("wrong").as_os_str(),
        "--layout".as_ref(),
        cw_layout.as_os_str(),
    ]);
    assert!(
        err.contains("transducers.csv") && err.contains("--layout") && err.contains("left"),
        "{err}"
    );
    assert!(
        !tmp.path().join("wrong").exists(),
        "nothing written on an error"
    );
}

/// `report --speeds --unmeasured-base` identifies as `plinth identify` does
/// with them: the speeds table holds the band only, the base fitted under
/// the pedestals is described, and the "how this report was made" section
/// names the identify command with both options.
#[test]
fn report_passes_speeds_and_unmeasured_base_to_identify() {
    let tmp = tempfile::tempdir().unwrap();
    let run = repo().join("examples/run-paper-2digits");
    let out = tmp.path().join("r.html");
    plinth(&[
        "report".as_ref(),
        run.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--speeds".as_ref(),
        "10:150".as_ref(),
        "--unmeasured-base".as_ref(),
        "left,right".as_ref(),
    ]);
    let html = std::fs::read_to_string(&out).unwrap();
    assert!(
        html.contains("identify") && html.contains("--speeds 10:150 --unmeasured-base left,right"),
        "the identify command in the report"
    );
    assert!(
        html.contains("(unmeasured) under left, right"),
        "the base is described"
    );
    // Bearings and speeds: within 10-150 Hz (the run has 5-200 Hz).
    let speeds = html.split("<h3>Bearings and speeds</h3>").nth(1).unwrap();
    let speeds = speeds.split("</table>").next().unwrap();
    for row in speeds.lines().filter(|l| l.contains("<td class=\"l\">")) {
        let cells: Vec<f64> = row
            .split("<td>")
            .skip(1)
            .map(|c| c.split('<').next().unwrap().parse().unwrap())
            .collect();
        let (lo, hi) = (cells[1], cells[2]);
        assert!(
            (10.0..12.0).contains(&lo) && (140.0..=150.0).contains(&hi),
            "{row}"
        );
    }
}
