//! The simulator against ROSS 2.3.0 (tests/reference/ross/make_reference.py):
//! two machines with pedestals linked through the bearings, unbalance
//! response at 196 speeds, rel and ped at every bearing within 1e-3.

use num_complex::Complex;
use plinth::sim::{unbalance_response, EffectSet, Machine};
use std::path::PathBuf;

fn reference_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("reference/ross")
}

/// Largest error of a channel relative to that channel's largest magnitude
/// over speed, and the largest point-wise relative error where the channel
/// is above 1% of its maximum.
fn compare(name: &str) -> f64 {
    let dir = reference_dir();
    let text = std::fs::read_to_string(dir.join(format!("{name}.json"))).unwrap();
    let r: serde_json::Value = serde_json::from_str(&text).unwrap();
    let machine = Machine::from_toml_path(dir.join(format!("{name}.toml"))).unwrap();
    let speeds: Vec<f64> = r["speeds_hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let resp = unbalance_response(&machine, &speeds, &EffectSet::none()).unwrap();
    let mut worst: f64 = 0.0;
    for (b, bname) in resp.bearing_names.iter().enumerate() {
        // Bearing coefficients: the same closed form, implemented twice.
        for (key, (i, j, is_k)) in [
            ("kyy", (0, 0, true)),
            ("kyz", (0, 1, true)),
            ("kzy", (1, 0, true)),
            ("kzz", (1, 1, true)),
            ("cyy", (0, 0, false)),
            ("czz", (1, 1, false)),
            ("cyz", (0, 1, false)),
        ] {
            let col = r["coefficients"][bname][key].as_array().unwrap();
            for (s, v) in col.iter().enumerate() {
                let c = resp.bearings[s][b].coefficients;
                let got = if is_k { c.k[i][j] } else { c.c[i][j] };
                let want = v.as_f64().unwrap();
                let scale = if is_k {
                    c.k[0][0].abs()
                } else {
                    c.c[0][0].abs()
                }
                .max(1e-30);
                assert!(
                    (got - want).abs() <= 1e-9 * scale,
                    "{name} {bname} {key} at {} Hz: {got} vs {want}",
                    speeds[s]
                );
            }
        }
        for (ch, pick) in [("rel_y", 0usize), ("rel_z", 1), ("ped_y", 2), ("ped_z", 3)] {
            let re = r["bearings"][bname][ch]["re"].as_array().unwrap();
            let im = r["bearings"][bname][ch]["im"].as_array().unwrap();
            let want: Vec<Complex<f64>> = re
                .iter()
                .zip(im)
                .map(|(a, b)| Complex::new(a.as_f64().unwrap(), b.as_f64().unwrap()))
                .collect();
            let got: Vec<Complex<f64>> = resp
                .bearings
                .iter()
                .map(|row| {
                    if pick < 2 {
                        row[b].rel[pick]
                    } else {
                        row[b].ped[pick - 2]
                    }
                })
                .collect();
            let max = want.iter().map(|w| w.norm()).fold(0.0, f64::max);
            assert!(max > 0.0, "{name} {bname} {ch}: reference is all zero");
            for (s, (g, w)) in got.iter().zip(&want).enumerate() {
                let err = (g - w).norm() / max;
                worst = worst.max(err);
                assert!(
                    err < 1e-3,
                    "{name} {bname} {ch} at {} Hz: plinth {g} vs ROSS {w} (error {err:.2e} of the channel maximum)",
                    speeds[s]
                );
                if w.norm() > 0.01 * max {
                    let pointwise = (g - w).norm() / w.norm();
                    assert!(
                        pointwise < 1e-2,
                        "{name} {bname} {ch} at {} Hz: point-wise {pointwise:.2e}",
                        speeds[s]
                    );
                }
            }
        }
    }
    eprintln!("{name}: largest error {worst:.2e} of the channel maximum");
    worst
}

#[test]
fn machine_a_cross_coupled_bearings_damped_pedestals_matches_ross() {
    compare("machine-a");
}

#[test]
fn machine_b_oil_film_bearings_damped_pedestals_matches_ross() {
    compare("machine-b");
}
