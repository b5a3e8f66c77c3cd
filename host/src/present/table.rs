//! The one printer of identified pedestals, used by `identify`, `diagnose`,
//! `stream` and `demo`, so that the same fit reads the same everywhere:
//!
//! - order k_y, k_z, m, c_y, c_z, then any other parameter by name;
//! - units MN/m for stiffness, kg for mass, N·s/m for damping (a
//!   parameter's unit is [`unit`]'s, nowhere else);
//! - `value ± standard error`, the value to the decimal of the standard
//!   error's second significant digit ([`value_pm`]);
//! - a damping within two standard errors of zero is shown as consistent
//!   with zero (`≈0`), and the fit column says so instead of a bare `ok`;
//! - under the parameters, the modal view ([`super::modal`]): per direction
//!   f_n in Hz and rpm and ζ in %, with ±.
//!
//! Callers fill a [`PedestalRow`] (this module's own input type, not the
//! estimator's), so the printer does not depend on how a fit is stored.

use super::modal::{DirectionModal, PedestalModal};

/// The five pedestal parameters in print order.
pub const PARAMETERS: [&str; 5] = ["k_y", "k_z", "m", "c_y", "c_z"];

/// Display unit of a parameter and the factor from its SI value:
/// stiffness (`k…`) in MN/m, mass (`m…`) in kg, damping (`c…`) in N·s/m;
/// ratios (`…_scale`, `…_ratio`) and anything else in SI as is (label empty).
pub fn unit(name: &str) -> (&'static str, f64) {
    // Ratios (`k_scale`, `clearance_ratio`) are dimensionless.
    if name.ends_with("_scale") || name.ends_with("_ratio") {
        return ("", 1.0);
    }
    let first = name.chars().next().unwrap_or(' ');
    let subscript = name.len() == 1 || name.as_bytes().get(1) == Some(&b'_');
    match first {
        'k' if subscript => ("MN/m", 1.0e-6),
        'm' if subscript => ("kg", 1.0),
        'c' if subscript => ("N·s/m", 1.0),
        _ => ("", 1.0),
    }
}

/// Damping ratio display factor: ζ is printed in %.
const ZETA_PERCENT: f64 = 100.0;

/// Rotational speed: Hz to rpm.
pub const RPM_PER_HZ: f64 = 60.0;

/// One pedestal as the printer shows it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PedestalRow {
    /// Bearing name (the first column).
    pub bearing: String,
    /// k_y, k_z, m, c_y, c_z in SI: `Some((value, standard error))`, or
    /// `None` when the model fixed it at 0 (not estimated).
    pub parameters: [Option<(f64, f64)>; 5],
    /// Other parameters (a model with effects: `k_yz`, `eta`, ...): name,
    /// value, standard error, SI.
    pub extra: Vec<(String, f64, f64)>,
    /// RMS of the equation residuals [N].
    pub residual_rms: Option<f64>,
    /// Condition number of the fit [-].
    pub condition_number: Option<f64>,
    /// Whether the fit may be used (`None`: not judged here).
    pub trusted: Option<bool>,
    /// The modal view, when known.
    pub modal: Option<PedestalModal>,
    /// Lines under the pedestal's row (truth, error, another estimator).
    pub below: Vec<SubRow>,
    /// The modal view of the truth (simulated runs), shown under the
    /// pedestal's modal rows.
    pub modal_truth: Option<PedestalModal>,
}

impl PedestalRow {
    /// A pedestal from parameters by name (SI values and standard errors,
    /// as a model with effects reports them): the five pedestal parameters
    /// in their columns (absent: not in the model), the others in `extra`.
    pub fn from_named(
        bearing: &str,
        values: &std::collections::BTreeMap<String, f64>,
        std_err: &std::collections::BTreeMap<String, f64>,
    ) -> PedestalRow {
        let se = |n: &str| std_err.get(n).copied().unwrap_or(f64::NAN);
        PedestalRow {
            bearing: bearing.to_string(),
            parameters: PARAMETERS.map(|n| values.get(n).map(|&v| (v, se(n)))),
            extra: values
                .iter()
                .filter(|(n, _)| !PARAMETERS.contains(&n.as_str()))
                .map(|(n, &v)| (n.clone(), v, se(n)))
                .collect(),
            ..PedestalRow::default()
        }
    }
}

/// A line under a pedestal's row: a label and one cell per parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct SubRow {
    /// Shown indented in the first column (`truth`, `error`, `ols`, ...).
    pub label: String,
    /// One cell per parameter of [`PARAMETERS`].
    pub cells: [String; 5],
}

