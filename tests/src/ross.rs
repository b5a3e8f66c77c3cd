//! Comparing the simulator with the ROSS 2.3.0 reference responses in
//! tests/reference/ross (`<name>.toml` the machine, `<name>.json` the
//! phasors ROSS gives, both made by make_reference.py).

use num_complex::Complex;
use plinth::sim::{Machine, Response};
use std::path::PathBuf;

type C = Complex<f64>;

/// The directory of the ROSS reference machines and responses.
pub fn reference_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("reference/ross")
}

/// One ROSS reference case: the machine file, ROSS's response and its speeds.
pub struct RossCase {
    /// The machine read from `<name>.toml`.
    pub machine: Machine,
    /// ROSS's answer, `<name>.json`.
    pub reference: serde_json::Value,
    /// The speeds [Hz] ROSS solved.
    pub speeds_hz: Vec<f64>,
}

impl RossCase {
    /// Reads reference case `name` (e.g. "machine-c").
    pub fn load(name: &str) -> Self {
        let dir = reference_dir();
        let text = std::fs::read_to_string(dir.join(format!("{name}.json")))
            .unwrap_or_else(|e| panic!("{name}.json: {e}"));
        let reference: serde_json::Value =
            serde_json::from_str(&text).unwrap_or_else(|e| panic!("{name}.json: {e}"));
        let machine = Machine::from_toml_path(dir.join(format!("{name}.toml")))
            .unwrap_or_else(|e| panic!("{name}.toml: {e}"));
        let speeds_hz = reference["speeds_hz"]
            .as_array()
            .expect("speeds_hz")
            .iter()
            .map(|v| v.as_f64().expect("a speed"))
            .collect();
        Self {
            machine,
            reference,
            speeds_hz,
        }
    }

    /// Largest error of every bearing channel (rel_y, rel_z, ped_y, ped_z)
    /// of `response` against ROSS, relative to the channel's largest
    /// magnitude over speed; panics naming the channel where one exceeds
    /// `tolerance` [-].
    pub fn bearing_error(&self, response: &Response, tolerance: f64) -> f64 {
        let mut worst: f64 = 0.0;
        for (b, bname) in response.bearing_names.iter().enumerate() {
            for (ch, pick) in [("rel_y", 0usize), ("rel_z", 1), ("ped_y", 2), ("ped_z", 3)] {
                let want = phasors(&self.reference["bearings"][bname][ch]);
                let got: Vec<C> = response
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
                let err = channel_error(&got, &want);
                assert!(
                    err < tolerance,
                    "{bname} {ch}: error {err:.2e} of the channel maximum"
                );
                worst = worst.max(err);
            }
        }
        worst
    }

    /// Largest error of the (y, z) motion `got` (one pair per speed) of the
    /// base ROSS names `name` under `group` ("bases" or "sub_bases"),
    /// relative to each axis's largest magnitude; panics where one exceeds
    /// `tolerance` [-].
    pub fn base_error(&self, group: &str, name: &str, got: &[[C; 2]], tolerance: f64) -> f64 {
        let mut worst: f64 = 0.0;
        for (d, axis) in ["y", "z"].iter().enumerate() {
            let want = phasors(&self.reference[group][name][axis]);
            let got: Vec<C> = got.iter().map(|m| m[d]).collect();
            let err = channel_error(&got, &want);
            assert!(err < tolerance, "{group} {name} {axis}: error {err:.2e}");
            worst = worst.max(err);
        }
        worst
    }
}

/// Complex phasors from a `{ "re": [...], "im": [...] }` JSON object.
pub fn phasors(v: &serde_json::Value) -> Vec<C> {
    let re = v["re"].as_array().expect("re");
    let im = v["im"].as_array().expect("im");
    re.iter()
        .zip(im)
        .map(|(a, b)| C::new(a.as_f64().expect("re"), b.as_f64().expect("im")))
        .collect()
}

/// Largest error of `got` against `want` relative to the channel's largest
/// magnitude over speed.
pub fn channel_error(got: &[C], want: &[C]) -> f64 {
    let max = want.iter().map(|w| w.norm()).fold(0.0, f64::max);
    assert!(max > 0.0, "reference channel is all zero");
    got.iter()
        .zip(want)
        .map(|(g, w)| (g - w).norm() / max)
        .fold(0.0, f64::max)
}
