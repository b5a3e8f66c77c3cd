//! `plinth identify`: batch identification of every pedestal in a run directory.

use super::{
    identify_prepared, mode_label, EquationMode, Estimator, Identification, Model, Options,
    Parameter, PedestalFit, WarningKind, DEFAULT_MAX_CONDITION_NUMBER,
};
use crate::estimate::noise::Quantisation;
use crate::present::table::{self, sig, PedestalRow, SubRow};
use crate::rundir::{bearings_without_truth, RunDir, Truth};
use anyhow::Context;
use std::path::PathBuf;

/// How eq. 4 is used (the paper's Table 2 variants).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Equations {
    /// R&I: the four real equations of every speed used independently (right with damping).
    RAndI,
    /// R+I: the real-part and imaginary-part equations added together.
    RPlusI,
    /// R: only the real-part equations.
    Real,
    /// I: only the imaginary-part equations.
    Imag,
}

impl From<Equations> for EquationMode {
    fn from(e: Equations) -> Self {
        match e {
            Equations::RAndI => EquationMode::RealAndImag,
            Equations::RPlusI => EquationMode::RealPlusImag,
            Equations::Real => EquationMode::Real,
            Equations::Imag => EquationMode::Imag,
        }
    }
}

/// Command-line arguments of `plinth identify`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Reads DIR/measurements.csv and DIR/bearings.csv (and DIR/truth.json when present, to show \
the errors), computes each bearing's force on its pedestal from the known bearing \
coefficients, and fits k_y, k_z [N/m], m [kg], c_y, c_z [N·s/m] of every pedestal on Feng & \
Hahn's eq. 4. Prints value ± standard error per parameter, the residual RMS [N] and the \
condition number; warnings go to stderr (and into the JSON), and a pedestal whose fit cannot \
be trusted is marked UNTRUSTED, with the reasons under the table.

