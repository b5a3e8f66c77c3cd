//! Plots an engineer puts in a report: 1X amplitude and phase against rotor
//! speed, the phase difference between a pedestal's response and the force
//! transmitted to it, and measured-versus-predicted overlays.
//!
//! Every figure is written twice, as PNG (bitmap) and SVG, from the same
//! drawing code. Text is laid out with a bundled font (DejaVu Sans, Bitstream
//! Vera licence, `host/assets/fonts/`) registered with plotters' `ab_glyph`
//! backend, so figures render identically on a machine without any system
//! fonts (CI containers, a newcomer's fresh laptop).
//!
//! Phasor conventions (formats.md): a signal q(t) has phasor Q when
//! q(t) = Re{Q·e^{iΩt}}, t = 0 at the keyphasor. The engineer's view
//! ([`PhasorView::Engineer`]) shows what field instruments print: the
//! peak-to-peak amplitude 2|Q| and the phase *lag* −arg Q in degrees, either
//! wrapped to [0, 360) or unwrapped along the speed axis (continuous, starting
//! in [0, 360) at the lowest speed). The raw views show the complex number
//! itself: real and imaginary parts, or |Q| and the angle arg Q (a lead,
//! wrapped to (−180, 180]).

use anyhow::{anyhow, Context, Result};
use num_complex::Complex;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The bundled sans-serif font (DejaVu Sans 2.37, Bitstream Vera licence).
static DEJAVU_SANS: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// Font family name every figure uses; registered once with [`ensure_fonts`].
const FONT: &str = "sans-serif";

/// Registers the bundled font with plotters (idempotent, thread-safe).
///
/// Called by every drawing function; public so callers that draw their own
/// plotters charts get the same font.
pub fn ensure_fonts() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, DEJAVU_SANS).is_ok()
            && plotters::style::register_font(FONT, FontStyle::Bold, DEJAVU_SANS).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(anyhow!(
            "the bundled font DejaVuSans.ttf could not be parsed"
        ))
    }
}

/// What a phasor's magnitude measures, for axis labels and scaling.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// Displacement: phasors in m, plotted in µm.
    DisplacementMicrons,
    /// Force: phasors in N, plotted in N.
    ForceNewtons,
    /// Force: phasors in N, plotted in kN.
    ForceKilonewtons,
}

impl Quantity {
    /// Factor from the phasor's SI unit to the plotted unit.
    pub fn scale(self) -> f64 {
        match self {
            Quantity::DisplacementMicrons => 1e6,
            Quantity::ForceNewtons => 1.0,
            Quantity::ForceKilonewtons => 1e-3,
        }
    }

    /// Unit symbol of the plotted values.
    pub fn unit(self) -> &'static str {
        match self {
            Quantity::DisplacementMicrons => "µm",
            Quantity::ForceNewtons => "N",
            Quantity::ForceKilonewtons => "kN",
        }
    }
}

/// How the phase of an engineer's plot is shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhaseStyle {
    /// Phase lag −arg Q in degrees, wrapped to [0, 360); lines break at wraps.
    Wrapped,
    /// Phase lag in degrees made continuous along increasing speed, starting
    /// in [0, 360) at the lowest speed.
    Unwrapped,
}

/// Which pair of rows a phasor figure shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhasorView {
    /// Peak-to-peak amplitude 2|Q| and phase lag [deg] (field instruments).
    Engineer(PhaseStyle),
    /// Re Q and Im Q of q(t) = Re{Q·e^{iΩt}}.
    ReIm,
    /// |Q| (zero-to-peak) and arg Q [deg] in (−180, 180].
    AmplitudeAngle,
}

/// Which rows of a phasor figure are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rows {
    /// The magnitude-like row (amplitude, or Re) and the angle-like row.
    Both,
    /// Only the magnitude-like row (e.g. the paper's Figs. 3 and 7).
    First,
    /// Only the angle-like row (e.g. the paper's Figs. 4 and 8).
    Second,
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// A solid line through the points.
    Line,
    /// Hollow circles at the points (measured data over a predicted line).
    Markers,
}

/// One named curve of 1X phasors against rotor speed.
#[derive(Clone, Debug, PartialEq)]
pub struct PhasorSeries {
    /// Legend entry, e.g. `Ly` (left bearing, vertical).
    pub name: String,
    /// (rotor speed [Hz], phasor [SI unit of the figure's quantity]).
    pub points: Vec<(f64, Complex<f64>)>,
    /// Line or markers.
    pub mark: Mark,
}

