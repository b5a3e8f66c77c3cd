//! The digits each number of `measurements.csv` is written with, and the
//! variance of its rounding: the floor of every noise source
//! ([`super::BearingNoise::digits_var`]). Module docs of [`super`], source 2.

use super::{real_value, Quantisation};
use crate::estimate::pedestal::number_variance;
use crate::rundir::Measurement;
use serde::Serialize;

pub use crate::rundir::written_digits;

/// Decimal exponent of a number printed by Rust's `{:e}`.
fn exponent_of(s: &str) -> i32 {
    s.rsplit('e')
        .next()
        .and_then(|e| e.parse().ok())
        .unwrap_or(0)
}

/// [`written_digits`] of real number `c` ([`REAL_CHANNELS`] order) of a
/// row: from the digits counted in the text as it was read when the row was
/// read from a file and the number is still the one read, else from the value.
pub fn digits_of(m: &Measurement, c: usize) -> Option<(u32, i32)> {
    let v = real_value(m, c);
    match &m.written {
        Some(w) => w.of(v),
        None => written_digits(v),
    }
}

/// How one column of `measurements.csv` is written.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ColumnDigits {
    /// Significant digits the column is written with (max over its values).
    pub digits: u32,
    /// Lowest decimal exponent of a last written digit in the column.
    pub lowest_digit_exponent: i32,
}

impl ColumnDigits {
    /// The digits of one column from its values.
    pub fn of(values: impl IntoIterator<Item = f64>) -> Self {
        Self::of_digits(values.into_iter().map(written_digits))
    }

    /// The digits of one column from the [`written_digits`] of its values.
    fn of_digits(values: impl IntoIterator<Item = Option<(u32, i32)>>) -> Self {
        let mut digits = 1;
        let mut lowest = i32::MAX;
        for (d, e) in values.into_iter().flatten() {
            digits = digits.max(d);
            lowest = lowest.min(e - d as i32 + 1);
        }
        if lowest == i32::MAX {
            // An all-zero column: zeros are taken to be exact.
            lowest = -330;
        }
        Self {
            digits,
            lowest_digit_exponent: lowest,
        }
    }

    /// The digits of every real column ([`REAL_CHANNELS`] order) of one
    /// bearing's `rows`. Counted per bearing, never over the whole run: a
    /// field instrument writes each bearing's channels with its own
    /// resolution, and a bearing written with fewer digits than another
    /// would otherwise be given the other's finer floor.
    pub fn of_rows(rows: &[&Measurement]) -> [ColumnDigits; 8] {
        // Each number's digits counted once: every column reads its own of
        // each row, and an iterator would count all eight for each column.
        let digits: Vec<[Option<(u32, i32)>; 8]> = rows
            .iter()
            .map(|m| std::array::from_fn(|c| digits_of(m, c)))
            .collect();
        Self::of_digit_rows(digits.iter().copied())
    }

    /// [`ColumnDigits::of_rows`] from the [`digits_of`] of every number of
    /// the rows (one array per row).
    pub(super) fn of_digit_rows(
        rows: impl Iterator<Item = [Option<(u32, i32)>; 8]> + Clone,
    ) -> [ColumnDigits; 8] {
        std::array::from_fn(|c| Self::of_digits(rows.clone().map(|d| d[c])))
    }

    /// The most digits of each column over the per-bearing `columns`
    /// ([`ColumnDigits::of_rows`] of each bearing): what a whole-run
    /// summary of the digits reports.
    pub fn most_of(columns: &[[ColumnDigits; 8]]) -> [u32; 8] {
        std::array::from_fn(|c| columns.iter().map(|b| b[c].digits).max().unwrap_or(0))
    }

    /// [`ColumnDigits::ulp`] of real number `c` of a row of this column,
    /// from the number's own digits ([`digits_of`]): no formatting when
    /// they were counted as the row was read.
    pub fn ulp_of(&self, m: &Measurement, c: usize) -> f64 {
        self.ulp_of_digits(digits_of(m, c), real_value(m, c))
    }

    /// [`ColumnDigits::ulp_of`] of a value `v` [m] of this column whose
    /// [`digits_of`] are `digits`.
    pub(super) fn ulp_of_digits(&self, digits: Option<(u32, i32)>, v: f64) -> f64 {
        let absolute = 10f64.powi(self.lowest_digit_exponent);
        match digits {
            // Written with d ≤ digits significant digits: printed with the
            // column's digits it keeps its exponent.
            Some((d, e)) if d <= self.digits => {
                10f64.powi(e - self.digits as i32 + 1).max(absolute)
            }
            _ => self.ulp(v),
        }
    }

    /// Unit in the last digit [m] of a value `v` [m] written in this column.
    pub fn ulp(&self, v: f64) -> f64 {
        let absolute = 10f64.powi(self.lowest_digit_exponent);
        if v == 0.0 || !v.is_finite() {
            return absolute;
        }
        let s = format!("{:.*e}", (self.digits.max(1) - 1) as usize, v);
        let e = exponent_of(&s);
        10f64.powi(e - self.digits as i32 + 1).max(absolute)
    }
}

/// The variance [m²] each real number of `rows` has from its rounding
/// alone, row for row ([`REAL_CHANNELS`] order): [`rounding_variance`].
pub(super) fn digits_variances(
    rows: &[&Measurement],
    columns: &[ColumnDigits; 8],
    quantisation: Quantisation,
) -> Vec<[f64; 8]> {
    rows.iter()
        .map(|m| {
            std::array::from_fn(|c| rounding_variance(quantisation, columns[c].ulp_of(m, c), m, c))
        })
        .collect()
}

/// Variance [m²] of the rounding of real number `c` ([`REAL_CHANNELS`]
/// order) of row `m`, written with unit in the last place `ulp` [m] and
/// reduced by `quantisation`: the variance of its digits
/// ([`number_variance`]), never below the rounding it carries from the
/// table it was converted from ([`table_variance`]).
pub fn rounding_variance(quantisation: Quantisation, ulp: f64, m: &Measurement, c: usize) -> f64 {
    number_variance(quantisation, ulp, None).max(table_variance(m, c))
}

/// Variance [m²] of the rounding real number `c` ([`REAL_CHANNELS`] order)
/// of row `m` carries from the table it was converted from: a vector
/// table's amplitude digits and phase steps, propagated through the unit
/// conversion and the angle transform by `plinth import` (`resolution.csv`,
/// [`crate::rundir::resolution`]), half of its channel's complex variance;
/// 0 when none is known or the number changed since it was read.
pub fn table_variance(m: &Measurement, c: usize) -> f64 {
    m.written
        .as_ref()
        .map_or(0.0, |w| w.floor_var_of(c, real_value(m, c)))
}
