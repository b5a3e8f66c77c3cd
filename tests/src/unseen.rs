//! The machines nobody tuned to (run directories made by ROSS 2.3.0 with
//! scripts/ross_unseen.py, seed 1 of each case kept under tests/data/) and
//! what their tests read off `identify` and `diagnose`: one definition for
//! every such machine.

use plinth::diagnose::diagnose;
use plinth::diagnose::machine::MachineCheck;
use plinth::diagnose::report::Diagnosis;
use plinth::diagnose::{cli::oil_films, Options};
use plinth::estimate::Pedestal;
use plinth::identify::Identification;
use plinth::rundir::RunDir;
use plinth::sim::Machine;
use std::path::Path;

/// The stored run directory of `case` under `data`.
pub fn stored(data: &str, case: &str) -> RunDir {
    RunDir::read(Path::new(data).join(case)).expect("stored run directory")
}

/// The machine file `file` under `data` and the diagnose options
/// `plinth diagnose --machine` gives its search (the file's oil-film
/// geometry).
pub fn machine_and_options(data: &str, file: &str) -> (Machine, Options) {
    let machine = Machine::from_toml_path(Path::new(data).join(file)).expect("machine file");
    let options = Options {
        oil_films: oil_films(&machine),
        ..Options::default()
    };
    (machine, options)
}

/// `plinth diagnose RUN --machine FILE` as the command line runs it (FILE
/// under `data`): the search with the file's oil-film geometry, then the
/// machine-level check applied to the verdict.
pub fn diagnosis_with_machine_check(data: &str, file: &str, run: &RunDir) -> Diagnosis {
    let (machine, options) = machine_and_options(data, file);
    let out = diagnose(run, &options).expect("diagnose");
    let check = MachineCheck::of(&machine, &out).expect("machine check");
    let mut d = out.diagnosis;
    check.apply(&mut d);
    d
}

/// A clean stored run `case` of the machine in `data` (machine file
/// `file`): [`assert_flagged_by_nothing`], every value identify prints `ok`
/// (the dampings too) within 3 of its ±, and diagnose's trusted pedestals
/// within 3 ± ([`assert_trusted_means_right`]).
pub fn assert_clean_run_right(data: &str, file: &str, case: &str) {
    let run = stored(data, case);
    let id = crate::rundown::identify(&run);
    let d = diagnosis_with_machine_check(data, file, &run);
    assert_flagged_by_nothing(&run, &id, &d, case);
    let wrong = ok_but_wrong(&run, &id, true);
    assert!(wrong.is_empty(), "{case}, dampings too: {wrong:?}");
    assert_trusted_means_right(&run, &d);
}

/// A stored run `case` with one library `effect` at `bearing`: identify
/// untrusts that bearing and only it, the other bearings' `ok` values (the
/// dampings too) within 3 ±; diagnose names exactly `effect` at `bearing`,
/// trusts its verdict, and its final pedestals are within 3 ± of the truth.
pub fn assert_one_effect_named_right(
    data: &str,
    file: &str,
    case: &str,
    effect: &str,
    bearing: &str,
) {
    let run = stored(data, case);
    let id = crate::rundown::identify(&run);
    assert_eq!(untrusted(&id), [bearing], "{case}");
    let wrong = ok_but_wrong(&run, &id, true);
    assert!(wrong.is_empty(), "{case}, the other bearings: {wrong:?}");
    let d = diagnosis_with_machine_check(data, file, &run);
    assert_eq!(
        named(&d),
        [(effect.to_string(), bearing.to_string())],
        "{case}: {}",
        d.to_text()
    );
    assert!(d.trusted, "{case}: {:?}\n{}", d.trust_reasons, d.to_text());
    assert_trusted_means_right(&run, &d);
}

/// The speeds identify listed as outliers at `bearing` [Hz], sorted.
pub fn listed(id: &Identification, bearing: &str) -> Vec<f64> {
    let mut v = id.noise[bearing].outlier_speeds_hz.clone();
    v.sort_by(f64::total_cmp);
    v
}

/// A clean run's promise: identify untrusts nothing, lists no speed at any
/// bearing, and every `ok` value is right within 3 of its ±; diagnose (`d`)
/// names nothing and is trusted.
pub fn assert_flagged_by_nothing(run: &RunDir, id: &Identification, d: &Diagnosis, case: &str) {
    assert!(untrusted(id).is_empty(), "{case}: {:?}", untrusted(id));
    for bearing in id.noise.keys() {
        assert!(
            listed(id, bearing).is_empty(),
            "{case}: {bearing} lists {:?}",
            listed(id, bearing)
        );
    }
    assert_ok_means_right(run, id, case);
    assert!(named(d).is_empty(), "{case}: {}", d.to_text());
    assert!(d.trusted, "{case}: {:?}\n{}", d.trust_reasons, d.to_text());
}

/// The convention mistakes identify suspected, as "bearing: mistake".
pub fn suspected(id: &Identification) -> Vec<String> {
    id.pedestals
        .iter()
        .filter_map(|p| {
            p.suspected_convention_error
                .map(|c| format!("{}: {}", p.bearing, c.name()))
        })
        .collect()
}

/// The effects diagnose kept, as (effect, bearing), sorted.
pub fn named(d: &Diagnosis) -> Vec<(String, String)> {
    let mut v: Vec<(String, String)> = d
        .steps
        .iter()
        .filter(|s| s.dropped.is_none())
        .map(|s| (s.effect.clone(), s.bearing.clone()))
        .collect();
    v.sort();
    v
}

