//! "Nothing physically impossible is ok": convention mistakes made in the
//! written CSV files (by text edits here, independent of Plinth's own
//! corrections) are detected and named, the fits are untrusted, `--json`
//! says so and `plinth identify` exits with code 2; clean data (2, 3 and 12
//! digits, 1 % noise) are never flagged. Runs: the bundled
//! `examples/run-paper-2digits` and simulator runs of two machines (oil-film
//! bearings; tabulated cross-coupled bearings).

use plinth::estimate::Observation;
use plinth::identify::cli::{run as identify_cli, Args, Equations};
use plinth::identify::convention::Convention;
use plinth::identify::physical::{exit_code, EXIT_NOT_PHYSICAL};
use plinth::identify::{
    fit_pedestal, identify_run, Identification, IdentifyError, Options, WarningKind,
};
use plinth::rundir::RunDir;
use plinth::sim::{unbalance_response, EffectSet, Machine, Noise};
use plinth_tests::write_run;
use std::path::{Path, PathBuf};

const MISTAKES: [&str; 6] = [
    "conjugated",
    "swapped_yz",
    "rel_negated",
    "bearing_transposed",
    "cross_coupling_sign",
    "speed_in_rpm",
];

fn example_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/run-paper-2digits")
}

/// A second machine, unlike the paper's: one disk, shorter and stiffer shaft,
/// tabulated bearings with unequal cross-coupling (kyz ≠ kzy) and cross
/// damping, heavier pedestal damping (ζ ≈ 1 %), resonances at 80-115 Hz.
const MACHINE_B: &str = r#"
name = "one-disk-tabulated"
[shaft]
material = { young_modulus = 2.0e11, poisson_ratio = 0.3, density = 7850.0 }
[[shaft.sections]]
length = 0.8
outer_diameter = 0.08
elements = 8
[[disks]]
position = 0.4
mass = 60.0
polar_inertia = 1.2
diametral_inertia = 0.6
unbalance = 2.0e-4
unbalance_angle = 30.0
[[bearings]]
name = "B1"
position = 0.0
coefficients = [
  { speed_hz = 0.0, kyy = 5.0e7, kyz = 1.0e7, kzy = -2.0e7, kzz = 4.0e7, cyy = 2.0e4, cyz = 1.0e3, czy = 1.0e3, czz = 1.5e4 },
  { speed_hz = 200.0, kyy = 6.0e7, kyz = 2.0e7, kzy = -3.0e7, kzz = 5.0e7, cyy = 1.5e4, cyz = 2.0e3, czy = 2.0e3, czz = 1.2e4 },
]
pedestal = { m = 40.0, k_y = 2.0e7, k_z = 1.2e7, c_y = 800.0, c_z = 600.0 }
[[bearings]]
name = "B2"
position = 0.8
coefficients = [
  { speed_hz = 0.0, kyy = 4.0e7, kyz = 0.6e7, kzy = -1.5e7, kzz = 3.5e7, cyy = 1.8e4, cyz = 1.5e3, czy = 1.5e3, czz = 1.4e4 },
  { speed_hz = 200.0, kyy = 4.5e7, kyz = 1.2e7, kzy = -2.5e7, kzz = 4.2e7, cyy = 1.4e4, cyz = 2.5e3, czy = 2.5e3, czz = 1.1e4 },
]
pedestal = { m = 55.0, k_y = 1.5e7, k_z = 2.5e7, c_y = 500.0, c_z = 900.0 }
"#;

fn machine_a() -> Machine {
    Machine::from_toml_path(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/feng-hahn-1997-damped.toml"),
    )
    .expect("paper machine")
}

fn machine_b() -> Machine {
    Machine::from_toml_str(MACHINE_B, "machine-b.toml").expect("machine B")
}

/// The machine's run-down (speeds `from..=to` in `step` Hz), with optional
/// noise, written with `digits` significant digits.
fn simulated(
    machine: &Machine,
    (from, to, step): (f64, f64, f64),
    noise: Option<f64>,
    digits: Option<u32>,
) -> tempfile::TempDir {
    let n = ((to - from) / step).round() as usize;
    let speeds: Vec<f64> = (0..=n).map(|i| from + step * i as f64).collect();
    let response = unbalance_response(machine, &speeds, &EffectSet::none()).expect("simulation");
    let run = response
        .to_run_dir(noise.map(|fraction| Noise { fraction, seed: 11 }))
        .expect("run directory");
    write_run(&run, digits)
}

