//! The estimation core against the Cramér–Rao bound, on run-downs the
//! simulator makes (Timoshenko rotor, oil-film or tabulated cross-coupled
//! bearings, pedestals) for three machines: the paper's damped machine, the
//! field coast-down machine and a three-bearing machine with tabulated
//! cross-coupled bearings. The bound comes from the Fisher information at the
//! truth with the noise the draws were made with; the estimates come from
//! `identify` with the noise model estimated from the data, as a user runs it.

use plinth::accuracy::{monte_carlo, Accuracy, Perturbation};
use plinth::sim::Machine;

fn machine(path: &str) -> Machine {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    Machine::from_toml_path(root.join(path)).expect("machine file")
}

const MACHINES: [&str; 3] = [
    "examples/feng-hahn-1997-damped.toml",
    "tests/machines/field-coast-down.toml",
    "tests/machines/three-bearing-tabulated.toml",
];

fn speeds() -> Vec<f64> {
    (5..=200).map(f64::from).collect()
}

/// ML within `rms_limit` × the bound and its standard errors within
/// `se_tolerance` of the observed scatter, for every parameter.
fn check(acc: &Accuracy, rms_limit: f64, se_tolerance: f64) {
    for p in &acc.parameters {
        let ratio = p.ml_rms / p.crb;
        assert!(
            ratio <= rms_limit,
            "{} {} {}: ML rms {:.3e} is {ratio:.2} × the bound {:.3e}",
            acc.machine,
            p.bearing,
            p.parameter,
            p.ml_rms,
            p.crb
        );
        assert!(
            (p.ml_se_ratio - 1.0).abs() <= se_tolerance,
            "{} {} {}: reported standard error / observed scatter = {:.2}",
            acc.machine,
            p.bearing,
            p.parameter,
            p.ml_se_ratio
        );
    }
    assert_eq!(acc.ml_failures, 0, "{}: ML fits failed", acc.machine);
}

#[test]
fn ml_reaches_the_bound_with_one_percent_noise_on_three_machines() {
    for path in MACHINES {
        let acc = monte_carlo(
            &machine(path),
            &speeds(),
            Perturbation::Noise(0.01),
            120,
            11,
        )
        .unwrap();
        check(&acc, 1.2, 0.2);
        // The paper's OLS is measurably worse on the same draws.
        let ols_mean = acc
            .parameters
            .iter()
            .map(|p| p.ols_rms / p.crb)
            .sum::<f64>()
            / acc.parameters.len() as f64;
        assert!(ols_mean > 1.2, "{path}: OLS mean rms/bound {ols_mean:.2}");
    }
}

#[test]
fn ml_reaches_the_bound_on_two_digit_data() {
    // Rounding errors are uniform, not Gaussian, and neighbouring speeds
    // round alike: the bound (ulp²/12 per number, independent) still holds.
    let acc = monte_carlo(
        &machine("tests/machines/field-coast-down.toml"),
        &speeds(),
        Perturbation::Digits(2),
        80,
        5,
    )
    .unwrap();
    check(&acc, 1.2, 0.25);
    for p in &acc.parameters {
        assert!(
            p.ols_rms > 3.0 * p.ml_rms,
            "{} {}: OLS {:.3e} vs ML {:.3e}",
            p.bearing,
            p.parameter,
            p.ols_rms,
            p.ml_rms
        );
    }
}