impl PhasorSeries {
    /// A solid-line series.
    pub fn line(name: impl Into<String>, points: Vec<(f64, Complex<f64>)>) -> Self {
        Self {
            name: name.into(),
            points,
            mark: Mark::Line,
        }
    }

    /// A marker series.
    pub fn markers(name: impl Into<String>, points: Vec<(f64, Complex<f64>)>) -> Self {
        Self {
            name: name.into(),
            points,
            mark: Mark::Markers,
        }
    }
}

/// One named curve of real values against rotor speed.
#[derive(Clone, Debug, PartialEq)]
pub struct ScalarSeries {
    /// Legend entry.
    pub name: String,
    /// (rotor speed [Hz], value [unit of the panel's y axis]).
    pub points: Vec<(f64, f64)>,
    /// Line or markers.
    pub mark: Mark,
}

/// A panel (one column of a phasor figure) with its own subtitle.
#[derive(Clone, Debug, PartialEq)]
pub struct PhasorPanel {
    /// Panel subtitle, e.g. "Rotor (relative to pedestal)".
    pub title: String,
    /// The curves in this panel.
    pub series: Vec<PhasorSeries>,
}

/// A figure of 1X phasors against speed: one column per panel, one or two
/// rows depending on [`Rows`].
#[derive(Clone, Debug, PartialEq)]
pub struct PhasorFigure {
    /// Figure title.
    pub title: String,
    /// What the phasors measure (axis units).
    pub quantity: Quantity,
    /// Engineer's or raw complex view.
    pub view: PhasorView,
    /// Which rows to draw.
    pub rows: Rows,
    /// Columns of the figure.
    pub panels: Vec<PhasorPanel>,
}

/// A figure of real values against speed (e.g. phase differences).
#[derive(Clone, Debug, PartialEq)]
pub struct ScalarFigure {
    /// Figure title.
    pub title: String,
    /// Y-axis label with unit, e.g. "Phase difference [deg]".
    pub y_label: String,
    /// Fixed y range, or `None` to fit the data.
    pub y_range: Option<(f64, f64)>,
    /// Spacing of y tick marks, or `None` for plotters' choice.
    pub y_tick_step: Option<f64>,
    /// The curves.
    pub series: Vec<ScalarSeries>,
}

/// Peak-to-peak amplitude [unit of Q] and phase lag [deg, 0-360] of a phasor.
pub fn peak_to_peak_and_lag(q: Complex<f64>) -> (f64, f64) {
    plinth_shared::phasor::peak_to_peak_and_lag_deg(q)
}

/// Phase lag of `response` behind `force` [deg], wrapped to [−180, 180).
///
/// For a pedestal (−Ω²m + iΩc + k)·X = F this is atan2(Ωc, k − Ω²m): 0 below
/// the pedestal's resonance, 180 above, 90 at it (the paper's Figs. 5 and 9).
pub fn phase_lag_deg(response: Complex<f64>, force: Complex<f64>) -> f64 {
    wrap_deg_pm180((force.arg() - response.arg()).to_degrees())
}

/// Wraps an angle [deg] to [−180, 180).
pub fn wrap_deg_pm180(deg: f64) -> f64 {
    (deg + 180.0).rem_euclid(360.0) - 180.0
}

/// Makes a sequence of angles [deg] continuous: each value is moved by a
/// multiple of 360 to lie within 180 of its predecessor.
pub fn unwrap_deg(angles: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(angles.len());
    let mut prev: Option<f64> = None;
    for &a in angles {
        let v = match prev {
            None => a,
            Some(p) => a - 360.0 * ((a - p) / 360.0).round(),
        };
        out.push(v);
        prev = Some(v);
    }
    out
}