Default estimator (--estimator ml): maximum likelihood with noise in both the rotor-relative \
and the pedestal phasors (errors in variables), the noise of every number from the *_sd \
columns, else from the digits the numbers carry, else from the scatter between neighbouring \
speeds (its level then set by the fit's χ²); standard errors from the Fisher information (the \
Cramér–Rao bound at the estimate). --estimator ols is the paper's least squares.

A passive pedestal has no negative mass or stiffness and no damping below zero by more than \
2 standard errors; a fit that breaks this is UNTRUSTED. Every pedestal is also refitted with \
each usual convention mistake undone (conjugated, swapped_yz, rel_negated, \
bearing_transposed, cross_coupling_sign, speed_in_rpm), and the one under which the data fit \
a passive pedestal to the noise floor, decisively better than every other reading, is named \
(`suspected_convention_error` in the JSON). Exit code 2 when any pedestal is physically \
impossible or has a suspected convention error (everything is printed first); 1 on errors.

Pedestals on a base (README, \"Bases\"): with DIR/base.csv (the base's measured 1X motion, \
optional y_sd,z_sd noise columns) the pedestals on a listed base are fitted relative to its \
motion (\"base_measured\": true in the JSON); --unmeasured-base left,right fits the named \
pedestals together with an unmeasured base and reports its stiffness, damping and mass to \
ground where its mode lies inside the speed range, only its quasi-static compliance 1/K_B \
when the mode lies above, only its mass when below, or that no base motion is detectable.

Default model: all five parameters for --equations r-and-i; k_y,k_z,m for real, imag and \
r-plus-i, which the paper used on undamped pedestals only (with damping they are biased: use \
r-and-i).")]
pub struct Args {
    /// Run directory (measurements.csv, bearings.csv, optional truth.json).
    pub dir: PathBuf,
    /// Print the identification as JSON (docs/formats.md) instead of a table.
    #[arg(long)]
    pub json: bool,
    /// How the real and imaginary parts of eq. 4 are used.
    #[arg(long, allow_negative_numbers = true, value_enum, default_value_t = Equations::RAndI)]
    pub equations: Equations,
    /// Parameters to estimate, comma-separated from k_y,k_z,m,c_y,c_z; the
    /// others are fixed at 0 [default: see below].
    #[arg(long, value_name = "LIST")]
    pub model: Option<Model>,
    /// Condition number of the column-scaled regression above which a fit is
    /// not trusted.
    #[arg(long, allow_negative_numbers = true, default_value_t = DEFAULT_MAX_CONDITION_NUMBER, value_parser = crate::args::positive)]
    pub max_condition: f64,
    /// Estimator: ml (maximum likelihood, errors in variables; R&I only) or
    /// ols (the paper's least squares; always used with the other --equations).
    #[arg(long, allow_negative_numbers = true, value_enum, default_value_t = Estimator::Ml)]
    pub estimator: Estimator,
    /// With ml: also show the paper's OLS and its efficiency (bound variance /
    /// OLS variance under the noise model) per parameter.
    #[arg(long)]
    pub compare_ols: bool,
    /// The numbers were truncated to their digits, not rounded (noise model:
    /// mean square ulp²/3 instead of ulp²/12).
    #[arg(long)]
    pub truncated: bool,
    /// Subtract each bearing's mean `rel` vector between LO and HI Hz (the
    /// slow-roll vector: probe runout) from every `rel` phasor before fitting.
    #[arg(long, value_name = "LO:HI")]
    pub slow_roll: Option<crate::field::slow_roll::SlowRollBand>,
    /// Pedestals that stand on a base whose motion was not measured, fitted
    /// together with the base's stiffness, damping and mass to ground
    /// (bearing names separated by `,`, one group per base, groups separated
    /// by `;`, e.g. `left,right;b3,b4`). A base.csv in DIR is used without
    /// this flag (identification relative to the measured base).
    #[arg(long, value_name = "B1,B2[;B3,B4]")]
    pub unmeasured_base: Option<super::on_base::BaseGroups>,
    /// Also draw each pedestal's measured dynamic stiffness F/X against the
    /// fitted model, with its ±1σ band and the residual, into DIR
    /// (`stiffness_<bearing>.png/.svg`; docs/figures.md).
    #[arg(long, value_name = "DIR")]
    pub plots: Option<PathBuf>,
    /// Speed unit of the figures.
    #[command(flatten)]
    pub figure_style: crate::plots::StyleArgs,
    /// Fit only the speeds from LO to HI Hz (ends included), e.g. 20:120.
    #[arg(long, allow_negative_numbers = true, value_name = "LO:HI", value_parser = crate::args::speed_band)]
    pub speeds: Option<crate::args::SpeedBand>,
    /// Relative standard uncertainty of each bearing table's common scale
    /// [%], carried into every ± (σ² = (1 + s²)·σ_noise² + (s·θ)²; the
    /// noise-only ± stays in the JSON as `std_err_noise`). Without it the ±
    /// is conditional on the table being exact.
    #[arg(long, value_name = "PCT", value_parser = super::conditional::parse_table_uncertainty)]
    pub table_uncertainty: Option<f64>,
    /// Standard uncertainty of the speed column [Hz]: how far the speed
    /// stamped on each vector may lie from the speed of the revolutions
    /// it is made of (a speed filter's lag times the run-down rate), one
    /// offset for the whole run, carried into every ± of the pedestals on
    /// rigid ground (σ² = σ_noise² + (b·σ_f)², b a value's shift per Hz;
    /// the noise-only ± stays in the JSON as `std_err_noise`). Without it
    /// the ± is conditional on the speed column being right.
    #[arg(long, value_name = "HZ", value_parser = crate::args::positive)]
    pub speed_uncertainty: Option<f64>,
    /// Relative standard uncertainty of each channel's sensitivity [%],
    /// independent between channels: one PCT for every channel or
    /// `rel=PCT,ped=PCT`; carried into every ± through each value's
    /// sensitivity to each channel (σ² = σ_noise² + Σ_c (σ_c·b_c)²; the
    /// noise-only ± stays in the JSON as `std_err_noise`). Without it the ±
    /// is conditional on every sensitivity being exact.
    #[arg(long, value_name = "PCT", value_parser = super::conditional::sensor::parse_sensor_uncertainty)]
    pub sensor_uncertainty: Option<super::conditional::sensor::SensorUncertainty>,
}

impl Args {
    /// The identification options these arguments ask for.
    pub fn options(&self) -> Options {
        Options {
            mode: self.equations.into(),
            model: self.model,
            max_condition_number: self.max_condition,
            estimator: self.estimator,
            quantisation: if self.truncated {
                Quantisation::Truncation
            } else {
                Quantisation::Rounding
            },
            compare_ols: self.compare_ols,
            ..Options::default()
        }
    }
}

/// Runs `plinth identify`: the table (or JSON) on stdout, warnings on stderr.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let equations: EquationMode = args.equations.into();
    if args.unmeasured_base.is_some() && (args.estimator == Estimator::Ols || args.model.is_some())
    {
        anyhow::bail!(
            "--unmeasured-base fits all five parameters by maximum likelihood: --estimator ols and --model cannot be used with it"
        );
    }
    if args.compare_ols && args.estimator == Estimator::Ols {
        anyhow::bail!(
            "--compare-ols compares the ML fit with OLS: it cannot be used with --estimator ols"
        );
    }
    if args.estimator == Estimator::Ml && equations != EquationMode::RealAndImag {
        anyhow::bail!(
            "--equations {}: the paper's equation variants are least-squares variants; add --estimator ols",
            super::mode_name(equations)
        );
    }
    let (run, mut identification) = identify_args(args)?;
    let table_sd = args.table_uncertainty.map(|pct| pct / 100.0);
    // The channels' sensitivities against the noise-only ±, before any
    // widening.
    let sensors = super::conditional::sensor::of(&identification);
    let noise_before = identification
        .pedestals
        .iter()
        .map(|p| p.std_err)
        .collect::<Vec<_>>();
    if let Some(sd) = table_sd {
        super::conditional::widen(&mut identification, sd);
    }
    if let Some(sd) = args.speed_uncertainty {
        super::conditional::speed::widen(&mut identification, sd);
    }
    if let Some(u) = args.sensor_uncertainty {
        super::conditional::sensor::widen(&mut identification, u);
    }
    let widened =
        table_sd.is_some() || args.speed_uncertainty.is_some() || args.sensor_uncertainty.is_some();
    let noise_only = widened.then(|| {
        crate::present::modal::attach(&mut identification);
        noise_before
    });
    let mut conditional = super::conditional::of(&run, &identification, table_sd)
        .with_sensors(sensors, args.sensor_uncertainty);
    conditional.speed_uncertainty_hz = args.speed_uncertainty;
    for p in &identification.pedestals {
        for w in &p.warnings {
            eprintln!("warning: pedestal `{}`: {}", p.bearing, w.message);
        }
    }
    let no_truth = (run.truth.as_ref()).map_or(Vec::new(), |t| bearings_without_truth(&run, t));
    if args.json {
        // Keys may be added (formats.md): the bearings truth.json lacks,
        // what the values are conditional on, the noise-only ±.
        let mut json = serde_json::to_value(&identification)?;
        if !no_truth.is_empty() {
            json["bearings_without_truth"] = serde_json::json!(no_truth);
        }
        json["conditional_on"] = serde_json::to_value(&conditional)?;
        for (i, se) in noise_only.iter().flatten().enumerate() {
            if let Some(p) = json["pedestals"].get_mut(i) {
                p["std_err_noise"] = serde_json::to_value(se)?;
            }
        }
        println!("{}", serde_json::to_string_pretty(&json)?);
    } else {
        print!("{}", table(&identification, run.truth.as_ref()));
        print!("{}", super::on_base::describe(&identification.bases));
        print!("{}", untrusted_reasons(&identification));
        print!("{}", super::delay_unknown::describe(&identification));
        print!("{}", super::speed_lag::describe(&identification));
        print!("{}", super::sensor_gain::describe(&identification));
        print!("{}", conditional.to_text());
    }
    if let Some(dir) = &args.plots {
        let files = crate::report::fitted::write_identify_plots(
            dir,
            &run,
            &identification,
            args.figure_style.style(),
        )?;
        eprintln!("{} figure files -> {}", files.len(), dir.display());
    }
    // A physically impossible pedestal or a suspected convention mistake:
    // everything is printed, then exit code 2 (`physical::EXIT_NOT_PHYSICAL`).
    match super::physical::NotPhysical::of(&identification) {
        Some(e) => Err(e.into()),
        None => Ok(()),
    }
}

/// What `plinth identify` computes for `args` (the run as read, after any
/// slow-roll subtraction, and its identification, pedestals on bases
/// included), without printing it.
pub fn identify_args(args: &Args) -> anyhow::Result<(RunDir, Identification)> {
    check_run_dir(&args.dir)?;
    let mut ticker = crate::progress::Ticker::new("identify: read, fit, bases", 3, true);
    let mut run = RunDir::read(&args.dir)?;
    // The measured base motion is read with the run, before any fit.
    let base_rows = crate::base_csv::read(&args.dir)?;
    if base_rows.is_some() && args.unmeasured_base.is_some() {
        anyhow::bail!(
            "--unmeasured-base: {} holds the measured base motion: use it (drop --unmeasured-base) or move base.csv away",
            args.dir.join(crate::base_csv::BASE_FILE).display()
        );
    }
    ticker.tick(1);
    if let Some(band) = args.speeds {
        band.select(&mut run)
            .map_err(|e| anyhow::anyhow!("{}: {e}", args.dir.display()))?;
    }
    if let Some(band) = args.slow_roll {
        let removed = crate::field::slow_roll::subtract_slow_roll(&mut run.measurements, band)?;
        for v in &removed.vectors {
            eprintln!(
                "slow roll {}..{} Hz, bearing `{}`: subtracted rel_y = {:.4e}{:+.4e}i m, rel_z = {:.4e}{:+.4e}i m (mean of {} speeds)",
                band.lo_hz, band.hi_hz, v.bearing, v.rel[0].re, v.rel[0].im, v.rel[1].re, v.rel[1].im, v.speeds
            );
        }
        for w in &removed.warnings {
            eprintln!("warning: {w}");
        }
    }
    if let Some(rows) = &base_rows {
        crate::base_csv::check_bearings(&args.dir, rows, &run.measured_bearings())?;
    }
    let options = args.options();
    // The run as fitted, its base and their noise, made once.
    let prepared = super::data::Prepared::new(&run, base_rows.as_deref(), options.quantisation);
    let mut identification =
        identify_prepared(&run, &prepared, &options).map_err(|e| located(&args.dir, e))?;
    ticker.tick(2);
    on_bases(args, &prepared, &mut identification)?;
    ticker.finish();
    crate::present::modal::attach(&mut identification);
    Ok((run, identification))
}

/// Pedestals on bases: refitted on the measured base of DIR/base.csv, then
/// with the unmeasured bases of `--unmeasured-base` ([`super::on_base`]),
/// from what was read and made ready before fitting (`prepared`).
fn on_bases(
    args: &Args,
    prepared: &super::data::Prepared,
    identification: &mut Identification,
) -> anyhow::Result<()> {
    let options = args.options();
    let context = || format!("identifying {} on its bases", args.dir.display());
    if !prepared.bases.is_empty() {
        let reports =
            super::on_base::apply_measured_base(prepared, identification).with_context(context)?;
        identification.bases.extend(reports);
    }
    if let Some(groups) = &args.unmeasured_base {
        let reports = super::on_base::apply_unmeasured_bases_prepared(
            prepared,
            &groups.0,
            identification,
            &options,
        )
        .with_context(context)?;
        identification.bases.extend(reports);
    }
    Ok(())
}

/// The run directory's own error before its files are read, in the CLI's
/// form (`DIR: what is wrong`), so that a missing directory or a file given
/// for one is not reported as a missing `DIR/measurements.csv` with the
/// operating system's text. Shared by `identify` and `diagnose`.
pub(crate) fn check_run_dir(dir: &std::path::Path) -> anyhow::Result<()> {
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(_) => anyhow::bail!(
            "{}: not a directory: a run directory holds measurements.csv and bearings.csv (docs/formats.md)",
            dir.display()
        ),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            anyhow::bail!("{}: no such run directory", dir.display())
        }
        Err(e) => anyhow::bail!("{}: cannot read the run directory ({e})", dir.display()),
    }
}

