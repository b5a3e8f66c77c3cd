//! The paper's regression equations (Feng & Hahn eq. 4) for one pedestal.
//!
//! Per speed, (−Ω²M + iΩC + K)·ped = F splits into four real equations that are
//! linear in the five pedestal parameters θ = (k_y, k_z, m, c_y, c_z):
//!
//! ```text
//! y, real:  k_y·Re X_y − Ω²·m·Re X_y − Ω·c_y·Im X_y = Re F_y
//! y, imag:  k_y·Im X_y − Ω²·m·Im X_y + Ω·c_y·Re X_y = Im F_y
//! z: the same with k_z, c_z
//! ```
//!
//! Parameters are handled in scaled units (θ_i / scale_i) so that the columns of
//! the regression are of similar size and f32 stays well conditioned.

use crate::bearing::BearingCoefficients;
use crate::phasor::Phasor2;
use num_traits::Float;

/// Number of pedestal parameters in the paper's model.
pub const PARAMETERS: usize = 5;

/// Index of each parameter in θ = (k_y, k_z, m, c_y, c_z).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Parameter {
    /// Vertical stiffness k_y [N/m].
    Ky = 0,
    /// Horizontal stiffness k_z [N/m].
    Kz = 1,
    /// Pedestal mass m [kg], the same in y and z.
    M = 2,
    /// Vertical viscous damping c_y [N·s/m].
    Cy = 3,
    /// Horizontal viscous damping c_z [N·s/m].
    Cz = 4,
}

impl Parameter {
    /// All parameters in θ order.
    pub const ALL: [Parameter; PARAMETERS] = [
        Parameter::Ky,
        Parameter::Kz,
        Parameter::M,
        Parameter::Cy,
        Parameter::Cz,
    ];

    /// The name used in files and on the command line (formats.md).
    pub const fn name(self) -> &'static str {
        match self {
            Parameter::Ky => "k_y",
            Parameter::Kz => "k_z",
            Parameter::M => "m",
            Parameter::Cy => "c_y",
            Parameter::Cz => "c_z",
        }
    }

    /// Parses a name as written in files and on the command line.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }
}

/// How the real and imaginary parts of eq. 3 are used (the paper's Table 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EquationMode {
    /// R&I: all four equations used independently (correct with damping).
    RealAndImag,
    /// R+I: the real-part and imaginary-part equations added together.
    RealPlusImag,
    /// R: only the real-part equations.
    Real,
    /// I: only the imaginary-part equations.
    Imag,
}

/// One real linear equation `row · θ = rhs` in physical units
/// (row entries in m, m·s⁻² ... such that row·θ is a force [N]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Equation<T> {
    /// Coefficients of (k_y, k_z, m, c_y, c_z).
    pub row: [T; PARAMETERS],
    /// Right-hand side: a force component [N].
    pub rhs: T,
}

/// The four equations of eq. 4 at one speed, in the order
/// (y real, y imag, z real, z imag).
///
/// `omega` [rad/s], `ped` the absolute pedestal 1X displacement [m], `force`
/// the force the bearing transmits to the pedestal [N].
pub fn equations<T: Float>(omega: T, ped: &Phasor2<T>, force: &Phasor2<T>) -> [Equation<T>; 4] {
    let z = T::zero();
    let w2 = omega * omega;
    let [xy, xz] = *ped;
    let [fy, fz] = *force;
    [
        Equation {
            row: [xy.re, z, -w2 * xy.re, -omega * xy.im, z],
            rhs: fy.re,
        },
        Equation {
            row: [xy.im, z, -w2 * xy.im, omega * xy.re, z],
            rhs: fy.im,
        },
        Equation {
            row: [z, xz.re, -w2 * xz.re, z, -omega * xz.im],
            rhs: fz.re,
        },
        Equation {
            row: [z, xz.im, -w2 * xz.im, z, omega * xz.re],
            rhs: fz.im,
        },
    ]
}

/// The equations of one speed as used by `mode`: four for R&I, two otherwise.
/// Returns the equations and how many of the four slots are filled.
pub fn equations_for_mode<T: Float>(
    mode: EquationMode,
    omega: T,
    ped: &Phasor2<T>,
    force: &Phasor2<T>,
) -> ([Equation<T>; 4], usize) {
    let [yr, yi, zr, zi] = equations(omega, ped, force);
    let add = |a: Equation<T>, b: Equation<T>| {
        let mut row = a.row;
        for (r, bi) in row.iter_mut().zip(b.row) {
            *r = *r + bi;
        }
        Equation {
            row,
            rhs: a.rhs + b.rhs,
        }
    };
    match mode {
        EquationMode::RealAndImag => ([yr, yi, zr, zi], 4),
        EquationMode::Real => ([yr, zr, yr, zr], 2),
        EquationMode::Imag => ([yi, zi, yi, zi], 2),
        EquationMode::RealPlusImag => {
            let y = add(yr, yi);
            let zz = add(zr, zi);
            ([y, zz, y, zz], 2)
        }
    }
}

/// Variance E|n_F|² [N²] of the noise of the bearing force
/// F = (K_b + iΩC_b)·rel per direction (y, z), for rotor-relative phasors
/// whose noises are independent, circular, of standard deviations `rel_sd`
/// [m] (y, z): Σ_j |K_ij + iΩC_ij|²·σ_j², cross terms included. `omega`
/// [rad/s]. Squares: scale the phasors to order one first (see
/// [`PedestalRls::update_weighted`](crate::rls::PedestalRls::update_weighted)).
pub fn force_noise_variance<T: Float>(
    bearing: &BearingCoefficients<T>,
    omega: T,
    rel_sd: &[T; 2],
) -> [T; 2] {
    core::array::from_fn(|i| {
        let term = |j: usize| {
            let (k, c) = (bearing.k[i][j], omega * bearing.c[i][j]);
            (k * k + c * c) * rel_sd[j] * rel_sd[j]
        };
        term(0) + term(1)
    })
}

