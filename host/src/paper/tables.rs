//! The paper's tables: the rows of Tables 1 and 2 (identified against true
//! values, errors in %), and their text for the terminal.

use super::*;
use crate::rundir::DigitsMode;
use anyhow::Result;
use serde::{Serialize, Serializer};
use std::collections::BTreeMap;

/// `round` or `truncate`: the name of a digits mode in the tables.
pub fn digits_mode_name(mode: DigitsMode) -> &'static str {
    match mode {
        DigitsMode::Round => "round",
        DigitsMode::Truncate => "truncate",
    }
}

pub(super) fn serialize_digits_mode<S: Serializer>(
    mode: &DigitsMode,
    s: S,
) -> Result<S::Ok, S::Error> {
    s.serialize_str(digits_mode_name(*mode))
}

/// One row of Table 1.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table1Row {
    /// Significant digits of the measured phasors.
    pub digits: u32,
    /// How the phasors were reduced to `digits` (`round` or `truncate`).
    #[serde(serialize_with = "serialize_digits_mode")]
    pub digits_mode: DigitsMode,
    /// Bearing (pedestal) name.
    pub bearing: String,
    /// `k_y` [N/m], `k_z` [N/m] or `m` [kg].
    pub param: String,
    /// The machine's value.
    pub truth: f64,
    /// The identified value (the paper's OLS).
    pub identified: f64,
    /// 100·(identified − truth)/truth [%].
    pub error_pct: f64,
    /// The maximum-likelihood estimate of the same data and model
    /// (`plinth identify`'s default).
    pub ml: f64,
    /// 100·(ml − truth)/truth [%].
    pub ml_error_pct: f64,
}

/// Which pedestal damping a Table 2 row was computed with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DampingCase {
    /// The damped example as the scan reads it (70-100 N·s/m).
    ScanDamping,
    /// The same machine with the pedestal damping scaled to a damping ratio
    /// of about 10 %.
    HeavyDamping,
}

impl DampingCase {
    /// `scan_damping` or `heavy_damping`, as in the JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::ScanDamping => "scan_damping",
            Self::HeavyDamping => "heavy_damping",
        }
    }
}

/// One row of Table 2.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table2Row {
    /// The damping case.
    pub case: DampingCase,
    /// Factor [-] applied to the damped machine's c_y, c_z in this case (1
    /// for the scan's damping).
    pub damping_scale: f64,
    /// `R&I`, `R+I`, `R` or `I`.
    pub mode: String,
    /// Bearing (pedestal) name.
    pub bearing: String,
    /// `k_y`, `k_z` [N/m], `m` [kg], and for R&I `c_y`, `c_z` [N·s/m].
    pub param: String,
    /// The machine's value.
    pub truth: f64,
    /// The identified value (the paper's OLS).
    pub identified: f64,
    /// 100·(identified − truth)/truth [%].
    pub error_pct: f64,
    /// R&I only: the maximum-likelihood estimate of the same data and model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ml: Option<f64>,
    /// R&I only: 100·(ml − truth)/truth [%].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ml_error_pct: Option<f64>,
}

/// The pedestal damping of one Table 2 case, one entry per pedestal.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CaseDamping {
    /// Bearing (pedestal) name.
    pub bearing: String,
    /// Vertical damping [N·s/m].
    pub c_y: f64,
    /// Horizontal damping [N·s/m].
    pub c_z: f64,
    /// Vertical damping ratio c_y/(2·sqrt(k_y·m)) of the pedestal alone [-].
    pub damping_ratio_y: f64,
    /// Horizontal damping ratio c_z/(2·sqrt(k_z·m)) of the pedestal alone [-].
    pub damping_ratio_z: f64,
}

/// One Table 2 case: which damping and how much.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table2Case {
    /// The case.
    pub case: DampingCase,
    /// Factor [-] applied to the damped machine's c_y, c_z.
    pub damping_scale: f64,
    /// The resulting damping of every pedestal.
    pub pedestals: Vec<CaseDamping>,
    /// Worst |error| in k_y, k_z, m [%] of each mode identified from the
    /// same run at full precision (no digit reduction): the error of the
    /// method itself, which the 2-digit rows add rounding noise to. R&I is
    /// exact there; R+I, R and I carry the error of leaving c out of eq. 4.
    pub full_precision_worst_km_pct: BTreeMap<String, f64>,
}