/// An identification error with the file it is about (`DIR/measurements.csv`
/// for the measured data, `DIR/bearings.csv` for the coefficients); errors
/// that already name their file, line and column pass unchanged.
fn located(dir: &std::path::Path, e: super::IdentifyError) -> anyhow::Error {
    use super::IdentifyError as E;
    let file = match &e {
        E::NoMeasurements | E::NoData { .. } | E::TooFewSpeeds { .. } => {
            crate::rundir::MEASUREMENTS_FILE
        }
        E::UnknownBearing { .. } | E::BearingRange { .. } => crate::rundir::BEARINGS_FILE,
        E::RunDir(_) | E::NonFinite(_) | E::Base(_) => return e.into(),
    };
    anyhow::anyhow!("{}: {e}", dir.join(file).display())
}

/// Under the table: why each UNTRUSTED pedestal is not trusted (the warnings
/// that make it so), the suspected convention mistake first.
pub fn untrusted_reasons(identification: &Identification) -> String {
    let mut out = String::new();
    for p in identification.pedestals.iter().filter(|p| !p.trusted) {
        out.push_str(&format!("\n{} UNTRUSTED:\n", p.bearing));
        let reasons = p.warnings.iter().filter(|w| w.kind.makes_untrusted());
        let (first, rest): (Vec<_>, Vec<_>) =
            reasons.partition(|w| w.kind == WarningKind::SuspectedConventionError);
        for w in first.into_iter().chain(rest) {
            out.push_str(&format!("  {}\n", w.message));
        }
    }
    out
}

