//! Drawing primitives: a figure's rows of charts (amplitude, phase, polar
//! views), colours, ranges, and one chart on any plotters backend.

use super::*;
use anyhow::{anyhow, Result};
use num_complex::Complex;
use plotters::coord::Shift;
use plotters::prelude::*;

/// The (speed, value) rows of one view row of a series, split into segments
/// where a wrapped angle jumps (so no vertical line is drawn across the wrap).
/// Speeds stay in Hz; amplitudes are in the plotted unit (`scale` from SI,
/// doubled for a peak-to-peak `quantity`) and, with `log`, their log10 (zero
/// amplitudes left out).
pub(super) fn view_rows(
    series: &PhasorSeries,
    view: PhasorView,
    row: usize,
    quantity: Quantity,
    log: bool,
) -> Vec<Vec<(f64, f64)>> {
    let scale = quantity.scale();
    let mut pts: Vec<(f64, Complex<f64>)> = series
        .points
        .iter()
        .copied()
        .filter(|(s, q)| s.is_finite() && q.re.is_finite() && q.im.is_finite())
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let pp = if quantity.peak_to_peak() { 1.0 } else { 0.5 };
    let values: Vec<(f64, f64)> = match (view, row) {
        (PhasorView::Engineer(_), 0) => pts
            .iter()
            .map(|&(s, q)| (s, peak_to_peak_and_lag(q).0 * scale * pp))
            .collect(),
        (PhasorView::Engineer(PhaseStyle::Wrapped), _) => pts
            .iter()
            .map(|&(s, q)| (s, peak_to_peak_and_lag(q).1))
            .collect(),
        (PhasorView::Engineer(PhaseStyle::Unwrapped), _) => {
            let lags: Vec<f64> = pts
                .iter()
                .map(|&(_, q)| peak_to_peak_and_lag(q).1)
                .collect();
            pts.iter()
                .zip(unwrap_deg(&lags))
                .map(|(&(s, _), l)| (s, l))
                .collect()
        }
        (PhasorView::ReIm, 0) => pts.iter().map(|&(s, q)| (s, q.re * scale)).collect(),
        (PhasorView::ReIm, _) => pts.iter().map(|&(s, q)| (s, q.im * scale)).collect(),
        (PhasorView::AmplitudeAngle, 0) => {
            pts.iter().map(|&(s, q)| (s, q.norm() * scale)).collect()
        }
        (PhasorView::AmplitudeAngle, _) => pts
            .iter()
            .map(|&(s, q)| (s, q.arg().to_degrees()))
            .collect(),
    };
    let values = if log && row_from_zero(view, row) {
        values
            .into_iter()
            .filter(|p| p.1 > 0.0)
            .map(|(s, v)| (s, v.log10()))
            .collect()
    } else {
        values
    };
    let wrapped = row == 1
        && matches!(
            view,
            PhasorView::Engineer(PhaseStyle::Wrapped) | PhasorView::AmplitudeAngle
        );
    split_at_wraps(values, wrapped)
}

/// Axis label of one row of a phasor figure.
pub(super) fn row_label(view: PhasorView, row: usize, quantity: Quantity) -> String {
    let u = quantity.unit();
    let measure = if quantity.peak_to_peak() {
        "pk-pk"
    } else {
        "pk"
    };
    match (view, row) {
        (PhasorView::Engineer(_), 0) => format!("Amplitude [{u} {measure}]"),
        (PhasorView::Engineer(PhaseStyle::Wrapped), _) => "Phase lag [deg]".into(),
        (PhasorView::Engineer(PhaseStyle::Unwrapped), _) => "Phase lag, unwrapped [deg]".into(),
        (PhasorView::ReIm, 0) => format!("Re Q [{u}]"),
        (PhasorView::ReIm, _) => format!("Im Q [{u}]"),
        (PhasorView::AmplitudeAngle, 0) => format!("|Q| [{u} 0-pk]"),
        (PhasorView::AmplitudeAngle, _) => "arg Q [deg]".into(),
    }
}

/// Fixed y range and tick step of a row, when the view prescribes one.
pub(super) fn row_fixed_range(view: PhasorView, row: usize) -> Option<((f64, f64), f64)> {
    match (view, row) {
        (PhasorView::Engineer(PhaseStyle::Wrapped), 1) => Some(((0.0, 360.0), 90.0)),
        (PhasorView::AmplitudeAngle, 1) => Some(((-180.0, 180.0), 90.0)),
        _ => None,
    }
}

/// Whether a row's axis should start at zero (amplitudes).
pub(super) fn row_from_zero(view: PhasorView, row: usize) -> bool {
    row == 0 && matches!(view, PhasorView::Engineer(_) | PhasorView::AmplitudeAngle)
}