impl Table2Case {
    /// Mean damping ratio over every pedestal and direction [-].
    pub fn mean_damping_ratio(&self) -> f64 {
        let n = (2 * self.pedestals.len()).max(1) as f64;
        self.pedestals
            .iter()
            .map(|p| p.damping_ratio_y + p.damping_ratio_z)
            .sum::<f64>()
            / n
    }
}

/// Both tables.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Tables {
    /// How the phasors were reduced to digits in both tables.
    #[serde(serialize_with = "serialize_digits_mode")]
    pub digits_mode: DigitsMode,
    /// Table 1 rows: digits × bearing × (k_y, k_z, m).
    pub table1: Vec<Table1Row>,
    /// Digits of Table 2's phasors.
    pub table2_digits: u32,
    /// Table 2's damping cases, in the order of the rows.
    pub table2_cases: Vec<Table2Case>,
    /// Table 2 rows: case × mode × bearing × parameters.
    pub table2: Vec<Table2Row>,
}

/// Significant-figure text of a value in a unit (e.g. MN/m).
pub(super) fn fmt_value(v: f64, scale: f64) -> String {
    format!("{:.4}", v * scale)
}

pub(super) fn unit_of(param: &str) -> (&'static str, f64) {
    match param {
        "k_y" | "k_z" => ("MN/m", 1e-6),
        "m" => ("kg", 1.0),
        _ => ("N·s/m", 1.0),
    }
}

/// The stiffness and mass parameters, k_y, k_z, m.
pub const KM: [&str; 3] = ["k_y", "k_z", "m"];

/// Worst |error_pct| [%] of the `rows` of one case and mode over `params`.
pub fn worst_error(rows: &[Table2Row], case: DampingCase, mode: &str, params: &[&str]) -> f64 {
    rows.iter()
        .filter(|r| r.case == case && r.mode == mode && params.contains(&r.param.as_str()))
        .map(|r| r.error_pct.abs())
        .fold(0.0, f64::max)
}

/// The two lines that say what a Table 2 case shows, with its numbers.
pub(super) fn case_explanation(case: &Table2Case) -> [String; 2] {
    let zeta = case.mean_damping_ratio();
    let exact = |m: &str| {
        case.full_precision_worst_km_pct
            .get(m)
            .copied()
            .unwrap_or(f64::NAN)
    };
    match case.case {
        DampingCase::ScanDamping => [
            format!(
                "  The scan's damping is below what 2-digit data resolve: at a pedestal resonance its force is only \
                 2ζ ≈ {:.2} % of the spring force;",
                200.0 * zeta
            ),
            format!(
                "  leaving c out (R+I, R, I) costs only {:.2}, {:.2}, {:.2} % in k, m on full-precision data, less than \
                 the 2-digit noise: no contrast, and R&I's c is noise.",
                exact("R+I"),
                exact("R"),
                exact("I")
            ),
        ],
        DampingCase::HeavyDamping => [
            format!(
                "  With real damping (ζ ≈ {:.0} %, the smooth phase of the paper's Fig. 9) only R&I is right, as the paper \
                 found: R&I gets k, m and c;",
                100.0 * zeta
            ),
            format!(
                "  R+I, R and I leave c out of eq. 4 and miss k or m by up to {:.1}, {:.1}, {:.1} % even on full-precision data.",
                exact("R+I"),
                exact("R"),
                exact("I")
            ),
        ],
    }
}

