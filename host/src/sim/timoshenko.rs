//! Timoshenko beam element of a rotating shaft: consistent mass with rotary
//! inertia, shear deformation and the gyroscopic matrix (Nelson 1980;
//! Friswell et al., *Dynamics of Rotating Machines*, 2010, ch. 5; the same
//! uniform-element formulas as ROSS 2.3 `ShaftElement`).
//!
//! Local DOF order of one element (node 0 then node 1), per node
//! `[y, z, θ_y, θ_z]`: y vertical, z horizontal displacements [m], θ_y and θ_z
//! the rotations [rad] about the y and z axes (right-handed, x along the rotor).
//! In the x-y plane the slope is dy/dx = θ_z; in the x-z plane dz/dx = −θ_y.
//! Equation of motion: M·q̈ + (C + Ω·G)·q̇ + K·q = f, Ω the spin [rad/s] about +x.

/// Material and cross-section of one uniform shaft element.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShaftElement {
    /// Element length [m].
    pub length: f64,
    /// Outer diameter [m].
    pub outer_diameter: f64,
    /// Inner diameter [m] (0 for a solid shaft).
    pub inner_diameter: f64,
    /// Young's modulus [Pa].
    pub young: f64,
    /// Shear modulus [Pa].
    pub shear: f64,
    /// Density [kg/m³].
    pub density: f64,
}

/// An 8×8 element matrix in the local DOF order of the module docs.
pub type Matrix8 = [[f64; 8]; 8];

/// Local DOFs of the x-y bending plane, as (w0, θ0, w1, θ1) with θ = dw/dx.
const PLANE_Y: [usize; 4] = [0, 3, 4, 7];
/// Local DOFs of the x-z bending plane, as (w0, θ0, w1, θ1); θ_y = −dz/dx.
const PLANE_Z: [usize; 4] = [1, 2, 5, 6];
/// Sign of each PLANE_Z DOF relative to (w, dw/dx).
const SIGN_Z: [f64; 4] = [1.0, -1.0, 1.0, -1.0];

impl ShaftElement {
    /// Cross-section area [m²].
    pub fn area(&self) -> f64 {
        std::f64::consts::PI * (self.outer_diameter.powi(2) - self.inner_diameter.powi(2)) / 4.0
    }

    /// Second moment of area about a diameter [m⁴].
    pub fn second_moment(&self) -> f64 {
        std::f64::consts::PI * (self.outer_diameter.powi(4) - self.inner_diameter.powi(4)) / 64.0
    }

    /// Mass [kg].
    pub fn mass(&self) -> f64 {
        self.density * self.area() * self.length
    }

    /// Poisson's ratio implied by E and G, ν = E/(2G) − 1.
    pub fn poisson(&self) -> f64 {
        self.young / (2.0 * self.shear) - 1.0
    }

    /// Shear coefficient κ of a hollow circular section (Cowper 1966, as ROSS).
    pub fn shear_coefficient(&self) -> f64 {
        let nu = self.poisson();
        let r = self.inner_diameter / self.outer_diameter;
        let r2 = r * r;
        let r12 = (1.0 + r2).powi(2);
        6.0 * r12 * (1.0 + nu) / (r12 * (7.0 + 6.0 * nu) + r2 * (20.0 + 12.0 * nu))
    }

    /// Shear-deformation parameter φ = 12·E·I / (κ·G·A·L²) [-].
    pub fn phi(&self) -> f64 {
        12.0 * self.young * self.second_moment()
            / (self.shear_coefficient() * self.shear * self.area() * self.length.powi(2))
    }

    /// Places a 4×4 plane matrix (in (w, dw/dx) coordinates) into both planes.
    fn both_planes(p: &[[f64; 4]; 4]) -> Matrix8 {
        let mut out = [[0.0; 8]; 8];
        for i in 0..4 {
            for j in 0..4 {
                out[PLANE_Y[i]][PLANE_Y[j]] = p[i][j];
                out[PLANE_Z[i]][PLANE_Z[j]] = SIGN_Z[i] * SIGN_Z[j] * p[i][j];
            }
        }
        out
    }

    /// Rotary-inertia pattern ρI/(30L(1+φ)²)·[...] in (w, dw/dx) coordinates.
    fn rotary_pattern(&self) -> [[f64; 4]; 4] {
        let (l, phi) = (self.length, self.phi());
        let s = self.density * self.second_moment() / (30.0 * l * (1.0 + phi).powi(2));
        let a = (3.0 - 15.0 * phi) * l;
        let b = (4.0 + 5.0 * phi + 10.0 * phi * phi) * l * l;
        let c = (-1.0 - 5.0 * phi + 5.0 * phi * phi) * l * l;
        [
            [36.0 * s, a * s, -36.0 * s, a * s],
            [a * s, b * s, -a * s, c * s],
            [-36.0 * s, -a * s, 36.0 * s, -a * s],
            [a * s, c * s, -a * s, b * s],
        ]
    }

