//! Whether one pedestal's values from two runs agree: χ² of the difference
//! with both runs' covariances, the ± as printed.
//!
//! With θ̂_A, θ̂_B the two fits of the same support, each with its printed
//! standard errors σ (every widening `plinth identify` applies included)
//! and its correlation matrix R (from the fit's covariance; the identity
//! when the fit gives none), the runs' noises are independent, so
//! d = θ̂_B − θ̂_A has covariance S = D_A R_A D_A + D_B R_B D_B (D = diag σ)
//! and, when the support is the same in both runs and each ± means what it
//! says, d ᵀS⁻¹d follows χ² with as many degrees of freedom as parameters
//! both fits estimated. A pedestal disagrees when that χ² lies beyond its
//! 1 − α quantile, α = [`FAMILY_FALSE_ALARM`] / (number of pedestals
//! compared), so that a pair of clean runs is flagged at any pedestal in at
//! most [`FAMILY_FALSE_ALARM`] of pairs (Bonferroni; measured on ROSS runs
//! of two machines, docs/trust-lack-of-fit.md, session 49).

use crate::identify::PedestalFit;
use nalgebra::{DMatrix, DVector};
use plinth_shared::regression::{Parameter, PARAMETERS};
use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Chance per pair of runs of the same support that some pedestal is said
/// to disagree [-]: 1 %.
pub const FAMILY_FALSE_ALARM: f64 = 0.01;

/// A difference is named in the message when it lies beyond this many of
/// its standard errors [-].
pub const NAMED_Z: f64 = 3.0;

/// One parameter of one pedestal in both runs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParameterPair {
    /// `k_y`, `k_z`, `m`, `c_y` or `c_z`.
    pub name: String,
    /// Run A's value and printed standard error [N/m, kg or N·s/m].
    pub a: [f64; 2],
    /// Run B's value and printed standard error [N/m, kg or N·s/m].
    pub b: [f64; 2],
    /// (B − A)/|A| [-] (NaN, `null`, when A's value is 0).
    pub difference_relative: f64,
    /// (B − A)/√(σ_A² + σ_B²) [-].
    pub z: f64,
}

/// The verdict on one pedestal.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Agreement {
    /// Bearing name.
    pub bearing: String,
    /// The parameters both fits estimated.
    pub parameters: Vec<ParameterPair>,
    /// d ᵀS⁻¹d [-] (NaN, `null`, when S is singular or a figure is not
    /// finite: then nothing is said).
    pub chi2: f64,
    /// Its degrees of freedom: the parameters compared.
    pub dof: usize,
    /// P(χ²_dof ≥ chi2) [-].
    pub p_value: f64,
    /// The level each pedestal is tested at, the family's over the
    /// pedestals compared [-].
    pub alpha: f64,
    /// False when the χ² lies beyond its 1 − alpha quantile.
    pub agree: bool,
    /// identify's trust in each run's fit (A, B).
    pub trusted: [bool; 2],
    /// One sentence for people.
    pub message: String,
}

/// Run A's fit `a` and run B's fit `b` of the same bearing, tested at
/// level `alpha` [-] (module docs).
pub fn compare(a: &PedestalFit, b: &PedestalFit, alpha: f64) -> Agreement {
    let estimated = |f: &PedestalFit, p: Parameter| !f.fixed.iter().any(|x| x == p.name());
    let columns: Vec<Parameter> = Parameter::ALL
        .into_iter()
        .filter(|&p| estimated(a, p) && estimated(b, p))
        .collect();
    let (ta, tb) = (a.pedestal.theta(), b.pedestal.theta());
    let (sa, sb) = (a.std_err.theta(), b.std_err.theta());
    let parameters: Vec<ParameterPair> = columns
        .iter()
        .map(|&p| {
            let i = p as usize;
            let d = tb[i] - ta[i];
            ParameterPair {
                name: p.name().to_string(),
                a: [ta[i], sa[i]],
                b: [tb[i], sb[i]],
                difference_relative: if ta[i] != 0.0 {
                    d / ta[i].abs()
                } else {
                    f64::NAN
                },
                z: d / (sa[i] * sa[i] + sb[i] * sb[i]).sqrt(),
            }
        })
        .collect();
    let n = columns.len();
    let s = covariance(a, &columns) + covariance(b, &columns);
    let d = DVector::from_iterator(n, columns.iter().map(|&p| tb[p as usize] - ta[p as usize]));
    let chi2 = if n > 0 && d.iter().chain(s.iter()).all(|v| v.is_finite()) {
        s.cholesky().map_or(f64::NAN, |c| d.dot(&c.solve(&d)))
    } else {
        f64::NAN
    };
    let p_value = ChiSquared::new(n.max(1) as f64).map_or(f64::NAN, |c| c.sf(chi2));
    // A χ² that cannot be formed (NaN) is not a disagreement.
    let agree = p_value.is_nan() || p_value >= alpha;
    let trusted = [a.trusted, b.trusted];
    let message = message(&a.bearing, &parameters, chi2, n, p_value, agree);
    Agreement {
        bearing: a.bearing.clone(),
        parameters,
        chi2,
        dof: n,
        p_value,
        alpha,
        agree,
        trusted,
        message,
    }
}

