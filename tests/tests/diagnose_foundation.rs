//! `plinth diagnose` on machines whose pedestals stand on a flexible base,
//! with data made by the simulator's base *element* (`[[base]]` in a machine
//! file: the base has its own DOFs in the assembly, `plinth::sim`), never by
//! the model the candidate fits. The base is not measured (no `base.csv`).
//!
//! - two machines (two and three bearings), base modes inside and outside
//!   the speed range, with noise columns and 0.5 % noise: `foundation_coupling`
//!   named, the gap falls to about its noise floor, pedestal k and m within
//!   2 %, the base's identified parameters within 10 %;
//! - out of the library (a second base under part of the pedestals): no
//!   fix claimed, the disagreement is said to be unexplained and the
//!   parameters untrusted;
//! - a bearing table 20 % off in stiffness at both bearings (out of the
//!   library until session 24): `bearing_coefficients` (`k_scale`) named at
//!   both, the pedestals after it within 2 %;
//! - rigid ground at 2, 3 and 12 digits, with noise, and with stiff
//!   rolling-element bearings under noise: nothing named.

use plinth::diagnose::machine::{machine_gap, resimulate};
use plinth::diagnose::trust::{AT_THE_FLOOR, UNEXPLAINED};
use plinth::diagnose::{diagnose, Options};
use plinth::rundir::RunDir;
use plinth::sim::base::Base;
use plinth::sim::{EffectSet, Machine};
use plinth_tests::simulated::{
    assert_pedestals_near_truth, on_rigid_ground, simulated_run, speeds, Writing,
};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};

const SKID: &str = include_str!("../../examples/two-pedestals-on-skid.toml");

/// Three bearings on one frame: a ROSS-style shaft with speed tables of
/// cross-coupled coefficients, written for this test.
const THREE_ON_FRAME: &str = r#"
name = "three-on-frame"

[[base]]
name = "frame"
m = 450.0
k_y = 2.4e7
k_z = 1.8e7
c_y = 6.0e3
c_z = 5.0e3

[shaft]
material = { young_modulus = 2.11e11, poisson_ratio = 0.3, density = 7810.0 }

[[shaft.sections]]
length = 1.6
outer_diameter = 0.09
elements = 16

[[disks]]
node = 4
mass = 40.0
polar_inertia = 0.6
diametral_inertia = 0.3
unbalance = 2.0e-4
unbalance_angle = 0.0

[[disks]]
node = 12
mass = 30.0
polar_inertia = 0.45
diametral_inertia = 0.23
unbalance = 1.5e-4
unbalance_angle = 100.0

[[bearings]]
name = "B1"
node = 1
coefficients = [ { speed_hz = 0.0, kyy = 6.0e7, kyz = 1.0e7, kzy = -1.5e7, kzz = 4.0e7, cyy = 4.0e4, cyz = 2.0e3, czy = 2.0e3, czz = 3.0e4 },
                 { speed_hz = 150.0, kyy = 9.0e7, kyz = 2.0e7, kzy = -3.0e7, kzz = 6.0e7, cyy = 3.0e4, cyz = 2.0e3, czy = 2.0e3, czz = 2.5e4 } ]
pedestal = { m = 90.0, k_y = 1.2e7, k_z = 9.0e6, c_y = 600.0, c_z = 400.0 }
base = "frame"

[[bearings]]
name = "B2"
node = 8
coefficients = [ { speed_hz = 0.0, kyy = 5.0e7, kyz = 8.0e6, kzy = -1.2e7, kzz = 3.5e7, cyy = 3.5e4, czz = 2.8e4 } ]
pedestal = { m = 70.0, k_y = 8.0e6, k_z = 1.0e7, c_y = 300.0, c_z = 500.0 }
base = "frame"

[[bearings]]
name = "B3"
node = 15
coefficients = [ { speed_hz = 0.0, kyy = 5.5e7, kyz = 9.0e6, kzy = -1.4e7, kzz = 3.8e7, cyy = 3.8e4, czz = 3.0e4 } ]
pedestal = { m = 110.0, k_y = 1.5e7, k_z = 1.1e7, c_y = 700.0, c_z = 500.0 }
base = "frame"
"#;

