//! Drawing: a figure's rows of charts (amplitude, phase, polar views),
//! colours, ranges, and the charts themselves on any plotters backend.

use super::*;
use anyhow::{anyhow, Result};
use num_complex::Complex;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// The (speed, value) rows of one view row of a series, split into segments
/// where a wrapped angle jumps (so no vertical line is drawn across the wrap).
pub(super) fn view_rows(
    series: &PhasorSeries,
    view: PhasorView,
    row: usize,
    scale: f64,
) -> Vec<Vec<(f64, f64)>> {
    let mut pts: Vec<(f64, Complex<f64>)> = series
        .points
        .iter()
        .copied()
        .filter(|(s, q)| s.is_finite() && q.re.is_finite() && q.im.is_finite())
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let values: Vec<(f64, f64)> = match (view, row) {
        (PhasorView::Engineer(_), 0) => pts
            .iter()
            .map(|&(s, q)| (s, peak_to_peak_and_lag(q).0 * scale))
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
    match (view, row) {
        (PhasorView::Engineer(_), 0) => format!("Amplitude [{u} p-p]"),
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

/// A line or marker series ready for one chart.
pub(super) struct Curve {
    name: String,
    mark: Mark,
    colour: RGBColor,
    segments: Vec<Vec<(f64, f64)>>,
}

/// Draws one chart with curves into `area`.
#[allow(clippy::too_many_arguments)]
pub(super) fn draw_chart<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    caption: &str,
    x_range: (f64, f64),
    y_range: (f64, f64),
    y_step: Option<f64>,
    y_label: &str,
    curves: &[Curve],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing chart '{caption}': {e:?}");
    let mut builder = ChartBuilder::on(area);
    builder
        .margin(12)
        .x_label_area_size(46)
        .y_label_area_size(70);
    if !caption.is_empty() {
        builder.caption(caption, (FONT, 20));
    }
    let y_ticks = match y_step {
        Some(step) if step > 0.0 => ticks_with_step(y_range, step),
        _ => nice_ticks(y_range, 8),
    };
    let x_ticks = nice_ticks(x_range, 10);
    let x_light = light_ticks(&x_ticks, x_range);
    let y_light = light_ticks(&y_ticks, y_range);
    let mut chart = builder
        .build_cartesian_2d(
            TickedAxis {
                range: x_range,
                bold: x_ticks,
                light: x_light,
            },
            TickedAxis {
                range: y_range,
                bold: y_ticks,
                light: y_light,
            },
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("Rotor speed [Hz]")
        .y_desc(y_label)
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 16))
        .light_line_style(RGBColor(240, 240, 240))
        .bold_line_style(RGBColor(205, 205, 205))
        .y_label_formatter(&|v| format_tick(*v))
        .x_label_formatter(&|v| format_tick(*v))
        .draw()
        .map_err(err)?;
    for c in curves {
        let colour = c.colour;
        let mut labelled = false;
        for seg in c.segments.iter().filter(|s| !s.is_empty()) {
            let anno = match c.mark {
                Mark::Line => chart
                    .draw_series(LineSeries::new(seg.iter().copied(), colour.stroke_width(2)))
                    .map_err(err)?,
                Mark::Markers => chart
                    .draw_series(
                        seg.iter()
                            .map(|&p| Circle::new(p, 3, colour.stroke_width(1))),
                    )
                    .map_err(err)?,
            };
            if !labelled {
                labelled = true;
                let mark = c.mark;
                anno.label(c.name.clone()).legend(move |(x, y)| {
                    let line_colour = match mark {
                        Mark::Line => colour.to_rgba(),
                        Mark::Markers => TRANSPARENT,
                    };
                    let circle_colour = match mark {
                        Mark::Line => TRANSPARENT,
                        Mark::Markers => colour.to_rgba(),
                    };
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (20, 0)], line_colour.stroke_width(2))
                        + Circle::new((10, 0), 3, circle_colour.stroke_width(1))
                });
            }
        }
    }
    if curves
        .iter()
        .any(|c| c.segments.iter().any(|s| !s.is_empty()))
    {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font((FONT, 14))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(150, 150, 150))
            .draw()
            .map_err(err)?;
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

impl PhasorFigure {
    /// Checks the figure has something to draw.
    fn check(&self) -> Result<()> {
        if self.panels.is_empty() {
            return Err(anyhow!("figure '{}' has no panels", self.title));
        }
        Ok(())
    }

