//! `plinth plot DIR --out FIGS`: the figures the field expects of a run-down,
//! for every bearing's resolved y and z phasors and, for a run made by
//! import/extract (its `transducers.csv`), every transducer's own reading:
//!
//! - **Bode**: amplitude and phase lag against speed
//!   (`bode_<bearing>_<rel|ped>.png/.svg`), the resolved y/z in one panel and
//!   the transducers' own readings in another (one per unit);
//! - **polar** (Nyquist): the 1X vector's locus in the Bently convention
//!   (`polar_<bearing>_<rel|ped>_<channel>.png/.svg`): amplitude as radius,
//!   phase lag as angle measured **against** the direction of rotation from
//!   0° at the top of the plot or, with `--zero-at-transducer` (Bently/Hatch),
//!   at the transducer's own position. The drawing is seen from the layout's
//!   `view` with its `rotation` (import/extract), else `--rotation`. With the
//!   shaft turning counter-clockwise as drawn lag increases clockwise: a 90°
//!   lag plots at three o'clock ([`polar_point`], checked by hand in the
//!   tests). Speed labels never overlap; the start (■) and end (▲) of the
//!   run are marked.
//!
//! Displacements are drawn in µm pk-pk (mil pk-pk for a layout in mils);
//! velocity and acceleration pick-ups, when the layout says so, in their own
//! units (mm/s pk, in/s pk, g pk): the reading iΩX or −Ω²X of the resolved
//! displacement along the transducer's axis.

use super::angle::Rotation;
use super::transducer::Quantity;
use crate::plots::{write_both, PhasorFigure, Quantity as PlotQuantity, Style, StyleArgs};
use crate::rundir::RunDir;
use anyhow::{anyhow, Result};
use std::path::{Path, PathBuf};

mod bode;
mod locus;
mod polar;

use bode::bode_figure;
pub use locus::{loci, Locus};
use polar::{draw_polar, POLAR_SIZE};
pub use polar::{polar_point, polar_point_at};

/// Command-line arguments of `plinth plot`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Run directory (docs/formats.md).
    pub dir: PathBuf,
    /// Directory for the figures (PNG and SVG).
    #[arg(long)]
    pub out: PathBuf,
    /// The transducers' units, rotation, 0° placement and style of the figures.
    #[command(flatten)]
    pub polar: PolarArgs,
    /// Replace the figures in an existing --out.
    #[arg(long)]
    pub force: bool,
}

/// The figure options `plot` and `report` share: the file a run was made
/// from (for what its `transducers.csv` does not hold: each transducer's
/// unit and the rotation as seen from its `view`), rotation and 0° of the
/// polar plots, speed unit and amplitude scale.
#[derive(clap::Args, Clone, Debug, Default, PartialEq, Eq)]
pub struct PolarArgs {
    /// The layout the run was imported with (`plinth import --layout`):
    /// pick-ups drawn in its units (mil pp, mm/s pk, in/s pk, g), polar
    /// plots with its `rotation`.
    #[arg(long, value_name = "LAYOUT.toml", conflicts_with = "channels")]
    pub layout: Option<PathBuf>,
    /// The channels file the run was extracted with (`plinth extract
    /// --channels`): velocity pick-ups in mm/s pk, accelerometers in g pk,
    /// polar plots with its `rotation`.
    #[arg(long, value_name = "CHANNELS.toml")]
    pub channels: Option<PathBuf>,
    /// Direction of rotation as drawn on the polar plots (lag runs against
    /// it) [default: the `rotation` of --layout or --channels, else ccw].
    #[arg(long, value_enum)]
    pub rotation: Option<RotationArg>,
    /// Polar plots with 0° at each transducer's own position (Bently/Hatch)
    /// instead of at the top.
    #[arg(long)]
    pub zero_at_transducer: bool,
    /// Speed unit and amplitude scale.
    #[command(flatten)]
    pub style: StyleArgs,
}

