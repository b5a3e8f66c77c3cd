//! Bases: rigid bodies (a baseplate, skid or steel frame) that pedestals
//! stand on, carried to the ground by their own springs and dampers.
//!
//! A base has two DOFs `[y, z]` (translation; its rocking is not modelled).
//! A pedestal standing on a base acts between pedestal and base: with
//! Z_p(Ω) = K_p(1 + iη_p) + iΩC_p its force on the base is
//! Z_p·(x_ped − x_base). The base stands on the ground through
//! Z_g(Ω) = K_B(1 + iη_B) + iΩC_B − Ω²M_B (diagonal in y, z).
//!
//! Bases couple pedestals that may be far apart along the shaft, so their
//! DOFs are kept out of the band: [`BaseBorder`] holds the border blocks of
//! the bordered system
//! ```text
//! [ A0  B ] [x ]   [f ]
//! [ B'  D ] [xb] = [fb]
//! ```
//! and solves it by the Schur complement of the (banded) A0, with one extra
//! banded solve per base DOF: the cost stays linear in the shaft elements.

use super::banded::C64;
use super::pedestal::PedestalDynamics;

/// A base body on its own springs and dampers to ground.
#[derive(Clone, Debug, PartialEq)]
pub struct Base {
    /// Name (used in `truth.json` and `base.csv`).
    pub name: String,
    /// Masses (m_y, m_z) [kg].
    pub m: [f64; 2],
    /// Stiffness to ground (k_y, k_z) [N/m]; `f64::INFINITY` is not allowed
    /// (use very large values for a near-rigid base).
    pub k: [f64; 2],
    /// Viscous damping to ground (c_y, c_z) [N·s/m].
    pub c: [f64; 2],
    /// Structural (hysteretic) loss factor of the springs to ground η [-]
    /// (K → K·(1 + iη)).
    pub eta: f64,
}

impl Base {
    /// Dynamic stiffness to ground −Ω²M + iΩC + K(1 + iη) at Ω [rad/s],
    /// (y, z) [N/m].
    pub fn impedance(&self, omega: f64) -> [C64; 2] {
        std::array::from_fn(|d| {
            C64::new(
                self.k[d] - omega * omega * self.m[d],
                omega * self.c[d] + self.eta * self.k[d],
            )
        })
    }

    /// Undamped natural frequencies (y, z) [Hz] of the base alone on its
    /// springs to ground, sqrt(k/m)/2π (pedestals not included).
    pub fn natural_frequencies_hz(&self) -> [f64; 2] {
        std::array::from_fn(|d| (self.k[d] / self.m[d]).sqrt() / std::f64::consts::TAU)
    }

    /// Checks that every value is physical; `Err` names the field.
    pub fn check(&self) -> Result<(), String> {
        for d in 0..2 {
            let axis = ["y", "z"][d];
            if !(self.m[d].is_finite() && self.m[d] > 0.0) {
                return Err(format!(
                    "m_{axis} must be finite and > 0 (got {})",
                    self.m[d]
                ));
            }
            if !(self.k[d].is_finite() && self.k[d] > 0.0) {
                return Err(format!(
                    "k_{axis} must be finite and > 0 (got {})",
                    self.k[d]
                ));
            }
            if !(self.c[d].is_finite() && self.c[d] >= 0.0) {
                return Err(format!(
                    "c_{axis} must be finite and >= 0 (got {})",
                    self.c[d]
                ));
            }
        }
        if !(self.eta.is_finite() && self.eta >= 0.0) {
            return Err(format!("eta must be finite and >= 0 (got {})", self.eta));
        }
        Ok(())
    }
}

/// A pedestal standing on a base: the link between its two DOFs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BaseLink {
    /// First pedestal DOF (y; z follows) in the banded part.
    pub pedestal_dof: usize,
    /// Index of the base.
    pub base: usize,
    /// The pedestal's stiffness, damping and loss factor (its mass stays on
    /// the pedestal DOFs).
    pub pedestal: PedestalDynamics,
}

impl BaseLink {
    /// Z_p(Ω) = K(1 + iη) + iΩC [N/m], the pedestal's spring and damper.
    fn impedance(&self, omega: f64) -> [[C64; 2]; 2] {
        let p = &self.pedestal;
        std::array::from_fn(|i| {
            std::array::from_fn(|j| C64::new(p.k[i][j], omega * p.c[i][j] + p.eta * p.k[i][j]))
        })
    }
}

/// The base DOFs of an assembly: bases, their links to pedestals, and where
/// their DOFs start (after the banded part).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BaseBorder {
    /// The bases, in file order; base i owns DOFs `first_dof + 2i` (y) and
    /// `first_dof + 2i + 1` (z).
    pub bases: Vec<Base>,
    /// Pedestal-to-base links.
    pub links: Vec<BaseLink>,
    /// First base DOF (= order of the banded part).
    pub first_dof: usize,
}

impl BaseBorder {
    /// Number of base DOFs.
    pub fn n_dof(&self) -> usize {
        2 * self.bases.len()
    }

    /// Whether there is no base.
    pub fn is_empty(&self) -> bool {
        self.bases.is_empty()
    }