const NOISY: Writing = Writing {
    digits: None,
    noise: 0.005,
    rel_noise: None,
};

/// Simulates `machine` with the noise of `w` ([`simulated_run`]).
fn run_dir(machine: &Machine, speeds: &[f64], w: Writing, seed: u64) -> RunDir {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut normal = || -> f64 { StandardNormal.sample(&mut rng) };
    simulated_run(machine, speeds, &EffectSet::none(), w, &mut normal)
}

fn machine(text: &str, file: &str) -> Machine {
    Machine::from_toml_str(text, file).expect("machine file")
}

/// Checks that `foundation_coupling` is named alone, the gap falls to about
/// its floor, pedestal k and m are within 2 % and the base's parameters
/// within 10 % where the data determine them.
fn check_named(machine: &Machine, run: &RunDir, label: &str) {
    let out = diagnose(run, &Options::default()).expect("diagnose");
    let d = &out.diagnosis;
    let text = d.to_text();
    println!("{label}:\n{text}");
    assert_eq!(
        d.effects_added,
        vec!["foundation_coupling".to_string()],
        "{label}"
    );
    let step = &d.steps[0];
    assert!(
        step.test
            .starts_with("likelihood-ratio, parametric bootstrap ("),
        "{label}: {}",
        step.test
    );
    assert!(
        d.gap_after <= AT_THE_FLOOR * d.noise.gap_floor_after,
        "{label}: gap {} -> {} (floor {})",
        d.gap_before,
        d.gap_after,
        d.noise.gap_floor_after
    );
    assert!(d.trusted, "{label}: {:?}", d.trust_reasons);
    assert!(!d.verdict.contains(UNEXPLAINED), "{label}");
    assert_pedestals_near_truth(run, &d.pedestals_after, 0.02, label);
    let found = step.foundation.as_ref().expect("foundation report");
    assert_eq!(found.groups.len(), 1, "{label}: one base");
    let g = &found.groups[0];
    let mut on_base = g.bearings.clone();
    on_base.sort();
    let mut want_on = machine.bearing_names();
    want_on.sort();
    assert_eq!(on_base, want_on, "{label}: every pedestal on the base");
    let base: &Base = &machine.bases[0];
    for d_ in 0..2 {
        let name = ["y", "z"][d_];
        let id = g.identifiability[d_];
        match id {
            plinth::estimate::base::BaseIdentifiability::Full => {
                for (what, got, want) in [
                    ("k", g.base.k[d_], base.k[d_]),
                    ("m", g.base.m[d_], base.m[d_]),
                    ("c", g.base.c[d_], base.c[d_]),
                ] {
                    assert!(
                        (got - want).abs() / want < 0.10,
                        "{label} base {what}_{name}: {got} vs {want}"
                    );
                }
            }
            plinth::estimate::base::BaseIdentifiability::QuasiStatic {
                compliance_m_per_n, ..
            } => {
                let want = 1.0 / base.k[d_];
                assert!(
                    (compliance_m_per_n - want).abs() / want < 0.10,
                    "{label} base compliance_{name}: {compliance_m_per_n} vs {want}"
                );
            }
            other => panic!("{label}: base in {name} {other:?}"),
        }
    }
    // `--machine`: the machine re-simulated with the identified pedestals on
    // a base element with the identified parameters reproduces every
    // channel (noise 0.5 %); with the rigid-ground fit it does not (when
    // that fit is physical enough to simulate at all).
    let last = out.states.last().expect("state");
    let with_base = resimulate(machine, &out.prep, last, out.foundation.as_ref()).expect("resim");
    let g_base = machine_gap(&out.prep, &with_base);
    let g_rigid = resimulate(machine, &out.prep, &out.states[0], None)
        .ok()
        .map(|r| machine_gap(&out.prep, &r));
    println!("{label}: machine-level gap rigid {g_rigid:?}, with the base {g_base:.4}");
    assert!(g_base < 0.02, "{label}: machine-level gap {g_base}");
    if let Some(g) = g_rigid {
        assert!(g_base < g / 5.0, "{label}: {g} -> {g_base}");
    }
    // The text says what the JSON says.
    assert!(text.contains(&format!("{:.4} to {:.4}", d.gap_before, d.gap_after)));
    let json = serde_json::to_value(d).expect("json");
    assert_eq!(json["trusted"], serde_json::Value::Bool(true));
    assert!(json["steps"][0]["foundation"]["test"]["test"]
        .as_str()
        .is_some_and(|t| t.starts_with("likelihood-ratio, parametric bootstrap")));
}

