//! `plinth diagnose DIR [--machine MACHINE.toml] [--base ...] [--json] [--plots DIR]`.

use super::plots::{write_machine_figure, write_pedestal_figures};
use super::refute::diagnose_checked;
use super::workflow::{diagnose, Options};
use crate::rundir::RunDir;
use crate::sim::machine::BearingModel;
use crate::sim::oil_film::OilFilmBearing;
use crate::sim::Machine;
use anyhow::{bail, Context, Result};
use plinth_shared::regression::Parameter;
use std::path::PathBuf;

/// Command-line arguments of `plinth diagnose`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Run directory (`measurements.csv`, `bearings.csv`).
    pub dir: PathBuf,
    /// Machine file: also re-simulate the whole machine with the identified
    /// pedestals and compare every channel (machine-level gap).
    #[arg(long)]
    pub machine: Option<PathBuf>,
    /// Parameters of the base pedestal model, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "k_y,k_z,m,c_y,c_z")]
    pub base: Vec<String>,
    /// Print the diagnosis as JSON (docs/formats.md) instead of the text report.
    #[arg(long)]
    pub json: bool,
    /// Write measured-vs-predicted figures (PNG and SVG) into this directory.
    #[arg(long)]
    pub plots: Option<PathBuf>,
    /// Write into an existing --plots/--out directory that already holds
    /// files (files Plinth did not write there are kept, never replaced).
    #[arg(long, requires = "plots")]
    pub force: bool,
    /// Family-wise significance level of each step (Bonferroni over candidates).
    #[arg(long, allow_negative_numbers = true, default_value_t = 1e-3, value_parser = crate::args::probability)]
    pub alpha: f64,
    /// Diagnose only the speeds from LO to HI Hz (ends included), e.g. 20:120.
    #[arg(long, allow_negative_numbers = true, value_name = "LO:HI", value_parser = crate::args::speed_band)]
    pub speeds: Option<crate::args::SpeedBand>,
}

/// Parses the `--base` list: known names (formats.md), no repeats, and
/// at least the two stiffnesses.
pub fn parse_base(names: &[String]) -> Result<Vec<Parameter>> {
    let mut out = Vec::new();
    for n in names {
        let p = Parameter::from_name(n.trim()).with_context(|| {
            format!("--base: unknown parameter {n:?} (known: k_y, k_z, m, c_y, c_z)")
        })?;
        if out.contains(&p) {
            bail!("--base: {n} given twice");
        }
        out.push(p);
    }
    if !(out.contains(&Parameter::Ky) && out.contains(&Parameter::Kz)) {
        bail!("--base must include k_y and k_z (the pedestal model needs its stiffnesses)");
    }
    Ok(out)
}

/// The oil-film bearings of `machine` by name (their geometry lets
/// `bearing_coefficients` correct a table written for another clearance).
pub fn oil_films(machine: &Machine) -> Vec<(String, OilFilmBearing)> {
    machine
        .bearings
        .iter()
        .filter_map(|b| match &b.model {
            BearingModel::OilFilm(f) => Some((b.name.clone(), *f)),
            BearingModel::Table(_) => None,
        })
        .collect()
}

/// Runs `plinth diagnose`.
pub fn run(args: &Args) -> Result<()> {
    if !(args.alpha > 0.0 && args.alpha < 1.0) {
        bail!(
            "--alpha must lie strictly between 0 and 1 (got {})",
            args.alpha
        );
    }
    let machine = args
        .machine
        .as_deref()
        .map(Machine::from_toml_path)
        .transpose()?;
    let options = Options {
        base: parse_base(&args.base)?,
        alpha: args.alpha,
        progress: true,
        oil_films: machine.as_ref().map(oil_films).unwrap_or_default(),
        ..Options::default()
    };
    let plots = (args.plots.as_deref())
        .map(|d| crate::output::OutputDir::create_as("--plots", d, args.force))
        .transpose()?;
    // Reader errors name their file, line and column already.
    crate::identify::cli::check_run_dir(&args.dir)?;
    // A measured base motion is validated, and named as not used here.
    if crate::base_csv::read(&args.dir)?.is_some() {
        eprintln!("warning: {}: measured base motion is not used by diagnose (it fits on rigid ground or fits a base model); `plinth identify` subtracts it", args.dir.join("base.csv").display());
    }
    // The whole command's line; the candidate rounds show theirs under it.
    let mut ticker = crate::progress::Ticker::activity("diagnose: fits, bootstrap, effects", true);
    let mut run = RunDir::read(&args.dir)?;
    if let Some(path) = &args.machine {
        crate::rundir::matches::check_machine(&run, &Machine::from_toml_path(path)?, path)?;
    }
    if let Some(band) = args.speeds {
        band.select(&mut run)
            .map_err(|e| anyhow::anyhow!("{}: {e}", args.dir.display()))?;
    }
    let checked = match (&args.machine, &machine) {
        // Every step's model re-simulated and the final gap judged; the
        // steps the check refutes dropped and searched again without
        // (`super::refute`).
        (Some(path), Some(machine)) => {
            let (outcome, check) =
                diagnose_checked(&run, &options, machine).with_context(|| {
                    format!("{} with --machine {}", args.dir.display(), path.display())
                })?;
            (outcome, Some(check))
        }
        _ => (
            diagnose(&run, &options).with_context(|| args.dir.display().to_string())?,
            None,
        ),
    };
    let mut outcome = checked.0;
    if let Some(check) = checked.1 {
        for w in &check.warnings {
            eprintln!("warning: {w}");
        }
        if let Some(dir) = plots.as_ref().map(|o| o.path()) {
            write_machine_figure(
                &outcome.prep,
                &check.before,
                dir,
                "machine_before",
                "base model",
            )?;
            if let Some(after) = check
                .after
                .as_ref()
                .filter(|_| !check.gaps_after.is_empty())
            {
                write_machine_figure(
                    &outcome.prep,
                    after,
                    dir,
                    "machine_after",
                    "with the effects added",
                )?;
            }
        }
        check.apply(&mut outcome.diagnosis);
    }
    if let Some(plots) = plots {
        write_pedestal_figures(&outcome, plots.path())?;
        plots.commit()?;
    }
    ticker.finish();
    // What the values are conditional on: the support as a whole
    // (`super::trust::apparent`), after the report in text, `conditional_on`
    // in JSON.
    let conditional = super::trust::apparent::of(&outcome.prep, &outcome.diagnosis);
    if args.json {
        let mut json = serde_json::to_value(&outcome.diagnosis)?;
        if let Some(map) = json.as_object_mut() {
            map.insert("conditional_on".into(), serde_json::to_value(&conditional)?);
        }
        println!("{}", serde_json::to_string_pretty(&json)?);
    } else {
        print!(
            "{}{}",
            outcome.diagnosis.to_text_with(&modal_views(&outcome)),
            conditional.to_text()
        );
    }
    Ok(())
}