/// The identification as text: the estimator and noise model, then the
/// shared result table ([`crate::present::table`]: value ± standard error
/// per parameter in MN/m, kg and N·s/m, residual RMS [N], condition number,
/// whether the fit can be trusted, and f_n/ζ per direction); with `truth`, a
/// row of the true values and one of the relative errors under each pedestal.
pub fn table(identification: &Identification, truth: Option<&Truth>) -> String {
    let mode = super::parse_mode(&identification.equations).map_or("?", mode_label);
    let estimator = match identification.estimator.as_str() {
        "ml" => "maximum likelihood (errors in variables)",
        _ => "least squares (the paper's)",
    };
    let mut out = format!(
        "estimator {estimator}, equations {mode}, model {}\n",
        identification.model.join(",")
    );
    for fit in &identification.pedestals {
        if let Some(n) = identification.noise.get(&fit.bearing) {
            let sd: Vec<String> = crate::estimate::noise::CHANNELS
                .iter()
                .map(|c| format!("{c} {}", sig(n.sd.get(*c).copied().unwrap_or(f64::NAN), 2)))
                .collect();
            out.push_str(&format!(
                "noise {}: {}{}, sd [m] {}; χ²/dof {}\n",
                fit.bearing,
                n.source.name(),
                if let Some(v) = &n.variance_function {
                    if v.p_value < crate::estimate::noise::variance::HETEROSCEDASTIC_P {
                        format!(
                            " (variance function from the fit's residuals: {} rejected)",
                            n.source.pattern_name()
                        )
                    } else {
                        format!(
                            " (variance function from the fit's residuals: {} carried to speeds it was not measured on)",
                            n.source.pattern_name()
                        )
                    }
                } else if n.scale_estimated {
                    " (level from the fit's χ²)".to_string()
                } else {
                    String::new()
                },
                sd.join(", "),
                sig(n.chi2 / n.dof.max(1) as f64, 3)
            ));
        }
    }
    out.push('\n');
    let rows: Vec<PedestalRow> = identification
        .pedestals
        .iter()
        .map(|fit| result_row(fit, truth))
        .collect();
    out.push_str(&table::render(&rows));
    out
}

