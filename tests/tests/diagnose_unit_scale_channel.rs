//! One channel in the wrong unit (one probe in mil, the others in µm) is
//! named at its bearing and channel by the machine-level check
//! (`plinth::diagnose::machine::unit_scale::channel`, session 43,
//! docs/robustness-hostile.md, Session 43 (unitfa17)), and the scale search's own false-alarm rate
//! is measured where it is forced to run on every reading
//! (`forced_search_on_listed_runs`, ignored: a measuring tool).

use plinth::diagnose::diagnose;
use plinth::diagnose::machine::unit_scale::{examine, Reading};
use plinth::diagnose::machine::MachineCheck;
use plinth::rundir::RunDir;
use plinth_tests::unseen;
use std::path::Path;

/// unseen-five's stored clean run with noise columns (seed 1, `tests/data/ross-unseen-5/clean-n3c`)
/// with B2's `rel_y` alone × 25.4 (`python3 scripts/unit_scale_run.py
/// tests/data/ross-unseen-5/clean-n3c tests/data/ross-unseen-5/clean-n3c-b2-rel_y-x25.4
/// 25.4 rel_y B2`): one probe in mil, the others in µm. Main (795fd3c)
/// untrusts it and names no `unit_scale` (the effects it names at B2 are
/// wrong); now `unit_scale` is that channel at B2, × 25.4 within 5 %.
#[test]
fn one_probe_in_mil_is_named_at_its_bearing_and_channel() {
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-5");
    let run = unseen::stored(data, "clean-n3c-b2-rel_y-x25.4");
    let d = unseen::diagnosis_with_machine_check(data, "unseen-five.toml", &run);
    let v = serde_json::to_value(&d).expect("diagnosis as JSON");
    let u = v.get("unit_scale").expect("no unit_scale named");
    assert!(!d.trusted);
    assert_eq!(u["kind"], "rel", "{u}");
    assert_eq!(u["bearing"], "B2", "{u}");
    assert_eq!(u["channel"], "rel_y", "{u}");
    let s = u["factor"].as_f64().expect("factor");
    assert!((s / 25.4 - 1.0).abs() < 0.05, "factor {s}");
    assert!(
        d.trust_reasons
            .iter()
            .any(|r| r.contains("the `rel_y` transducer of B2") && r.contains("×25.4 (mil")),
        "{:?}",
        d.trust_reasons
    );
}

/// The false-alarm measurement (docs/robustness-hostile.md, Session 43 (unitfa17)): for each line
/// `RUN TOML` of the file `$UNIT_SCALE_FORCED`, the run is diagnosed and
/// every reading ([`Reading::all`]: every bearing's kinds, each bearing's,
/// each channel) is examined on its base model whether or not the check
/// would have asked (`examine` without stopping): one TSV line per
/// reading on stdout (`--nocapture`), and whether the check as run names a
/// scale; `$UNIT_SCALE_FORCED_CHANNELS` set: the channels' readings only. Run with `cargo test --release -p plinth-tests --test
/// diagnose_unit_scale_channel -- --ignored --nocapture`.
#[test]
#[ignore = "a measuring tool: needs $UNIT_SCALE_FORCED"]
fn forced_search_on_listed_runs() {
    let Ok(list) = std::env::var("UNIT_SCALE_FORCED") else {
        return;
    };
    let text = std::fs::read_to_string(&list).expect("the list of runs");
    // `UNIT_SCALE_FORCED_CHANNELS=1`: only the one-channel readings.
    let channels_only = std::env::var_os("UNIT_SCALE_FORCED_CHANNELS").is_some();
    println!("run\treading\tfactor\tgap\tfloor\tpasses\tas_read_gap\tas_read_fails\tlog_sd\tnamed\tchecked_names");
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        let mut it = line.split_whitespace();
        let (Some(run_dir), Some(toml)) = (it.next(), it.next()) else {
            continue;
        };
        let toml = Path::new(toml);
        let data = toml.parent().and_then(Path::to_str).expect("toml dir");
        let file = toml.file_name().and_then(|f| f.to_str()).expect("toml");
        let (machine, options) = unseen::machine_and_options(data, file);
        let Ok(run) = RunDir::read(run_dir) else {
            println!("{run_dir}\tunreadable");
            continue;
        };
        let Ok(out) = diagnose(&run, &options) else {
            println!("{run_dir}\tdiagnose failed");
            continue;
        };
        let checked = MachineCheck::of(&machine, &out)
            .ok()
            .and_then(|c| c.unit_scale)
            .map_or("-".to_string(), |u| {
                format!("{}@{:?}x{}", u.columns(), u.bearing, u.factor)
            });
        let Some(first) = out.states.first() else {
            continue;
        };
        let nb = out.prep.bearings.len();
        let readings: Vec<Reading> = if channels_only {
            (0..nb).flat_map(Reading::channels).collect()
        } else {
            Reading::all(nb)
        };
        for reading in readings {
            let what = format!(
                "{}{}{}",
                reading.kind.columns(),
                reading.dir.map_or("", |d| if d == 0 { "_y" } else { "_z" }),
                reading
                    .bearing
                    .map_or("@all".to_string(), |b| format!("@{}", out.prep.bearings[b]))
            );
            match examine(&machine, &out.prep, first, reading, false) {
                Some(e) => println!(
                    "{run_dir}\t{what}\t{:.6}\t{:.5}\t{:.5}\t{}\t{:.5}\t{}\t{:.5}\t{}\t{checked}",
                    e.factor,
                    e.gap,
                    e.floor,
                    e.passes,
                    e.as_read_gap,
                    e.as_read_fails,
                    e.log_sd,
                    e.named
                ),
                None => println!("{run_dir}\t{what}\tnone"),
            }
        }
    }
}
