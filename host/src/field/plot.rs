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
use crate::plots::labels::{place, text_box, TextBox};
use crate::plots::{
    colour, ensure_fonts, peak_to_peak_and_lag, write_both, PhaseStyle, PhasorFigure, PhasorPanel,
    PhasorSeries, PhasorView, Quantity as PlotQuantity, Rows, Style, StyleArgs,
};
use crate::rundir::RunDir;
use anyhow::{anyhow, Result};
use num_complex::Complex;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

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

/// Where a displacement phasor `q` [m] plots on a Bently polar chart:
/// (right, up) [µm pk-pk], lag measured from the top against `rotation`.
pub fn polar_point(q: Complex<f64>, rotation: Rotation) -> (f64, f64) {
    polar_point_at(q * 1e6, rotation, 0.0, true)
}

/// Where a phasor `q` (in the plotted unit) plots on a polar chart whose 0°
/// lies `zero_deg` from the top in the direction of `rotation` (the
/// transducer's angle, or 0 for the top): (right, up), radius peak-to-peak
/// when `peak_to_peak`, else zero-to-peak.
pub fn polar_point_at(
    q: Complex<f64>,
    rotation: Rotation,
    zero_deg: f64,
    peak_to_peak: bool,
) -> (f64, f64) {
    let (pp, lag) = peak_to_peak_and_lag(q);
    let r = if peak_to_peak { pp } else { 0.5 * pp };
    // Angle from the top, positive in the direction of rotation.
    let (s, c) = (zero_deg - lag).to_radians().sin_cos();
    match rotation {
        // Counter-clockwise: the direction of rotation is to the left.
        Rotation::Ccw => (-r * s, r * c),
        Rotation::Cw => (r * s, r * c),
    }
}

/// One locus to draw: name and (speed [Hz], phasor [m]) points.
#[derive(Clone, Debug)]
pub struct Locus {
    /// Title, e.g. `B1 rel y` or `B1 rel 45°`.
    pub name: String,
    /// File-name stem.
    pub stem: String,
    /// Points in speed order (displacement [m]).
    pub points: Vec<(f64, Complex<f64>)>,
    /// The transducer's axis [deg from +y towards +z] (y: 0, z: 90).
    pub angle_deg: f64,
    /// Unit the locus is drawn in.
    pub unit: PlotQuantity,
    /// True for a transducer's own reading, false for a resolved y or z.
    pub transducer: bool,
}

impl Locus {
    /// The points in the drawn unit's SI signal (displacement, velocity or
    /// acceleration).
    pub fn signal(&self) -> Vec<(f64, Complex<f64>)> {
        self.points
            .iter()
            .map(|&(f, x)| (f, self.unit.from_displacement(x, f)))
            .collect()
    }
}

/// The loci of a run: each bearing's y and z, and each extra transducer
/// reconstructed as cos α·Y + sin α·Z.
pub fn loci(run: &RunDir, transducers: &[PlotTransducer]) -> Vec<Locus> {
    let mut out = Vec::new();
    for b in run.measured_bearings() {
        let mut rows: Vec<_> = run.measurements.iter().filter(|m| m.bearing == b).collect();
        rows.sort_by(|x, y| x.speed_hz.total_cmp(&y.speed_hz));
        for q in [Quantity::Rel, Quantity::Ped] {
            let pick = |m: &crate::rundir::Measurement| match q {
                Quantity::Rel => m.rel,
                Quantity::Ped => m.ped,
            };
            let file_b = crate::names::file_name(b);
            for (i, axis) in ["y", "z"].iter().enumerate() {
                out.push(Locus {
                    name: format!("{b} {} {axis}", q.name()),
                    stem: format!("{file_b}_{}_{axis}", q.name()),
                    points: rows.iter().map(|m| (m.speed_hz, pick(m)[i])).collect(),
                    angle_deg: 90.0 * i as f64,
                    unit: PlotQuantity::DisplacementMicrons,
                    transducer: false,
                });
            }
            for t in transducers
                .iter()
                .filter(|t| t.bearing == b && t.quantity == q)
            {
                let a = t.angle_deg;
                let (s, c) = a.to_radians().sin_cos();
                out.push(Locus {
                    name: format!("{} {} {a}°", t.bearing, q.name()),
                    stem: format!("{file_b}_{}_{}deg", q.name(), a),
                    points: rows
                        .iter()
                        .map(|m| (m.speed_hz, pick(m)[0] * c + pick(m)[1] * s))
                        .collect(),
                    angle_deg: a,
                    unit: t.unit,
                    transducer: true,
                });
            }
        }
    }
    out
}