// ------------------------------------------------------------------------
// The mistakes, made in the CSV text (never through Plinth's corrections).

struct Csv {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Csv {
    fn read(path: &Path) -> Csv {
        let text = std::fs::read_to_string(path).expect("csv");
        let mut lines = text.lines().filter(|l| !l.trim().is_empty());
        let header = lines
            .next()
            .expect("header")
            .split(',')
            .map(String::from)
            .collect();
        let rows = lines
            .map(|l| l.split(',').map(String::from).collect())
            .collect();
        Csv { header, rows }
    }

    fn write(&self, path: &Path) {
        let mut text = self.header.join(",") + "\n";
        for r in &self.rows {
            text += &(r.join(",") + "\n");
        }
        std::fs::write(path, text).expect("writing csv");
    }

    fn col(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("column {name}"))
    }

    /// Negates a column by its written sign (the digits stay as written).
    fn negate(&mut self, name: &str) {
        let c = self.col(name);
        for r in &mut self.rows {
            let v = &mut r[c];
            *v = match v.strip_prefix('-') {
                Some(rest) => rest.to_string(),
                None => format!("-{v}"),
            };
        }
    }

    fn swap(&mut self, a: &str, b: &str) {
        let (a, b) = (self.col(a), self.col(b));
        for r in &mut self.rows {
            r.swap(a, b);
        }
    }

    fn scale(&mut self, name: &str, factor: f64) {
        let c = self.col(name);
        for r in &mut self.rows {
            let v: f64 = r[c].parse().expect("number");
            r[c] = format!("{}", v * factor);
        }
    }
}

/// A copy of the run directory `src` with `mistake` made in its files.
fn with_mistake(src: &Path, mistake: &str) -> tempfile::TempDir {
    let dst = tempfile::tempdir().expect("temporary directory");
    for entry in std::fs::read_dir(src).expect("run directory") {
        let entry = entry.expect("entry");
        std::fs::copy(entry.path(), dst.path().join(entry.file_name())).expect("copy");
    }
    let m_path = dst.path().join("measurements.csv");
    let b_path = dst.path().join("bearings.csv");
    let mut m = Csv::read(&m_path);
    let mut b = Csv::read(&b_path);
    match mistake {
        "conjugated" => {
            for c in ["rel_y_im", "rel_z_im", "ped_y_im", "ped_z_im"] {
                m.negate(c);
            }
        }
        "swapped_yz" => {
            for q in ["rel", "ped"] {
                for part in ["re", "im"] {
                    m.swap(&format!("{q}_y_{part}"), &format!("{q}_z_{part}"));
                }
            }
        }
        "rel_negated" => {
            for c in ["rel_y_re", "rel_y_im", "rel_z_re", "rel_z_im"] {
                m.negate(c);
            }
        }
        "bearing_transposed" => {
            b.swap("kyz", "kzy");
            b.swap("cyz", "czy");
        }
        "cross_coupling_sign" => {
            for c in ["kyz", "kzy", "cyz", "czy"] {
                b.negate(c);
            }
        }
        "speed_in_rpm" => {
            m.scale("speed_hz", 60.0);
            b.scale("speed_hz", 60.0);
        }
        other => panic!("unknown mistake {other}"),
    }
    m.write(&m_path);
    b.write(&b_path);
    dst
}

// ------------------------------------------------------------------------

/// `plinth identify DIR`'s exit code (0, or what main maps the error to).
fn identify_exit_code(dir: &Path) -> u8 {
    let args = Args {
        dir: dir.to_path_buf(),
        json: true,
        equations: Equations::RAndI,
        model: None,
        max_condition: plinth::identify::DEFAULT_MAX_CONDITION_NUMBER,
        estimator: plinth::identify::Estimator::Ml,
        compare_ols: false,
        truncated: false,
        slow_roll: None,
        unmeasured_base: None,
        plots: None,
        figure_style: plinth::plots::StyleArgs::default(),
        speeds: None,
        table_uncertainty: None,
        speed_uncertainty: None,
        sensor_uncertainty: None,
    };
    match identify_cli(&args) {
        Ok(()) => 0,
        Err(e) => exit_code(&e),
    }
}

