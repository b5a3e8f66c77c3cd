//! `plinth predict`: re-simulate a machine with identified pedestals and
//! measure how far the prediction is from a measured run.
//!
//! The difference of one channel (bearing × `rel_y`, `rel_z`, `ped_y`,
//! `ped_z`) at speed i is the complex phasor difference d_i = P_i − M_i
//! (predicted minus measured, [m]); |d_i| is the amplitude of the vibration
//! the model gets wrong (zero-to-peak). Per channel this module reports
//!
//! - `max_abs_m` = max_i |d_i| and `rms_abs_m` = sqrt(mean_i |d_i|²) [m],
//! - `max_rel` = max_i |d_i| / max_i |M_i| and
//!   `rms_rel` = rms_abs / sqrt(mean_i |M_i|²) [-],
//!
//! and the same over all channels and speeds together (`overall`, whose
//! `rms_rel` is sqrt(Σ|d|²/Σ|M|²)).

use super::inject::{EffectRequest, EffectSet};
use super::machine::Machine;
use super::response::unbalance_response;
use super::signals::ChannelQuantity;
use crate::estimate::Pedestal;
use crate::rundir::{Measurement, RunDir};
use anyhow::{anyhow, bail, Context};
use plinth_shared::regression::Parameter;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A pedestal as `plinth identify --json` gives it (formats.md): the keys
/// every conforming file has; the others are ignored. A `null` value (the
/// identification failed for it) reads as NaN.
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct IdentifiedPedestal {
    /// Bearing name.
    pub bearing: String,
    /// The identified parameters (k [N/m], m [kg], c [N·s/m]).
    #[serde(flatten)]
    pub pedestal: Pedestal,
    /// Their standard errors (same units; `null`: not estimable, +∞), when
    /// the file gives them.
    #[serde(
        default,
        deserialize_with = "crate::estimate::params::optional_std_err"
    )]
    pub std_err: Option<Pedestal>,
    /// `false` when the identification says its numbers must not be used
    /// as they are (formats.md `trusted`); absent in older files.
    #[serde(default)]
    pub trusted: Option<bool>,
}

#[derive(Deserialize)]
struct IdentifiedFile {
    pedestals: Vec<IdentifiedPedestal>,
}

impl IdentifiedPedestal {
    /// The pedestal parameters, refusing missing, non-finite or negative
    /// values (a negative identified mass, stiffness or damping is not a
    /// pedestal the simulator can be given).
    pub fn params(&self) -> anyhow::Result<Pedestal> {
        self.params_with_notes().map(|(p, _)| p)
    }

    /// [`IdentifiedPedestal::params`], and a note for every damping that
    /// was negative but consistent with zero and is taken as zero: within
    /// two standard errors of zero, or (without a standard error) smaller
    /// than 1e-6 of the critical damping 2·sqrt(k·m) [N·s/m].
    pub fn params_with_notes(&self) -> anyhow::Result<(Pedestal, Vec<String>)> {
        let mut notes = Vec::new();
        let known = |v: f64| (!v.is_nan()).then_some(v);
        let (k_y, k_z, m) = (
            known(self.pedestal.k_y),
            known(self.pedestal.k_z),
            known(self.pedestal.m),
        );
        let mut damping = |p: Parameter, k: Option<f64>| -> Option<f64> {
            let name = p.name();
            let x = known(self.pedestal.get(p))?;
            if !(x.is_finite() && x < 0.0) {
                return Some(x);
            }
            let se = self.std_err.map(|s| s.get(p)).filter(|s| s.is_finite());
            let critical = 2.0 * (k.unwrap_or(0.0).abs() * m.unwrap_or(0.0).abs()).sqrt();
            let zero = match se {
                Some(se) if se > 0.0 => x >= -2.0 * se,
                _ => -x <= 1e-6 * critical,
            };
            if !zero {
                return Some(x);
            }
            let within = match se {
                Some(se) => format!("± {se:.3e}, within two standard errors of zero"),
                None => format!("below 1e-6 of the critical damping {critical:.3e} N·s/m"),
            };
            notes.push(format!(
                "pedestal {:?}: identified {name} = {x:.3e} N·s/m ({within}) is consistent with zero: re-predicted with {name} = 0",
                self.bearing
            ));
            Some(0.0)
        };
        let c_y = damping(Parameter::Cy, k_y);
        let c_z = damping(Parameter::Cz, k_z);
        let get = |name: &str, v: Option<f64>| -> anyhow::Result<f64> {
            match v {
                Some(x) if x.is_finite() && x >= 0.0 => Ok(x),
                Some(x) => bail!(
                    "pedestal {:?}: identified {name} = {x} is not a physical value (must be finite and >= 0)",
                    self.bearing
                ),
                None => bail!(
                    "pedestal {:?}: {name} is null (the identification failed for it)",
                    self.bearing
                ),
            }
        };
        let p = Pedestal {
            k_y: get("k_y", k_y)?,
            k_z: get("k_z", k_z)?,
            m: get("m", m)?,
            c_y: get("c_y", c_y)?,
            c_z: get("c_z", c_z)?,
        };
        if p.m <= 0.0 {
            bail!(
                "pedestal {:?}: identified m = {} must be > 0",
                self.bearing,
                p.m
            );
        }
        Ok((p, notes))
    }
}