/// `--rotation` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum RotationArg {
    /// Clockwise as drawn.
    Cw,
    /// Counter-clockwise as drawn.
    Ccw,
}

impl From<RotationArg> for Rotation {
    fn from(r: RotationArg) -> Rotation {
        match r {
            RotationArg::Cw => Rotation::Cw,
            RotationArg::Ccw => Rotation::Ccw,
        }
    }
}

/// How the field figures are drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlotOptions {
    /// Direction of rotation as drawn on the polar plots.
    pub rotation: Rotation,
    /// 0° at the transducer's position on polar plots (else at the top).
    pub zero_at_transducer: bool,
    /// Speed unit and amplitude scale.
    pub style: Style,
}

impl Default for PlotOptions {
    fn default() -> Self {
        Self {
            rotation: Rotation::Ccw,
            zero_at_transducer: false,
            style: Style::default(),
        }
    }
}

impl PlotOptions {
    /// The defaults with the rotation a layout gives (`None`: CCW).
    pub fn with_rotation(rotation: Option<Rotation>) -> Self {
        Self {
            rotation: rotation.unwrap_or(Rotation::Ccw),
            ..Self::default()
        }
    }
}

/// A transducer as the figures need it: where it sits and, for a velocity
/// or acceleration pick-up, the unit its readings are shown in.
#[derive(Clone, Debug, PartialEq)]
pub struct PlotTransducer {
    /// Bearing name.
    pub bearing: String,
    /// `rel` or `ped`.
    pub quantity: Quantity,
    /// Axis [deg from +y towards +z].
    pub angle_deg: f64,
    /// Unit its readings are drawn in (displacement µm pk-pk by default).
    pub unit: PlotQuantity,
}

impl PlotTransducer {
    /// A displacement transducer (µm pk-pk).
    pub fn displacement(bearing: &str, quantity: Quantity, angle_deg: f64) -> Self {
        Self {
            bearing: bearing.to_string(),
            quantity,
            angle_deg,
            unit: PlotQuantity::DisplacementMicrons,
        }
    }
}

/// The unit a field instrument's reading of `kind` is drawn in, from the
/// reading's SI factor (`to_si`: m, m/s or m/s² per unit): mils and in/s
/// kept, other displacements µm pk-pk, other velocities mm/s pk,
/// accelerations g pk.
pub fn native_unit(kind: plinth_shared::extractor::SensorKind, to_si: f64) -> PlotQuantity {
    use plinth_shared::extractor::SensorKind as K;
    // `to_si` holds the measure too (pp ×½, rms ×√2): match any of them.
    let near = |a: f64, b: f64| {
        [0.5, 1.0, std::f64::consts::SQRT_2]
            .iter()
            .any(|f| (a - f * b).abs() <= 1e-9 * b)
    };
    match kind {
        K::Displacement if near(to_si, super::units::MIL) => PlotQuantity::DisplacementMils,
        K::Displacement => PlotQuantity::DisplacementMicrons,
        K::Velocity if near(to_si, super::units::INCH) => PlotQuantity::VelocityInchPerSecond,
        K::Velocity => PlotQuantity::VelocityMmPerSecond,
        K::Acceleration => PlotQuantity::AccelerationG,
    }
}

/// What `import --plots` and `extract --plots` draw: every transducer of
/// the layout in its own unit, polar plots seen as the layout says.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldFigures {
    /// The transducers with their units.
    pub transducers: Vec<PlotTransducer>,
    /// Rotation from the layout (CCW when it gives none).
    pub options: PlotOptions,
}

impl FieldFigures {
    /// From an import layout: its rotation and each transducer's unit.
    pub fn from_layout(layout: &super::import::Layout) -> Self {
        Self {
            transducers: layout
                .transducers
                .iter()
                .map(|t| PlotTransducer {
                    unit: native_unit(t.unit.kind, t.unit.to_si_zero_peak),
                    ..PlotTransducer::displacement(
                        &t.placement.bearing,
                        t.placement.quantity,
                        t.placement.angle_deg,
                    )
                })
                .collect(),
            options: PlotOptions::with_rotation(layout.rotation),
        }
    }