/// The bearings identify did not trust.
pub fn untrusted(id: &Identification) -> Vec<String> {
    id.pedestals
        .iter()
        .filter(|p| !p.trusted)
        .map(|p| p.bearing.clone())
        .collect()
}

/// The pedestal `bearing` of `run`'s truth.json (k [N/m], m [kg], c [N·s/m]).
pub fn truth_of<'a>(run: &'a RunDir, bearing: &str) -> &'a Pedestal {
    &run.truth
        .as_ref()
        .expect("truth")
        .pedestals
        .iter()
        .find(|t| t.bearing == bearing)
        .expect("truth of the bearing")
        .pedestal
}

/// Every value of every pedestal identify printed as `ok`, against the
/// truth: ("bearing parameter", estimate, ±, truth) for k_y, k_z and m, and
/// c_y, c_z with `damping` (SI units).
pub fn printed_ok(
    run: &RunDir,
    id: &Identification,
    damping: bool,
) -> Vec<(String, f64, f64, f64)> {
    let mut out = Vec::new();
    for p in id.pedestals.iter().filter(|p| p.trusted) {
        let t = truth_of(run, &p.bearing);
        let (f, e) = (&p.pedestal, &p.std_err);
        let mut values = vec![
            ("k_y", f.k_y, e.k_y, t.k_y),
            ("k_z", f.k_z, e.k_z, t.k_z),
            ("m", f.m, e.m, t.m),
        ];
        if damping {
            values.extend([("c_y", f.c_y, e.c_y, t.c_y), ("c_z", f.c_z, e.c_z, t.c_z)]);
        }
        out.extend(
            values
                .into_iter()
                .map(|(name, got, se, want)| (format!("{} {name}", p.bearing), got, se, want)),
        );
    }
    out
}

/// The values identify printed as `ok` that lie more than 3 of their ±
/// from the truth ([`printed_ok`]), as messages.
pub fn ok_but_wrong(run: &RunDir, id: &Identification, damping: bool) -> Vec<String> {
    printed_ok(run, id, damping)
        .into_iter()
        .filter(|(_, got, se, want)| (got - want).abs() > 3.0 * se)
        .map(|(name, got, se, want)| {
            format!("{name} = {got:.6e} ± {se:.2e} printed ok, truth {want:.6e}")
        })
        .collect()
}

/// Where diagnose trusts its verdict, every pedestal after its steps lies
/// within 3 of its ± of the truth in k_y, k_z and m (the method's promise;
/// nothing is asserted of an untrusted verdict).
pub fn assert_trusted_means_right(run: &RunDir, d: &Diagnosis) {
    trusted_within_three(run, d, "", false);
}

/// [`assert_trusted_means_right`] with the dampings c_y, c_z too, where the
/// verdict gives them a ± (`case` names the run in the message).
pub fn assert_trusted_dampings_right_too(run: &RunDir, d: &Diagnosis, case: &str) {
    trusted_within_three(run, d, case, true);
}

/// The check of [`assert_trusted_means_right`]: k_y, k_z, m always, and
/// c_y, c_z with `dampings` where they have a ±.
fn trusted_within_three(run: &RunDir, d: &Diagnosis, case: &str, dampings: bool) {
    if !d.trusted {
        return;
    }
    for after in &d.pedestals_after {
        let truth = truth_of(run, &after.bearing);
        let mut keys = vec![("k_y", truth.k_y), ("k_z", truth.k_z), ("m", truth.m)];
        if dampings {
            keys.extend([("c_y", truth.c_y), ("c_z", truth.c_z)]);
        }
        for (key, t) in keys {
            let (v, se) = if key.starts_with('c') {
                match (after.values.get(key), after.std_err.get(key)) {
                    (Some(v), Some(se)) => (*v, *se),
                    _ => continue,
                }
            } else {
                (after.values[key], after.std_err[key])
            };
            assert!(
                ((v - t) / se).abs() < 3.0,
                "{case} {} {key}: {v:.6e} ± {se:.2e}, truth {t:.6e} ({:.1} ±), trusted\n{}",
                after.bearing,
                (v - t) / se,
                d.to_text()
            );
        }
    }
}

/// Every pedestal identify printed as `ok` lies within 3 of its ± of the
/// truth in k_y, k_z and m (the method's promise).
pub fn assert_ok_means_right(run: &RunDir, id: &Identification, label: &str) {
    let wrong = ok_but_wrong(run, id, false);
    assert!(wrong.is_empty(), "{label}: {wrong:?}");
}

/// The delay τ [s] step `step` of `d` reports, with its standard error.
pub fn delay_of(d: &Diagnosis, step: usize) -> &plinth::diagnose::report::Estimate {
    d.steps[step]
        .parameters
        .iter()
        .find(|p| p.name == "tau")
        .expect("tau")
}

/// Asserts that step `step` of `d` gives the true `sensor_delay` of `run`
/// (truth.json's `tau_s` [s]) within 3 of its standard errors.
pub fn assert_delay_in_its_error(run: &RunDir, d: &Diagnosis, step: usize) {
    let truth = run
        .truth
        .as_ref()
        .expect("truth")
        .effect_details
        .iter()
        .find(|e| e.name == "sensor_delay")
        .and_then(|e| e.parameters.get("tau_s").copied())
        .expect("true delay");
    let tau = delay_of(d, step);
    assert!(
        (tau.value - truth).abs() < 3.0 * tau.std_err,
        "tau {:.3e} ± {:.1e} s, true {truth:.3e} s",
        tau.value,
        tau.std_err
    );
}