/// The modal view (f_n, ζ with ± by the delta method through the
/// covariance whose ± the pedestals report, [`super::state::reported_inference`],
/// by the same rule, [`super::criterion::Inference::reported_std_err_of`]) of the
/// pedestals of the base model (first state) and of the final model (last
/// state; values only, ± unknown, when `foundation_coupling` refitted them).
/// Where the values are identify's (the base model's ML fit) the ± are
/// identify's modal ± (docs/diagnose-verdict.md, "Session 47 (apparent17)").
pub fn modal_views(outcome: &super::Outcome) -> super::report::ModalViews {
    let last = outcome
        .states
        .last()
        .filter(|_| outcome.foundation.is_none());
    let d = &outcome.diagnosis;
    super::report::ModalViews {
        before: modal_view(outcome, outcome.states.first(), &d.pedestals_before),
        after: modal_view(outcome, last, &d.pedestals_after),
    }
}

/// [`modal_views`] of one list of pedestals fitted as `state`.
fn modal_view(
    outcome: &super::Outcome,
    state: Option<&super::workflow::State>,
    list: &[super::report::Pedestal],
) -> std::collections::BTreeMap<String, crate::present::modal::PedestalModal> {
    use super::candidates::ParamRef;
    let infs =
        state.and_then(|s| Some((s, super::state::reported_inference(&outcome.prep, s).ok()?)));
    let mut out = std::collections::BTreeMap::new();
    for (b, p) in list.iter().enumerate() {
        let direction = |d: &str| {
            // (k, m, c) of the direction; one mass unless it is split.
            let m_d = format!("m_{d}");
            let m = if p.values.contains_key(&m_d) {
                m_d
            } else {
                "m".into()
            };
            let names = [format!("k_{d}"), m, format!("c_{d}")];
            let v = |i: usize| p.values.get(&names[i]).copied().unwrap_or(0.0);
            // Where each sits in its group's inference (absent: fixed at 0).
            let found = infs.as_ref().and_then(|(s, infs)| {
                infs.iter().find_map(|(_, inf, refs)| {
                    let at = |n: &String| {
                        refs.iter().position(|r| {
                            matches!(r, ParamRef::Term(k)
                                if s.model.terms[*k].bearings() == [Some(b), None]
                                    && s.model.terms[*k].name() == *n)
                        })
                    };
                    Some((inf, at(&names[0])?, names.each_ref().map(at)))
                })
            });
            // No ± of f_n or ζ where one of k, m, c has none (withheld:
            // `super::summaries::withhold_std_errs`).
            let known = names
                .iter()
                .all(|n| p.std_err.get(n).is_none_or(|s| s.is_finite()));
            crate::present::modal::direction_by_gradient(v(0), v(1), v(2), |g| {
                let Some((inf, _, at)) = found.filter(|_| known) else {
                    return f64::NAN;
                };
                let mut c = vec![0.0; inf.estimate.len()];
                for (gi, a) in g.iter().zip(at) {
                    if let Some(a) = a {
                        c[a] = *gi;
                    }
                }
                inf.reported_std_err_of(&c)
            })
        };
        if p.values.contains_key("k_y") && p.values.contains_key("k_z") {
            out.insert(
                p.bearing.clone(),
                crate::present::modal::PedestalModal {
                    y: direction("y"),
                    z: direction("z"),
                },
            );
        }
    }
    out
}
