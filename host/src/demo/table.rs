//! The demo's result table: per pedestal and parameter, the true value, the
//! box's final recursive (RLS) estimate, the batch least-squares fit of the
//! run directory, and their differences.

use crate::identify::Identification;
use crate::rundir::Truth;
use crate::stream::report::PedestalComparison;
use serde::Serialize;

/// One parameter of one pedestal: truth, box, batch and their differences.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ComparisonRow {
    /// Bearing (pedestal) name.
    pub bearing: String,
    /// Parameter name (formats.md: k_y, k_z, m, c_y, c_z).
    pub parameter: String,
    /// Unit of every value in this row (N/m, kg, N·s/m).
    pub unit: String,
    /// The machine's value (`null` if the machine has no pedestal there).
    pub truth: Option<f64>,
    /// The box's final RLS estimate.
    pub box_value: Option<f64>,
    /// Its standard error.
    pub box_std_err: Option<f64>,
    /// The batch least-squares value.
    pub batch_value: Option<f64>,
    /// Its standard error.
    pub batch_std_err: Option<f64>,
    /// 100·(box − truth)/|truth| [%].
    pub box_error_pct: Option<f64>,
    /// 100·(batch − truth)/|truth| [%].
    pub batch_error_pct: Option<f64>,
    /// (batch − truth)/batch standard error: how many standard errors the
    /// batch fit is off.
    pub batch_error_sigmas: Option<f64>,
    /// 100·(box − batch)/|batch| [%].
    pub box_minus_batch_pct: Option<f64>,
}

fn pct(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) if b != 0.0 => Some(100.0 * (a - b) / b.abs()),
        _ => None,
    }
}

/// The table rows from the stream's box-vs-batch comparison and the truth.
pub fn rows(comparisons: &[PedestalComparison], truth: &Truth) -> Vec<ComparisonRow> {
    let mut out = Vec::new();
    for c in comparisons {
        let t = truth.pedestals.iter().find(|p| p.bearing == c.bearing);
        for p in &c.parameters {
            let tv = t.map(|t| match p.parameter {
                "k_y" => t.k_y,
                "k_z" => t.k_z,
                "m" => t.m,
                "c_y" => t.c_y,
                _ => t.c_z,
            });
            let sigmas = match (p.batch_value, tv, p.batch_std_err) {
                (Some(b), Some(t), Some(s)) if s > 0.0 => Some((b - t) / s),
                _ => None,
            };
            out.push(ComparisonRow {
                bearing: c.bearing.clone(),
                parameter: p.parameter.to_string(),
                unit: p.unit.to_string(),
                truth: tv,
                box_value: p.box_value,
                box_std_err: p.box_std_err,
                batch_value: p.batch_value,
                batch_std_err: p.batch_std_err,
                box_error_pct: pct(p.box_value, tv),
                batch_error_pct: pct(p.batch_value, tv),
                batch_error_sigmas: sigmas,
                box_minus_batch_pct: pct(p.box_value, p.batch_value),
            });
        }
    }
    out
}

/// Display unit and factor from SI of a parameter's unit.
fn display_unit(unit: &str) -> (&'static str, f64) {
    match unit {
        "N/m" => ("MN/m", 1e-6),
        "kg" => ("kg", 1.0),
        _ => ("N·s/m", 1.0),
    }
}

/// `v ± s` in display units, the value to the decimal of the standard
/// error's second significant digit (5 significant digits without one).
fn value_pm(v: Option<f64>, s: Option<f64>, k: f64) -> String {
    let Some(v) = v else {
        return "—".into();
    };
    let v = v * k;
    match s.map(|s| s * k) {
        Some(s) if s.is_finite() && s > 0.0 => {
            let decimals = (1 - s.log10().floor() as i32).clamp(0, 9) as usize;
            format!("{v:.decimals$} ± {}", sig(s, 2))
        }
        _ => sig(v, 5),
    }
}

/// `x` with `digits` significant digits.
fn sig(x: f64, digits: usize) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x == 0.0 {
        return "0".into();
    }
    let mag = x.abs().log10().floor() as i32;
    if !(-4..9).contains(&mag) {
        return format!("{:.*e}", digits.saturating_sub(1), x);
    }
    let decimals = (digits as i32 - 1 - mag).max(0) as usize;
    format!("{x:.decimals$}")
}

fn pct_text(x: Option<f64>) -> String {
    x.map_or("—".into(), |v| format!("{v:+.2}%"))
}

/// The table as aligned text, one block per pedestal.
pub fn render(rows: &[ComparisonRow], identification: &Identification) -> String {
    let mut s = String::new();
    let mut bearings: Vec<&str> = Vec::new();
    for r in rows {
        if !bearings.contains(&r.bearing.as_str()) {
            bearings.push(&r.bearing);
        }
    }
    for b in bearings {
        let fit = identification.pedestal(b);
        s.push_str(&format!(
            "pedestal {b}: box RLS vs batch least squares{} vs truth\n",
            fit.map_or(String::new(), |f| format!(
                " ({} speeds {:.1}-{:.1} Hz, condition {:.1e}{})",
                f.speeds,
                f.speed_range_hz[0],
                f.speed_range_hz[1],
                f.condition_number,
                if f.trusted { "" } else { ", NOT TRUSTED" }
            ))
        ));
        let mut table: Vec<[String; 9]> = vec![[
            "".into(),
            "unit".into(),
            "truth".into(),
            "box RLS ± σ".into(),
            "batch ± σ".into(),
            "box−truth".into(),
            "batch−truth".into(),
            "[σ]".into(),
            "box−batch".into(),
        ]];
        for r in rows.iter().filter(|r| r.bearing == b) {
            let (unit, k) = display_unit(&r.unit);
            table.push([
                r.parameter.clone(),
                unit.into(),
                r.truth.map_or("—".into(), |t| sig(t * k, 6)),
                value_pm(r.box_value, r.box_std_err, k),
                value_pm(r.batch_value, r.batch_std_err, k),
                pct_text(r.box_error_pct),
                pct_text(r.batch_error_pct),
                r.batch_error_sigmas
                    .map_or("—".into(), |v| format!("{v:+.1}")),
                pct_text(r.box_minus_batch_pct),
            ]);
        }
        let widths: Vec<usize> = (0..9)
            .map(|c| {
                table
                    .iter()
                    .map(|r| r[c].chars().count())
                    .max()
                    .unwrap_or(0)
            })
            .collect();
        for row in &table {
            let mut line = String::from("  ");
            for (c, cell) in row.iter().enumerate() {
                let pad = widths[c].saturating_sub(cell.chars().count());
                if c <= 1 {
                    line.push_str(cell);
                    line.push_str(&" ".repeat(pad));
                } else {
                    line.push_str(&" ".repeat(pad));
                    line.push_str(cell);
                }
                line.push_str("  ");
            }
            s.push_str(line.trim_end());
            s.push('\n');
        }
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn value_and_standard_error_share_decimals() {
        assert_eq!(
            value_pm(Some(9.98765e6), Some(1.2e4), 1e-6),
            "9.988 ± 0.012"
        );
        assert_eq!(value_pm(Some(149.87), Some(0.25), 1.0), "149.87 ± 0.25");
        assert_eq!(value_pm(Some(105.0), None, 1.0), "105.00");
        assert_eq!(value_pm(None, None, 1.0), "—");
        assert_eq!(pct(Some(101.0), Some(100.0)), Some(1.0));
        assert_eq!(pct(Some(1.0), Some(0.0)), None);
    }
}