    /// The border blocks at Ω [rad/s]: `b[l]` the (pedestal, base) 2×2 block
    /// of link l (= −Z_p, also the (base, pedestal) block), and the dense
    /// base-base block D (2nb × 2nb, row-major).
    fn blocks(&self, omega: f64) -> (Vec<[[C64; 2]; 2]>, nalgebra::DMatrix<C64>) {
        let nb = self.n_dof();
        let mut d = nalgebra::DMatrix::<C64>::zeros(nb, nb);
        for (i, base) in self.bases.iter().enumerate() {
            let z = base.impedance(omega);
            d[(2 * i, 2 * i)] += z[0];
            d[(2 * i + 1, 2 * i + 1)] += z[1];
        }
        let mut b = Vec::with_capacity(self.links.len());
        for l in &self.links {
            let z = l.impedance(omega);
            for i in 0..2 {
                for j in 0..2 {
                    d[(2 * l.base + i, 2 * l.base + j)] += z[i][j];
                }
            }
            b.push(std::array::from_fn(|i| std::array::from_fn(|j| -z[i][j])));
        }
        (b, d)
    }

    /// Solves the bordered system for spin Ω [rad/s], given `inner` that
    /// solves A0·y = r in place on the banded part (length `first_dof`).
    /// `f` (length `first_dof + n_dof()`) is overwritten by the solution.
    pub fn solve<E>(
        &self,
        omega: f64,
        f: &mut [C64],
        mut inner: impl FnMut(&mut [C64]) -> Result<(), E>,
        singular: impl Fn(usize) -> E,
    ) -> Result<(), E> {
        let n0 = self.first_dof;
        let (head, tail) = f.split_at_mut(n0);
        inner(head)?;
        if self.is_empty() {
            return Ok(());
        }
        let nb = self.n_dof();
        let (b, mut s) = self.blocks(omega);
        // W = A0⁻¹·B, one banded solve per base DOF.
        let mut w = Vec::with_capacity(nb);
        for col in 0..nb {
            let mut u = vec![C64::new(0.0, 0.0); n0];
            for (l, blk) in self.links.iter().zip(&b) {
                if 2 * l.base <= col && col < 2 * l.base + 2 {
                    let j = col - 2 * l.base;
                    u[l.pedestal_dof] += blk[0][j];
                    u[l.pedestal_dof + 1] += blk[1][j];
                }
            }
            inner(&mut u)?;
            w.push(u);
        }
        // S = D − B'·W, rhs = fb − B'·x0 (B' rows: base, columns: pedestal).
        let mut rhs = nalgebra::DVector::<C64>::from_fn(nb, |i, _| tail[i]);
        for (l, blk) in self.links.iter().zip(&b) {
            for (i, blk_row) in blk.iter().enumerate() {
                let row = 2 * l.base + i;
                for (j, &z) in blk_row.iter().enumerate() {
                    let dof = l.pedestal_dof + j;
                    rhs[row] -= z * head[dof];
                    for (col, wc) in w.iter().enumerate() {
                        s[(row, col)] -= z * wc[dof];
                    }
                }
            }
        }
        let xb = s.lu().solve(&rhs).ok_or_else(|| singular(n0))?;
        for (col, wc) in w.iter().enumerate() {
            for (x, wi) in head.iter_mut().zip(wc) {
                *x -= *wi * xb[col];
            }
        }
        for (t, v) in tail.iter_mut().zip(xb.iter()) {
            *t = *v;
        }
        Ok(())
    }

    /// Adds the bases' real stiffness and mass (links and ground springs) to
    /// dense matrices of the whole model (modal checks on small models).
    pub fn add_dense(&self, k: &mut nalgebra::DMatrix<f64>, m: &mut nalgebra::DMatrix<f64>) {
        let n0 = self.first_dof;
        for (i, base) in self.bases.iter().enumerate() {
            for d in 0..2 {
                k[(n0 + 2 * i + d, n0 + 2 * i + d)] += base.k[d];
                m[(n0 + 2 * i + d, n0 + 2 * i + d)] += base.m[d];
            }
        }
        for l in &self.links {
            let bd = n0 + 2 * l.base;
            for i in 0..2 {
                for j in 0..2 {
                    let v = l.pedestal.k[i][j];
                    k[(bd + i, bd + j)] += v;
                    k[(l.pedestal_dof + i, bd + j)] -= v;
                    k[(bd + i, l.pedestal_dof + j)] -= v;
                }
            }
        }
    }
}

/// The bases of `machine` as recorded in `truth.json` (`Truth::bases`).
pub fn truth(machine: &super::machine::Machine) -> Vec<crate::rundir::BaseTruth> {
    machine
        .bases
        .iter()
        .enumerate()
        .map(|(i, b)| crate::rundir::BaseTruth {
            name: b.name.clone(),
            bearings: machine
                .bearings
                .iter()
                .filter(|brg| brg.base == Some(i))
                .map(|brg| brg.name.clone())
                .collect(),
            m_y: b.m[0],
            m_z: b.m[1],
            k_y: b.k[0],
            k_z: b.k[1],
            c_y: b.c[0],
            c_z: b.c[1],
            eta: b.eta,
        })
        .collect()
}

impl BaseBorder {
    /// The (y, z) phasors [m] of every base from a full solution vector `x`.
    pub fn motion(&self, x: &[C64]) -> Vec<[C64; 2]> {
        (0..self.bases.len())
            .map(|j| {
                let d = self.first_dof + 2 * j;
                [x[d], x[d + 1]]
            })
            .collect()
    }
}