impl SubRow {
    /// Values in SI (with standard errors when given), printed as the
    /// pedestal's own; `None` prints `-`.
    pub fn values(label: &str, values: [Option<(f64, Option<f64>)>; 5]) -> SubRow {
        SubRow {
            label: label.to_string(),
            cells: std::array::from_fn(|i| match values[i] {
                Some((v, Some(s))) => {
                    value_pm(v * unit(PARAMETERS[i]).1, s * unit(PARAMETERS[i]).1)
                }
                Some((v, None)) => sig(v * unit(PARAMETERS[i]).1, 6),
                None => "-".into(),
            }),
        }
    }

    /// Cells already written (percentages, efficiencies).
    pub fn text(label: &str, cells: [String; 5]) -> SubRow {
        SubRow {
            label: label.to_string(),
            cells,
        }
    }

    /// Relative errors of `estimate` against `truth` per parameter (`+0.12%`;
    /// an absolute error in the display unit where the truth is 0).
    pub fn errors(label: &str, estimate: [f64; 5], truth: [f64; 5]) -> SubRow {
        SubRow::text(
            label,
            std::array::from_fn(|i| {
                let (v, t) = (estimate[i], truth[i]);
                if t != 0.0 {
                    format!("{:+.2}%", 100.0 * (v - t) / t.abs())
                } else {
                    format!("{:+} abs", sig((v - t) * unit(PARAMETERS[i]).1, 2))
                }
            }),
        )
    }
}

/// True when a damping is consistent with zero: |value| < 2 standard errors.
pub fn consistent_with_zero(value: f64, std_err: f64) -> bool {
    std_err.is_finite() && std_err > 0.0 && value.abs() < 2.0 * std_err
}

/// The pedestals as an aligned text table, then their modal view; with a
/// legend line for every mark the table uses.
pub fn render(rows: &[PedestalRow]) -> String {
    let mut table: Vec<Vec<String>> = Vec::new();
    let mut header = vec!["bearing".to_string()];
    header.extend(PARAMETERS.iter().map(|p| format!("{p} [{}]", unit(p).0)));
    let stats = rows.iter().any(|r| r.residual_rms.is_some());
    let judged = rows.iter().any(|r| r.trusted.is_some());
    if stats {
        header.extend(["rms [N]", "cond"].map(String::from));
    }
    if judged {
        header.push("fit".into());
    }
    table.push(header);
    let mut any_zero = false;
    for r in rows {
        let mut line = vec![r.bearing.clone()];
        let mut unresolved = Vec::new();
        for (i, p) in r.parameters.iter().enumerate() {
            let k = unit(PARAMETERS[i]).1;
            line.push(match p {
                None => "0 (fixed)".into(),
                Some((v, s)) => {
                    let mut cell = value_pm(v * k, s * k);
                    if PARAMETERS[i].starts_with('c') && consistent_with_zero(*v, *s) {
                        cell.push_str(" ≈0");
                        unresolved.push(PARAMETERS[i]);
                    }
                    cell
                }
            });
        }
        any_zero |= !unresolved.is_empty();
        if stats {
            line.push(r.residual_rms.map_or("-".into(), |x| sig(x, 3)));
            line.push(match r.condition_number {
                Some(c) if c.is_finite() => format!("{c:.1e}"),
                Some(_) => "∞".into(),
                None => "-".into(),
            });
        }
        if judged {
            line.push(match r.trusted {
                Some(false) => "UNTRUSTED".into(),
                Some(true) if unresolved.is_empty() => "ok".into(),
                Some(true) => format!("ok, {} ≈ 0", unresolved.join(", ")),
                None => "-".into(),
            });
        }
        table.push(line);
        for b in &r.below {
            let mut l = vec![format!("  {}", b.label)];
            l.extend(b.cells.iter().cloned());
            table.push(l);
        }
    }
    let mut out = align(&table);
    let extra: Vec<String> = rows
        .iter()
        .filter(|r| !r.extra.is_empty())
        .map(|r| {
            let items: Vec<String> = r
                .extra
                .iter()
                .map(|(n, v, s)| {
                    let (u, k) = unit(n);
                    let u = if u.is_empty() {
                        String::new()
                    } else {
                        format!(" {u}")
                    };
                    format!("{n} = {}{u}", value_pm(v * k, s * k))
                })
                .collect();
            format!("{}: also {}\n", r.bearing, items.join(", "))
        })
        .collect();
    out.extend(extra);
    if rows
        .iter()
        .any(|r| r.below.iter().any(|b| b.label == "ols eff."))
    {
        out.push_str("ols eff.: efficiency of the paper's least squares, Cramér–Rao variance / OLS variance under the noise model (100% = as good as maximum likelihood)\n");
    }
    if any_zero {
        out.push_str(
            "≈0: within 2 standard errors of zero: the data do not resolve this damping\n",
        );
    }
    if rows.iter().any(|r| r.modal.is_some()) {
        out.push('\n');
        out.push_str(&render_modal(rows));
    }
    out
}

