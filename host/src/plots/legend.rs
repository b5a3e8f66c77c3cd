//! Legends beside the data: a column to the right of each chart, never over
//! a curve (a legend inside the plot area hid the demo's 27 and 45 Hz peaks).

use super::FONT;
use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Width [px] of the legend column beside a chart.
pub(super) const LEGEND_WIDTH: u32 = 210;

/// How an entry is drawn in the legend.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Swatch {
    /// A solid line (a model, a simulation).
    Line,
    /// A hollow circle (measured points).
    Marker,
    /// A shaded block (an uncertainty band).
    Band,
}

/// One line of a legend.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct LegendEntry {
    pub(super) name: String,
    pub(super) colour: RGBColor,
    pub(super) swatch: Swatch,
}

/// Splits `cell` into the chart's area and, when `entries` is non-empty,
/// the legend column to its right.
pub(super) fn beside<DB: DrawingBackend>(
    cell: &DrawingArea<DB, Shift>,
    with_legend: bool,
) -> (DrawingArea<DB, Shift>, Option<DrawingArea<DB, Shift>>) {
    let width = cell.dim_in_pixel().0;
    if !with_legend || width <= 2 * LEGEND_WIDTH {
        return (cell.clone(), None);
    }
    let (chart, legend) = cell.split_horizontally(width - LEGEND_WIDTH);
    (chart, Some(legend))
}

/// Draws `entries` top-down in `area` (the legend column): a framed list,
/// long names cut to fit with an ellipsis.
pub(super) fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    if entries.is_empty() {
        return Ok(());
    }
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing a legend: {e:?}");
    let line_h = 20;
    let top = 40;
    let (w, _) = area.dim_in_pixel();
    let w = w as i32;
    let height = line_h * entries.len() as i32 + 10;
    area.draw(&Rectangle::new(
        [(2, top - 6), (w - 6, top + height - 6)],
        RGBColor(170, 170, 170).stroke_width(1),
    ))
    .map_err(err)?;
    let max_chars = ((w - 46) as f64 / 7.5).max(4.0) as usize;
    for (i, e) in entries.iter().enumerate() {
        let y = top + 4 + i as i32 * line_h;
        match e.swatch {
            Swatch::Line => area
                .draw(&PathElement::new(
                    vec![(8, y), (32, y)],
                    e.colour.stroke_width(2),
                ))
                .map_err(err)?,
            Swatch::Marker => area
                .draw(&Circle::new((20, y), 3, e.colour.stroke_width(1)))
                .map_err(err)?,
            Swatch::Band => area
                .draw(&Rectangle::new(
                    [(8, y - 6), (32, y + 6)],
                    e.colour.mix(0.25).filled(),
                ))
                .map_err(err)?,
        }
        let name: String = if e.name.chars().count() > max_chars {
            let mut s: String = e.name.chars().take(max_chars - 1).collect();
            s.push('…');
            s
        } else {
            e.name.clone()
        };
        area.draw(&Text::new(
            name,
            (40, y - 8),
            (FONT, 14).into_font().color(&BLACK),
        ))
        .map_err(err)?;
    }
    Ok(())
}