    /// Consistent mass matrix [kg, kg·m, kg·m²]: translational plus rotary inertia.
    pub fn mass_matrix(&self) -> Matrix8 {
        let (l, phi) = (self.length, self.phi());
        let s = self.density * self.area() * l / (840.0 * (1.0 + phi).powi(2));
        let m1 = 312.0 + 588.0 * phi + 280.0 * phi * phi;
        let m2 = (44.0 + 77.0 * phi + 35.0 * phi * phi) * l;
        let m3 = 108.0 + 252.0 * phi + 140.0 * phi * phi;
        let m4 = (26.0 + 63.0 * phi + 35.0 * phi * phi) * l;
        let m5 = (8.0 + 14.0 * phi + 7.0 * phi * phi) * l * l;
        let m6 = (6.0 + 14.0 * phi + 7.0 * phi * phi) * l * l;
        let t = [
            [m1 * s, m2 * s, m3 * s, -m4 * s],
            [m2 * s, m5 * s, m4 * s, -m6 * s],
            [m3 * s, m4 * s, m1 * s, -m2 * s],
            [-m4 * s, -m6 * s, -m2 * s, m5 * s],
        ];
        let r = self.rotary_pattern();
        let mut p = [[0.0; 4]; 4];
        for i in 0..4 {
            for j in 0..4 {
                p[i][j] = t[i][j] + r[i][j];
            }
        }
        Self::both_planes(&p)
    }

    /// Stiffness matrix [N/m, N, N·m] with shear deformation.
    pub fn stiffness_matrix(&self) -> Matrix8 {
        let (l, phi) = (self.length, self.phi());
        let s = self.young * self.second_moment() / (l.powi(3) * (1.0 + phi));
        let p = [
            [12.0 * s, 6.0 * l * s, -12.0 * s, 6.0 * l * s],
            [
                6.0 * l * s,
                (4.0 + phi) * l * l * s,
                -6.0 * l * s,
                (2.0 - phi) * l * l * s,
            ],
            [-12.0 * s, -6.0 * l * s, 12.0 * s, -6.0 * l * s],
            [
                6.0 * l * s,
                (2.0 - phi) * l * l * s,
                -6.0 * l * s,
                (4.0 + phi) * l * l * s,
            ],
        ];
        Self::both_planes(&p)
    }

    /// The stiffness in deformation form (see [`StiffnessForm`]).
    pub fn stiffness_form(&self) -> StiffnessForm {
        let l = self.length;
        let bending = self.young * self.second_moment() / l.powi(3);
        StiffnessForm {
            length: l,
            shear: 12.0 * bending / (1.0 + self.phi()),
            bending,
        }
    }

    /// Gyroscopic matrix [kg·m²] (multiplied by Ω and the velocities):
    /// skew-symmetric, coupling the two bending planes; twice the rotary
    /// inertia pattern because the polar moment is twice the diametral one.
    pub fn gyroscopic_matrix(&self) -> Matrix8 {
        let r = self.rotary_pattern();
        let mut g = [[0.0; 8]; 8];
        for i in 0..4 {
            for j in 0..4 {
                let v = 2.0 * r[i][j] * SIGN_Z[j];
                g[PLANE_Y[i]][PLANE_Z[j]] = v;
                g[PLANE_Z[j]][PLANE_Y[i]] = -v;
            }
        }
        g
    }
}

/// An element's stiffness written through its deformations: per bending
/// plane, with (w0, θ0, w1, θ1) in (w, dw/dx) coordinates, the chord
/// deviation a = w1 − w0 − l(θ0 + θ1)/2 [m] and the bending b = l(θ1 − θ0)
/// [m], qᵀKq = 12s·a² + (1+φ)s·b² with s = EI/(l³(1+φ)) (the same K as
/// [`ShaftElement::stiffness_matrix`]). K·q computed this way has no large
/// terms that cancel (on a fine mesh 12s ≈ κGA/l is huge but a is tiny) and
/// gives exactly zero for rigid translation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StiffnessForm {
    /// Element length l [m].
    pub length: f64,
    /// 12s = 12EI/(l³(1+φ)) [N/m].
    pub shear: f64,
    /// (1+φ)s = EI/l³ [N/m].
    pub bending: f64,
}