/// The modal view of the pedestals: per bearing and direction f_n [Hz],
/// f_n [rpm] and ζ [%] with ±, and the truth's under it when known.
pub fn render_modal(rows: &[PedestalRow]) -> String {
    let mut table: Vec<Vec<String>> = vec![vec![
        "pedestal".into(),
        "f_n [Hz]".into(),
        "f_n [rpm]".into(),
        "ζ [%]".into(),
    ]];
    let mut any_zero = false;
    let mut unknown = false;
    for r in rows {
        let Some(m) = &r.modal else { continue };
        for (dir, d, t) in [
            ("y", &m.y, r.modal_truth.map(|t| t.y)),
            ("z", &m.z, r.modal_truth.map(|t| t.z)),
        ] {
            let (cells, zero) = modal_cells(d);
            any_zero |= zero;
            unknown |= d.f_n_hz.is_finite() && !d.f_n_std_err.is_finite();
            let mut line = vec![format!("{} {dir}", r.bearing)];
            line.extend(cells);
            table.push(line);
            if let Some(t) = t {
                table.push(vec![
                    "  truth".into(),
                    sig(t.f_n_hz, 6),
                    sig(t.f_n_hz * RPM_PER_HZ, 6),
                    sig(t.zeta * ZETA_PERCENT, 4),
                ]);
            }
        }
    }
    let mut out = String::from(
        "natural frequency f_n = √(k/m)/2π and damping ratio ζ = c/(2√(km)) of each pedestal on its own:\n",
    );
    out.push_str(&align(&table));
    if any_zero {
        out.push_str("≈0: ζ within 2 standard errors of zero (damping not resolved)\n");
    }
    if unknown {
        out.push_str("± -: no covariance of this fit (standard errors unknown)\n");
    }
    out
}

/// f_n [Hz], f_n [rpm], ζ [%] cells of one direction, and whether ζ is
/// consistent with zero.
fn modal_cells(d: &DirectionModal) -> ([String; 3], bool) {
    if !d.f_n_hz.is_finite() {
        let why = "- (k or m ≤ 0)".to_string();
        return ([why.clone(), why, "-".into()], false);
    }
    let with = |v: f64, s: f64| {
        if s.is_finite() {
            value_pm(v, s)
        } else {
            format!("{} ± -", sig(v, 5))
        }
    };
    let zero = consistent_with_zero(d.zeta, d.zeta_std_err);
    let mut zeta = with(d.zeta * ZETA_PERCENT, d.zeta_std_err * ZETA_PERCENT);
    if d.zeta == 0.0 && d.zeta_std_err == 0.0 {
        zeta = "0 (c fixed)".into();
    } else if zero {
        zeta.push_str(" ≈0");
    }
    (
        [
            with(d.f_n_hz, d.f_n_std_err),
            with(d.f_n_hz * RPM_PER_HZ, d.f_n_std_err * RPM_PER_HZ),
            zeta,
        ],
        zero,
    )
}

