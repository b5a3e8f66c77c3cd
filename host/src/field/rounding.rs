//! The noise a vector table's own rounding puts into its readings, so that
//! `plinth import` can write it as the run directory's noise columns
//! (docs/formats.md, "Noise columns") and `identify` weighs every speed by
//! the precision the instrument printed, not by the 17 digits of the
//! converted and resolved phasors.
//!
//! A number written as `23.4` was rounded to its last digit: its error is
//! uniform on ±0.05, variance ulp²/12. A reading of 0-pk amplitude A with
//! amplitude ulp u_A and phase ulp u_φ [deg] has the complex error
//! n ≈ δA·e^{iφ} + i·A·δφ·e^{iφ}, so E|n|² = u_A²/12 + A²·(u_φ·π/180)²/12.

/// The unit in the last written place of a decimal number as text:
/// `23.4` → 0.1, `120` → 1, `0.050` → 0.001, `1.25e-3` → 1e-5; `None` when
/// the text is not a plain or exponent decimal.
pub fn last_place(text: &str) -> Option<f64> {
    let t = text.trim().trim_start_matches(['+', '-']);
    let (mantissa, exponent) = match t.find(['e', 'E']) {
        Some(i) => (&t[..i], t[i + 1..].parse::<i32>().ok()?),
        None => (t, 0),
    };
    if mantissa.is_empty() || !mantissa.chars().all(|c| c.is_ascii_digit() || c == '.') {
        return None;
    }
    let decimals = match mantissa.split_once('.') {
        Some((_, frac)) => frac.len() as i32,
        None => 0,
    };
    Some(10f64.powi(exponent - decimals))
}

/// sqrt(E|n|²) of the complex error of a reading of 0-pk amplitude
/// `amplitude` (any unit) rounded to `amplitude_ulp` (same unit) with its
/// phase rounded to `phase_ulp_deg` [deg]: the noise sd of the reading's
/// phasor in the amplitude's unit.
pub fn reading_sd(amplitude: f64, amplitude_ulp: f64, phase_ulp_deg: f64) -> f64 {
    let phase = phase_ulp_deg.to_radians();
    ((amplitude_ulp * amplitude_ulp + amplitude * amplitude * phase * phase) / 12.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_complex::Complex;
    use rand::{Rng, SeedableRng};

    #[test]
    fn last_written_place() {
        assert_eq!(last_place("23.4"), Some(0.1f64.powi(1)));
        assert_eq!(last_place("120"), Some(1.0));
        assert!((last_place("0.050").unwrap() - 1e-3).abs() < 1e-18);
        assert!((last_place("1.25e-3").unwrap() - 1e-5).abs() < 1e-20);
        assert!((last_place("-7E2").unwrap() - 100.0).abs() < 1e-12);
        assert_eq!(last_place("abc"), None);
        assert_eq!(last_place(""), None);
    }

    /// The formula against a Monte-Carlo of rounding: amplitudes and phases
    /// drawn at random, rounded to 0.1 and 1°, the complex error's rms.
    #[test]
    fn reading_sd_matches_a_monte_carlo_of_rounding() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let n = 200_000;
        let mut sum = 0.0;
        for _ in 0..n {
            let a: f64 = rng.random_range(20.0..30.0);
            let p: f64 = rng.random_range(0.0..360.0);
            let (ar, pr) = ((a * 10.0).round() / 10.0, p.round());
            let exact = Complex::from_polar(a, -p.to_radians());
            let rounded = Complex::from_polar(ar, -pr.to_radians());
            sum += (exact - rounded).norm_sqr();
        }
        let mc = (sum / n as f64).sqrt();
        // E over A uniform on 20..30 of A² is 633.3.
        let want = ((0.01 + 633.333 * 1f64.to_radians().powi(2)) / 12.0).sqrt();
        assert!((mc / want - 1.0).abs() < 0.01, "{mc} vs {want}");
        assert!((reading_sd(25.0, 0.1, 1.0) - ((0.01 + 625.0 * 1f64.to_radians().powi(2)) / 12.0).sqrt()).abs() < 1e-15);
    }
}
