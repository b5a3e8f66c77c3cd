//! Whether a number of `measurements.csv` or `bearings.csv` can be real: a
//! phasor component beyond any machine's vibration, or a bearing
//! coefficient beyond any bearing (a `1.8e308` typo, a unit mistake), is
//! refused at its line and column before anything is fitted. The bounds
//! are those of a 1X vector table (`field::plausible`) for displacements,
//! and [`MAX_STIFFNESS`] and [`MAX_DAMPING`] for coefficients.

use super::{RunDirError, BEARING_COLUMNS, MEASUREMENT_COLUMNS};
use std::path::Path;

/// The largest plausible bearing stiffness coefficient |k_ij| [N/m]: a
/// thousand times the stiffest journal or rolling-element bearing (about
/// 1e10 N/m), the margin `field::plausible` gives amplitudes.
pub const MAX_STIFFNESS: f64 = 1e13;

/// The largest plausible bearing damping coefficient |c_ij| [N·s/m]: a
/// thousand times a large turbine journal bearing's (about 1e8 N·s/m).
pub const MAX_DAMPING: f64 = 1e11;

/// The bound of the eight numbers of a row of the table with `columns`
/// (measurements: displacement phasor components [m]; bearings: four
/// stiffness [N/m] then four damping coefficients [N·s/m]), with their
/// unit; `None` for another table.
fn bounds(columns: &[&str; 10]) -> Option<[(f64, &'static str); 8]> {
    let displacement = crate::field::plausible::max_amplitude_si(
        plinth_shared::extractor::SensorKind::Displacement,
    );
    if *columns == MEASUREMENT_COLUMNS {
        Some([(displacement, "m"); 8])
    } else if *columns == BEARING_COLUMNS {
        Some(std::array::from_fn(|k| {
            if k < 4 {
                (MAX_STIFFNESS, "N/m")
            } else {
                (MAX_DAMPING, "N·s/m")
            }
        }))
    } else {
        None
    }
}

/// Checks the eight numbers `values` of one data row (file `path`, 1-based
/// `line`; `index[k]` is the 0-based field of `columns[k]`) against their
/// bounds: the first beyond its bound is an error naming its line and
/// column.
pub fn check(
    path: &Path,
    line: u64,
    columns: &[&'static str; 10],
    index: &[usize; 10],
    values: &[f64; 8],
) -> Result<(), RunDirError> {
    let Some(bounds) = bounds(columns) else {
        return Ok(());
    };
    for (k, (&v, (bound, unit))) in values.iter().zip(bounds).enumerate() {
        if v.abs() > bound {
            return Err(RunDirError::Csv {
                file: path.to_path_buf(),
                line,
                message: format!(
                    "column {} (`{}`): {} {unit} is beyond any machine's (at most {bound:e} {unit}): a typo, or not in SI units (formats.md: m, N/m, N·s/m)?",
                    index[k + 2] + 1,
                    columns[k + 2],
                    super::format_number(v)
                ),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_past_their_bound_are_named_by_column() {
        let index = std::array::from_fn(|k| k);
        let p = Path::new("bearings.csv");
        let mut v = [1e8, -2e7, 3e6, 1e9, 1e5, 0.0, -1e4, 1e6];
        assert!(check(p, 2, &BEARING_COLUMNS, &index, &v).is_ok());
        v[3] = 1.7976931348623157e308;
        let e = check(p, 7, &BEARING_COLUMNS, &index, &v)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bearings.csv:7:") && e.contains("column 6 (`kzz`)"),
            "{e}"
        );
        v[3] = 1e9;
        v[7] = -2e11;
        let e = check(p, 3, &BEARING_COLUMNS, &index, &v)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("column 10 (`czz`)") && e.contains("N·s/m"),
            "{e}"
        );
        let m = [1e-5, -2e-6, 0.0, 3e-5, 1e-7, 1e-7, 0.049, -0.049];
        let p = Path::new("measurements.csv");
        assert!(check(p, 2, &MEASUREMENT_COLUMNS, &index, &m).is_ok());
        let mut m2 = m;
        m2[4] = 1e300;
        let e = check(p, 9, &MEASUREMENT_COLUMNS, &index, &m2)
            .unwrap_err()
            .to_string();
        assert!(e.contains("column 7 (`ped_y_re`)"), "{e}");
    }
}
