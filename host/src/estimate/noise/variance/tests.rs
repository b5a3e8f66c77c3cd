use super::*;
use num_complex::Complex;

/// An observation at `speed_hz` [Hz] whose four channels have the
/// magnitudes `mag` [m] (bearing stiffness zero: only the magnitudes and
/// the speed matter to the variance function).
fn at(speed_hz: f64, mag: [f64; 4]) -> Observation {
    let c = |m: f64| Complex::new(0.6 * m, 0.8 * m);
    Observation {
        speed_hz,
        rel: [c(mag[0]), c(mag[1])],
        ped: [c(mag[2]), c(mag[3])],
        kstar: [[Complex::new(0.0, 0.0); 2]; 2],
        var: [0.0; 8],
    }
}

#[test]
fn the_fraction_and_floor_family_frees_no_velocity_floor() {
    let fraction = Family::FractionFloor.components();
    assert_eq!(fraction, vec![0, 1, 3, 4, 6, 7, 9, 10]);
    assert_eq!(
        Family::VelocityFloor.components(),
        (0..COMPONENTS).collect::<Vec<_>>()
    );
}

#[test]
fn a_velocity_floor_falls_as_one_over_omega_squared_in_variance() {
    // ped y: α = 1e-4 (1 % of |X|), β = 1e-18 m², γ = 1e-12 m²/s².
    let mut p = [0.0; COMPONENTS];
    p[6] = 1e-4;
    p[7] = 1e-18;
    p[8] = 1e-12;
    let mag = [0.0, 0.0, 2e-7, 0.0];
    for f in [5.0, 50.0] {
        let o = at(f, mag);
        let omega = 2.0 * std::f64::consts::PI * f;
        let want = 1e-4 * 4e-14 + 1e-18 + 1e-12 / (omega * omega);
        let v = variances(&o, &p, &[0.0; 8]);
        for c in [4, 5] {
            assert!(
                (v[c] / want - 1.0).abs() < 1e-12,
                "{f} Hz: {:e} vs {want:e}",
                v[c]
            );
        }
        assert_eq!(v[0], 0.0);
        // The digits still floor it.
        assert_eq!(variances(&o, &p, &[1.0; 8])[4], 1.0);
    }
}
