//! Identification with a measured base (README, "Bases"): when `base.csv`
//! gives the 1X motion X_B of the base a pedestal stands on, the pedestal's
//! spring and damper act on X_ped − X_B while its inertia acts on X_ped:
//!
//! ```text
//! −Ω²m·X_ped + (k + iΩc)·(X_ped − X_B) = F,   F = (K_b + iΩC_b)·rel
//! ```
//!
//! still linear in θ = (k_y, k_z, m, c_y, c_z): eq. 4 with X_ped − X_B in the
//! k and c columns, solved by the same least squares as `identify`.

use super::{lsq, pedestal_points, IdentifyError};
use crate::base_csv::BaseRow;
use crate::estimate::{Observation, Pedestal};
use crate::rundir::RunDir;
use nalgebra::{DMatrix, DVector};
use plinth_shared::phasor::omega_from_hz;
use plinth_shared::regression::{equations, Parameter, PARAMETERS};

/// One pedestal identified on its measured base.
#[derive(Clone, Debug, PartialEq)]
pub struct BaseFit {
    /// Bearing name.
    pub bearing: String,
    /// Base it stands on (`base.csv`).
    pub base: String,
    /// The identified parameters (k [N/m], m [kg], c [N·s/m]).
    pub pedestal: Pedestal,
    /// Their standard errors, same units.
    pub std_err: Pedestal,
    /// Root-mean-square equation residual [N].
    pub residual_rms: f64,
    /// Condition number of the column-scaled regression.
    pub condition_number: f64,
    /// Speeds used.
    pub speeds: usize,
}

/// Identifies every measured pedestal that stands on a base listed in
/// `base` (the rows of `base.csv`), relative to the base's motion. Bearings
/// on no listed base are left out (identify them on rigid ground). A speed
/// of a bearing without a base row at exactly that speed is an error.
pub fn identify_on_measured_base(
    run: &RunDir,
    base: &[BaseRow],
) -> Result<Vec<BaseFit>, IdentifyError> {
    let schedules = run.bearing_schedules();
    let mut fits = Vec::new();
    for bearing in run.measured_bearings() {
        let rows: Vec<&BaseRow> = base
            .iter()
            .filter(|r| r.bearings.iter().any(|b| b == bearing))
            .collect();
        let Some(first) = rows.first() else {
            continue;
        };
        let schedule = schedules
            .get(bearing)
            .ok_or_else(|| IdentifyError::UnknownBearing {
                bearing: bearing.to_string(),
            })?;
        let points: Vec<Observation> = pedestal_points(
            run.measurements.iter().filter(|m| m.bearing == bearing),
            schedule,
        )
        .map_err(|source| IdentifyError::BearingRange {
            bearing: bearing.to_string(),
            source,
        })?;
        let mut a = Vec::new();
        let mut b = Vec::new();
        for p in &points {
            let row = rows
                .iter()
                .find(|r| r.speed_hz == p.speed_hz && r.base == first.base)
                .ok_or_else(|| IdentifyError::NoData {
                    bearing: format!(
                        "{bearing} (base.csv has no row for base {:?} at {} Hz)",
                        first.base, p.speed_hz
                    ),
                })?;
            let omega = omega_from_hz(p.speed_hz);
            let rel = [p.ped[0] - row.motion[0], p.ped[1] - row.motion[1]];
            // k and c act on X_ped − X_B, the inertia on X_ped.
            let force = p.force();
            let on_rel = equations(omega, &rel, &force);
            let on_abs = equations(omega, &p.ped, &force);
            for (eq, abs) in on_rel.iter().zip(&on_abs) {
                let mut r = eq.row;
                r[Parameter::M as usize] = abs.row[Parameter::M as usize];
                a.extend_from_slice(&r);
                b.push(eq.rhs);
            }
        }
        if b.is_empty() {
            return Err(IdentifyError::NoData {
                bearing: bearing.to_string(),
            });
        }
        let solution = lsq::solve(
            &DMatrix::from_row_slice(b.len(), PARAMETERS, &a),
            &DVector::from_vec(b),
        );
        fits.push(BaseFit {
            bearing: bearing.to_string(),
            base: first.base.clone(),
            pedestal: Pedestal::from_theta(std::array::from_fn(|i| solution.theta[i])),
            std_err: Pedestal::from_theta(std::array::from_fn(|i| solution.std_err[i])),
            residual_rms: solution.residual_rms(),
            condition_number: solution.condition_number,
            speeds: points.len(),
        });
    }
    Ok(fits)
}