    /// From an extract channels file: its rotation and each sensor's kind
    /// (velocity in mm/s pk, acceleration in g pk).
    pub fn from_channels(channels: &crate::extract::channels::Channels) -> Self {
        let si = |k: plinth_shared::extractor::SensorKind| match k {
            plinth_shared::extractor::SensorKind::Displacement => 1e-6,
            plinth_shared::extractor::SensorKind::Velocity => 1e-3,
            plinth_shared::extractor::SensorKind::Acceleration => super::units::STANDARD_GRAVITY,
        };
        Self {
            transducers: channels
                .channels
                .iter()
                .map(|c| PlotTransducer {
                    unit: native_unit(c.kind, si(c.kind)),
                    ..PlotTransducer::displacement(
                        &c.placement.bearing,
                        c.placement.quantity,
                        c.placement.angle_deg,
                    )
                })
                .collect(),
            options: PlotOptions::with_rotation(channels.rotation),
        }
    }
}

/// Writes the Bode and polar figures of `run` into `dir`.
pub fn plot_run_with(
    run: &RunDir,
    dir: &Path,
    transducers: &[PlotTransducer],
    options: &PlotOptions,
) -> Result<Vec<PathBuf>> {
    let all = loci(run, transducers);
    let mut written = Vec::new();
    for b in run.measured_bearings() {
        for q in [Quantity::Rel, Quantity::Ped] {
            let prefix = format!("{b} {} ", q.name());
            let mine: Vec<&Locus> = all.iter().filter(|l| l.name.starts_with(&prefix)).collect();
            let figure = bode_figure(b, q, &mine, options.style);
            let stem = format!("bode_{b}_{}", q.name());
            written.extend(figure.write(&crate::names::file_in(dir, &stem))?);
        }
    }
    for l in &all {
        let stem = crate::names::file_in(dir, &format!("polar_{}", l.stem));
        written.extend(write_both(
            &stem,
            POLAR_SIZE,
            |root| draw_polar(root, l, options),
            |root| draw_polar(root, l, options),
        )?);
    }
    Ok(written)
}

/// The Bode figures and polar loci of a run, for a report: (Bode figures,
/// loci).
pub fn figures(
    run: &RunDir,
    transducers: &[PlotTransducer],
    style: Style,
) -> (Vec<PhasorFigure>, Vec<Locus>) {
    let all = loci(run, transducers);
    let mut bode = Vec::new();
    for b in run.measured_bearings() {
        for q in [Quantity::Rel, Quantity::Ped] {
            let prefix = format!("{b} {} ", q.name());
            let mine: Vec<&Locus> = all.iter().filter(|l| l.name.starts_with(&prefix)).collect();
            bode.push(bode_figure(b, q, &mine, style));
        }
    }
    (bode, all)
}

/// A polar figure as an SVG document in memory.
pub fn polar_svg(locus: &Locus, options: &PlotOptions) -> Result<String> {
    crate::plots::svg_string(POLAR_SIZE, |root| draw_polar(root, locus, options))
}

/// [`plot_run_with`] for the resolved phasors only, default options.
pub fn plot_run(run: &RunDir, dir: &Path) -> Result<Vec<PathBuf>> {
    plot_run_with(run, dir, &[], &PlotOptions::default())
}