/// Colour of the i-th series (a colour-blind-safe qualitative palette).
pub fn colour(i: usize) -> RGBColor {
    const PALETTE: [RGBColor; 8] = [
        RGBColor(0, 114, 178),   // blue
        RGBColor(213, 94, 0),    // vermillion
        RGBColor(0, 158, 115),   // bluish green
        RGBColor(204, 121, 167), // reddish purple
        RGBColor(230, 159, 0),   // orange
        RGBColor(86, 180, 233),  // sky blue
        RGBColor(0, 0, 0),       // black
        RGBColor(240, 228, 66),  // yellow
    ];
    PALETTE[i % PALETTE.len()]
}

/// Colour of a series by its index among same-named series: measured markers
/// and the predicted line of the same channel share a colour.
pub(super) fn colour_for(names: &[&str], i: usize) -> RGBColor {
    let name = names[i];
    let key = name
        .split_whitespace()
        .next()
        .unwrap_or(name)
        .trim_end_matches(',');
    let mut distinct: Vec<&str> = Vec::new();
    for n in names {
        let k = n
            .split_whitespace()
            .next()
            .unwrap_or(n)
            .trim_end_matches(',');
        if !distinct.contains(&k) {
            distinct.push(k);
        }
    }
    colour(distinct.iter().position(|k| *k == key).unwrap_or(i))
}

/// Range of finite values with a margin, never empty.
pub(super) fn padded_range(
    values: impl Iterator<Item = f64>,
    from_zero: bool,
    margin_frac: f64,
) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if from_zero {
        lo = lo.min(0.0);
    }
    let span = hi - lo;
    let pad = if span > 0.0 {
        span * margin_frac
    } else {
        hi.abs().max(1.0) * 0.1
    };
    let lo = if from_zero && lo >= 0.0 {
        0.0
    } else {
        lo - pad
    };
    (lo, hi + pad)
}

/// A line or marker series ready for one chart (x in the plotted speed unit).
pub(super) struct Curve {
    pub(super) name: String,
    pub(super) mark: Mark,
    pub(super) colour: RGBColor,
    pub(super) segments: Vec<Vec<(f64, f64)>>,
}

impl Curve {
    /// Its legend entry.
    pub(super) fn entry(&self) -> LegendEntry {
        LegendEntry {
            name: self.name.clone(),
            colour: self.colour,
            swatch: match self.mark {
                Mark::Line => Swatch::Line,
                Mark::Markers => Swatch::Marker,
            },
        }
    }

    /// True when it has a point to draw.
    pub(super) fn has_points(&self) -> bool {
        self.segments.iter().any(|s| !s.is_empty())
    }
}

/// A shaded band between `lower` and `upper` at the same x values (a
/// fitted curve's ± uncertainty).
pub(super) struct Band {
    pub(super) colour: RGBColor,
    /// (x, lower, upper) in the plotted units.
    pub(super) points: Vec<(f64, f64, f64)>,
}

impl Band {
    /// Its legend entry, named `name`.
    pub(super) fn entry(&self, name: String) -> LegendEntry {
        LegendEntry {
            name,
            colour: self.colour,
            swatch: Swatch::Band,
        }
    }
}

/// The figure's white page with its title on top: the area left for the
/// charts.
pub(super) fn titled_page<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
) -> Result<DrawingArea<DB, Shift>>
where
    DB::ErrorType: 'static,
{
    ensure_fonts()?;
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing figure '{title}': {e:?}");
    root.fill(&WHITE).map_err(err)?;
    root.titled(title, (FONT, title_size(title, root.dim_in_pixel().0)))
        .map_err(err)
}

/// The speed axis over `speeds` [Hz], in `unit`.
pub(super) fn speed_axis<'a>(speeds: impl Iterator<Item = &'a f64>, unit: SpeedUnit) -> (f64, f64) {
    let (lo, hi) = speed_range(speeds);
    (lo * unit.factor(), hi * unit.factor())
}

/// One chart in `cell` with the legend column beside it when `entries`
/// has any: drawn there when `show_legend` (else left empty, so that the
/// charts of a column line up).
pub(super) fn draw_cell<DB: DrawingBackend>(
    cell: &DrawingArea<DB, Shift>,
    axes: &Axes<'_>,
    bands: &[Band],
    curves: &[Curve],
    entries: &[LegendEntry],
    show_legend: bool,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let (chart, legend) = beside(cell, !entries.is_empty());
    draw_chart(&chart, axes, bands, curves)?;
    match legend {
        Some(area) if show_legend => draw_legend(&area, entries),
        _ => Ok(()),
    }
}

/// The axes of one chart.
pub(super) struct Axes<'a> {
    /// Caption above the chart ("" for none).
    pub(super) caption: &'a str,
    /// x range in the plotted speed unit.
    pub(super) x_range: (f64, f64),
    /// x-axis label.
    pub(super) x_label: &'a str,
    /// y range (log10 of the value when `log_y`).
    pub(super) y_range: (f64, f64),
    /// Fixed y tick spacing, or `None` for nice ticks.
    pub(super) y_step: Option<f64>,
    /// y-axis label.
    pub(super) y_label: &'a str,
    /// y values are log10 of the quantity: decade ticks labelled 10^v.
    pub(super) log_y: bool,
}

