//! The polar (Nyquist) plot in the Bently convention: where a phasor plots,
//! and the drawing of one locus with its speed labels.

use super::{Locus, PlotOptions};
use crate::field::angle::Rotation;
use crate::plots::labels::{place, text_box, TextBox};
use crate::plots::{colour, ensure_fonts, peak_to_peak_and_lag};
use anyhow::{anyhow, Result};
use num_complex::Complex;
use plotters::coord::Shift;
use plotters::prelude::*;

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

/// Pixel size of a polar figure.
pub(super) const POLAR_SIZE: (u32, u32) = (720, 780);

/// Draws one polar plot.
pub(super) fn draw_polar<DB: DrawingBackend>(
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
}
