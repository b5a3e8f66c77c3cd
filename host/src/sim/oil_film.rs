//! Plain cylindrical oil-film bearing, short-bearing (Ocvirk) theory:
//! static eccentricity from the modified Sommerfeld number, then the eight
//! linearised stiffness and damping coefficients (Friswell et al., *Dynamics
//! of Rotating Machines*, 2010, §5.5, with half-Sommerfeld cavitation).
//!
//! Axes: y vertical (up), z horizontal, rotation from +y towards +z (positive
//! spin about +x). The static load W acts on the journal in −y (gravity); the
//! film pushes the journal up with +W. The coefficients give the increment of
//! the force the film exerts on the journal as −K·δe − C·δė, so the force on
//! the bearing shell (pedestal) is +(K + iΩC)·rel, as in formats.md.

use plinth_shared::bearing::BearingCoefficients;
use std::f64::consts::PI;

/// Geometry, lubricant and static load of a plain cylindrical bearing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OilFilmBearing {
    /// Journal diameter D [m].
    pub diameter: f64,
    /// Axial length L [m].
    pub length: f64,
    /// Radial clearance c [m].
    pub clearance: f64,
    /// Dynamic viscosity μ [Pa·s].
    pub viscosity: f64,
    /// Static load W carried by the film, acting on the journal in −y [N].
    pub load: f64,
}

/// Why the oil-film coefficients could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OilFilmError {
    /// The speed is zero, negative or not finite: a plain bearing has no film stiffness at rest.
    #[error("oil-film bearing needs a positive speed (got {0} Hz)")]
    Speed(f64),
    /// The eccentricity is so close to 1 that the linearisation is meaningless.
    #[error("eccentricity ratio {eccentricity:.6} at {} Hz: the film is too thin for short-bearing theory (ε must stay below 0.98): start the speeds (--speeds, --rundown) higher", crate::rundir::digits::format_number(*speed_hz))]
    TooEccentric {
        /// Rotor speed [Hz].
        speed_hz: f64,
        /// Eccentricity ratio found [-].
        eccentricity: f64,
    },
}

/// ε·sqrt(16ε² + π²(1−ε²))/(1−ε²)², the short-bearing load function; it
/// rises monotonically from 0 (ε = 0) to ∞ (ε → 1).
fn load_function(e: f64) -> f64 {
    let e2 = e * e;
    e * (16.0 * e2 + PI * PI * (1.0 - e2)).sqrt() / (1.0 - e2).powi(2)
}

