//! `plinth plot DIR --out FIGS`: the figures the field expects of a run-down,
//! for every bearing's resolved y and z phasors and, for a run made by
//! import/extract (its `transducers.csv`), every transducer's own reading:
//!
//! - **Bode**: amplitude [µm pk-pk] and phase lag [deg] against speed
//!   (`bode_<bearing>_<rel|ped>.png/.svg`);
//! - **polar** (Nyquist): the 1X vector's locus, speed-labelled, in the
//!   Bently convention (`polar_<bearing>_<rel|ped>_<channel>.png/.svg`):
//!   amplitude as radius [µm pk-pk], phase lag as angle from the top of the
//!   plot (the transducer's position), measured **against** the direction of
//!   rotation. With the shaft turning counter-clockwise as drawn
//!   (`--rotation ccw`, the default) lag increases clockwise: a 90° lag plots
//!   at three o'clock ([`polar_point`], checked by hand in the tests).

use super::angle::Rotation;
use super::transducer::Quantity;
use crate::plots::{
    colour, ensure_fonts, peak_to_peak_and_lag, write_both, PhaseStyle, PhasorFigure, PhasorPanel,
    PhasorSeries, PhasorView, Quantity as PlotQuantity, Rows,
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
    /// Direction of rotation as drawn on the polar plots (lag runs against it).
    #[arg(long, value_enum, default_value = "ccw")]
    pub rotation: RotationArg,
    /// Replace the figures in an existing --out.
    #[arg(long)]
    pub force: bool,
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

/// Where a displacement phasor `q` [m] plots on a Bently polar chart:
/// (right, up) [µm pk-pk], lag measured from the top against `rotation`.
pub fn polar_point(q: Complex<f64>, rotation: Rotation) -> (f64, f64) {
    let (pp, lag) = peak_to_peak_and_lag(q * 1e6);
    let (s, c) = lag.to_radians().sin_cos();
    match rotation {
        // Rotation counter-clockwise: lag grows clockwise (towards +right first).
        Rotation::Ccw => (pp * s, pp * c),
        Rotation::Cw => (-pp * s, pp * c),
    }
}

/// One locus to draw: name and (speed [Hz], phasor [m]) points.
#[derive(Clone, Debug)]
pub struct Locus {
    /// Title, e.g. `B1 rel y` or `B1 rel 45°`.
    pub name: String,
    /// File-name stem.
    pub stem: String,
    /// Points in speed order.
    pub points: Vec<(f64, Complex<f64>)>,
}

/// The loci of a run: each bearing's y and z, and each extra transducer
/// (bearing, quantity, angle [deg]) reconstructed as cos α·Y + sin α·Z.
pub fn loci(run: &RunDir, transducers: &[(String, Quantity, f64)]) -> Vec<Locus> {
    let mut out = Vec::new();
    for b in run.measured_bearings() {
        let mut rows: Vec<_> = run.measurements.iter().filter(|m| m.bearing == b).collect();
        rows.sort_by(|x, y| x.speed_hz.total_cmp(&y.speed_hz));
        for q in [Quantity::Rel, Quantity::Ped] {
            let pick = |m: &crate::rundir::Measurement| match q {
                Quantity::Rel => m.rel,
                Quantity::Ped => m.ped,
            };
            for (i, axis) in ["y", "z"].iter().enumerate() {
                out.push(Locus {
                    name: format!("{b} {} {axis}", q.name()),
                    stem: format!("{b}_{}_{axis}", q.name()),
                    points: rows.iter().map(|m| (m.speed_hz, pick(m)[i])).collect(),
                });
            }
            for (tb, tq, a) in transducers.iter().filter(|t| t.0 == b && t.1 == q) {
                let (s, c) = a.to_radians().sin_cos();
                out.push(Locus {
                    name: format!("{tb} {} {a}°", tq.name()),
                    stem: format!("{tb}_{}_{}deg", tq.name(), a),
                    points: rows
                        .iter()
                        .map(|m| (m.speed_hz, pick(m)[0] * c + pick(m)[1] * s))
                        .collect(),
                });
            }
        }
    }
    out
}

/// Writes the Bode and polar figures of `run` into `dir`.
pub fn plot_run_with(
    run: &RunDir,
    dir: &Path,
    transducers: &[(String, Quantity, f64)],
    rotation: Rotation,
) -> Result<Vec<PathBuf>> {
    let all = loci(run, transducers);
    let mut written = Vec::new();
    for b in run.measured_bearings() {
        for q in [Quantity::Rel, Quantity::Ped] {
            let prefix = format!("{b} {} ", q.name());
            let series: Vec<PhasorSeries> = all
                .iter()
                .filter(|l| l.name.starts_with(&prefix))
                .map(|l| PhasorSeries::line(l.name[prefix.len()..].to_string(), l.points.clone()))
                .collect();
            let figure = PhasorFigure {
                title: format!(
                    "Bode: bearing {b}, {} (1X, µm pk-pk and phase lag)",
                    q.name()
                ),
                quantity: PlotQuantity::DisplacementMicrons,
                view: PhasorView::Engineer(PhaseStyle::Wrapped),
                rows: Rows::Both,
                panels: vec![PhasorPanel {
                    title: format!("{b} {}", q.name()),
                    series,
                }],
            };
            written.extend(figure.write(&crate::names::file_in(
                dir,
                &format!("bode_{b}_{}", q.name()),
            ))?);
        }
    }
    for l in &all {
        let stem = crate::names::file_in(dir, &format!("polar_{}", l.stem));
        written.extend(write_both(
            &stem,
            (700, 720),
            |root| draw_polar(root, l, rotation),
            |root| draw_polar(root, l, rotation),
        )?);
    }
    Ok(written)
}

/// [`plot_run_with`] for the resolved phasors only, counter-clockwise rotation.
pub fn plot_run(run: &RunDir, dir: &Path) -> Result<Vec<PathBuf>> {
    plot_run_with(run, dir, &[], Rotation::Ccw)
}

/// Draws one polar plot.
fn draw_polar<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    locus: &Locus,
    rotation: Rotation,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    ensure_fonts()?;
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("polar plot {}: {e:?}", locus.name);
    root.fill(&WHITE).map_err(err)?;
    let pts: Vec<(f64, f64, f64)> = locus
        .points
        .iter()
        .map(|(f, q)| {
            let (x, y) = polar_point(*q, rotation);
            (*f, x, y)
        })
        .collect();
    let max = pts.iter().map(|p| p.1.hypot(p.2)).fold(0.0, f64::max);
    let r = nice_radius(max);
    let title = format!(
        "Polar: {} (µm pk-pk, lag against {} rotation)",
        locus.name,
        match rotation {
            Rotation::Ccw => "CCW",
            Rotation::Cw => "CW",
        }
    );
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 18))
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
        let (x, y) = polar_point(
            Complex::from_polar(1e-6 * r / 2.0, -lag.to_radians()),
            rotation,
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
    // Speed labels at about ten points spread along the locus.
    let step = (pts.len() / 10).max(1);
    for p in pts.iter().step_by(step) {
        chart
            .draw_series(std::iter::once(Text::new(
                format!("{:.1} Hz", p.0),
                (p.1 + 0.02 * r, p.2),
                ("sans-serif", 11),
            )))
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

/// Runs `plinth plot`.
pub fn run(args: &Args) -> Result<()> {
    let run = RunDir::read(&args.dir)?;
    // An imported or extracted run keeps where its transducers sat: draw
    // each one's reading too.
    let transducers = super::transducers_csv::read(&args.dir)?.unwrap_or_default();
    let mut n = 0;
    crate::output::write_dir(&args.out, args.force, |dir| {
        n = plot_run_with(&run, dir, &transducers, args.rotation.into())?.len();
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
}