/// Ticks of a log10 axis: bold at the decades (or at 1, 2, 5 when the range
/// spans under two decades), light at 1..9 × 10^n.
fn log_ticks(range: (f64, f64)) -> (Vec<f64>, Vec<f64>) {
    let (lo, hi) = (range.0.floor() as i32, range.1.ceil() as i32);
    let mut bold = Vec::new();
    let mut light = Vec::new();
    let few = range.1 - range.0 < 2.0;
    for e in lo..=hi {
        for m in 1..10 {
            let v = f64::from(e) + f64::from(m).log10();
            if v < range.0 - 1e-9 || v > range.1 + 1e-9 {
                continue;
            }
            if m == 1 || (few && (m == 2 || m == 5)) {
                bold.push(v);
            }
            light.push(v);
        }
    }
    (bold, light)
}

/// Draws one chart with bands and curves into `area` (no legend: the
/// figure draws it beside the data, [`draw_legend`]).
pub(super) fn draw_chart<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    axes: &Axes<'_>,
    bands: &[Band],
    curves: &[Curve],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let caption = axes.caption;
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing chart '{caption}': {e:?}");
    let mut builder = ChartBuilder::on(area);
    builder
        .margin(12)
        .x_label_area_size(46)
        .y_label_area_size(70);
    if !caption.is_empty() {
        builder.caption(caption, (FONT, 20));
    }
    let (y_ticks, y_light) = if axes.log_y {
        log_ticks(axes.y_range)
    } else {
        let t = match axes.y_step {
            Some(step) if step > 0.0 => ticks_with_step(axes.y_range, step),
            _ => nice_ticks(axes.y_range, 8),
        };
        let l = light_ticks(&t, axes.y_range);
        (t, l)
    };
    let x_ticks = nice_ticks(axes.x_range, 10);
    let x_light = light_ticks(&x_ticks, axes.x_range);
    let mut chart = builder
        .build_cartesian_2d(
            TickedAxis {
                range: axes.x_range,
                bold: x_ticks,
                light: x_light,
            },
            TickedAxis {
                range: axes.y_range,
                bold: y_ticks,
                light: y_light,
            },
        )
        .map_err(err)?;
    let log_y = axes.log_y;
    let y_format = move |v: &f64| {
        if log_y {
            format_tick(10f64.powf(*v))
        } else {
            format_tick(*v)
        }
    };
    chart
        .configure_mesh()
        .x_desc(axes.x_label)
        .y_desc(axes.y_label)
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 16))
        .light_line_style(RGBColor(240, 240, 240))
        .bold_line_style(RGBColor(205, 205, 205))
        .y_label_formatter(&y_format)
        .x_label_formatter(&|v| format_tick(*v))
        .draw()
        .map_err(err)?;
    for b in bands.iter().filter(|b| b.points.len() > 1) {
        let mut outline: Vec<(f64, f64)> = b.points.iter().map(|p| (p.0, p.2)).collect();
        outline.extend(b.points.iter().rev().map(|p| (p.0, p.1)));
        chart
            .draw_series(std::iter::once(Polygon::new(outline, b.colour.mix(0.18))))
            .map_err(err)?;
    }
    for c in curves {
        let colour = c.colour;
        for seg in c.segments.iter().filter(|s| !s.is_empty()) {
            match c.mark {
                Mark::Line => {
                    chart
                        .draw_series(LineSeries::new(seg.iter().copied(), colour.stroke_width(2)))
                        .map_err(err)?;
                }
                Mark::Markers => {
                    chart
                        .draw_series(
                            seg.iter()
                                .map(|&p| Circle::new(p, 3, colour.stroke_width(1))),
                        )
                        .map_err(err)?;
                }
            }
        }
    }
    Ok(())
}

/// Title font size [px] that fits `title` into `width` pixels (DejaVu Sans
/// averages about 0.55 em per character), at most 26.
pub(super) fn title_size(title: &str, width: u32) -> f64 {
    let chars = title.chars().count().max(1) as f64;
    (0.95 * f64::from(width) / (0.55 * chars)).clamp(12.0, 26.0)
}

/// Speed range over all points, never empty.
pub(super) fn speed_range<'a>(speeds: impl Iterator<Item = &'a f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &s in speeds.filter(|s| s.is_finite()) {
        lo = lo.min(s);
        hi = hi.max(s);
    }
    if !lo.is_finite() {
        (0.0, 1.0)
    } else if hi > lo {
        (lo, hi)
    } else {
        (lo - 1.0, hi + 1.0)
    }
}