/// The (speed, value) rows of one view row of a series, split into segments
/// where a wrapped angle jumps (so no vertical line is drawn across the wrap).
fn view_rows(
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

/// Splits a curve where consecutive wrapped angles differ by more than 180°.
fn split_at_wraps(values: Vec<(f64, f64)>, wrapped: bool) -> Vec<Vec<(f64, f64)>> {
    if !wrapped {
        return vec![values];
    }
    let mut segments: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    for v in values {
        if let Some(last) = segments.last().and_then(|s| s.last()) {
            if (v.1 - last.1).abs() > 180.0 {
                segments.push(Vec::new());
            }
        }
        if let Some(seg) = segments.last_mut() {
            seg.push(v);
        }
    }
    segments
}

/// Axis label of one row of a phasor figure.
fn row_label(view: PhasorView, row: usize, quantity: Quantity) -> String {
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
fn row_fixed_range(view: PhasorView, row: usize) -> Option<((f64, f64), f64)> {
    match (view, row) {
        (PhasorView::Engineer(PhaseStyle::Wrapped), 1) => Some(((0.0, 360.0), 90.0)),
        (PhasorView::AmplitudeAngle, 1) => Some(((-180.0, 180.0), 90.0)),
        _ => None,
    }
}

/// Whether a row's axis should start at zero (amplitudes).
fn row_from_zero(view: PhasorView, row: usize) -> bool {
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
fn colour_for(names: &[&str], i: usize) -> RGBColor {
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
fn padded_range(
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
struct Curve {
    name: String,
    mark: Mark,
    colour: RGBColor,
    segments: Vec<Vec<(f64, f64)>>,
}

/// Draws one chart with curves into `area`.
#[allow(clippy::too_many_arguments)]
fn draw_chart<DB: DrawingBackend>(
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

/// A linear f64 axis with tick positions chosen by this module (plotters'
/// own choice cannot be forced to multiples of 90° for phase axes).
#[derive(Clone)]
struct TickedAxis {
    range: (f64, f64),
    bold: Vec<f64>,
    light: Vec<f64>,
}

impl Ranged for TickedAxis {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let (lo, hi) = self.range;
        if hi <= lo {
            return (limit.0 + limit.1) / 2;
        }
        let t = ((value - lo) / (hi - lo)).clamp(-10.0, 10.0);
        limit.0 + (t * f64::from(limit.1 - limit.0)).round() as i32
    }

    fn key_points<Hint: plotters::coord::ranged1d::KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.light.clone()
        } else {
            self.bold.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.range.0..self.range.1
    }
}

/// Tick positions at multiples of `step` inside `range`.
fn ticks_with_step(range: (f64, f64), step: f64) -> Vec<f64> {
    let first = (range.0 / step - 1e-9).ceil() as i64;
    let last = (range.1 / step + 1e-9).floor() as i64;
    (first..=last).map(|i| i as f64 * step).collect()
}

/// About `target` tick positions at 1, 2 or 5 × 10^n spacing inside `range`.
fn nice_ticks(range: (f64, f64), target: usize) -> Vec<f64> {
    let span = range.1 - range.0;
    if span.is_nan() || span <= 0.0 || !span.is_finite() {
        return vec![range.0];
    }
    let raw = span / target.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    ticks_with_step(range, step)
}

/// Minor grid lines: five per major interval.
fn light_ticks(major: &[f64], range: (f64, f64)) -> Vec<f64> {
    let step = match major {
        [a, b, ..] => (b - a) / 5.0,
        _ => return Vec::new(),
    };
    ticks_with_step(range, step)
}

/// Title font size [px] that fits `title` into `width` pixels (DejaVu Sans
/// averages about 0.55 em per character), at most 26.
fn title_size(title: &str, width: u32) -> f64 {
    let chars = title.chars().count().max(1) as f64;
    (0.95 * f64::from(width) / (0.55 * chars)).clamp(12.0, 26.0)
}

/// Tick label: at most 4 significant digits, no trailing zeros.
fn format_tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        return format!("{v:.1e}");
    }
    let decimals = (3 - a.log10().floor() as i32).clamp(0, 6) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Speed range over all points, never empty.
fn speed_range<'a>(speeds: impl Iterator<Item = &'a f64>) -> (f64, f64) {
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

/// Renders a figure once to PNG and once to SVG beside each other.
pub fn write_both(
    stem: &Path,
    size: (u32, u32),
    png: impl FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>) -> Result<()>,
    svg: impl FnOnce(&DrawingArea<SVGBackend<'_>, Shift>) -> Result<()>,
) -> Result<[PathBuf; 2]> {
    let png_path = stem.with_extension("png");
    let svg_path = stem.with_extension("svg");
    if let Some(dir) = stem.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("creating figure directory {}", dir.display()))?;
    }
    {
        let root = BitMapBackend::new(&png_path, size).into_drawing_area();
        png(&root).with_context(|| format!("rendering {}", png_path.display()))?;
        root.present()
            .map_err(|e| anyhow!("writing {}: {e:?}", png_path.display()))?;
    }
    {
        let root = SVGBackend::new(&svg_path, size).into_drawing_area();
        svg(&root).with_context(|| format!("rendering {}", svg_path.display()))?;
        root.present()
            .map_err(|e| anyhow!("writing {}: {e:?}", svg_path.display()))?;
    }
    Ok([png_path, svg_path])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn resonance(k: f64, m: f64, c: f64) -> Vec<(f64, Complex<f64>)> {
        (1..=200)
            .map(|i| {
                let f = i as f64;
                let w = std::f64::consts::TAU * f;
                let x = Complex::new(1e-3, 0.0) / Complex::new(k - w * w * m, w * c);
                (f, x)
            })
            .collect()
    }

    #[test]
    fn unwrap_removes_jumps() {
        let u = unwrap_deg(&[350.0, 10.0, 30.0, 300.0]);
        assert_eq!(u, vec![350.0, 370.0, 390.0, 300.0]);
    }

    #[test]
    fn phase_lag_of_a_pedestal_goes_from_0_to_180() {
        let (k, m, c): (f64, f64, f64) = (1e7, 100.0, 500.0);
        let fr = (k / m).sqrt() / std::f64::consts::TAU;
        for (f, x) in resonance(k, m, c) {
            let lag = phase_lag_deg(x, Complex::new(1e-3, 0.0));
            assert!((-1e-9..=180.0).contains(&lag), "lag {lag} at {f}");
            if f < 0.5 * fr {
                assert!(lag < 10.0);
            }
            if f > 2.0 * fr {
                assert!(lag > 170.0);
            }
        }
    }

    #[test]
    fn wrapped_phase_is_split_at_wraps() {
        let s = PhasorSeries::line(
            "x",
            vec![
                (1.0, Complex::from_polar(1.0, -350f64.to_radians())),
                (2.0, Complex::from_polar(1.0, -5f64.to_radians())),
                (3.0, Complex::from_polar(1.0, -15f64.to_radians())),
            ],
        );
        let segs = view_rows(&s, PhasorView::Engineer(PhaseStyle::Wrapped), 1, 1.0);
        assert_eq!(segs.len(), 2);
        let segs = view_rows(&s, PhasorView::Engineer(PhaseStyle::Unwrapped), 1, 1.0);
        assert_eq!(segs.len(), 1);
        assert!((segs[0][1].1 - 365.0).abs() < 1e-9);
    }

    #[test]
    fn figures_render_to_png_and_svg() {
        let dir = tempfile::tempdir().unwrap();
        let keep = std::env::var_os("PLINTH_PLOT_DIR");
        let out = keep
            .as_ref()
            .map(std::path::PathBuf::from)
            .unwrap_or_else(|| dir.path().to_path_buf());
        let a = resonance(1e7, 100.0, 0.0);
        let b = resonance(1.5e7, 80.0, 2000.0);
        let fig = PhasorFigure {
            title: "Test response".into(),
            quantity: Quantity::DisplacementMicrons,
            view: PhasorView::Engineer(PhaseStyle::Wrapped),
            rows: Rows::Both,
            panels: vec![
                PhasorPanel {
                    title: "Rotor (relative)".into(),
                    series: vec![
                        PhasorSeries::line("Ly", a.clone()),
                        PhasorSeries::line("Lz", b.clone()),
                    ],
                },
                PhasorPanel {
                    title: "Pedestal (absolute)".into(),
                    series: vec![
                        PhasorSeries::markers(
                            "Ly measured",
                            a.iter().step_by(5).copied().collect(),
                        ),
                        PhasorSeries::line("Ly predicted", a.clone()),
                    ],
                },
            ],
        };
        let [png, svg] = fig.write(&out.join("test_response")).unwrap();
        let bytes = std::fs::read(&png).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.starts_with("<svg") && text.contains("Rotor speed [Hz]"));
        let diff = ScalarFigure {
            title: "Phase difference".into(),
            y_label: "Lag of response behind force [deg]".into(),
            y_range: Some((-30.0, 210.0)),
            y_tick_step: Some(30.0),
            series: vec![ScalarSeries {
                name: "Ly".into(),
                points: b
                    .iter()
                    .map(|&(f, x)| (f, phase_lag_deg(x, Complex::new(1e-3, 0.0))))
                    .collect(),
                mark: Mark::Line,
            }],
        };
        diff.write(&out.join("test_phase_diff")).unwrap();
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(format_tick(0.0), "0");
        assert_eq!(format_tick(90.0), "90");
        assert_eq!(format_tick(2.5), "2.5");
        assert_eq!(format_tick(12.3456), "12.35");
    }
}
