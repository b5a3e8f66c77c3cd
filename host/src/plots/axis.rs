//! Axes: tick positions (nice steps, fixed steps, light minor ticks) and
//! their labels.

use plotters::prelude::*;

/// A linear f64 axis with tick positions chosen by this module (plotters'
/// own choice cannot be forced to multiples of 90° for phase axes).
#[derive(Clone)]
pub(super) struct TickedAxis {
    pub(super) range: (f64, f64),
    pub(super) bold: Vec<f64>,
    pub(super) light: Vec<f64>,
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
pub(super) fn ticks_with_step(range: (f64, f64), step: f64) -> Vec<f64> {
    let first = (range.0 / step - 1e-9).ceil() as i64;
    let last = (range.1 / step + 1e-9).floor() as i64;
    (first..=last).map(|i| i as f64 * step).collect()
}

/// About `target` tick positions at 1, 2 or 5 × 10^n spacing inside `range`.
pub(super) fn nice_ticks(range: (f64, f64), target: usize) -> Vec<f64> {
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
pub(super) fn light_ticks(major: &[f64], range: (f64, f64)) -> Vec<f64> {
    let step = match major {
        [a, b, ..] => (b - a) / 5.0,
        _ => return Vec::new(),
    };
    ticks_with_step(range, step)
}

/// Tick label: at most 4 significant digits, no trailing zeros.
pub(super) fn format_tick(v: f64) -> String {
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
