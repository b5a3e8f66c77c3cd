//! Undamped natural frequencies of the non-rotating machine (no gyroscopic
//! coupling, no damping): the generalized symmetric eigenproblem
//! K·v = ω²·M·v, solved densely through the Cholesky factor of M. For
//! validation and for placing the speed range against the modes; not on the
//! response path.

use super::assembly::Assembly;
use super::machine::Machine;
use super::pedestal::PedestalDynamics;
use super::response::SimError;

/// Natural frequencies [Hz], ascending, of `machine` at rest with the bearing
/// stiffness it has at `bearing_speed_hz` [Hz]. Bearing stiffness must be
/// symmetric (kyz = kzy) or this is an error. Rigid-body modes give ≈ 0 Hz.
pub fn natural_frequencies_hz(
    machine: &Machine,
    bearing_speed_hz: f64,
) -> Result<Vec<f64>, SimError> {
    let pedestals: Vec<Option<PedestalDynamics>> = machine
        .bearings
        .iter()
        .map(|b| b.pedestal.map(PedestalDynamics::from))
        .collect();
    let assembly = Assembly::new(machine, &pedestals).map_err(SimError::Model)?;
    let coefs = (0..machine.bearings.len())
        .map(|b| machine.bearing_coefficients(b, bearing_speed_hz))
        .collect::<Result<Vec<_>, _>>()?;
    for (b, c) in coefs.iter().enumerate() {
        let scale = c.k[0][0].abs().max(c.k[1][1].abs()).max(1.0);
        if (c.k[0][1] - c.k[1][0]).abs() > 1e-12 * scale {
            return Err(SimError::Model(format!(
                "bearing {:?}: cross-coupled stiffness is not symmetric; natural frequencies of a non-conservative system are not defined here",
                machine.bearings[b].name
            )));
        }
    }
    let (k, m) = assembly.dense_stiffness_and_mass(&coefs);
    let chol = m
        .cholesky()
        .ok_or_else(|| SimError::Model("mass matrix is not positive definite".into()))?;
    let l = chol.l();
    let linv = l
        .clone()
        .try_inverse()
        .ok_or_else(|| SimError::Model("mass matrix factor is singular".into()))?;
    let a = &linv * k * linv.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let eig = nalgebra::SymmetricEigen::new(a);
    let mut f: Vec<f64> = eig
        .eigenvalues
        .iter()
        .map(|&l| l.max(0.0).sqrt() / std::f64::consts::TAU)
        .collect();
    f.sort_by(f64::total_cmp);
    Ok(f)
}
