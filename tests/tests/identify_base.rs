//! Identification with a base, on data made by the simulator's base element
//! (host/src/sim/base.rs, a machine file's `[[base]]`), not by the model
//! under test (host/src/estimate/base.rs).

use num_complex::Complex;
use plinth::estimate::base::{self, BaseGroup, BaseParams};
use plinth::estimate::noise::{BearingNoise, ColumnDigits, Quantisation};
use plinth::estimate::Observation;
use plinth::identify::{observations, Options};
use plinth::rundir::{Measurement, RunDir};
use plinth::sim::{unbalance_response, EffectSet, Machine};

fn machine(path: &str) -> Machine {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    Machine::from_toml_path(root.join(path)).expect("machine file")
}

fn obs_of(run: &RunDir, bearing: &str) -> Vec<Observation> {
    let rows: Vec<&Measurement> = run
        .measurements
        .iter()
        .filter(|m| m.bearing == bearing)
        .collect();
    let columns = ColumnDigits::of_run(&run.measurements);
    let noise = BearingNoise::estimate(&rows, &columns, Quantisation::Rounding);
    let sched = run.bearing_schedules();
    observations(&rows, &sched[bearing], &noise).unwrap()
}

#[test]
fn debug_truth_chi2() {
    let m = machine("examples/two-pedestals-on-skid.toml");
    let speeds: Vec<f64> = (5..=200).map(f64::from).collect();
    let resp = unbalance_response(&m, &speeds, &EffectSet::none()).unwrap();
    let run = resp.to_run_dir(None).unwrap();
    let dir = plinth_tests::write_run(&run, Some(4));
    let run = RunDir::read(dir.path()).unwrap();
    let obs: Vec<Vec<Observation>> = ["left", "right"].iter().map(|b| obs_of(&run, b)).collect();
    let t = run.truth.as_ref().unwrap();
    let theta: Vec<[f64; 5]> = t
        .pedestals
        .iter()
        .map(|p| [p.k_y, p.k_z, p.m, p.c_y, p.c_z])
        .collect();
    let b = &t.bases[0];
    let bp = BaseParams {
        k: [b.k_y, b.k_z],
        c: [b.c_y, b.c_z],
        m: [b.m_y, b.m_z],
    };
    let g = BaseGroup {
        bearings: vec![0, 1],
    };
    println!("truth chi2 {}", base::chi2(&obs, &g, &theta, &bp).unwrap());
    println!(
        "rigid chi2 {}",
        base::chi2(&obs, &g, &theta, &BaseParams::RIGID).unwrap()
    );
    let pred = base::predict(&obs, &g, &theta, &bp).unwrap();
    let mut worst: f64 = 0.0;
    for (s, (_, x)) in pred.iter().enumerate() {
        for i in 0..2 {
            for d in 0..2 {
                let meas = obs[i][s].ped[d];
                worst = worst.max((x[i][d] - meas).norm() / meas.norm());
            }
        }
    }
    println!("predict worst rel err {worst}");
    let start: Vec<[f64; 5]> = theta
        .iter()
        .map(|t| [t[0] * 0.3, t[1] * 1.05, t[2] * 0.95, t[3] * 3.0, t[4] * 2.0])
        .collect();
    let t0 = std::time::Instant::now();
    let fit = base::fit_on_unmeasured_base(&obs, &g, &start).unwrap();
    println!("{:?} {:?}", fit, t0.elapsed());
    let _ = Complex::new(0.0, 0.0);
    let _ = Options::default();
}