/// Checks that no fix is claimed: the disagreement is said to be
/// unexplained and the parameters untrusted; the text's gaps are the JSON's.
fn check_unexplained(run: &RunDir, label: &str) {
    let out = diagnose(run, &Options::default()).expect("diagnose");
    let d = &out.diagnosis;
    let text = d.to_text();
    println!("{label}:\n{text}");
    assert!(text.contains(UNEXPLAINED), "{label}");
    assert!(!d.trusted, "{label}");
    assert!(
        d.trust_reasons.iter().any(|r| r.contains(UNEXPLAINED)),
        "{label}: {:?}",
        d.trust_reasons
    );
    if !d.steps.is_empty() {
        // The verdict's numbers are the JSON's, and its verb follows them.
        assert!(
            text.contains(&format!("from {:.4} to {:.4}", d.gap_before, d.gap_after)),
            "{label}"
        );
        let moved = if d.gap_after < d.gap_before {
            "gap fell"
        } else {
            "gap ROSE"
        };
        assert!(d.verdict.contains(moved), "{label}");
    }
    let json = serde_json::to_value(d).expect("json");
    assert_eq!(json["trusted"], serde_json::Value::Bool(false));
}

#[test]
fn two_bearings_on_a_skid_with_its_mode_in_the_speed_range() {
    // Skid modes near 29 Hz (y) and 26 Hz (z), speeds 5-120 Hz.
    let m = machine(SKID, "two-pedestals-on-skid.toml");
    let run = run_dir(&m, &speeds(5.0, 120.0, 2.0), NOISY, 11);
    check_named(&m, &run, "skid, mode in range");
}

#[test]
fn three_bearings_on_a_frame_in_and_above_the_speed_range() {
    // Frame modes near 37 Hz (y) and 32 Hz (z): inside 5-120 Hz.
    let m = machine(THREE_ON_FRAME, "three-on-frame.toml");
    let run = run_dir(&m, &speeds(5.0, 120.0, 2.5), NOISY, 12);
    check_named(&m, &run, "frame, mode in range");
    // A stiff frame (modes near 160 and 140 Hz) above a 5-90 Hz run-down:
    // only the quasi-static compliance is determined.
    let mut stiff = m.clone();
    stiff.bases[0].k = [4.5e8, 3.5e8];
    let run = run_dir(&stiff, &speeds(5.0, 90.0, 2.0), NOISY, 13);
    check_named(&stiff, &run, "frame, mode above range");
}

#[test]
fn out_of_library_data_are_not_claimed_fixed() {
    // A second base under one of the three pedestals (its own mode at
    // 45 Hz): two bases, one of them under a single pedestal, is not a
    // grouping of the library.
    let mut m = machine(THREE_ON_FRAME, "three-on-frame.toml");
    m.bases.push(Base {
        name: "plinth".into(),
        m: [200.0, 200.0],
        k: [1.6e7, 1.4e7],
        c: [2.0e3, 2.0e3],
        eta: 0.0,
    });
    m.bearings[2].base = Some(1);
    m.validate().expect("valid machine");
    let run = run_dir(&m, &speeds(5.0, 120.0, 2.5), NOISY, 21);
    check_unexplained(&run, "second base under B3");
}

