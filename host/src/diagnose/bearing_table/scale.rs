//! The scaled table: a bearing table of any origin (tilting pads, a vendor's
//! sheet, an oil film whose geometry the machine file does not give) whose
//! stiffness is off relative to its damping (see the parent module for why
//! only this ratio is seen at the pedestal level).
//!
//! With K* = K + iΩC the written table (K, C real matrices, so K = Re K*,
//! ΩC = Im K*), the corrected bearing is
//!
//! ```text
//! K*(Ω; δ) = (1 + δ)·K + iΩC,      δ = k_scale − 1 (c_scale held at 1)
//! ```
//!
//! so the correction is δ·Re K*; at δ = 0 it is the table (the null is
//! nested and interior: δ may have either sign).

use super::super::data::Complex2x2;
use num_complex::Complex;

/// Widest stiffness ratios searched: k_scale = 1 + δ ∈ [1 + LOWEST,
/// 1 + HIGHEST] [-] (a table's stiffness between 0.4 and 2.5 times right).
pub const LOWEST: f64 = -0.6;
/// See [`LOWEST`].
pub const HIGHEST: f64 = 1.5;

/// The correction δ·K [N/m] to the written complex stiffness `kstar`
/// (K + iΩC [N/m]) for k_scale = 1 + δ, the damping as written.
pub fn correction(kstar: &Complex2x2, delta: f64) -> Complex2x2 {
    std::array::from_fn(|r| std::array::from_fn(|c| Complex::new(delta * kstar[r][c].re, 0.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The corrected table is the written one with its stiffness × k_scale
    /// and its damping unchanged; δ = 0 leaves it as written.
    #[test]
    fn scales_the_stiffness_and_leaves_the_damping() {
        let k = [
            [Complex::new(2.0e7, 6.0e5), Complex::new(1.0e6, -2.0e4)],
            [Complex::new(-3.0e5, 1.0e4), Complex::new(1.8e7, 5.0e5)],
        ];
        let c = correction(&k, -0.2);
        for r in 0..2 {
            for j in 0..2 {
                let got = k[r][j] + c[r][j];
                assert_eq!(got.im, k[r][j].im);
                assert!((got.re - 0.8 * k[r][j].re).abs() <= 1e-9 * k[r][j].re.abs());
            }
        }
        assert!(correction(&k, 0.0)
            .iter()
            .flatten()
            .all(|v| v.norm() == 0.0));
    }
}