/// The Bode figure of one bearing and quantity: resolved y/z in one panel,
/// the transducers' own readings in one panel per unit.
fn bode_figure(bearing: &str, q: Quantity, loci: &[&Locus], style: Style) -> PhasorFigure {
    // Series named by direction or angle only (the panel names the
    // bearing): each its own colour.
    let prefix = format!("{bearing} {} ", q.name());
    let short = |l: &Locus| l.name.strip_prefix(&prefix).unwrap_or(&l.name).to_string();
    let resolved: Vec<PhasorSeries> = loci
        .iter()
        .filter(|l| !l.transducer)
        .map(|l| PhasorSeries::line(short(l), l.signal()))
        .collect();
    let mut panels = vec![PhasorPanel::new(
        format!("{bearing} {}: resolved y, z", q.name()),
        resolved,
    )];
    let mut units: Vec<PlotQuantity> = Vec::new();
    for l in loci.iter().filter(|l| l.transducer) {
        if !units.contains(&l.unit) {
            units.push(l.unit);
        }
    }
    for u in units {
        let series: Vec<PhasorSeries> = loci
            .iter()
            .filter(|l| l.transducer && l.unit == u)
            .map(|l| PhasorSeries::line(short(l), l.signal()))
            .collect();
        panels.push(PhasorPanel {
            title: format!("{bearing} {}: transducers", q.name()),
            series,
            quantity: Some(u),
        });
    }
    PhasorFigure {
        title: format!(
            "Bode: bearing {bearing}, {} (1X amplitude and phase lag)",
            q.name()
        ),
        quantity: PlotQuantity::DisplacementMicrons,
        view: PhasorView::Engineer(PhaseStyle::Wrapped),
        rows: Rows::Both,
        panels,
        style,
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

/// Pixel size of a polar figure.
const POLAR_SIZE: (u32, u32) = (720, 780);

/// Draws one polar plot.
fn draw_polar<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    locus: &Locus,
    options: &PlotOptions,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    ensure_fonts()?;
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("polar plot {}: {e:?}", locus.name);
    root.fill(&WHITE).map_err(err)?;
    let rotation = options.rotation;
    let unit = locus.unit;
    let pp = unit.peak_to_peak();
    let zero = if options.zero_at_transducer {
        locus.angle_deg
    } else {
        0.0
    };
    let pts: Vec<(f64, f64, f64)> = locus
        .signal()
        .iter()
        .filter(|(f, q)| f.is_finite() && q.re.is_finite() && q.im.is_finite())
        .map(|(f, q)| {
            let (x, y) = polar_point_at(*q * unit.scale(), rotation, zero, pp);
            (*f, x, y)
        })
        .collect();
    let max = pts.iter().map(|p| p.1.hypot(p.2)).fold(0.0, f64::max);
    let r = nice_radius(max);
    let title = format!(
        "Polar: {} ({} {}, lag against {} rotation{})",
        locus.name,
        unit.unit(),
        if pp { "pk-pk" } else { "pk" },
        match rotation {
            Rotation::Ccw => "CCW",
            Rotation::Cw => "CW",
        },
        if options.zero_at_transducer {
            ", 0° at the transducer"
        } else {
            ""
        }
    );
    let (upper, footer) = root.split_vertically(POLAR_SIZE.1 - 50);
    let mut chart = ChartBuilder::on(&upper)
        .caption(title, ("sans-serif", 17))
        .margin(30)
        .build_cartesian_2d(-1.15 * r..1.15 * r, -1.15 * r..1.15 * r)
        .map_err(err)?;
    let grey = RGBColor(200, 200, 200);
    for k in 1..=4 {
        let rr = r * k as f64 / 4.0;
        let ring: Vec<(f64, f64)> = (0..=120)
            .map(|i| {
                let t = i as f64 / 120.0 * std::f64::consts::TAU;
                (rr * t.sin(), rr * t.cos())
            })
            .collect();
        chart
            .draw_series(LineSeries::new(ring, grey))
            .map_err(err)?;
        chart
            .draw_series(std::iter::once(Text::new(
                trim(rr),
                (0.02 * r, rr),
                ("sans-serif", 12)
                    .into_font()
                    .color(&RGBColor(120, 120, 120)),
            )))
            .map_err(err)?;
    }
    for k in 0..12 {
        let lag = 30.0 * k as f64;
        let (x, y) = polar_point_at(
            Complex::from_polar(r / 2.0, -lag.to_radians()),
            rotation,
            zero,
            true,
        );
        chart
            .draw_series(LineSeries::new([(0.0, 0.0), (x, y)], grey))
            .map_err(err)?;
        chart
            .draw_series(std::iter::once(Text::new(
                format!("{lag:.0}°"),
                (1.07 * x - 0.03 * r, 1.07 * y + 0.02 * r),
                ("sans-serif", 13),
            )))
            .map_err(err)?;
    }
    let c = colour(0);
    chart
        .draw_series(LineSeries::new(
            pts.iter().map(|p| (p.1, p.2)),
            c.stroke_width(2),
        ))
        .map_err(err)?;
    chart
        .draw_series(pts.iter().map(|p| Circle::new((p.1, p.2), 2, c.filled())))
        .map_err(err)?;
    // Speed labels: start and end first, then spread along the locus, never
    // overlapping each other or the start/end marks.
    let pixels: Vec<(f64, f64)> = pts
        .iter()
        .map(|p| {
            let (x, y) = chart.backend_coord(&(p.1, p.2));
            (f64::from(x), f64::from(y))
        })
        .collect();
    let speed_unit = options.style.speed_unit;
    let texts: Vec<String> = pts.iter().map(|p| speed_unit.label(p.0)).collect();
    let (xr, yr) = chart.plotting_area().get_pixel_range();
    let bounds = TextBox {
        x: f64::from(xr.start),
        y: f64::from(yr.start),
        w: f64::from(xr.end - xr.start),
        h: f64::from(yr.end - yr.start),
    };
    let font = 11.0;
    for p in place(&pixels, &texts, font, 6.0, 12, &[], bounds) {
        let b = text_box(&texts[p.index], font, p.x, p.y);
        upper
            .draw(&Text::new(
                texts[p.index].clone(),
                (b.x as i32, b.y as i32),
                ("sans-serif", font)
                    .into_font()
                    .color(&RGBColor(40, 40, 40)),
            ))
            .map_err(err)?;
    }
    let dark = RGBColor(40, 40, 40);
    if let (Some(first), Some(last)) = (pixels.first(), pixels.last()) {
        let (x, y) = (first.0 as i32, first.1 as i32);
        upper
            .draw(&Rectangle::new(
                [(x - 5, y - 5), (x + 5, y + 5)],
                dark.filled(),
            ))
            .map_err(err)?;
        upper
            .draw(&TriangleMarker::new(
                (last.0 as i32, last.1 as i32),
                7,
                colour(1).filled(),
            ))
            .map_err(err)?;
    }
    // The key below the chart, outside the data.
    if let (Some(first), Some(last)) = (pts.first(), pts.last()) {
        footer
            .draw(&Rectangle::new([(34, 12), (44, 22)], dark.filled()))
            .map_err(err)?;
        footer
            .draw(&Text::new(
                format!("start {}", speed_unit.label(first.0)),
                (52, 9),
                ("sans-serif", 14),
            ))
            .map_err(err)?;
        footer
            .draw(&TriangleMarker::new((250, 17), 7, colour(1).filled()))
            .map_err(err)?;
        footer
            .draw(&Text::new(
                format!("end {}", speed_unit.label(last.0)),
                (262, 9),
                ("sans-serif", 14),
            ))
            .map_err(err)?;
    }
    Ok(())
}

fn nice_radius(max: f64) -> f64 {
    if !(max > 0.0 && max.is_finite()) {
        return 1.0;
    }
    let e = 10f64.powf(max.log10().floor());
    for m in [1.0, 2.0, 2.5, 5.0, 10.0] {
        if m * e >= max {
            return m * e;
        }
    }
    10.0 * e
}

fn trim(v: f64) -> String {
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
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

    #[test]
    fn polar_orientation_hand_worked() {
        // 10 µm 0-pk = 20 µm pk-pk. Lag 0 plots at the top.
        let top = polar_point(Complex::new(10e-6, 0.0), Rotation::Ccw);
        assert!((top.0).abs() < 1e-9 && (top.1 - 20.0).abs() < 1e-9);
        // Lag 90° (q = −10i µm: the peak comes a quarter turn after the
        // pulse): with CCW rotation, lag runs clockwise, so 3 o'clock.
        let q = Complex::new(0.0, -10e-6);
        let p = polar_point(q, Rotation::Ccw);
        assert!((p.0 - 20.0).abs() < 1e-9 && p.1.abs() < 1e-9, "{p:?}");
        // CW rotation: 9 o'clock.
        let p = polar_point(q, Rotation::Cw);
        assert!((p.0 + 20.0).abs() < 1e-9 && p.1.abs() < 1e-9, "{p:?}");
        // Lag 180°: the bottom either way.
        let p = polar_point(Complex::new(-10e-6, 0.0), Rotation::Cw);
        assert!(p.0.abs() < 1e-9 && (p.1 + 20.0).abs() < 1e-9);
    }

    #[test]
    fn zero_at_the_transducer_hand_worked() {
        // A probe at 45° (from +y towards +z). Seen with CCW rotation +z is
        // on the left, so the probe sits at 10:30; lag 0 plots there.
        let q = Complex::new(10.0, 0.0);
        let p = polar_point_at(q, Rotation::Ccw, 45.0, true);
        let h = 20.0 * std::f64::consts::FRAC_1_SQRT_2;
        assert!((p.0 + h).abs() < 1e-9 && (p.1 - h).abs() < 1e-9, "{p:?}");
        // Lag 45° runs against CCW rotation (clockwise) back to the top.
        let q = Complex::from_polar(10.0, -45f64.to_radians());
        let p = polar_point_at(q, Rotation::Ccw, 45.0, true);
        assert!(p.0.abs() < 1e-9 && (p.1 - 20.0).abs() < 1e-9, "{p:?}");
        // CW rotation: the probe at 45° sits at 1:30.
        let p = polar_point_at(Complex::new(10.0, 0.0), Rotation::Cw, 45.0, true);
        assert!((p.0 - h).abs() < 1e-9 && (p.1 - h).abs() < 1e-9, "{p:?}");
        // Zero-to-peak radius for a velocity pick-up.
        let p = polar_point_at(Complex::new(10.0, 0.0), Rotation::Cw, 0.0, false);
        assert!((p.1 - 10.0).abs() < 1e-9);
    }

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
