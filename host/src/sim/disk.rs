//! Rigid disk on a shaft node: mass, diametral and polar inertia, and its
//! gyroscopic coupling (ROSS `DiskElement` convention).

/// A rigid disk attached to one shaft node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    /// Shaft node index the disk sits on.
    pub node: usize,
    /// Mass [kg].
    pub mass: f64,
    /// Polar moment of inertia about the rotor axis [kg·m²].
    pub polar_inertia: f64,
    /// Diametral moment of inertia about a diameter through its centre [kg·m²].
    pub diametral_inertia: f64,
}

/// Mass [kg], polar and diametral inertia [kg·m²] of a uniform annular disk
/// of `width`, `outer_diameter`, `inner_diameter` [m] and `density` [kg/m³]:
/// m = ρπw(D²−d²)/4, I_p = m(D²+d²)/8, I_d = I_p/2 + m·w²/12.
pub fn inertia_from_geometry(
    width: f64,
    outer_diameter: f64,
    inner_diameter: f64,
    density: f64,
) -> (f64, f64, f64) {
    let m =
        density * std::f64::consts::PI * width * (outer_diameter.powi(2) - inner_diameter.powi(2))
            / 4.0;
    let ip = m * (outer_diameter.powi(2) + inner_diameter.powi(2)) / 8.0;
    let id = ip / 2.0 + m * width * width / 12.0;
    (m, ip, id)
}

impl Disk {
    /// 4×4 mass matrix in the node DOF order `[y, z, θ_y, θ_z]`.
    pub fn mass_matrix(&self) -> [[f64; 4]; 4] {
        let mut m = [[0.0; 4]; 4];
        m[0][0] = self.mass;
        m[1][1] = self.mass;
        m[2][2] = self.diametral_inertia;
        m[3][3] = self.diametral_inertia;
        m
    }

    /// 4×4 gyroscopic matrix (times Ω and the velocities), skew-symmetric:
    /// G[θ_y][θ_z] = I_p, G[θ_z][θ_y] = −I_p.
    pub fn gyroscopic_matrix(&self) -> [[f64; 4]; 4] {
        let mut g = [[0.0; 4]; 4];
        g[2][3] = self.polar_inertia;
        g[3][2] = -self.polar_inertia;
        g
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thin_solid_disk_has_polar_twice_diametral() {
        let (m, ip, id) = inertia_from_geometry(1e-6, 0.5, 0.0, 7800.0);
        assert!((ip - m * 0.25 / 8.0).abs() < 1e-18);
        assert!((ip - 2.0 * id).abs() < 1e-9 * ip);
    }
}
