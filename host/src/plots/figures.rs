//! The figures: a phasor figure's panels and rows of charts, a scalar
//! figure, and their PNG/SVG output (`figure_output!`).

use super::*;
use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;

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
        self.check()?;
        let body = titled_page(root, &self.title)?;
        let rows: Vec<usize> = match self.rows {
            Rows::Both => vec![0, 1],
            Rows::First => vec![0],
            Rows::Second => vec![1],
        };
        let cells = body.split_evenly((rows.len(), self.panels.len()));
        let unit = self.style.speed_unit;
        let x_range = speed_axis(
            self.panels
                .iter()
                .flat_map(|p| p.series.iter())
                .flat_map(|s| s.points.iter().map(|(sp, _)| sp)),
            unit,
        );
        let x_label = unit.axis_label();
        for (ri, &row) in rows.iter().enumerate() {
            for (pi, panel) in self.panels.iter().enumerate() {
                let quantity = panel.quantity.unwrap_or(self.quantity);
                let log = self.style.log_amplitude && row_from_zero(self.view, row);
                let names: Vec<&str> = panel.series.iter().map(|s| s.name.as_str()).collect();
                let curves: Vec<Curve> = panel
                    .series
                    .iter()
                    .enumerate()
                    .map(|(i, s)| Curve {
                        name: s.name.clone(),
                        mark: s.mark,
                        colour: colour_for(&names, i),
                        segments: in_speed_unit(view_rows(s, self.view, row, quantity, log), unit),
                    })
                    .collect();
                let (y_range, step) = match row_fixed_range(self.view, row) {
                    Some((r, s)) => (r, Some(s)),
                    None => (
                        padded_range(
                            curves
                                .iter()
                                .flat_map(|c| c.segments.iter().flatten().map(|p| p.1)),
                            row_from_zero(self.view, row) && !log,
                            0.08,
                        ),
                        None,
                    ),
                };
                let caption = if ri == 0 { panel.title.as_str() } else { "" };
                let entries: Vec<LegendEntry> = curves
                    .iter()
                    .filter(|c| c.has_points())
                    .map(Curve::entry)
                    .collect();
                let y_label = row_label(self.view, row, quantity);
                draw_cell(
                    &cells[ri * self.panels.len() + pi],
                    &Axes {
                        caption,
                        x_range,
                        x_label: &x_label,
                        y_range,
                        y_step: step,
                        y_label: &y_label,
                        log_y: log,
                    },
                    &[],
                    &curves,
                    &entries,
                    ri == 0,
                )?;
            }
        }
        Ok(())
    }

    /// Pixel size that keeps each chart readable.
    fn size(&self) -> (u32, u32) {
        let rows = if self.rows == Rows::Both { 2 } else { 1 };
        let cols = self.panels.len().max(1) as u32;
        ((700 * cols).max(1000), 60 + 420 * rows)
    }
}

figure_output!(PhasorFigure);

/// Segments with their x (speed [Hz]) in `unit`.
pub(super) fn in_speed_unit(
    segments: Vec<Vec<(f64, f64)>>,
    unit: SpeedUnit,
) -> Vec<Vec<(f64, f64)>> {
    let f = unit.factor();
    segments
        .into_iter()
        .map(|s| s.into_iter().map(|(x, y)| (x * f, y)).collect())
        .collect()
}

/// Renders a drawing of `size` pixels into an SVG document in memory.
pub fn svg_string(
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<SVGBackend<'_>, Shift>) -> Result<()>,
) -> Result<String> {
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        draw(&root)?;
        root.present()
            .map_err(|e| anyhow!("rendering an SVG figure: {e:?}"))?;
    }
    Ok(text)
}

impl ScalarFigure {
    /// Draws the figure into a drawing area of any plotters backend.
    pub fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let body = titled_page(root, &self.title)?;
        let unit = self.style.speed_unit;
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
                    segments: in_speed_unit(vec![pts], unit),
                }
            })
            .collect();
        let x_range = speed_axis(
            self.series
                .iter()
                .flat_map(|s| s.points.iter().map(|(x, _)| x)),
            unit,
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
        let entries: Vec<LegendEntry> = curves
            .iter()
            .filter(|c| c.has_points())
            .map(Curve::entry)
            .collect();
        draw_cell(
            &body,
            &Axes {
                caption: "",
                x_range,
                x_label: &unit.axis_label(),
                y_range,
                y_step: self.y_tick_step,
                y_label: &self.y_label,
                log_y: false,
            },
            &[],
            &curves,
            &entries,
            true,
        )
    }

    /// Pixel size: one chart.
    fn size(&self) -> (u32, u32) {
        (1100, 600)
    }
}

figure_output!(ScalarFigure);