/// Rigid ground, but bearings.csv's stiffnesses 20 % high (damping right):
/// the forces are wrong in a speed-dependent, complex way. Until session
/// 24 no library effect held it and this run was checked to be left
/// unexplained; the table's stiffness relative to its damping
/// (`bearing_coefficients`, `k_scale`, for a table no clearance of the
/// file's oil film matches) now names it at both bearings, and the
/// pedestals after the correction are the machine's.
#[test]
fn a_table_stiffness_off_at_both_bearings_is_named_at_both() {
    let rigid = on_rigid_ground(&machine(SKID, "two-pedestals-on-skid.toml"));
    let mut run = run_dir(&rigid, &speeds(5.0, 120.0, 2.0), NOISY, 22);
    for row in &mut run.bearings {
        for r in 0..2 {
            for c in 0..2 {
                row.coefficients.k[r][c] *= 1.2;
            }
        }
    }
    let d = diagnose(&run, &Options::default())
        .expect("diagnose")
        .diagnosis;
    let text = d.to_text();
    let mut named: Vec<(&str, &str)> = d
        .steps
        .iter()
        .filter(|s| s.dropped.is_none())
        .map(|s| (s.effect.as_str(), s.bearing.as_str()))
        .collect();
    named.sort();
    assert_eq!(
        named,
        [
            ("bearing_coefficients", "left"),
            ("bearing_coefficients", "right")
        ],
        "{text}"
    );
    for s in &d.steps {
        let k = s
            .parameters
            .iter()
            .find(|p| p.name == "k_scale")
            .expect("k_scale");
        let want = 1.0 / 1.2;
        assert!(
            (k.value / want - 1.0).abs() < 0.01 && (k.value - want).abs() < 4.0 * k.std_err,
            "{}: k_scale {} ± {} vs {want}\n{text}",
            s.bearing,
            k.value,
            k.std_err
        );
    }
    assert!(d.trusted, "{:?}\n{text}", d.trust_reasons);
    assert_pedestals_near_truth(&run, &d.pedestals_after, 0.02, "table 20 % stiff");
}

#[test]
fn rigid_ground_names_nothing() {
    let rigid = on_rigid_ground(&machine(SKID, "two-pedestals-on-skid.toml"));
    let sp = speeds(5.0, 120.0, 1.0);
    let cases = [
        (
            "2 digits",
            Writing {
                digits: Some(2),
                noise: 0.0,
                rel_noise: None,
            },
        ),
        (
            "3 digits",
            Writing {
                digits: Some(3),
                noise: 0.0,
                rel_noise: None,
            },
        ),
        (
            "12 digits",
            Writing {
                digits: Some(12),
                noise: 0.0,
                rel_noise: None,
            },
        ),
        ("0.5 % noise", NOISY),
    ];
    for (label, w) in cases {
        let run = run_dir(&rigid, &sp, w, 31);
        let d = diagnose(&run, &Options::default())
            .expect("diagnose")
            .diagnosis;
        assert!(d.effects_added.is_empty(), "{label}: {}", d.to_text());
    }
}

#[test]
fn stiff_rolling_element_bearings_under_noise_name_nothing() {
    // Rolling-element bearings (1e9 N/m, little damping): the rel readings
    // are tiny, and the probes' noise (5 % of their RMS) dominates the
    // forces; pedestal sensors at 0.5 %.
    // The frame machine with every pedestal on rigid ground and its oil
    // films replaced by rolling-element bearings.
    let mut rolling = String::new();
    let mut in_base = false;
    for line in THREE_ON_FRAME.lines() {
        if line.starts_with("[[base]]") {
            in_base = true;
            continue;
        }
        if line.starts_with("[shaft]") {
            in_base = false;
        }
        if in_base || line.starts_with("base = ") || line.trim_start().starts_with("{ speed_hz") {
            continue;
        }
        if line.starts_with("coefficients = ") {
            rolling += "coefficients = [ { speed_hz = 0.0, kyy = 1.0e9, kzz = 1.0e9, cyy = 2.0e3, czz = 2.0e3 } ]\n";
        } else {
            rolling += line;
            rolling += "\n";
        }
    }
    let m = machine(&rolling, "three-rolling.toml");
    assert!(m.bases.is_empty());
    let w = Writing {
        digits: None,
        noise: 0.005,
        rel_noise: Some(0.05),
    };
    let run = run_dir(&m, &speeds(5.0, 120.0, 2.5), w, 41);
    let d = diagnose(&run, &Options::default())
        .expect("diagnose")
        .diagnosis;
    println!("{}", d.to_text());
    assert!(d.effects_added.is_empty(), "{}", d.to_text());
    assert!(d.trusted, "{:?}", d.trust_reasons);
}
