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

fn plinth(args: &[&std::ffi::OsStr]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_plinth"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "plinth {:?} failed: {}",
        args,
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).to_string()
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
    let t = repo().join("tests/fixtures/field/tables");
    let out = tmp.path().join("run");
    plinth(&[
        "import".as_ref(),
        t.join("mil_lead_cw.csv").as_os_str(),
        "--layout".as_ref(),
        t.join("mil_lead_cw.toml").as_os_str(),
        "--bearings".as_ref(),
        repo()
            .join("tests/fixtures/field/sim/bearings.csv")
            .as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--plots".as_ref(),
    ]);
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