fn identify(dir: &Path) -> (Identification, serde_json::Value) {
    let run = RunDir::read(dir).expect("reading the run directory");
    let id = identify_run(&run, &Options::default()).expect("identification");
    let json = serde_json::to_value(&id).expect("json");
    (id, json)
}

/// Every pedestal is untrusted and names `mistake`, in the JSON too, and
/// identify exits with code 2.
fn assert_named(dir: &Path, mistake: &str, what: &str) {
    let (id, json) = identify(dir);
    for (p, pj) in id
        .pedestals
        .iter()
        .zip(json["pedestals"].as_array().unwrap())
    {
        assert_eq!(
            pj["suspected_convention_error"].as_str(),
            Some(mistake),
            "{what}: pedestal {} names {:?}; warnings {:#?}",
            p.bearing,
            pj["suspected_convention_error"],
            p.warnings
        );
        assert_eq!(pj["trusted"], serde_json::Value::Bool(false), "{what}");
        assert!(p.has_warning(WarningKind::SuspectedConventionError));
    }
    assert_eq!(identify_exit_code(dir), EXIT_NOT_PHYSICAL, "{what}");
}

/// Nothing flagged: every pedestal trusted, passive, no suspected mistake,
/// exit code 0.
fn assert_clean(dir: &Path, what: &str) {
    let (id, json) = identify(dir);
    for (p, pj) in id
        .pedestals
        .iter()
        .zip(json["pedestals"].as_array().unwrap())
    {
        assert!(
            pj.get("suspected_convention_error").is_none(),
            "{what}: {} flagged {:?}",
            p.bearing,
            pj["suspected_convention_error"]
        );
        assert!(
            p.trusted,
            "{what}: {} untrusted: {:#?}",
            p.bearing, p.warnings
        );
        assert!(!p.has_warning(WarningKind::PhysicallyImpossible), "{what}");
    }
    assert_eq!(identify_exit_code(dir), 0, "{what}");
}

#[test]
fn bundled_example_every_mistake_is_named() {
    let src = example_dir();
    assert_clean(&src, "run-paper-2digits as bundled");
    for mistake in MISTAKES {
        let dir = with_mistake(&src, mistake);
        assert_named(
            dir.path(),
            mistake,
            &format!("run-paper-2digits, {mistake}"),
        );
    }
}

#[test]
fn simulated_machines_every_mistake_is_named() {
    let cases = [
        (
            "paper machine, 3 digits",
            machine_a(),
            (5.0, 200.0, 2.5),
            None,
            Some(3),
        ),
        (
            "machine B, 3 digits",
            machine_b(),
            (5.0, 180.0, 2.5),
            None,
            Some(3),
        ),
        (
            "machine B, 1 % noise",
            machine_b(),
            (5.0, 180.0, 2.5),
            Some(0.01),
            Some(6),
        ),
        (
            "paper machine, 3 % noise",
            machine_a(),
            (5.0, 200.0, 2.5),
            Some(0.03),
            Some(6),
        ),
    ];
    for (what, machine, speeds, noise, digits) in cases {
        let src = simulated(&machine, speeds, noise, digits);
        assert_clean(src.path(), what);
        for mistake in MISTAKES {
            let dir = with_mistake(src.path(), mistake);
            assert_named(dir.path(), mistake, &format!("{what}, {mistake}"));
        }
    }
}

#[test]
fn clean_data_are_never_flagged() {
    for digits in [Some(2), Some(3), Some(12)] {
        let a = simulated(&machine_a(), (5.0, 200.0, 2.5), None, digits);
        assert_clean(a.path(), &format!("paper machine, {digits:?} digits"));
        let b = simulated(&machine_b(), (5.0, 180.0, 2.5), None, digits);
        assert_clean(b.path(), &format!("machine B, {digits:?} digits"));
    }
    let a = simulated(&machine_a(), (5.0, 200.0, 2.5), Some(0.01), Some(6));
    assert_clean(a.path(), "paper machine, 1 % noise");
}