/// Eccentricity ratio ε ∈ (0, 1) that satisfies the short-bearing load
/// relation S_s · ε·sqrt(16ε² + π²(1−ε²))/(1−ε²)² = 1 for the modified
/// Sommerfeld number S_s = D·Ω·μ·L³/(8·W·c²) [-] (bisection to machine precision).
pub fn eccentricity_from_sommerfeld(modified_sommerfeld: f64) -> f64 {
    let target = 1.0 / modified_sommerfeld;
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if load_function(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Dimensionless short-bearing coefficients at eccentricity ratio ε in
/// Friswell's frame (u horizontal, v along the static load line):
/// `(a, b)` with K = (W/c)·a and C = (W/(c·Ω))·b, indexed `[row][col]` over
/// (u, v) (Friswell et al. 2010, §5.5; the same forms as ROSS
/// `CylindricalBearing`). [`OilFilmBearing::coefficients`] maps them to (y, z).
pub fn dimensionless_coefficients(e: f64) -> ([[f64; 2]; 2], [[f64; 2]; 2]) {
    let e2 = e * e;
    let pi2 = PI * PI;
    let s = (1.0 - e2).sqrt();
    let h0 = 1.0 / (pi2 * (1.0 - e2) + 16.0 * e2).powf(1.5);
    let auu = h0 * 4.0 * (pi2 * (2.0 - e2) + 16.0 * e2);
    let auv = h0 * PI * (pi2 * (1.0 - e2).powi(2) - 16.0 * e2 * e2) / (e * s);
    let avu = -h0 * PI * (pi2 * (1.0 - e2) * (1.0 + 2.0 * e2) + 32.0 * e2 * (1.0 + e2)) / (e * s);
    let avv = h0 * 4.0 * (pi2 * (1.0 + 2.0 * e2) + 32.0 * e2 * (1.0 + e2) / (1.0 - e2));
    let buu = h0 * 2.0 * PI * s * (pi2 * (1.0 + 2.0 * e2) - 16.0 * e2) / e;
    let buv = -h0 * 8.0 * (pi2 * (1.0 + 2.0 * e2) - 16.0 * e2);
    let bvv = h0 * 2.0 * PI * (pi2 * (1.0 - e2).powi(2) + 48.0 * e2) / (e * s);
    ([[auu, auv], [avu, avv]], [[buu, buv], [buv, bvv]])
}

/// Attitude angle ψ [rad] between the load line and the line of centres,
/// tan ψ = π·sqrt(1−ε²)/(4ε); the journal is displaced by ψ from the load
/// direction, in the direction of rotation.
pub fn attitude_angle(e: f64) -> f64 {
    (PI * (1.0 - e * e).sqrt()).atan2(4.0 * e)
}

impl OilFilmBearing {
    /// Modified Sommerfeld (Ocvirk) number S_s = D·Ω·μ·L³/(8·W·c²) [-] at `speed_hz` [Hz].
    pub fn modified_sommerfeld(&self, speed_hz: f64) -> f64 {
        let omega = 2.0 * PI * speed_hz;
        self.diameter * omega * self.viscosity * self.length.powi(3)
            / (8.0 * self.load * self.clearance.powi(2))
    }

    /// Static eccentricity ratio ε [-] at `speed_hz` [Hz].
    pub fn eccentricity(&self, speed_hz: f64) -> Result<f64, OilFilmError> {
        if !(speed_hz > 0.0 && speed_hz.is_finite()) {
            return Err(OilFilmError::Speed(speed_hz));
        }
        Ok(eccentricity_from_sommerfeld(
            self.modified_sommerfeld(speed_hz),
        ))
    }

    /// Static journal position (y, z) [m] relative to the bearing centre at `speed_hz` [Hz].
    pub fn static_position(&self, speed_hz: f64) -> Result<[f64; 2], OilFilmError> {
        let e = self.eccentricity(speed_hz)?;
        let psi = attitude_angle(e);
        // Load direction −y, turned by ψ in the direction of rotation (y → z): −y → −z.
        Ok([
            -e * self.clearance * psi.cos(),
            -e * self.clearance * psi.sin(),
        ])
    }

    /// The eight coefficients in (y, z) at `speed_hz` [Hz]: K [N/m], C [N·s/m].
    pub fn coefficients(&self, speed_hz: f64) -> Result<BearingCoefficients<f64>, OilFilmError> {
        let e = self.eccentricity(speed_hz)?;
        if e > 0.98 {
            return Err(OilFilmError::TooEccentric {
                speed_hz,
                eccentricity: e,
            });
        }
        let omega = 2.0 * PI * speed_hz;
        let (a, b) = dimensionless_coefficients(e);
        let ks = self.load / self.clearance;
        let cs = self.load / (self.clearance * omega);
        // Friswell's frame has u horizontal and v along the load line; in
        // (y, z) with rotation y → z the published forms become
        // K_yy = a_vv, K_yz = −a_vu, K_zy = −a_uv, K_zz = a_uu (and C alike),
        // as the numerical derivatives of the film force confirm (tests).
        Ok(BearingCoefficients {
            k: [[ks * a[1][1], -ks * a[1][0]], [-ks * a[0][1], ks * a[0][0]]],
            c: [[cs * b[1][1], -cs * b[1][0]], [-cs * b[0][1], cs * b[0][0]]],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Film force on the journal (y, z) [N] from the short-bearing Reynolds
    /// equation with half-Sommerfeld cavitation, integrated numerically: an
    /// independent route to the coefficients (no closed forms used).
    fn film_force(b: &OilFilmBearing, omega: f64, e: [f64; 2], v: [f64; 2]) -> [f64; 2] {
        let n = 20_000;
        let r = b.diameter / 2.0;
        let mu = b.viscosity;
        let l3 = b.length.powi(3);
        let mut f = [0.0; 2];
        let dth = 2.0 * PI / n as f64;
        for k in 0..n {
            let th = (k as f64 + 0.5) * dth;
            let (s, c) = th.sin_cos();
            let h = b.clearance - e[0] * c - e[1] * s;
            let h_th = e[0] * s - e[1] * c;
            let h_t = -v[0] * c - v[1] * s;
            let g = 0.5 * omega * h_th + h_t;
            // ∫p dz over the length: p = 6μG(z² − L²/4)/h³ → −μ L³ G / h³.
            let p = (-mu * l3 * g / h.powi(3)).max(0.0);
            f[0] -= p * c * r * dth;
            f[1] -= p * s * r * dth;
        }
        f
    }

    fn bearing() -> OilFilmBearing {
        OilFilmBearing {
            diameter: 0.1,
            length: 0.0254,
            clearance: 100e-6,
            viscosity: 0.0069,
            load: 2000.0,
        }
    }

    #[test]
    fn sommerfeld_relation_is_inverted() {
        for &e in &[0.05, 0.3, 0.5, 0.8, 0.95] {
            let s = 1.0 / load_function(e);
            assert!((eccentricity_from_sommerfeld(s) - e).abs() < 1e-12);
        }
    }

    #[test]
    fn static_position_carries_the_load() {
        let b = bearing();
        for &hz in &[10.0, 50.0, 150.0] {
            let omega = 2.0 * PI * hz;
            let pos = b.static_position(hz).unwrap();
            let f = film_force(&b, omega, pos, [0.0, 0.0]);
            assert!((f[0] - b.load).abs() < 1e-4 * b.load, "{hz} Hz: {f:?}");
            assert!(f[1].abs() < 1e-4 * b.load, "{hz} Hz: {f:?}");
        }
    }

    #[test]
    fn coefficients_match_numerical_derivatives_of_the_film_force() {
        let b = bearing();
        for &hz in &[8.0, 40.0, 120.0] {
            let omega = 2.0 * PI * hz;
            let pos = b.static_position(hz).unwrap();
            let coef = b.coefficients(hz).unwrap();
            let de = 1e-4 * b.clearance;
            let dv = de * omega;
            for j in 0..2 {
                let (mut ep, mut em) = (pos, pos);
                ep[j] += de;
                em[j] -= de;
                let fp = film_force(&b, omega, ep, [0.0, 0.0]);
                let fm = film_force(&b, omega, em, [0.0, 0.0]);
                let mut vp = [0.0; 2];
                let mut vm = [0.0; 2];
                vp[j] = dv;
                vm[j] = -dv;
                let gp = film_force(&b, omega, pos, vp);
                let gm = film_force(&b, omega, pos, vm);
                for i in 0..2 {
                    let k_num = -(fp[i] - fm[i]) / (2.0 * de);
                    let c_num = -(gp[i] - gm[i]) / (2.0 * dv);
                    let k_scale = b.load / b.clearance;
                    let c_scale = k_scale / omega;
                    assert!(
                        (k_num - coef.k[i][j]).abs() < 2e-3 * k_scale,
                        "{hz} Hz k[{i}][{j}]: closed form {} numerical {k_num}",
                        coef.k[i][j]
                    );
                    assert!(
                        (c_num - coef.c[i][j]).abs() < 2e-3 * c_scale,
                        "{hz} Hz c[{i}][{j}]: closed form {} numerical {c_num}",
                        coef.c[i][j]
                    );
                }
            }
        }
    }

    #[test]
    fn zero_speed_is_an_error() {
        assert_eq!(bearing().coefficients(0.0), Err(OilFilmError::Speed(0.0)));
    }
}