/// One pedestal as the shared printer shows it ([`crate::present::table`]),
/// with the paper's OLS beside it (`--compare-ols`) and the truth when known.
pub fn result_row(fit: &PedestalFit, truth: Option<&Truth>) -> PedestalRow {
    let se = fit.std_err.theta();
    let mut below = Vec::new();
    if let Some(ols) = &fit.ols {
        let named = |map: &std::collections::BTreeMap<String, f64>, p: Parameter| {
            map.get(p.name()).copied()
        };
        below.push(SubRow::values(
            "ols",
            Parameter::ALL.map(|p| named(&ols.estimate, p).map(|v| (v, named(&ols.std_err, p)))),
        ));
        below.push(SubRow::text(
            "ols eff.",
            Parameter::ALL.map(|p| {
                named(&ols.efficiency, p).map_or("-".into(), |e| format!("{:.0}%", 100.0 * e))
            }),
        ));
    }
    let own = truth.and_then(|t| t.pedestals.iter().find(|t| t.bearing == fit.bearing));
    let mut modal_truth = None;
    if let Some(t) = own {
        let values = t.pedestal.theta();
        below.push(SubRow::values("truth", values.map(|v| Some((v, None)))));
        below.push(SubRow::errors("error", fit.pedestal.theta(), values));
        modal_truth = Some(crate::present::modal::pedestal(&values, None));
    } else if truth.is_some() {
        // truth.json without this bearing (`rundir::read::bearings_without_truth`).
        below.push(SubRow::text("truth", Parameter::ALL.map(|_| "none".into())));
    }
    PedestalRow {
        bearing: fit.bearing.clone(),
        parameters: Parameter::ALL
            .map(|p| (!is_fixed(fit, p)).then(|| (fit.pedestal.get(p), se[p as usize]))),
        extra: Vec::new(),
        residual_rms: Some(fit.residual_rms),
        condition_number: Some(fit.condition_number),
        trusted: Some(fit.trusted),
        modal: fit.modal,
        below,
        modal_truth,
    }
}

fn is_fixed(fit: &PedestalFit, p: Parameter) -> bool {
    fit.fixed.iter().any(|f| f == p.name())
}