#[test]
fn negative_mass_and_stiffness_are_untrusted_with_the_reason() {
    let dir = with_mistake(&example_dir(), "rel_negated");
    let (id, _) = identify(dir.path());
    for p in &id.pedestals {
        assert!(
            p.pedestal.m < 0.0 && p.pedestal.k_y < 0.0 && p.pedestal.k_z < 0.0,
            "{p:?}"
        );
        assert!(!p.trusted);
        let reasons: Vec<&str> = p
            .warnings
            .iter()
            .filter(|w| w.kind == WarningKind::PhysicallyImpossible)
            .map(|w| w.message.as_str())
            .collect();
        assert!(
            reasons
                .iter()
                .any(|r| r.starts_with("m = ") && r.contains("negative mass")),
            "{reasons:?}"
        );
        for k in ["k_y = ", "k_z = "] {
            assert!(
                reasons
                    .iter()
                    .any(|r| r.starts_with(k) && r.contains("negative stiffness")),
                "{reasons:?}"
            );
        }
    }
    // The text table says UNTRUSTED and, under it, why.
    let table = plinth::identify::cli::table(&id, None);
    assert!(table.contains("UNTRUSTED"), "{table}");
    let reasons = plinth::identify::cli::untrusted_reasons(&id);
    assert!(reasons.contains("negative mass"), "{reasons}");
    assert!(reasons.contains("rel_negated"), "{reasons}");
}

#[test]
fn an_overflowing_result_is_an_error_not_a_row() {
    // Numbers near the top of f64's range: every product in the regression
    // overflows.
    let points: Vec<Observation> = (1..=20)
        .map(|i| {
            let s = 10.0 * i as f64;
            let z = num_complex::Complex::new(1.0e300, -3.0e299 * i as f64);
            // The bearing forces [z·1e7, z·2e7] from rel = (z, 2z) and a
            // diagonal bearing of 1e7 N/m.
            let k = num_complex::Complex::new(1.0e7, 0.0);
            let zero = num_complex::Complex::new(0.0, 0.0);
            Observation {
                speed_hz: s,
                rel: [z, z * 2.0],
                ped: [z, z * 0.5],
                kstar: [[k, zero], [zero, k]],
                var: [0.0; 8],
            }
        })
        .collect();
    match fit_pedestal("left", &points, &Options::default()) {
        Err(IdentifyError::NonFinite(e)) => {
            assert_eq!(e.bearing, "left");
            let text = IdentifyError::NonFinite(e).to_string();
            assert!(text.contains("pedestal `left`"), "{text}");
        }
        other => panic!("expected a non-finite result error, got {other:?}"),
    }
}

#[test]
fn diagnose_lists_the_convention_error_among_its_findings() {
    let dir = with_mistake(&example_dir(), "conjugated");
    let run = RunDir::read(dir.path()).unwrap();
    let outcome = plinth::diagnose::diagnose(&run, &plinth::diagnose::Options::default()).unwrap();
    let d = &outcome.diagnosis;
    let named: Vec<(&str, Convention)> = d
        .suspected_convention_errors
        .iter()
        .map(|c| (c.bearing.as_str(), c.convention))
        .collect();
    assert_eq!(
        named,
        [
            ("left", Convention::Conjugated),
            ("right", Convention::Conjugated)
        ]
    );
    let json = serde_json::to_value(d).unwrap();
    assert_eq!(
        json["suspected_convention_errors"][0]["convention"],
        "conjugated"
    );
    let text = d.to_text();
    assert!(
        text.contains("SUSPECTED CONVENTION ERROR at left: conjugated"),
        "{text}"
    );
    // Clean data: the list is there and empty.
    let clean = RunDir::read(example_dir()).unwrap();
    let outcome =
        plinth::diagnose::diagnose(&clean, &plinth::diagnose::Options::default()).unwrap();
    let json = serde_json::to_value(&outcome.diagnosis).unwrap();
    assert_eq!(json["suspected_convention_errors"], serde_json::json!([]));
}
