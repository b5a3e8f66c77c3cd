//! The demo's result table: per pedestal and parameter, the true value, the
//! box's final recursive (RLS, noise-weighted) estimate, the host's batch
//! fits of the run directory (the paper's OLS and the maximum-likelihood fit
//! `plinth identify` makes by default), each with its ± and its error
//! against the truth in % and in its own standard errors.

use crate::identify::{Identification, Parameter};
use crate::present::table::{self, sig};
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
    /// The batch least-squares value (the paper's OLS).
    pub batch_value: Option<f64>,
    /// Its standard error.
    pub batch_std_err: Option<f64>,
    /// The host's maximum-likelihood value (errors in variables).
    pub ml_value: Option<f64>,
    /// Its standard error (Fisher information).
    pub ml_std_err: Option<f64>,
    /// 100·(box − truth)/|truth| [%].
    pub box_error_pct: Option<f64>,
    /// 100·(batch − truth)/|truth| [%].
    pub batch_error_pct: Option<f64>,
    /// (batch − truth)/batch standard error: how many standard errors the
    /// batch fit is off.
    pub batch_error_sigmas: Option<f64>,
    /// 100·(ML − truth)/|truth| [%].
    pub ml_error_pct: Option<f64>,
    /// (ML − truth)/ML standard error: how many standard errors the ML fit
    /// is off.
    pub ml_error_sigmas: Option<f64>,
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
            let tv = t.map(|t| {
                Parameter::from_name(p.parameter).map_or(t.pedestal.c_z, |q| t.pedestal.get(q))
            });
            let sigmas = |v: Option<f64>, s: Option<f64>| match (v, tv, s) {
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
                ml_value: p.ml_value,
                ml_std_err: p.ml_std_err,
                box_error_pct: pct(p.box_value, tv),
                batch_error_pct: pct(p.batch_value, tv),
                batch_error_sigmas: sigmas(p.batch_value, p.batch_std_err),
                ml_error_pct: pct(p.ml_value, tv),
                ml_error_sigmas: sigmas(p.ml_value, p.ml_std_err),
                box_minus_batch_pct: pct(p.box_value, p.batch_value),
            });
        }
    }
    out
}

/// `v ± s` in display units (the shared printer's notation,
/// [`table::value_pm`]; 5 significant digits without a standard error).
fn value_pm(v: Option<f64>, s: Option<f64>, k: f64) -> String {
    let Some(v) = v else {
        return "—".into();
    };
    match s {
        Some(s) if s.is_finite() && s > 0.0 => table::value_pm(v * k, s * k),
        _ => sig(v * k, 5),
    }
}

fn pct_text(x: Option<f64>) -> String {
    x.map_or("—".into(), |v| format!("{v:+.2}%"))
}

/// The estimators shown side by side, in column order: (name, value,
/// standard error). The one place where a column is added.
pub fn estimators(r: &ComparisonRow) -> Vec<(&'static str, Option<f64>, Option<f64>)> {
    vec![
        ("box RLS", r.box_value, r.box_std_err),
        ("host OLS", r.batch_value, r.batch_std_err),
        ("host ML", r.ml_value, r.ml_std_err),
    ]
}

/// The table as aligned text, one block per pedestal: per estimator its
/// value ± σ, its error against the truth [%] and in its own σ. `ols` and
/// `ml` are the host's two fits (for the speeds used and whether each is
/// trusted).
pub fn render(rows: &[ComparisonRow], ols: &Identification, ml: &Identification) -> String {
    let mut s = String::new();
    let mut bearings: Vec<&str> = Vec::new();
    for r in rows {
        if !bearings.contains(&r.bearing.as_str()) {
            bearings.push(&r.bearing);
        }
    }
    for b in bearings {
        let fit = ml.pedestal(b).or_else(|| ols.pedestal(b));
        let mine: Vec<&ComparisonRow> = rows.iter().filter(|r| r.bearing == b).collect();
        let names: Vec<&str> = mine
            .first()
            .map(|r| estimators(r).iter().map(|e| e.0).collect())
            .unwrap_or_default();
        let untrusted: Vec<&str> = [("host OLS", ols), ("host ML", ml)]
            .iter()
            .filter(|(_, id)| id.pedestal(b).is_some_and(|f| !f.trusted))
            .map(|(n, _)| *n)
            .collect();
        s.push_str(&format!(
            "pedestal {b}: {} vs truth{}\n",
            names.join(" vs "),
            fit.map_or(String::new(), |f| format!(
                " (host: {} speeds {:.1}-{:.1} Hz, condition {:.1e}{})",
                f.speeds,
                f.speed_range_hz[0],
                f.speed_range_hz[1],
                f.condition_number,
                if untrusted.is_empty() {
                    String::new()
                } else {
                    format!(", {} NOT TRUSTED", untrusted.join(" and "))
                }
            ))
        ));
        let mut header: Vec<String> = vec!["".into(), "unit".into(), "truth".into()];
        for n in &names {
            header.push(format!("{n} ± σ"));
            header.push("−truth".into());
            header.push("[σ]".into());
        }
        let mut table: Vec<Vec<String>> = vec![header];
        for r in &mine {
            let (unit, k) = table::unit(&r.parameter);
            let mut line = vec![
                r.parameter.clone(),
                unit.into(),
                r.truth.map_or("—".into(), |t| sig(t * k, 6)),
            ];
            for (_, v, e) in estimators(r) {
                line.push(value_pm(v, e, k));
                line.push(pct_text(pct(v, r.truth)));
                line.push(match (v, r.truth, e) {
                    (Some(v), Some(t), Some(e)) if e > 0.0 => format!("{:+.1}", (v - t) / e),
                    _ => "—".into(),
                });
            }
            table.push(line);
        }
        let columns = table.first().map_or(0, Vec::len);
        let widths: Vec<usize> = (0..columns)
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
    // The host ML fit's natural frequencies and damping ratios, with the
    // truth's (the shared printer's modal view).
    let modal_rows: Vec<table::PedestalRow> = ml
        .pedestals
        .iter()
        .filter(|p| p.modal.is_some())
        .map(|p| {
            let truth: Vec<Option<f64>> = table::PARAMETERS
                .iter()
                .map(|name| {
                    rows.iter()
                        .find(|r| r.bearing == p.bearing && r.parameter == *name)
                        .and_then(|r| r.truth)
                })
                .collect();
            let modal_truth = truth.iter().all(Option::is_some).then(|| {
                crate::present::modal::pedestal(
                    &std::array::from_fn(|i| truth[i].unwrap_or(f64::NAN)),
                    None,
                )
            });
            table::PedestalRow {
                bearing: p.bearing.clone(),
                modal: p.modal,
                modal_truth,
                ..table::PedestalRow::default()
            }
        })
        .collect();
    if !modal_rows.is_empty() {
        s.push_str("host ML, ");
        s.push_str(&table::render_modal(&modal_rows));
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