/// Reads the pedestals of an identification JSON file (formats.md).
pub fn read_identified(path: &Path) -> anyhow::Result<Vec<IdentifiedPedestal>> {
    let text = crate::input_file::read_to_string(path)
        .with_context(|| format!("reading {}", path.display()))?;
    let file: IdentifiedFile = serde_json::from_str(&text).map_err(|e| {
        anyhow!(
            "{}:{}:{}: not an identification file (docs/formats.md): {e}",
            path.display(),
            e.line(),
            e.column()
        )
    })?;
    if file.pedestals.is_empty() {
        bail!("{}: no pedestals", path.display());
    }
    // One bearing has one pedestal: a file listing one twice (two
    // identifications pasted together) would be applied last-one-wins.
    let mut seen = std::collections::HashSet::new();
    for p in &file.pedestals {
        if !seen.insert(p.bearing.as_str()) {
            let (line, column) =
                crate::input_file::json_value_place(path, "bearing", &p.bearing, 2);
            bail!(
                "{}:{line}:{column}: pedestal {:?} is listed twice: one bearing has one pedestal (two identifications in one file?)",
                path.display(),
                p.bearing
            );
        }
    }
    Ok(file.pedestals)
}

/// Replaces the machine's pedestals with the identified ones (by bearing).
/// A pedestal the identification marks untrusted is used with a warning; a
/// machine bearing the identification does not list keeps the machine
/// file's pedestal, said in a note.
pub fn apply_identified(
    machine: &mut Machine,
    pedestals: &[IdentifiedPedestal],
) -> anyhow::Result<()> {
    for name in machine.bearing_names() {
        let kept = machine
            .bearings
            .iter()
            .any(|b| b.name == name && b.pedestal.is_some());
        if kept && !pedestals.iter().any(|p| p.bearing == name) {
            eprintln!(
                "note: bearing {name:?} has no identified pedestal: re-predicted with the machine file's"
            );
        }
    }
    for p in pedestals {
        let (params, notes) = p.params_with_notes()?;
        for n in notes {
            eprintln!("note: {n}");
        }
        if p.trusted == Some(false) {
            eprintln!(
                "warning: pedestal {:?} is UNTRUSTED in the identification (its `warnings` say why): the prediction uses numbers that must not be used as they are",
                p.bearing
            );
        }
        machine
            .set_pedestal(&p.bearing, Some(params))
            .with_context(|| format!("applying the identified pedestal {:?}", p.bearing))?;
    }
    Ok(())
}

/// The difference of one channel (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ChannelDifference {
    /// Bearing name, or `all` for the overall figure.
    pub bearing: String,
    /// `rel_y`, `rel_z`, `ped_y`, `ped_z`, or `all`.
    pub channel: String,
    /// Speeds compared.
    pub speeds: usize,
    /// Largest |P − M| [m].
    pub max_abs_m: f64,
    /// RMS of |P − M| over speed [m].
    pub rms_abs_m: f64,
    /// Largest |P − M| over the largest |M| [-].
    pub max_rel: f64,
    /// RMS |P − M| over RMS |M| [-].
    pub rms_rel: f64,
}

/// Prediction versus measurement, per channel and overall.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Comparison {
    /// One entry per (bearing, channel) present in both.
    pub channels: Vec<ChannelDifference>,
    /// Over all channels and speeds.
    pub overall: ChannelDifference,
}

#[derive(Default)]
struct Acc {
    n: usize,
    max_d: f64,
    max_m: f64,
    sum_d2: f64,
    sum_m2: f64,
}