/// Both tables as text, laid out like the paper's.
pub fn tables_text(t: &Tables) -> String {
    let mode = digits_mode_name(t.digits_mode);
    let mut s = String::new();
    s += &format!(
        "Table 1: identified pedestal parameters (c = 0), R&I, model k_y, k_z, m; digits: {mode}\n"
    );
    s += &format!(
        "  digits {} (the paper's \"maximum error of 5 %\" at 2 digits; --truncate for the literal \"truncated\")\n",
        match t.digits_mode {
            DigitsMode::Round => "rounded",
            DigitsMode::Truncate => "truncated",
        }
    );
    s += "  identified: the paper's least squares; ML: maximum likelihood, errors in variables (plinth identify's default)\n";
    s += &format!(
        "{:<10} {:<6} {:<5} {:>12} {:>12} {:>10} {:>12} {:>10}\n",
        "digits", "ped", "param", "truth", "identified", "error [%]", "ML", "error [%]"
    );
    for r in &t.table1 {
        let (u, k) = unit_of(&r.param);
        s += &format!(
            "{:<10} {:<6} {:<5} {:>12} {:>12} {:>10.3} {:>12} {:>10.3}  {u}\n",
            format!("{} {}", r.digits, digits_mode_name(r.digits_mode)),
            r.bearing,
            r.param,
            fmt_value(r.truth, k),
            fmt_value(r.identified, k),
            r.error_pct,
            fmt_value(r.ml, k),
            r.ml_error_pct
        );
    }
    s += &format!(
        "\nTable 2: identified pedestal parameters (c ≠ 0, {} digits, {mode}) by use of eq. 4\n",
        t.table2_digits
    );
    s += "  R&I: all equations independently (model k_y, k_z, m, c_y, c_z)\n";
    s += "  R+I: real- and imaginary-part equations added; R: real parts only; I: imaginary parts only (model k_y, k_z, m)\n";
    for (label, case) in ["(a)", "(b)"].iter().zip(&t.table2_cases) {
        let c: Vec<String> = case
            .pedestals
            .iter()
            .map(|p| format!("{} c_y {:.0}, c_z {:.0}", p.bearing, p.c_y, p.c_z))
            .collect();
        s += &format!(
            "\nCase {label} {}: pedestal damping ×{} of the damped example ({} N·s/m; mean damping ratio {:.2} %)\n",
            case.case.name(),
            case.damping_scale,
            c.join("; "),
            100.0 * case.mean_damping_ratio()
        );
        for line in case_explanation(case) {
            s += &line;
            s += "\n";
        }
        s += &format!(
            "{:<10} {:<6} {:<5} {:>12} {:>12} {:>10} {:>12} {:>10}\n",
            "mode", "ped", "param", "truth", "identified", "error [%]", "ML", "error [%]"
        );
        for r in t.table2.iter().filter(|r| r.case == case.case) {
            let (u, k) = unit_of(&r.param);
            let (ml, ml_err) = match (r.ml, r.ml_error_pct) {
                (Some(v), Some(e)) => (fmt_value(v, k), format!("{e:.3}")),
                _ => (String::new(), String::new()),
            };
            s += &format!(
                "{:<10} {:<6} {:<5} {:>12} {:>12} {:>10.3} {:>12} {:>10}  {u}\n",
                r.mode,
                r.bearing,
                r.param,
                fmt_value(r.truth, k),
                fmt_value(r.identified, k),
                r.error_pct,
                ml,
                ml_err
            );
        }
        let w = |m: &str| worst_error(&t.table2, case.case, m, &KM);
        s += &format!(
            "  worst |error| in k, m: R&I {:.2} %, R+I {:.2} %, R {:.2} %, I {:.2} %; in c (R&I): {:.1} %\n",
            w("R&I"),
            w("R+I"),
            w("R"),
            w("I"),
            worst_error(&t.table2, case.case, "R&I", &["c_y", "c_z"])
        );
    }
    s
}

/// The Fig. 6 re-prediction gap as text (max, RMS, where it concentrates).
pub fn reprediction_text(paper: &Paper) -> String {
    let o = &paper.reprediction.overall;
    let g = &paper.reprediction_gap;
    let mut s = format!(
        "Fig. 6: re-predicted with the {d}-digit identified pedestals vs the {d}-digit measurement \
         (every channel, both pedestals): max |dX| {:.3} um = {:.1} % of the largest |X|, RMS {:.1} %\n",
        o.max_abs_m * 1e6,
        o.max_rel * 100.0,
        o.rms_rel * 100.0,
        d = paper.fig6_digits,
    );
    if !g.bands.is_empty() {
        let bands: Vec<String> = g
            .bands
            .iter()
            .map(|b| {
                format!(
                    "{:.0} % at {}-{} Hz (peak {} Hz)",
                    b.share * 100.0,
                    b.from_hz,
                    b.to_hz,
                    b.speed_hz
                )
            })
            .collect();
        s += &format!(
            "  the squared gap concentrates in narrow bands: {}; elsewhere the RMS gap is {:.1} %\n",
            bands.join(", "),
            g.rms_rel_outside * 100.0
        );
        s += "  (nearly undamped resonances of the rotor on its pedestals in the undamped machine: a small error in k or m shifts them)\n";
    }
    s
}
