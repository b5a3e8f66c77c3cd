//! Starts of the unmeasured-base fit where a pedestal is stiffer than the
//! base it stands on.
//!
//! A pedestal's rigid-ground fit sees it in series with its base: the
//! apparent support (k_a, c_a, m_a). When the pedestal is much stiffer
//! than the base (a massive block on a bedplate), the apparent spring is
//! mostly the base's and the apparent mass is the block's and the base's
//! together. The profile of the base frequency in [`super`] keeps every
//! pedestal at its apparent values and adds a base: from there the search
//! must move the pedestal's stiffness up a decade and part of its mass into
//! the base along a nearly flat valley, and can stop on the way (on the
//! flexible roll's bedplate it ended with the base's mass negative and the
//! block at 2604 kg for 450, χ² 989 where the true parameters give 847).
//! These starts put the split in directly: pedestal i's spring and damper
//! R times its apparent ones (the same loss factor), the base's spring and
//! damper the rest of the series (K_B = k_a·R/(R − 1), C_B/K_B = c_a/k_a,
//! so the series is the apparent support at every speed), and a fraction φ
//! of the apparent mass moved to the base (the total mass is what the
//! rigid fit sees).

use super::equations::base_at;

/// Stiffness ratios R of pedestal to base tried (a decade each side of ~10).
const STIFFNESS_RATIOS: [f64; 3] = [3.0, 10.0, 30.0];
/// Fractions φ of the apparent mass given to the base.
const MASS_FRACTIONS: [f64; 3] = [0.3, 0.5, 0.7];

/// The starts (parameter vectors of the unmeasured-base fit, `n` members)
/// made from `rigid`, the group's rigid-ground parameters (module docs).
/// A member with a non-positive apparent stiffness, damping or mass gives
/// none (no series split of a non-physical support).
pub(super) fn stiff_pedestal_starts(rigid: &[f64], n: usize) -> Vec<Vec<f64>> {
    let mut out = Vec::new();
    for i in 0..n {
        let th = &rigid[5 * i..5 * i + 5];
        if th.iter().any(|&v| !(v > 0.0 && v.is_finite())) {
            continue;
        }
        for &r in &STIFFNESS_RATIOS {
            for &phi in &MASS_FRACTIONS {
                let mut p = rigid.to_vec();
                p[5 * i + 2] = (1.0 - phi) * th[2];
                for d in 0..2 {
                    let (k_a, c_a) = (th[d], th[3 + d]);
                    p[5 * i + d] = r * k_a;
                    p[5 * i + 3 + d] = r * c_a;
                    // κ = 1/K_B, μ = M_B/K_B, γ = C_B/K_B.
                    let kappa = (1.0 - 1.0 / r) / k_a;
                    let o = base_at(n, d);
                    p[o] = kappa;
                    p[o + 1] = phi * th[2] * kappa;
                    p[o + 2] = c_a / k_a;
                }
                out.push(p);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_complex::Complex;

    /// The series of the start's pedestal and base is the apparent support
    /// at zero speed (springs) and its total mass the apparent mass.
    #[test]
    fn the_series_of_a_start_is_the_apparent_support() {
        let rigid = [
            2.5e8, 1.0e8, 900.0, 2.6e4, 2.8e4, 5e7, 1.5e7, 175.0, 2.5e3, 1.2e3,
        ];
        let mut p = rigid.to_vec();
        p.extend([0.0; 6]);
        let starts = stiff_pedestal_starts(&p, 2);
        assert_eq!(starts.len(), 2 * 9);
        for s in &starts[..9] {
            for d in 0..2 {
                let o = base_at(2, d);
                let (k_b, m_b, c_b) = (1.0 / s[o], s[o + 1] / s[o], s[o + 2] / s[o]);
                let w = 300.0;
                let series = Complex::new(1.0, 0.0)
                    / (Complex::new(1.0, 0.0) / Complex::new(s[d], w * s[3 + d])
                        + Complex::new(1.0, 0.0) / Complex::new(k_b, w * c_b));
                let apparent = Complex::new(rigid[d], w * rigid[3 + d]);
                assert!((series - apparent).norm() < 1e-9 * apparent.norm());
                assert!((m_b + s[2] - rigid[2]).abs() < 1e-9 * rigid[2]);
            }
            // The other member is left at its apparent values.
            assert_eq!(&s[5..10], &rigid[5..10]);
        }
    }

    #[test]
    fn a_non_physical_support_gives_no_start() {
        let mut p = vec![2.5e8, 1.0e8, -900.0, 2.6e4, 2.8e4];
        p.extend([0.0; 6]);
        assert!(stiff_pedestal_starts(&p, 1).is_empty());
    }
}