impl StiffnessForm {
    /// K·q [N, N·m] for the 8 local DOFs `q` (module order, complex
    /// phasors [m, rad]), from the deformations.
    pub fn forces(&self, q: &[num_complex::Complex<f64>; 8]) -> [num_complex::Complex<f64>; 8] {
        let mut f = [num_complex::Complex::new(0.0, 0.0); 8];
        let half = 0.5 * self.length;
        for (plane, sign) in [(PLANE_Y, [1.0; 4]), (PLANE_Z, SIGN_Z)] {
            let [w0, t0, w1, t1] = std::array::from_fn(|i| q[plane[i]] * sign[i]);
            let a = (w1 - w0) - (t0 + t1) * half;
            let b = (t1 - t0) * self.length;
            let fa = a * self.shear;
            let fb = b * (self.bending * self.length);
            let local = [-fa, -fa * half - fb, fa, -fa * half + fb];
            for i in 0..4 {
                f[plane[i]] = local[i] * sign[i];
            }
        }
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn steel(l: f64, od: f64, id: f64) -> ShaftElement {
        ShaftElement {
            length: l,
            outer_diameter: od,
            inner_diameter: id,
            young: 211e9,
            shear: 81.2e9,
            density: 7810.0,
        }
    }

    #[test]
    fn mass_matrix_carries_the_element_mass_in_translation() {
        let e = steel(0.25, 0.05, 0.01);
        let m = e.mass_matrix();
        // A rigid translation in y: q = (1,0,0,0,1,0,0,0) with zero slopes.
        let q = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0];
        let mut total = 0.0;
        for i in 0..8 {
            for j in 0..8 {
                total += q[i] * m[i][j] * q[j];
            }
        }
        assert!((total - e.mass()).abs() < 1e-12 * e.mass());
    }

    #[test]
    fn rigid_motions_cost_no_strain_energy() {
        let e = steel(0.3, 0.08, 0.0);
        let k = e.stiffness_matrix();
        let l = e.length;
        // Rigid tilt in the x-y plane: y = x·a, θ_z = a; in x-z: z = x·b, θ_y = −b.
        let q = [0.0, 0.0, -2.0, 1.0, l, 2.0 * l, -2.0, 1.0];
        for row in &k {
            let f: f64 = row.iter().zip(q.iter()).map(|(a, b)| a * b).sum();
            assert!(
                f.abs() < 1e-6 * e.young * e.second_moment() / l.powi(2),
                "{f}"
            );
        }
    }

    #[test]
    fn matrices_are_symmetric_and_gyroscopic_is_skew() {
        let e = steel(0.1, 0.1, 0.02);
        let (m, k, g) = (e.mass_matrix(), e.stiffness_matrix(), e.gyroscopic_matrix());
        for i in 0..8 {
            for j in 0..8 {
                assert!((m[i][j] - m[j][i]).abs() <= 1e-12 * m[i][i].abs().max(1.0));
                assert!((k[i][j] - k[j][i]).abs() <= 1e-9 * k[0][0].abs());
                assert!((g[i][j] + g[j][i]).abs() <= 1e-15);
            }
        }
    }

    /// The deformation form is the stiffness matrix, on a long and on a
    /// very short element (φ ≈ 10⁸), and a rigid translation costs nothing.
    #[test]
    fn deformation_form_is_the_stiffness_matrix() {
        type C = num_complex::Complex<f64>;
        for l in [0.3, 1.2e-5] {
            let e = steel(l, 0.1, 0.02);
            let k = e.stiffness_matrix();
            let q: [C; 8] = std::array::from_fn(|i| {
                C::new(1.0 + 0.37 * i as f64, -0.5 + 0.11 * (i * i) as f64)
            });
            let f = e.stiffness_form().forces(&q);
            let scale = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            for i in 0..8 {
                let want: C = (0..8).map(|j| q[j] * k[i][j]).sum();
                assert!(
                    (f[i] - want).norm() <= 1e-12 * scale * 10.0,
                    "l={l} row {i}"
                );
            }
            let rigid = [
                C::new(0.7, 0.1),
                C::new(-0.2, 0.3),
                C::new(0.0, 0.0),
                C::new(0.0, 0.0),
                C::new(0.7, 0.1),
                C::new(-0.2, 0.3),
                C::new(0.0, 0.0),
                C::new(0.0, 0.0),
            ];
            assert!(e
                .stiffness_form()
                .forces(&rigid)
                .iter()
                .all(|v| v.norm() == 0.0));
        }
    }

    #[test]
    fn cowper_shear_coefficient_of_a_solid_section() {
        let e = steel(1.0, 0.1, 0.0);
        let nu = e.poisson();
        let expected = 6.0 * (1.0 + nu) / (7.0 + 6.0 * nu);
        assert!((e.shear_coefficient() - expected).abs() < 1e-15);
    }
}
