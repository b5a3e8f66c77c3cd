//! A machine's simulated run-down written to disk and read back, and the
//! trust rules that fired when it is identified: the scaffolding of the
//! identify-side trust tests (identify_plausibility, identify_trust).

use crate::write_run;
use plinth::identify::{identify_run, Identification, Options, PedestalFit, WarningKind};
use plinth::rundir::RunDir;
use plinth::sim::{unbalance_response, EffectSet, Machine, Noise};
use std::path::Path;

/// The machine file at `file`, relative to the repository root.
pub fn machine(file: &str) -> Machine {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(file);
    let text = std::fs::read_to_string(&path).expect("machine file");
    Machine::from_toml_str(&text, file).expect("machine")
}

/// The machine's run-down 5..=200 Hz in 2.5 Hz steps, with `noise`
/// (fraction of each channel's RMS, seed), written with `digits` and read
/// back (so that the digits are what the numbers carry).
pub fn run(machine: &Machine, noise: Option<(f64, u64)>, digits: Option<u32>) -> RunDir {
    let speeds: Vec<f64> = (0..=78).map(|i| 5.0 + 2.5 * i as f64).collect();
    let response = unbalance_response(machine, &speeds, &EffectSet::none()).expect("simulation");
    let run = response
        .to_run_dir(noise.map(|(fraction, seed)| Noise { fraction, seed }))
        .expect("run directory");
    let dir = write_run(&run, digits);
    RunDir::read(dir.path()).expect("read back")
}

/// `identify` with its default options.
pub fn identify(run: &RunDir) -> Identification {
    identify_run(run, &Options::default()).expect("identify")
}

/// `identify` with its default options on the run directory at `dir`.
pub fn identify_dir(dir: &Path) -> Identification {
    identify(&RunDir::read(dir).expect("reading the run directory"))
}

/// The pedestal fit of `bearing` in `id`.
pub fn pedestal<'a>(id: &'a Identification, bearing: &str) -> &'a PedestalFit {
    id.pedestals
        .iter()
        .find(|p| p.bearing == bearing)
        .expect("pedestal")
}

/// The warnings of the kinds in `rules` that fired on `id`, as
/// "bearing: message".
pub fn flags(id: &Identification, rules: &[WarningKind]) -> Vec<String> {
    id.pedestals
        .iter()
        .flat_map(|p| {
            p.warnings
                .iter()
                .filter(|w| rules.contains(&w.kind))
                .map(move |w| format!("{}: {}", p.bearing, w.message))
        })
        .collect()
}
