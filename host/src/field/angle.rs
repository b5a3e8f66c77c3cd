//! Transducer angles: `angle_deg` (formats.md: degrees from +y, vertical up,
//! towards +z) or the Bently-style `45L`/`45R`, and the resolution of two or
//! more transducers at distinct angles into y and z.
//!
//! # `45L` / `45R`
//!
//! In the field a probe is named by its angle from vertical, left (`L`) or
//! right (`R`) of it, as seen by an observer at a stated end of the machine
//! (`view = "driver"`: standing at the driver, looking along the shaft
//! towards the driven end), with the shaft's direction of rotation as seen
//! from there (`rotation = "cw"` or `"ccw"`). Plinth's rotor turns from +y
//! towards +z (the simulator's convention, `sim::machine::Unbalance`), so:
//!
//! - `rotation = "ccw"` seen from the view: turning counter-clockwise from
//!   vertical-up goes to the observer's left, so +z is on the left:
//!   `45L` → angle_deg = +45, `45R` → −45;
//! - `rotation = "cw"`: +z is on the right: `45R` → +45, `45L` → −45.
//!
//! Hand-worked example (checked in the tests): view from the driver, shaft
//! turning CCW, X–Y probes at 45L and 45R. A purely vertical motion Y = 1
//! reads cos 45° = 0.707 on both; a horizontal motion Z = 1 (to the left, the
//! direction the shaft's top moves) reads +0.707 on 45L and −0.707 on 45R.
//! `0` (or `0L`/`0R`) is vertical, `90L`/`90R` horizontal; angles up to 180.

use nalgebra::{Matrix2, Vector2};
use num_complex::Complex;

/// The smallest separation [deg] (modulo 180°) between two transducers
/// resolved into y and z: noise is amplified by 1/sin(separation).
pub const MIN_SEPARATION_DEG: f64 = 10.0;

/// Direction of rotation as seen by the stated observer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Rotation {
    /// Clockwise.
    Cw,
    /// Counter-clockwise.
    Ccw,
}

/// Where the observer of `45L`/`45R` angles stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum View {
    /// At the driver (motor, turbine) end, looking towards the driven end.
    Driver,
    /// At the driven end, looking towards the driver.
    Driven,
}

/// Parses a Bently-style angle (`45L`, `45 R`, `45°L`, `0`) into angle_deg
/// (from +y towards +z) given the rotation seen from the stated view.
pub fn parse_bently(text: &str, rotation: Option<Rotation>) -> Result<f64, String> {
    let t: String = text
        .chars()
        .filter(|c| !c.is_whitespace() && *c != '°')
        .collect::<String>()
        .to_ascii_uppercase();
    let (number, side) = match t.chars().last() {
        Some('L') => (&t[..t.len() - 1], Some('L')),
        Some('R') => (&t[..t.len() - 1], Some('R')),
        _ => (t.as_str(), None),
    };
    let deg: f64 = number.parse().map_err(|_| {
        format!(
            "`{text}` is not an angle like `45L`, `45R` or `0` (degrees left or right of vertical)"
        )
    })?;
    if !(0.0..=180.0).contains(&deg) {
        return Err(format!(
            "`{text}`: degrees from vertical must be in 0..=180"
        ));
    }
    let Some(side) = side else {
        if deg == 0.0 || deg == 180.0 {
            return Ok(deg);
        }
        return Err(format!(
            "`{text}`: say which side of vertical, e.g. `{deg}L` or `{deg}R`"
        ));
    };
    let rotation = rotation.ok_or_else(|| {
        format!("`{text}` needs the top-level keys `view` and `rotation` (e.g. view = \"driver\", rotation = \"ccw\") to know which side +z is on")
    })?;
    // +z is on the side the top of the shaft moves towards.
    let z_side = match rotation {
        Rotation::Ccw => 'L',
        Rotation::Cw => 'R',
    };
    Ok(if side == z_side { deg } else { -deg })
}

/// Smallest separation [deg] between two axes, modulo 180° (opposite
/// directions measure the same axis).
pub fn separation_deg(a_deg: f64, b_deg: f64) -> f64 {
    let d = (a_deg - b_deg).rem_euclid(180.0);
    d.min(180.0 - d)
}

