//! A probe runout on a bearing that stands on a shared base, on data Plinth
//! has never made: unseen-four's `base-runout-d3` at seeds 112 and 106
//! (`scripts/ross_unseen.py --machine unseen-four DIR base-runout-d3 SEED`,
//! ROSS 2.3.0; B1 and B2 on a 350 kg frame, a runout on B2's probes, no
//! noise, 3 significant digits), read by the `plinth` binary as a user would.
//!
//! The runout and the base are correlated through B2's pedestal; fitted by
//! alternating between them (session 36), B2's final k_y/k_z/m stayed
//! pulled low by −0.17/−0.20/−0.18 %, −5.2/−7.2/−12.6 of their ±, while the
//! verdict was trusted (seed 112). The joint Newton fit that fixed it was
//! skipped whenever the base refitted at the settled runout came out a hair
//! (1e-10 relative) above the settled χ²: seed 106 kept B2's m −5.3 ± off,
//! trusted (session 37). Expected on both: the same names, trusted, and
//! every final pedestal k and m within 3 of its ± of the truth.
//!
//! And ± that mean what they say (session 38): the workflow's noise is an
//! upper bound (3 digits taken as truncated, mean square ulp²/3), the base
//! group's χ²/dof was 0.19-0.20 on both runs, and the base pedestals'
//! RMS z (B1, B2; k_y, k_z, m; both runs) was 0.24: ± 4 times too wide.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/ross-unseen")
        .join(rel)
}

#[test]
fn runout_on_a_base_bearing_leaves_its_pedestal_within_its_error() {
    within_error_on("base-runout-d3-112");
}

#[test]
fn the_joint_fit_runs_when_the_refit_ties_the_settled_base() {
    within_error_on("base-runout-d3-106");
}

/// The base pedestals' ± calibrated against the truth: over both stored
/// runs, the RMS of z = (value − truth)/± of B1's and B2's k_y, k_z and m
/// (12 values) is at least 0.4 (at most 2.5 times too wide; main eacba08:
/// 0.24, the ± from the noise bound) and below 2.
#[test]
fn the_base_pedestals_errors_are_not_inflated_by_the_noise_bound() {
    let mut zs = Vec::new();
    for name in ["base-runout-d3-106", "base-runout-d3-112"] {
        for (bearing, z) in z_scores(name) {
            if bearing == "B1" || bearing == "B2" {
                zs.extend(z);
            }
        }
    }
    assert_eq!(zs.len(), 12);
    let rms = (zs.iter().map(|z| z * z).sum::<f64>() / zs.len() as f64).sqrt();
    eprintln!("base pedestals' RMS z over both runs: {rms:.3}");
    assert!(
        rms >= 0.4,
        "the ± are {:.1} times too wide (RMS z {rms:.3})",
        1.0 / rms
    );
    assert!(rms < 2.0, "the ± are too narrow (RMS z {rms:.3})");
}

/// The stored run `name` diagnosed once per test binary: its JSON output.
fn diagnosed(name: &str) -> &'static Value {
    static RUN_106: OnceLock<Value> = OnceLock::new();
    static RUN_112: OnceLock<Value> = OnceLock::new();
    let cell = match name {
        "base-runout-d3-106" => &RUN_106,
        "base-runout-d3-112" => &RUN_112,
        other => panic!("no stored run {other}"),
    };
    cell.get_or_init(|| {
        let run = data(name);
        let machine = data("unseen-four.toml");
        let out = Command::new(env!("CARGO_BIN_EXE_plinth"))
            .args(["diagnose", run.to_str().unwrap(), "--json", "--machine"])
            .arg(&machine)
            .output()
            .expect("plinth runs");
        assert_eq!(
            out.status.code(),
            Some(0),
            "diagnose exited {:?}: {}",
            out.status.code(),
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).expect("JSON on stdout")
    })
}

/// Per bearing of truth.json: z of the final k_y, k_z and m of `name`.
fn z_scores(name: &str) -> Vec<(String, [f64; 3])> {
    let json = diagnosed(name);
    let truth: Value = serde_json::from_str(
        &std::fs::read_to_string(data(name).join("truth.json")).expect("truth.json"),
    )
    .expect("truth parses");
    let mut out = Vec::new();
    for t in truth["pedestals"].as_array().expect("truth pedestals") {
        let bearing = t["bearing"].as_str().expect("bearing");
        let got = json["pedestals_after"]
            .as_array()
            .expect("pedestals_after")
            .iter()
            .find(|p| p["bearing"] == bearing)
            .expect("the bearing in the output");
        let z = ["k_y", "k_z", "m"].map(|key| {
            let (g, w) = (got[key].as_f64().unwrap(), t[key].as_f64().unwrap());
            let se = got["std_err"][key].as_f64().unwrap();
            let z = (g - w) / se;
            eprintln!("{name} {bearing} {key}: {g:.6e} truth {w:.6e} ± {se:.3e}, z {z:+.2}");
            z
        });
        out.push((bearing.to_string(), z));
    }
    out
}

/// Diagnoses the stored run `name` and checks the names, the verdict and
/// every final pedestal k and m against truth.json within 3 ±.
fn within_error_on(name: &str) {
    let json = diagnosed(name);
    assert_eq!(json["trusted"], Value::Bool(true));
    let named: Vec<(String, String)> = json["steps"]
        .as_array()
        .expect("steps")
        .iter()
        .filter(|s| s["dropped"].is_null())
        .map(|s| {
            (
                s["effect"].as_str().unwrap_or("").to_string(),
                s["bearing"].as_str().unwrap_or("").to_string(),
            )
        })
        .collect();
    assert!(named.contains(&("probe_runout".to_string(), "B2".to_string())));
    assert!(named.iter().any(|(e, _)| e == "foundation_coupling"));
    let worst = z_scores(name)
        .iter()
        .flat_map(|(_, z)| z.iter().map(|v| v.abs()))
        .fold(0.0_f64, f64::max);
    assert!(worst < 3.0, "{name}: a final pedestal is {worst:.2} ± off");
}
