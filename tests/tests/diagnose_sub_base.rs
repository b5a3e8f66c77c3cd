//! `plinth diagnose` names `pedestal_sub_base` at the right bearing on data
//! made by another program: ROSS 2.3.0's unbalance response of reference
//! machine D (tests/reference/ross/machine-d.{toml,json}, made by
//! make_reference.py: three bearings, B1's pedestal on its own flexible
//! sub-base, its motion not measured), written at 3 digits. The clean
//! control is ROSS's response of machine A (the same rotor on rigid ground,
//! two bearings): nothing named.
//!
//! Only the bearing table (bearings.csv) and the file layout come from
//! Plinth; every measured phasor is ROSS's.

use plinth::diagnose::{diagnose, Options};
use plinth::rundir::RunDir;
use plinth::sim::{unbalance_response, EffectSet};
use plinth_tests::ross::{phasors, RossCase};
use plinth_tests::simulated::assert_pedestals_near_truth;
use plinth_tests::write_run;

/// ROSS's response of reference case `name` at every `every`-th of its
/// speeds, as a run directory written with `digits` and read back.
fn ross_run(name: &str, every: usize, digits: Option<u32>) -> RunDir {
    let case = RossCase::load(name);
    let speeds: Vec<f64> = case.speeds_hz.iter().copied().step_by(every).collect();
    let mut resp =
        unbalance_response(&case.machine, &speeds, &EffectSet::none()).expect("simulation");
    for (b, bearing) in resp.bearing_names.clone().iter().enumerate() {
        let channel = |ch: &str| -> Vec<_> {
            phasors(&case.reference["bearings"][bearing][ch])
                .into_iter()
                .step_by(every)
                .collect()
        };
        let (ry, rz, py, pz) = (
            channel("rel_y"),
            channel("rel_z"),
            channel("ped_y"),
            channel("ped_z"),
        );
        assert_eq!(ry.len(), speeds.len(), "{name} {bearing}: speeds");
        for (s, row) in resp.bearings.iter_mut().enumerate() {
            row[b].rel = [ry[s], rz[s]];
            row[b].ped = [py[s], pz[s]];
        }
    }
    let run = resp.to_run_dir(None).expect("run directory");
    let dir = write_run(&run, digits);
    RunDir::read(dir.path()).expect("read back")
}

#[test]
fn ross_machine_d_sub_base_is_named_at_b1() {
    let run = ross_run("machine-d", 2, Some(3));
    let started = std::time::Instant::now();
    let d = diagnose(&run, &Options::default())
        .expect("diagnose")
        .diagnosis;
    println!(
        "ROSS machine-d ({:.1} s):\n{}",
        started.elapsed().as_secs_f64(),
        d.to_text()
    );
    assert_eq!(d.effects_added, vec!["pedestal_sub_base".to_string()]);
    assert_eq!(d.steps[0].bearing, "B1");
    let params = &d.steps[0].parameters;
    assert!(
        !params.is_empty() && params.iter().all(|e| e.name.starts_with("sub_")),
        "{params:?}"
    );
    // The pedestals after the sub-base: within 2 % of the machine file's
    // (B1's own pedestal, not pedestal and sub-base lumped).
    assert_pedestals_near_truth(&run, &d.pedestals_after, 0.02, "machine-d");
}

#[test]
fn ross_machine_a_on_rigid_ground_names_nothing() {
    let run = ross_run("machine-a", 2, Some(3));
    let d = diagnose(&run, &Options::default())
        .expect("diagnose")
        .diagnosis;
    println!("ROSS machine-a:\n{}", d.to_text());
    assert!(d.effects_added.is_empty(), "{:?}", d.effects_added);
}