impl Acc {
    fn add(&mut self, d: f64, m: f64) {
        self.n += 1;
        self.max_d = self.max_d.max(d);
        self.max_m = self.max_m.max(m);
        self.sum_d2 += d * d;
        self.sum_m2 += m * m;
    }

    fn finish(&self, bearing: &str, channel: &str) -> ChannelDifference {
        let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { f64::INFINITY };
        let n = self.n.max(1) as f64;
        ChannelDifference {
            bearing: bearing.into(),
            channel: channel.into(),
            speeds: self.n,
            max_abs_m: self.max_d,
            rms_abs_m: (self.sum_d2 / n).sqrt(),
            max_rel: ratio(self.max_d, self.max_m),
            rms_rel: ratio(self.sum_d2.sqrt(), self.sum_m2.sqrt()),
        }
    }
}

/// Compares predicted with measured rows matched by (bearing, speed); a
/// measured row without a prediction is an error.
pub fn compare(predicted: &[Measurement], measured: &[Measurement]) -> anyhow::Result<Comparison> {
    let key = |m: &Measurement| (m.bearing.clone(), m.speed_hz.to_bits());
    let pred: BTreeMap<(String, u64), &Measurement> =
        predicted.iter().map(|m| (key(m), m)).collect();
    let mut accs: BTreeMap<(String, ChannelQuantity), Acc> = BTreeMap::new();
    let mut all = Acc::default();
    for m in measured {
        let p = pred.get(&key(m)).ok_or_else(|| {
            anyhow!(
                "no prediction for bearing {:?} at {} Hz",
                m.bearing,
                m.speed_hz
            )
        })?;
        for q in ChannelQuantity::ALL {
            let (mv, pv) = (q.of(m), q.of(p));
            if !(mv.re.is_finite() && mv.im.is_finite()) {
                continue;
            }
            let d = (pv - mv).norm();
            accs.entry((m.bearing.clone(), q))
                .or_default()
                .add(d, mv.norm());
            all.add(d, mv.norm());
        }
    }
    if all.n == 0 {
        bail!("nothing to compare: the run has no finite measurements");
    }
    Ok(Comparison {
        channels: accs
            .iter()
            .map(|((b, q), a)| a.finish(b, q.name()))
            .collect(),
        overall: all.finish("all", "all"),
    })
}

/// The distinct speeds of `run` [Hz], ascending: what [`predict_run`]
/// simulates.
fn run_speeds(run: &RunDir) -> Vec<f64> {
    let mut speeds: Vec<f64> = run.measurements.iter().map(|m| m.speed_hz).collect();
    speeds.sort_by(f64::total_cmp);
    speeds.dedup();
    speeds
}

/// Simulates `machine` (pedestals already set) at the speeds of `run` and
/// returns the predicted rows (sensor effects of `effects` applied, no noise).
pub fn predict_run(
    machine: &Machine,
    effects: &EffectSet,
    run: &RunDir,
) -> anyhow::Result<Vec<Measurement>> {
    let speeds = run_speeds(run);
    if speeds.is_empty() {
        bail!("the run has no measurements");
    }
    let names = machine.bearing_names();
    for m in &run.measurements {
        if !names.contains(&m.bearing) {
            bail!(
                "the run measures bearing {:?}, the machine has {}",
                m.bearing,
                names.join(", ")
            );
        }
    }
    let response = unbalance_response(machine, &speeds, effects)?;
    Ok(response.measurements())
}

/// The comparison as an aligned text table (µm and %).
pub fn table(c: &Comparison) -> String {
    let mut s = String::from(
        "bearing  channel  speeds  max|dX| [um]  rms|dX| [um]  max rel [%]  rms rel [%]\n",
    );
    for d in c.channels.iter().chain(std::iter::once(&c.overall)) {
        s += &format!(
            "{:<8} {:<8} {:>6}  {:>12.4}  {:>12.4}  {:>11.3}  {:>11.3}\n",
            d.bearing,
            d.channel,
            d.speeds,
            d.max_abs_m * 1e6,
            d.rms_abs_m * 1e6,
            d.max_rel * 100.0,
            d.rms_rel * 100.0
        );
    }
    s
}

