//! `plinth diagnose` on whole-machine run-downs made by the simulator
//! (`plinth::sim`), written to disk at 3 significant digits (truncated, as the
//! paper did) and read back with the run-directory reader: every effect of the
//! library, each on one bearing, on two machines; clean runs name nothing.

use plinth::diagnose::{diagnose, Options};
use plinth::effects::EffectKind;
use plinth::rundir::{DigitsMode, RunDir, WriteOptions};
use plinth::sim::{unbalance_response, EffectSet, Machine, Noise};

const PAPER: &str = include_str!("../../examples/feng-hahn-1997-damped.toml");
const ROSS_A: &str = include_str!("../reference/ross/machine-a.toml");

fn speeds() -> Vec<f64> {
    (0..196).map(|i| 5.0 + i as f64).collect()
}

/// Simulates, writes with `digits` (truncated) and reads back.
fn run_dir(
    machine: &Machine,
    effects: &EffectSet,
    digits: Option<u32>,
    noise: Option<Noise>,
) -> RunDir {
    let response = unbalance_response(machine, &speeds(), effects).expect("simulation");
    let run = response.to_run_dir(noise).expect("run dir");
    let dir = tempfile::tempdir().expect("tempdir");
    run.write_with(
        dir.path(),
        &WriteOptions {
            digits,
            digits_mode: DigitsMode::Truncate,
        },
    )
    .expect("write");
    RunDir::read(dir.path()).expect("read back")
}

fn check_effect(machine: &Machine, kind: EffectKind, bearing: &str) {
    let effects = EffectSet::none().with(kind, Some(bearing), None);
    let run = run_dir(machine, &effects, Some(3), None);
    let truth = run.truth.clone().expect("truth.json");
    let out = diagnose(&run, &Options::default()).expect("diagnose");
    let d = &out.diagnosis;
    assert_eq!(
        d.effects_added,
        vec![kind.name().to_string()],
        "{}\n{}",
        kind.name(),
        d.to_text()
    );
    let step = &d.steps[0];
    assert!(
        step.bearing == bearing,
        "{}: named at {}",
        kind.name(),
        step.bearing
    );
    assert!(
        d.gap_after <= d.gap_before / 5.0 || d.gap_after <= d.noise.gap_floor_after,
        "{}: gap {} -> {} (floor {})",
        kind.name(),
        d.gap_before,
        d.gap_after,
        d.noise.gap_floor_after
    );
    let detail = truth
        .effect_details
        .iter()
        .find(|e| e.name == kind.name())
        .expect("effect details");
    for (name, value) in &detail.parameters {
        let est = step
            .parameters
            .iter()
            .find(|p| &p.name == name)
            .unwrap_or_else(|| panic!("{} missing", name));
        let err = (est.value - value).abs() / value.abs();
        assert!(
            err < 0.10,
            "{} {name}: {} vs {value}",
            kind.name(),
            est.value
        );
    }
    for p in &truth.pedestals {
        let after = d
            .pedestals_after
            .iter()
            .find(|x| x.bearing == p.bearing)
            .expect("pedestal");
        let m_truth = if kind == EffectKind::PedestalMassAnisotropy && p.bearing == bearing {
            vec![
                ("m_y", detail.parameters["m_y"]),
                ("m_z", detail.parameters["m_z"]),
            ]
        } else {
            vec![("m", p.m)]
        };
        for (key, truth) in [("k_y", p.k_y), ("k_z", p.k_z)].into_iter().chain(m_truth) {
            let v = after.values[key];
            assert!(
                (v - truth).abs() / truth < 0.02,
                "{} {} {key}: {v} vs {truth}",
                kind.name(),
                p.bearing
            );
        }
    }
}

// The simulator's `foundation_coupling` effect (a constant spring between
// neighbouring pedestals) is not in this list any more: diagnose's
// `foundation_coupling` is now the physical shared base (`[[base]]` in a
// machine file), tested in `diagnose_foundation.rs`.
const PEDESTAL_EFFECTS: [EffectKind; 5] = [
    EffectKind::StructuralDamping,
    EffectKind::PedestalCrossCoupling,
    EffectKind::PedestalMassAnisotropy,
    EffectKind::ProbeRunout,
    EffectKind::SensorDelay,
];

#[test]
fn paper_machine_every_effect_named() {
    let m = Machine::from_toml_str(PAPER, "feng-hahn-1997-damped.toml").expect("machine");
    for (i, kind) in PEDESTAL_EFFECTS.into_iter().enumerate() {
        check_effect(&m, kind, if i % 2 == 0 { "right" } else { "left" });
    }
}

#[test]
fn ross_machine_every_effect_named() {
    let m = Machine::from_toml_str(ROSS_A, "machine-a.toml").expect("machine");
    let names = m.bearing_names();
    for (i, kind) in PEDESTAL_EFFECTS.into_iter().enumerate() {
        check_effect(&m, kind, &names[i % names.len()]);
    }
}

#[test]
fn clean_machine_runs_name_nothing() {
    for (text, file) in [(PAPER, "paper"), (ROSS_A, "ross-a")] {
        let m = Machine::from_toml_str(text, file).expect("machine");
        for (digits, noise) in [
            (Some(2), None),
            (Some(3), None),
            (Some(12), None),
            (Some(12), Some(0.01)),
        ] {
            let noise = noise.map(|fraction| Noise { fraction, seed: 9 });
            let run = run_dir(&m, &EffectSet::none(), digits, noise);
            let d = diagnose(&run, &Options::default())
                .expect("diagnose")
                .diagnosis;
            assert!(
                d.effects_added.is_empty(),
                "{file} {digits:?} {noise:?}: {}",
                d.to_text()
            );
        }
    }
}