/// Nominal parameter sizes used to scale the regression columns: the solver
/// works with θ_i / scale_i, which are of order one for typical pedestals.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParameterScale<T> {
    /// Stiffness scale [N/m] (default 1e7).
    pub k: T,
    /// Mass scale [kg] (default 1e2).
    pub m: T,
    /// Damping scale [N·s/m] (default 1e3).
    pub c: T,
}

impl<T: Float> Default for ParameterScale<T> {
    fn default() -> Self {
        let cv = |x: f64| T::from(x).unwrap_or_else(T::one);
        Self {
            k: cv(1.0e7),
            m: cv(1.0e2),
            c: cv(1.0e3),
        }
    }
}

impl<T: Float> ParameterScale<T> {
    /// The scale of each parameter in θ order.
    pub fn as_array(&self) -> [T; PARAMETERS] {
        [self.k, self.k, self.m, self.c, self.c]
    }

    /// Rewrites an equation for scaled parameters θ_i / scale_i.
    #[inline]
    pub fn scale(&self, eq: &Equation<T>) -> Equation<T> {
        let s = self.as_array();
        let mut row = eq.row;
        for (r, si) in row.iter_mut().zip(s) {
            *r = *r * si;
        }
        Equation { row, rhs: eq.rhs }
    }

    /// Physical parameter values from scaled ones.
    #[inline]
    pub fn unscale(&self, scaled: &[T; PARAMETERS]) -> [T; PARAMETERS] {
        let s = self.as_array();
        let mut out = *scaled;
        for (o, si) in out.iter_mut().zip(s) {
            *o = *o * si;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phasor::Complex;

    fn residual(eq: &Equation<f64>, theta: &[f64; 5]) -> f64 {
        eq.row.iter().zip(theta).map(|(a, b)| a * b).sum::<f64>() - eq.rhs
    }

    #[test]
    fn exact_pedestal_satisfies_all_four_equations() {
        let theta = [1.0e7, 1.5e7, 120.0, 90.0, 70.0];
        let omega = 300.0;
        let ped = [Complex::new(3e-6, -1e-6), Complex::new(-2e-6, 4e-6)];
        // F = (−Ω²m + iΩc + k)·X per direction.
        let f = |k: f64, c: f64, x: Complex<f64>| {
            Complex::new(k - omega * omega * theta[2], omega * c) * x
        };
        let force = [f(theta[0], theta[3], ped[0]), f(theta[1], theta[4], ped[1])];
        for mode in [
            EquationMode::RealAndImag,
            EquationMode::RealPlusImag,
            EquationMode::Real,
            EquationMode::Imag,
        ] {
            let (eqs, n) = equations_for_mode(mode, omega, &ped, &force);
            for eq in &eqs[..n] {
                assert!(residual(eq, &theta).abs() < 1e-9, "{mode:?}");
            }
        }
    }

    #[test]
    fn scaling_round_trips() {
        let s = ParameterScale::<f64>::default();
        let theta = [1.0e7, 1.5e7, 120.0, 90.0, 70.0];
        let scaled: [f64; 5] = core::array::from_fn(|i| theta[i] / s.as_array()[i]);
        let back = s.unscale(&scaled);
        for i in 0..5 {
            assert!((back[i] - theta[i]).abs() <= 1e-9 * theta[i]);
        }
        let eq = Equation {
            row: [1.0, 2.0, 3.0, 4.0, 5.0],
            rhs: 7.0,
        };
        let se = s.scale(&eq);
        let lhs: f64 = se.row.iter().zip(&scaled).map(|(a, b)| a * b).sum();
        let lhs0: f64 = eq.row.iter().zip(&theta).map(|(a, b)| a * b).sum();
        assert!((lhs - lhs0).abs() < 1e-6 * lhs0.abs());
    }

    #[test]
    fn force_noise_is_the_scatter_of_forces_from_noisy_rel() {
        // Cross-coupled oil-film-like coefficients; the force noise of each
        // direction by brute force over the four real noise directions.
        let b = BearingCoefficients {
            k: [[2.0e8, 5.0e7], [-3.0e7, 1.5e8]],
            c: [[4.0e5, 1.0e4], [2.0e4, 3.0e5]],
        };
        let omega = 250.0;
        let sd = [2e-7, 5e-7];
        // Circular noise of sd σ: σ/√2 on each of re and im.
        let mut var = [0.0f64; 2];
        for j in 0..2 {
            for unit in [Complex::new(1.0, 0.0), Complex::new(0.0, 1.0)] {
                let mut rel = [Complex::new(0.0, 0.0); 2];
                rel[j] = unit * (sd[j] / 2f64.sqrt());
                let f = b.force(omega, &rel);
                for i in 0..2 {
                    var[i] += f[i].norm_sqr();
                }
            }
        }
        let got = force_noise_variance(&b, omega, &sd);
        for i in 0..2 {
            assert!((got[i] - var[i]).abs() < 1e-12 * got[i], "{i}");
        }
    }

    #[test]
    fn parameter_names_round_trip() {
        for p in Parameter::ALL {
            assert_eq!(Parameter::from_name(p.name()), Some(p));
        }
        assert_eq!(Parameter::from_name("k_x"), None);
    }
}