/// Command-line arguments of `plinth predict`.
#[derive(clap::Args, Debug)]
pub struct PredictArgs {
    /// Machine file (TOML); its pedestals are replaced by the identified ones.
    pub machine: PathBuf,
    /// Identification JSON (`plinth identify DIR --json` output).
    #[arg(long)]
    pub pedestals: PathBuf,
    /// Measured run directory to compare with.
    #[arg(long)]
    pub against: PathBuf,
    /// Effect to include in the prediction: NAME[:BEARING][=SIZE] (repeatable).
    #[arg(long = "effect")]
    pub effects: Vec<String>,
    /// Print the comparison as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `plinth predict`.
pub fn predict(args: &PredictArgs) -> anyhow::Result<()> {
    let mut machine = Machine::from_toml_path(&args.machine)?;
    let identified = read_identified(&args.pedestals)?;
    apply_identified(&mut machine, &identified)
        .with_context(|| format!("{}", args.pedestals.display()))?;
    let mut effects = EffectSet::none();
    for e in &args.effects {
        let req: EffectRequest = e.parse().map_err(anyhow::Error::msg)?;
        effects.requests.push(req);
    }
    let run = RunDir::read(&args.against)?;
    // The run's speeds are re-simulated: the same limits as `--speeds`.
    let speeds = run_speeds(&run).len();
    let request = format!("--against {} ({speeds} speeds)", args.against.display());
    crate::sim::budget::SPEEDS
        .check(&request, speeds as u64)
        .and_then(|()| crate::sim::budget::check_solves(&request, &machine, speeds))
        .map_err(anyhow::Error::msg)?;
    let predicted = predict_run(&machine, &effects, &run)
        .with_context(|| format!("predicting {}", args.against.display()))?;
    let comparison = compare(&predicted, &run.measurements)
        .with_context(|| format!("comparing with {}", args.against.display()))?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&comparison)?);
    } else {
        println!(
            "{} with identified pedestals vs {} (|dX| = |predicted - measured| phasor, 0-pk):",
            machine.name,
            args.against.display()
        );
        print!("{}", table(&comparison));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_complex::Complex;

    fn row(speed: f64, v: f64) -> Measurement {
        let c = Complex::new(v, 0.0);
        Measurement {
            speed_hz: speed,
            bearing: "left".into(),
            rel: [c, c],
            ped: [c, c],
            noise_sd: None,
            written: None,
        }
    }

    #[test]
    fn differences_are_absolute_and_relative() {
        let measured = vec![row(10.0, 1e-5), row(20.0, 2e-5)];
        let predicted = vec![row(10.0, 1.1e-5), row(20.0, 2e-5)];
        let c = compare(&predicted, &measured).unwrap();
        assert_eq!(c.channels.len(), 4);
        let d = &c.channels[0];
        assert!((d.max_abs_m - 1e-6).abs() < 1e-15);
        assert!((d.rms_abs_m - 1e-6 / 2f64.sqrt()).abs() < 1e-15);
        assert!((d.max_rel - 0.05).abs() < 1e-12);
        assert!((d.rms_rel - 1e-6 / (5e-10f64).sqrt()).abs() < 1e-12);
        assert!((c.overall.rms_rel - d.rms_rel).abs() < 1e-12);
        assert!(compare(&predicted[..1], &measured).is_err());
    }

    #[test]
    fn negative_identified_values_are_refused() {
        let p = IdentifiedPedestal {
            bearing: "left".into(),
            pedestal: Pedestal::from_theta([1e7, 1e7, 100.0, -1.0, 0.0]),
            std_err: None,
            trusted: None,
        };
        assert!(p.params().unwrap_err().to_string().contains("c_y"));
        // Within two standard errors of zero: zero, and said so.
        let mut p = p;
        let unknown = Pedestal::from_theta([f64::INFINITY; 5]);
        p.std_err = Some(Pedestal {
            c_y: 0.6,
            ..unknown
        });
        let (params, notes) = p.params_with_notes().unwrap();
        assert_eq!(params.c_y, 0.0);
        assert!(notes[0].contains("consistent with zero"), "{notes:?}");
        p.std_err = Some(Pedestal {
            c_y: 0.4,
            ..unknown
        });
        assert!(p.params().is_err());
        // Round-off on noise-free data, without a standard error.
        p.std_err = None;
        p.pedestal.c_y = -2.6e-13;
        assert_eq!(p.params().unwrap().c_y, 0.0);
        // Negative stiffness is never zeroed.
        p.pedestal.k_y = -1.0;
        assert!(p.params().is_err());
    }
}