/// D R D over `columns` of one fit: its printed standard errors with the
/// correlations of its covariance (module docs).
fn covariance(f: &PedestalFit, columns: &[Parameter]) -> DMatrix<f64> {
    let se = f.std_err.theta();
    let n = columns.len();
    DMatrix::from_fn(n, n, |r, c| {
        let (i, j) = (columns[r] as usize, columns[c] as usize);
        let rho = if i == j {
            1.0
        } else {
            f.covariance
                .as_ref()
                .map_or(0.0, |cov: &[[f64; PARAMETERS]; PARAMETERS]| {
                    let v = cov[i][j] / (cov[i][i] * cov[j][j]).sqrt();
                    if v.is_finite() {
                        v.clamp(-1.0, 1.0)
                    } else {
                        0.0
                    }
                })
        };
        rho * se[i] * se[j]
    })
}

fn message(
    bearing: &str,
    parameters: &[ParameterPair],
    chi2: f64,
    dof: usize,
    p_value: f64,
    agree: bool,
) -> String {
    if !chi2.is_finite() {
        return format!(
            "{bearing}: cannot be compared (a ± that is not finite, or the two covariances leave no test)"
        );
    }
    if agree {
        return format!("{bearing}: the two runs agree (χ² {chi2:.1} on {dof}, p {p_value:.2})");
    }
    let mut named: Vec<&ParameterPair> =
        parameters.iter().filter(|p| p.z.abs() > NAMED_Z).collect();
    named.sort_by(|x, y| y.z.abs().total_cmp(&x.z.abs()));
    if named.is_empty() {
        // Jointly beyond, no single one beyond NAMED_Z: name the largest.
        named.extend(
            parameters
                .iter()
                .max_by(|x, y| x.z.abs().total_cmp(&y.z.abs())),
        );
    }
    let what: Vec<String> = named
        .iter()
        .map(|p| {
            format!(
                "{} differs by {:+.2} % ({:+.1} ±)",
                p.name,
                100.0 * p.difference_relative,
                p.z
            )
        })
        .collect();
    format!(
        "{bearing}: {} between the runs (B against A; χ² {chi2:.1} on {dof}, p {p_value:.1e}): the support is not the same in both (temperature, a drift over the run, a loose bolt); neither run's {bearing} is to be trusted alone",
        what.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::Pedestal;

    /// A trusted fit of θ with diagonal covariance.
    fn fit(bearing: &str, theta: [f64; PARAMETERS], se: [f64; PARAMETERS]) -> PedestalFit {
        let mut cov = [[0.0; PARAMETERS]; PARAMETERS];
        for i in 0..PARAMETERS {
            cov[i][i] = se[i] * se[i];
        }
        PedestalFit {
            bearing: bearing.into(),
            pedestal: Pedestal::from_theta(theta),
            std_err: Pedestal::from_theta(se),
            residual_rms: 0.0,
            condition_number: 2.0,
            fixed: Vec::new(),
            trusted: true,
            speeds: 50,
            equations: 200,
            speed_range_hz: [100.0, 500.0],
            warnings: Vec::new(),
            ols: None,
            suspected_convention_error: None,
            base: None,
            base_measured: None,
            covariance: Some(cov),
            modal: None,
        }
    }

    const THETA: [f64; PARAMETERS] = [1.6e8, 9.0e7, 30.0, 2770.0, 2080.0];
    const SE: [f64; PARAMETERS] = [2.0e5, 1.2e5, 0.1, 20.0, 15.0];

    #[test]
    fn the_same_values_agree_and_a_shift_of_many_sigma_does_not() {
        let a = fit("B2", THETA, SE);
        let same = compare(&a, &fit("B2", THETA, SE), 0.005);
        assert!(same.agree && same.chi2 == 0.0 && same.dof == 5, "{same:?}");
        let mut moved = THETA;
        moved[2] *= 1.02; // m +2 %: 0.6 kg, 4.2 combined ±
        moved[1] *= 1.01;
        let b = compare(&a, &fit("B2", moved, SE), 0.005);
        assert!(!b.agree, "{b:?}");
        assert!(b.message.contains("m differs by +2.00 %"), "{}", b.message);
        assert!(b.message.contains("neither run's B2"), "{}", b.message);
        assert!((b.parameters[2].z - 0.6 / (2.0f64 * 0.01).sqrt()).abs() < 1e-9);
    }

    #[test]
    fn the_chi2_is_the_combined_covariances_and_a_fixed_parameter_is_left_out() {
        let a = fit("B1", THETA, SE);
        let mut t = THETA;
        t[0] += 2.0 * (2.0f64).sqrt() * SE[0]; // z = 2 on k_y alone
        let mut b = fit("B1", t, SE);
        b.fixed = vec!["c_z".into()];
        let r = compare(&a, &b, 0.005);
        assert_eq!(r.dof, 4);
        assert!((r.chi2 - 4.0).abs() < 1e-9, "{}", r.chi2);
        assert!(r.agree);
        let mut bad = fit("B1", THETA, SE);
        bad.std_err.m = f64::INFINITY;
        let r = compare(&a, &bad, 0.005);
        assert!(r.agree && r.chi2.is_nan() && r.message.contains("cannot be compared"));
    }
}