/// Left-aligned columns, two spaces apart, trailing blanks trimmed.
fn align(table: &[Vec<String>]) -> String {
    let columns = table.iter().map(Vec::len).max().unwrap_or(0);
    let widths: Vec<usize> = (0..columns)
        .map(|c| {
            table
                .iter()
                .map(|r| r.get(c).map_or(0, |s| s.chars().count()))
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut out = String::new();
    for r in table {
        let mut line = String::new();
        for (c, cell) in r.iter().enumerate() {
            let pad = widths[c].saturating_sub(cell.chars().count());
            line.push_str(cell);
            line.push_str(&" ".repeat(pad + 2));
        }
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

/// `value ± std_err` with the value given to the decimal of the standard
/// error's second significant digit (6 significant digits when the standard
/// error is zero, tiny or not finite).
pub fn value_pm(value: f64, std_err: f64) -> String {
    if !std_err.is_finite() {
        return format!("{} ± ∞", sig(value, 6));
    }
    let v_mag = if value != 0.0 {
        value.abs().log10().floor() as i32
    } else {
        0
    };
    if std_err <= 0.0 || (std_err.log10().floor() as i32) < v_mag - 5 {
        return format!("{} ± {}", sig(value, 6), sig(std_err, 2));
    }
    let decimals = (1 - std_err.log10().floor() as i32).max(0) as usize;
    if (v_mag - decimals as i32).abs() > 12 || !(-4..9).contains(&v_mag) {
        return format!("{} ± {}", sig(value, 3), sig(std_err, 2));
    }
    format!("{value:.decimals$} ± {}", sig(std_err, 2))
}

/// `x` with `digits` significant digits, in plain notation for moderate
/// magnitudes (1e-4 to 1e9), else in exponent notation.
pub fn sig(x: f64, digits: usize) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x == 0.0 {
        return "0".into();
    }
    let magnitude = x.abs().log10().floor() as i32;
    if !(-4..9).contains(&magnitude) {
        return format!("{:.*e}", digits.saturating_sub(1), x);
    }
    let decimals = (digits as i32 - 1 - magnitude).max(0) as usize;
    format!("{x:.decimals$}")
}

/// An SI value and standard error as the printer writes them, with the
/// parameter's display unit: `12.000 ± 0.016 MN/m` (for one-line reports).
pub fn parameter_text(name: &str, value: f64, std_err: f64) -> String {
    let (u, k) = unit(name);
    let text = value_pm(value * k, std_err * k);
    if u.is_empty() {
        text
    } else {
        format!("{text} {u}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn significant_digit_formatting() {
        assert_eq!(sig(10.00213, 6), "10.0021");
        assert_eq!(sig(0.0031, 2), "0.0031");
        assert_eq!(sig(150.0, 6), "150.000");
        assert_eq!(sig(1.5e-7, 2), "1.5e-7");
        assert_eq!(sig(-2.0, 3), "-2.00");
        assert_eq!(value_pm(105.045, 106.0), "105 ± 106");
        assert_eq!(value_pm(9.93343, 0.057), "9.933 ± 0.057");
        assert_eq!(value_pm(149.542, 0.19), "149.54 ± 0.19");
        assert_eq!(value_pm(10.0, 1.6e-15), "10.0000 ± 1.6e-15");
        assert_eq!(value_pm(10.0, f64::INFINITY), "10.0000 ± ∞");
        assert_eq!(parameter_text("k_y", 1.2e7, 1.6e4), "12.000 ± 0.016 MN/m");
        assert_eq!(parameter_text("m", 150.0, 0.25), "150.00 ± 0.25 kg");
        assert_eq!(unit("k_yz"), ("MN/m", 1e-6));
        assert_eq!(unit("m_y").0, "kg");
        assert_eq!(unit("eta").0, "");
        assert_eq!(unit("c_z").0, "N·s/m");
    }

    fn row(c_y: (f64, f64)) -> PedestalRow {
        PedestalRow {
            bearing: "left".into(),
            parameters: [
                Some((1.0e7, 1.2e4)),
                Some((1.5e7, 2.0e4)),
                Some((100.0, 0.1)),
                Some(c_y),
                None,
            ],
            residual_rms: Some(0.5),
            condition_number: Some(12.0),
            trusted: Some(true),
            modal: Some(super::super::modal::pedestal(
                &[1.0e7, 1.5e7, 100.0, c_y.0, 0.0],
                Some(&std::array::from_fn(|i| {
                    std::array::from_fn(|j| {
                        if i != j {
                            0.0
                        } else {
                            [1.2e4_f64, 2.0e4, 0.1, c_y.1, 0.0][i].powi(2)
                        }
                    })
                })),
            )),
            ..PedestalRow::default()
        }
    }

    #[test]
    fn units_order_and_damping_consistent_with_zero() {
        let text = render(&[row((500.0, 30.0))]);
        assert!(text.contains("k_y [MN/m]  "), "{text}");
        assert!(text.contains("10.000 ± 0.012"), "{text}");
        assert!(text.contains("0 (fixed)"), "{text}");
        assert!(text.contains("left y"), "{text}");
        assert!(text.contains("f_n [rpm]"), "{text}");
        // f_n = √(1e5)/2π = 50.33 Hz = 3019.9 rpm.
        assert!(text.contains("50.329"), "{text}");
        assert!(text.contains("0 (c fixed)"), "{text}");
        let fit_col = text.lines().nth(1).unwrap();
        assert!(fit_col.trim_end().ends_with("ok"), "{text}");
        assert!(!text.contains("≈0"));

        let text = render(&[row((20.0, 30.0))]);
        assert!(text.contains("20 ± 30 ≈0"), "{text}");
        assert!(text.contains("ok, c_y ≈ 0"), "{text}");
        assert!(text.contains("≈0: within 2 standard errors"), "{text}");
    }
}
