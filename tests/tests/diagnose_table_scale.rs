//! `bearing_coefficients` for a table that is no oil film of known geometry
//! (issue 17 item 4): the paper's damped machine simulated by the
//! simulator's elements (`plinth::sim`, its oil-film bearings computed
//! there), written at 3 significant digits (truncated, as the paper did) and
//! read back; then the left bearing's table in `bearings.csv` is written
//! with its stiffness (all four K entries) 25 % high and its damping right,
//! as a vendor's table with a wrong stiffness would be. diagnose has no
//! machine file, so no geometry: the correction it may fit is the table's
//! stiffness relative to its damping (`k_scale` = K_true/K_written = 0.8).

use plinth::diagnose::{diagnose, Options};
use plinth::rundir::{DigitsMode, RunDir, WriteOptions};
use plinth::sim::{unbalance_response, EffectSet, Machine};
use plinth_tests::simulated::assert_pedestals_near_truth;

const PAPER: &str = include_str!("../../examples/feng-hahn-1997-damped.toml");

/// Written table stiffness / true stiffness at the left bearing.
const WRITTEN_STIFFNESS: f64 = 1.25;

/// One seed, 3 digits: named `bearing_coefficients` at `left` alone,
/// k_scale within 2 % and 4 of its ± of 0.8, the pedestals' k and m after
/// the correction within 2 % of the simulated ones. (The same case by hand
/// at 1 % noise, `plinth simulate examples/feng-hahn-1997-damped.toml
/// --noise 0.01 --seed 3 --speeds 5:100:1` and the left table's K × 1.25:
/// k_scale 0.8020 ± 0.0013, runner-up sensor_delay ΔBIC 344 against 12 713.)
#[test]
fn a_table_with_its_stiffness_off_is_named_as_bearing_coefficients() {
    let machine =
        Machine::from_toml_str(PAPER, "feng-hahn-1997-damped.toml").expect("paper machine");
    let speeds: Vec<f64> = (0..74).map(|i| 5.0 + 2.0 * i as f64).collect();
    let response = unbalance_response(&machine, &speeds, &EffectSet::none()).expect("simulation");
    let run = response.to_run_dir(None).expect("run dir");
    let dir = tempfile::tempdir().expect("tempdir");
    run.write_with(
        dir.path(),
        &WriteOptions {
            digits: Some(3),
            digits_mode: DigitsMode::Truncate,
        },
    )
    .expect("write");
    let mut run = RunDir::read(dir.path()).expect("read back");
    for row in run.bearings.iter_mut().filter(|r| r.bearing == "left") {
        for k in row.coefficients.k.iter_mut().flatten() {
            *k *= WRITTEN_STIFFNESS;
        }
    }
    let out = diagnose(&run, &Options::default()).expect("diagnose");
    let d = &out.diagnosis;
    let named: Vec<(&str, &str)> = d
        .steps
        .iter()
        .filter(|s| s.dropped.is_none())
        .map(|s| (s.effect.as_str(), s.bearing.as_str()))
        .collect();
    assert_eq!(named, [("bearing_coefficients", "left")], "{}", d.to_text());
    let k = d.steps[0]
        .parameters
        .iter()
        .find(|p| p.name == "k_scale")
        .expect("k_scale");
    let want = 1.0 / WRITTEN_STIFFNESS;
    assert!(
        (k.value / want - 1.0).abs() < 0.02 && (k.value - want).abs() < 4.0 * k.std_err,
        "k_scale {} ± {} vs {want}",
        k.value,
        k.std_err
    );
    assert_pedestals_near_truth(&run, &d.pedestals_after, 0.02, "left table K × 1.25");
}