/// The y and z phasors behind the readings of transducers at `angles_deg`
/// (each reads cos α·Y + sin α·Z), by least squares (exact for two), and
/// the standard deviations [same unit] of Y and Z from the readings' own
/// (`sd`, independent). Angles must be checked apart beforehand.
pub fn resolve(
    angles_deg: &[f64],
    readings: &[Complex<f64>],
    sd: Option<&[f64]>,
) -> ([Complex<f64>; 2], Option<[f64; 2]>) {
    let mut ata = Matrix2::<f64>::zeros();
    let mut atb = [Complex::new(0.0, 0.0); 2];
    for (a, q) in angles_deg.iter().zip(readings) {
        let (s, c) = a.to_radians().sin_cos();
        let row = Vector2::new(c, s);
        ata += row * row.transpose();
        atb[0] += q * c;
        atb[1] += q * s;
    }
    let inv = ata.try_inverse().unwrap_or_else(Matrix2::zeros);
    let yz = [
        atb[0] * inv[(0, 0)] + atb[1] * inv[(0, 1)],
        atb[0] * inv[(1, 0)] + atb[1] * inv[(1, 1)],
    ];
    let noise = sd.map(|sd| {
        // cov = inv·Aᵀ·diag(sd²)·A·inv.
        let mut m = Matrix2::<f64>::zeros();
        for (a, s) in angles_deg.iter().zip(sd) {
            let (sn, c) = a.to_radians().sin_cos();
            let row = Vector2::new(c, sn);
            m += row * row.transpose() * (s * s);
        }
        let cov = inv * m * inv;
        [cov[(0, 0)].max(0.0).sqrt(), cov[(1, 1)].max(0.0).sqrt()]
    });
    (yz, noise)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bently_angles_hand_worked() {
        let ccw = Some(Rotation::Ccw);
        assert_eq!(parse_bently("45L", ccw).unwrap(), 45.0);
        assert_eq!(parse_bently("45R", ccw).unwrap(), -45.0);
        assert_eq!(parse_bently("45 R", Some(Rotation::Cw)).unwrap(), 45.0);
        assert_eq!(parse_bently("90°l", Some(Rotation::Cw)).unwrap(), -90.0);
        assert_eq!(parse_bently("0", None).unwrap(), 0.0);
        assert!(parse_bently("45L", None).is_err());
        assert!(parse_bently("45", ccw).is_err());
        assert!(parse_bently("200R", ccw).is_err());
        // Horizontal motion to +z (left, seen from the driver, CCW shaft):
        // +0.707 on 45L, −0.707 on 45R.
        let z = Complex::new(1.0, 0.0);
        let read = |deg: f64| z * deg.to_radians().sin();
        assert!(
            (read(parse_bently("45L", ccw).unwrap()).re - std::f64::consts::FRAC_1_SQRT_2).abs()
                < 1e-12
        );
        assert!(
            (read(parse_bently("45R", ccw).unwrap()).re + std::f64::consts::FRAC_1_SQRT_2).abs()
                < 1e-12
        );
    }

    #[test]
    fn resolves_arbitrary_angles() {
        let y = Complex::new(3.0, -1.0);
        let z = Complex::new(-0.5, 2.0);
        let angles = [30.0, 100.0];
        let r: Vec<_> = angles
            .iter()
            .map(|a: &f64| y * a.to_radians().cos() + z * a.to_radians().sin())
            .collect();
        let ([ry, rz], sd) = resolve(&angles, &r, Some(&[1.0, 1.0]));
        assert!((ry - y).norm() < 1e-12 && (rz - z).norm() < 1e-12);
        assert!(sd.unwrap()[0] > 1.0);
        // X–Y at 0 and 90: noise passes unchanged.
        let (_, sd) = resolve(&[0.0, 90.0], &[y, z], Some(&[2.0, 3.0]));
        let sd = sd.unwrap();
        assert!((sd[0] - 2.0).abs() < 1e-12 && (sd[1] - 3.0).abs() < 1e-12);
        assert_eq!(separation_deg(45.0, 225.0), 0.0);
        assert_eq!(separation_deg(-45.0, 45.0), 90.0);
        assert_eq!(separation_deg(10.0, 175.0), 15.0);
    }
}
