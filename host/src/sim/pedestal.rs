//! Pedestals: the flexible supports between each bearing and the rigid ground.
//! The paper's pedestal is the one parameter type [`Pedestal`]; the
//! simulator's effects need the richer [`PedestalDynamics`] built from it.

use crate::estimate::Pedestal;
use num_complex::Complex;

/// A pedestal with everything the simulator can give it beyond the paper's
/// model (the effects of `crate::effects`): M = diag(m_y, m_z), full 2×2
/// stiffness and damping, and a structural loss factor η (K → K·(1 + iη)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PedestalDynamics {
    /// Masses (m_y, m_z) [kg].
    pub m: [f64; 2],
    /// Stiffness to ground [[k_y, k_yz], [k_zy, k_z]] [N/m].
    pub k: [[f64; 2]; 2],
    /// Viscous damping to ground [[c_y, c_yz], [c_zy, c_z]] [N·s/m].
    pub c: [[f64; 2]; 2],
    /// Structural (hysteretic) loss factor η [-].
    pub eta: f64,
}

impl From<Pedestal> for PedestalDynamics {
    fn from(p: Pedestal) -> Self {
        Self {
            m: [p.m, p.m],
            k: [[p.k_y, 0.0], [0.0, p.k_z]],
            c: [[p.c_y, 0.0], [0.0, p.c_z]],
            eta: 0.0,
        }
    }
}

impl PedestalDynamics {
    /// Dynamic stiffness −Ω²M + iΩC + K(1 + iη) at Ω [rad/s], [N/m].
    pub fn impedance(&self, omega: f64) -> [[Complex<f64>; 2]; 2] {
        let mut z = [[Complex::new(0.0, 0.0); 2]; 2];
        for (i, row) in z.iter_mut().enumerate() {
            for (j, zij) in row.iter_mut().enumerate() {
                let mass = if i == j { self.m[i] } else { 0.0 };
                *zij = Complex::new(
                    self.k[i][j] - omega * omega * mass,
                    omega * self.c[i][j] + self.eta * self.k[i][j],
                );
            }
        }
        z
    }
}