    /// Draws the figure into a drawing area of any plotters backend.
    pub fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        ensure_fonts()?;
        self.check()?;
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| {
            anyhow!("drawing figure '{}': {e:?}", self.title)
        };
        root.fill(&WHITE).map_err(err)?;
        let body = root
            .titled(
                &self.title,
                (FONT, title_size(&self.title, root.dim_in_pixel().0)),
            )
            .map_err(err)?;
        let rows: Vec<usize> = match self.rows {
            Rows::Both => vec![0, 1],
            Rows::First => vec![0],
            Rows::Second => vec![1],
        };
        let cells = body.split_evenly((rows.len(), self.panels.len()));
        let scale = self.quantity.scale();
        let x_range = speed_range(
            self.panels
                .iter()
                .flat_map(|p| p.series.iter())
                .flat_map(|s| s.points.iter().map(|(sp, _)| sp)),
        );
        for (ri, &row) in rows.iter().enumerate() {
            for (pi, panel) in self.panels.iter().enumerate() {
                let names: Vec<&str> = panel.series.iter().map(|s| s.name.as_str()).collect();
                let curves: Vec<Curve> = panel
                    .series
                    .iter()
                    .enumerate()
                    .map(|(i, s)| Curve {
                        name: s.name.clone(),
                        mark: s.mark,
                        colour: colour_for(&names, i),
                        segments: view_rows(s, self.view, row, scale),
                    })
                    .collect();
                let (y_range, step) = match row_fixed_range(self.view, row) {
                    Some((r, s)) => (r, Some(s)),
                    None => (
                        padded_range(
                            curves
                                .iter()
                                .flat_map(|c| c.segments.iter().flatten().map(|p| p.1)),
                            row_from_zero(self.view, row),
                            // Room above the data for the legend.
                            if row == 0 { 0.3 } else { 0.1 },
                        ),
                        None,
                    ),
                };
                let caption = if ri == 0 { panel.title.as_str() } else { "" };
                draw_chart(
                    &cells[ri * self.panels.len() + pi],
                    caption,
                    x_range,
                    y_range,
                    step,
                    &row_label(self.view, row, self.quantity),
                    &curves,
                )?;
            }
        }
        Ok(())
    }

    /// Pixel size that keeps each chart readable.
    fn size(&self) -> (u32, u32) {
        let rows = if self.rows == Rows::Both { 2 } else { 1 };
        let cols = self.panels.len().max(1) as u32;
        ((560 * cols).max(900), 60 + 420 * rows)
    }

    /// Writes `<stem>.png` and `<stem>.svg`; returns both paths.
    pub fn write(&self, stem: &Path) -> Result<[PathBuf; 2]> {
        write_both(
            stem,
            self.size(),
            |root| self.draw(root),
            |root| self.draw(root),
        )
    }
}

impl ScalarFigure {
    /// Draws the figure into a drawing area of any plotters backend.
    pub fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        ensure_fonts()?;
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| {
            anyhow!("drawing figure '{}': {e:?}", self.title)
        };
        root.fill(&WHITE).map_err(err)?;
        let body = root
            .titled(
                &self.title,
                (FONT, title_size(&self.title, root.dim_in_pixel().0)),
            )
            .map_err(err)?;
        let names: Vec<&str> = self.series.iter().map(|s| s.name.as_str()).collect();
        let curves: Vec<Curve> = self
            .series
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let mut pts: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .copied()
                    .filter(|(x, y)| x.is_finite() && y.is_finite())
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                Curve {
                    name: s.name.clone(),
                    mark: s.mark,
                    colour: colour_for(&names, i),
                    segments: vec![pts],
                }
            })
            .collect();
        let x_range = speed_range(
            self.series
                .iter()
                .flat_map(|s| s.points.iter().map(|(x, _)| x)),
        );
        let y_range = self.y_range.unwrap_or_else(|| {
            padded_range(
                curves
                    .iter()
                    .flat_map(|c| c.segments.iter().flatten().map(|p| p.1)),
                false,
                0.1,
            )
        });
        draw_chart(
            &body,
            "",
            x_range,
            y_range,
            self.y_tick_step,
            &self.y_label,
            &curves,
        )
    }

    /// Writes `<stem>.png` and `<stem>.svg`; returns both paths.
    pub fn write(&self, stem: &Path) -> Result<[PathBuf; 2]> {
        write_both(
            stem,
            (1000, 600),
            |root| self.draw(root),
            |root| self.draw(root),
        )
    }
}