/// The transducers of the run in `dir` (its `transducers.csv`) in the
/// units of `polar`'s layout or channels file, and the figure options of
/// `polar` (the rotation of that file unless `--rotation` is given).
///
/// Without a layout or channels file the transducers are drawn as displacements (µm pk-pk):
/// `transducers.csv` holds where each sat, not its unit (docs/formats.md).
/// With it, every transducer of `transducers.csv` must be in the file, at
/// the same bearing, quantity and angle; a run without `transducers.csv`
/// takes the file's transducers.
pub fn run_figures(dir: &Path, polar: &PolarArgs) -> Result<(Vec<PlotTransducer>, PlotOptions)> {
    let (named, rotation, file) = if let Some(path) = &polar.layout {
        let layout = super::import::Layout::read(path)?;
        let f = FieldFigures::from_layout(&layout);
        (
            Some(f.transducers),
            layout.rotation,
            format!("--layout {}", path.display()),
        )
    } else if let Some(path) = &polar.channels {
        let channels = crate::extract::channels::Channels::read(path)?;
        let f = FieldFigures::from_channels(&channels);
        (
            Some(f.transducers),
            channels.rotation,
            format!("--channels {}", path.display()),
        )
    } else {
        (None, None, String::new())
    };
    let placed = super::transducers_csv::read(dir)?;
    let transducers = match (placed, named) {
        (Some(placed), Some(named)) => placed
            .into_iter()
            .map(|(b, q, a)| {
                named
                    .iter()
                    .find(|t| t.bearing == b && t.quantity == q && (t.angle_deg - a).abs() < 1e-6)
                    .cloned()
                    .ok_or_else(|| {
                        anyhow!(
                            "{}: transducer `{}` {} at {a}° is not in {file}: give the file the run was made with",
                            dir.join(super::transducers_csv::TRANSDUCERS_FILE).display(),
                            b,
                            q.name()
                        )
                    })
            })
            .collect::<Result<Vec<_>>>()?,
        (Some(placed), None) => placed
            .into_iter()
            .map(|(b, q, a)| PlotTransducer::displacement(&b, q, a))
            .collect(),
        (None, named) => named.unwrap_or_default(),
    };
    let options = PlotOptions {
        rotation: polar
            .rotation
            .map(Rotation::from)
            .or(rotation)
            .unwrap_or(Rotation::Ccw),
        zero_at_transducer: polar.zero_at_transducer,
        style: polar.style.style(),
    };
    Ok((transducers, options))
}

/// Runs `plinth plot`.
pub fn run(args: &Args) -> Result<()> {
    let run = RunDir::read(&args.dir)?;
    // An imported or extracted run keeps where its transducers sat: draw
    // each one's reading too.
    let (transducers, options) = run_figures(&args.dir, &args.polar)?;
    let mut n = 0;
    crate::output::write_dir(&args.out, args.force, |dir| {
        n = plot_run_with(&run, dir, &transducers, &options)?.len();
        Ok(())
    })?;
    println!("{n} figure files -> {}", args.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plots::peak_to_peak_and_lag;
    use num_complex::Complex;

    #[test]
    fn native_units_of_the_layout() {
        use plinth_shared::extractor::SensorKind as K;
        assert_eq!(
            native_unit(K::Velocity, 0.0254),
            PlotQuantity::VelocityInchPerSecond
        );
        assert_eq!(
            native_unit(K::Velocity, 1e-3),
            PlotQuantity::VelocityMmPerSecond
        );
        assert_eq!(
            native_unit(K::Acceleration, 9.80665),
            PlotQuantity::AccelerationG
        );
        assert_eq!(
            native_unit(K::Displacement, 0.5 * 25.4e-6),
            PlotQuantity::DisplacementMils
        );
        // A velocity pick-up reads iΩX: 1 µm 0-pk at 100 Hz is 0.628 mm/s pk,
        // leading the displacement by 90° (lag −90 ≡ 270).
        let v = PlotQuantity::VelocityMmPerSecond.from_displacement(Complex::new(1e-6, 0.0), 100.0);
        assert!((v.norm() * 1e3 - 0.2 * std::f64::consts::PI).abs() < 1e-12);
        assert!((peak_to_peak_and_lag(v).1 - 270.0).abs() < 1e-9);
    }
}
