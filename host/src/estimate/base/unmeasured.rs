//! The joint fit of a group of pedestals with an unmeasured base (module
//! docs of [`super`]): the equations with X_B eliminated, the profile of the
//! base mode, the identifiability decision, and the model's prediction.
//!
//! This module is the fit; `equations` holds the equations it solves and
//! `predict` the model's prediction and misfit at given parameters.

use super::{BaseFitError, BaseFitResult, BaseGroup, BaseIdentifiability, BaseParams};
use crate::estimate::gauss_helmert::{self as gh, Equations};
use crate::estimate::Observation;
use nalgebra::DMatrix;
use std::f64::consts::TAU;

mod equations;
mod predict;
mod profile;
mod starts;

use equations::{base_at, common_speeds, Unmeasured};
pub use predict::{chi2, predict, Prediction};
pub use profile::{widen_by_profile, Misfit};

/// Most iterations of a profiling fit and of the final fit.
const GRID_ITERATIONS: usize = 8;
const FINAL_ITERATIONS: usize = 200;
/// Base frequencies of the profile grid, and the damping ratio each of its
/// fits starts from.
const GRID_FREQUENCIES: usize = 24;
const GRID_DAMPING: f64 = 0.05;
/// Largest relative standard error of μ = 1/Ω_B² for a full identification.
const MODE_REL_SE: f64 = 1.0 / 3.0;
/// Stiff-pedestal starts (`starts`) fitted to the end, the best by J
/// after the short fits, and the most iterations of each (the one kept is
/// polished on, [`polish`]).
const STIFF_FINAL_FITS: usize = 3;
const STIFF_ITERATIONS: usize = 50;
/// Likelihood ratio J_rigid − J above which the data show a base at all:
/// the 1e-3 upper point of χ²(6) (the base's six parameters) [-].
const BASE_SHOWN: f64 = 22.46;
/// Largest |μ|·Ω_max² of a negative base mass still read as
/// quasi-static (the mass changes the base's receptance by under 10 % at
/// the top speed) [-].
const NEGATIVE_MASS_EFFECT: f64 = 0.1;
/// Likelihood-ratio threshold (J_rigid − J) for base motion in one
/// direction: the 1e-3 upper point of χ²(3) (three base parameters).
pub const DETECTION_THRESHOLD: f64 = 16.27;

/// Joint ML fit of all pedestals of `group` and its base (module docs).
/// `obs[b]` are bearing b's observations (with their noise variances, from
/// [`crate::estimate::noise`]); `start[b]` its rigid-ground fit θ (both indexed like
/// `obs`; only the group's entries are read).
pub fn fit_on_unmeasured_base(
    obs: &[Vec<Observation>],
    group: &BaseGroup,
    start: &[[f64; 5]],
) -> Result<BaseFitResult, BaseFitError> {
    let speeds = common_speeds(obs, group)?;
    let n = group.bearings.len();
    let n_par = 5 * n + 6;
    let n_eq = 4 * n * speeds.len();
    if n_eq <= n_par || speeds.len() < 4 {
        return Err(BaseFitError::TooFewEquations {
            equations: n_eq,
            parameters: n_par,
        });
    }
    let (w_lo, w_hi) = (speeds[0].omega, speeds[speeds.len() - 1].omega);
    let w_mid = (w_lo * w_hi).sqrt();
    let eq = Unmeasured { speeds };
    let theta: Vec<[f64; 5]> = group
        .bearings
        .iter()
        .map(|&b| start.get(b).copied().unwrap_or([0.0; 5]))
        .collect();
    let p0: Vec<f64> = theta.iter().flatten().copied().chain([0.0; 6]).collect();
    let scale = scales(&theta, w_mid);
    let pedestal_free: Vec<bool> = (0..n_par).map(|k| k < 5 * n).collect();
    let frozen: Vec<DMatrix<f64>> = (0..eq.speeds())
        .map(|s| gh::whitening(&eq, s, &p0))
        .collect::<Option<_>>()
        .ok_or(BaseFitError::NotEvaluable)?;

    // Rigid ground, refitted under this model's weights (the null).
    let rigid = gh::fit(&eq, &p0, &scale, &pedestal_free, None, FINAL_ITERATIONS)
        .ok_or(BaseFitError::NotEvaluable)?;

    // Profile the base frequency with frozen weights: every fit of the grid
    // starts from the rigid pedestals with the base mode at f (both
    // directions, then each direction alone) and frees everything.
    let (f_lo, f_hi) = (w_lo / TAU, w_hi / TAU);
    let grid: Vec<f64> = (0..GRID_FREQUENCIES)
        .map(|j| {
            let (a, b) = ((f_lo / 3.0).ln(), (3.0 * f_hi).ln());
            (a + (b - a) * j as f64 / (GRID_FREQUENCIES - 1) as f64).exp()
        })
        .collect();
    let all = vec![true; n_par];
    let shaped = |from: &[f64], d: usize, f: f64, zeta: f64| -> Vec<f64> {
        let mut p = from.to_vec();
        let wb = TAU * f;
        let o = base_at(n, d);
        // A base as compliant as the pedestals together, mode at f.
        p[o] = scale[o];
        p[o + 1] = 1.0 / (wb * wb);
        p[o + 2] = 2.0 * zeta / wb;
        p
    };
    let mut best = rigid.p.clone();
    let mut best_cost =
        gh::whitened(&eq, &best, Some(&frozen)).map_or(f64::INFINITY, |w| w.norm_squared());
    let consider =
        |p: Vec<f64>, frozen: &[DMatrix<f64>], best: &mut Vec<f64>, best_cost: &mut f64| {
            if let Some(m) = gh::fit(&eq, &p, &scale, &all, Some(frozen), GRID_ITERATIONS) {
                if m.cost < *best_cost {
                    *best_cost = m.cost;
                    *best = m.p;
                }
            }
        };
    for &f in &grid {
        let p = shaped(&shaped(&rigid.p, 0, f, GRID_DAMPING), 1, f, GRID_DAMPING);
        consider(p, &frozen, &mut best, &mut best_cost);
    }
    // Weights at the best so far, then each direction's mode on its own.
    let refrozen: Vec<DMatrix<f64>> = (0..eq.speeds())
        .map(|s| gh::whitening(&eq, s, &best))
        .collect::<Option<_>>()
        .unwrap_or(frozen);
    best_cost =
        gh::whitened(&eq, &best, Some(&refrozen)).map_or(f64::INFINITY, |w| w.norm_squared());
    for d in 0..2 {
        let from = best.clone();
        for &f in &grid {
            consider(
                shaped(&from, d, f, GRID_DAMPING),
                &refrozen,
                &mut best,
                &mut best_cost,
            );
        }
    }

    // Everything free, with the likelihood's own weights, from the
    // profile's best.
    let full = gh::fit(&eq, &best, &scale, &all, None, FINAL_ITERATIONS)
        .ok_or(BaseFitError::NotEvaluable)?;
    // An end outside physics (a negative base mass that matters,
    // [`negative_mass_matters`], or a pedestal stiffness or mass ≤ 0) where
    // the data show a base (J_rigid − J above [`BASE_SHOWN`]) says the
    // search ended in the wrong basin. (Where they show none, as in the
    // bootstrap's rigid-ground replicates, a non-physical end is the noise
    // fitted: there is no basin to find.) Then each pedestal stiffer than
    // the base, part of its apparent mass in the base (`starts`), is tried
    // too: the best few after the same short fits are fitted to the end
    // (their basin and the profile's are apart, a nearly flat valley
    // between them, where the short fits' costs do not rank the basins'
    // ends; at most [`STIFF_ITERATIONS`] each, the one kept is polished
    // on), and the lowest J of the ends inside physics is kept (ML under
    // M_B ≥ 0), else the lowest J. A physical end is kept as it is: these
    // fits are most of a base fit's cost.
    let non_physical = |m: &gh::Minimum| {
        (0..2).any(|d| negative_mass_matters(m.p[base_at(n, d) + 1], w_hi))
            || (0..n).any(|i| m.p[5 * i..5 * i + 3].iter().any(|v| *v <= 0.0))
    };
    let full = if non_physical(&full) && rigid.cost - full.cost >= BASE_SHOWN {
        let mut stiff: Vec<gh::Minimum> = starts::stiff_pedestal_starts(&rigid.p, n)
            .into_iter()
            .filter_map(|p| gh::fit(&eq, &p, &scale, &all, Some(&refrozen), GRID_ITERATIONS))
            .collect();
        stiff.sort_by(|a, b| a.cost.total_cmp(&b.cost));
        stiff
            .iter()
            .take(STIFF_FINAL_FITS)
            .filter_map(|s| gh::fit(&eq, &s.p, &scale, &all, None, STIFF_ITERATIONS))
            .fold(full, |a, b| {
                if (non_physical(&b), b.cost) < (non_physical(&a), a.cost) {
                    b
                } else {
                    a
                }
            })
    } else {
        full
    };
    let full = polish(&eq, full, &scale, &all);
    let full = if full.cost <= rigid.cost {
        full
    } else {
        rigid.clone()
    };
    let mut p = full.p.clone();
    let mut free = all.clone();

    // What the data determine, per direction.
    let mut ident = [BaseIdentifiability::NotDetected; 2];
    for (d, slot) in ident.iter_mut().enumerate() {
        let o = base_at(n, d);
        let mut null = p.clone();
        null[o..o + 3].copy_from_slice(&[0.0; 3]);
        let mut free_null = all.clone();
        free_null[o..o + 3].copy_from_slice(&[false; 3]);
        let j_null = gh::fit(&eq, &null, &scale, &free_null, None, FINAL_ITERATIONS)
            .map_or(f64::INFINITY, |m| m.cost);
        if j_null - full.cost < DETECTION_THRESHOLD {
            p[o..o + 3].copy_from_slice(&[0.0; 3]);
            free[o..o + 3].copy_from_slice(&[false; 3]);
            continue;
        }
        let (kappa, mu) = (p[o], p[o + 1]);
        let w_b = if mu > 0.0 {
            mu.powf(-0.5)
        } else {
            f64::INFINITY
        };
        *slot = if negative_mass_matters(mu, w_hi) {
            // No mode above the range: a negative base mass that shapes
            // the receptance. Kept as fitted (M_B < 0), which
            // `diagnose::foundation::physical` rejects.
            BaseIdentifiability::Full
        } else if w_b < w_lo {
            BaseIdentifiability::MassLine {
                mass_kg: mu / kappa,
                std_err: f64::NAN,
            }
        } else if w_b > w_hi {
            BaseIdentifiability::QuasiStatic {
                compliance_m_per_n: kappa,
                std_err: f64::NAN,
            }
        } else {
            BaseIdentifiability::Full
        };
    }
    // Refit with the undetected directions held rigid.
    let fin = if free != all {
        gh::fit(&eq, &p, &scale, &free, None, FINAL_ITERATIONS).ok_or(BaseFitError::NotEvaluable)?
    } else {
        full
    };
    let p = fin.p.clone();
    let (cov, f) = covariance(&eq, &p, &scale, &free).ok_or(BaseFitError::NotEvaluable)?;
    let n_free = f.nrows();
    let se = |k: usize| cov[(k, k)].max(0.0).sqrt();
    // Delta method: variance of g(p) with gradient `grad` over indices `at`.
    let delta = |at: &[usize], grad: &[f64]| -> f64 {
        let mut v = 0.0;
        for (a, ga) in at.iter().zip(grad) {
            for (b, gb) in at.iter().zip(grad) {
                v += ga * gb * cov[(*a, *b)];
            }
        }
        v.max(0.0).sqrt()
    };
    let mut base = BaseParams::RIGID;
    let mut base_se = BaseParams {
        k: [f64::INFINITY; 2],
        c: [f64::INFINITY; 2],
        m: [f64::INFINITY; 2],
    };
    let mut base_frequency_hz = [f64::NAN; 2];
    for d in 0..2 {
        let o = base_at(n, d);
        let (kappa, mu, gamma) = (p[o], p[o + 1], p[o + 2]);
        if ident[d] == BaseIdentifiability::NotDetected {
            continue;
        }
        let at = [o, o + 1, o + 2];
        base.k[d] = 1.0 / kappa;
        base.m[d] = mu / kappa;
        base.c[d] = gamma / kappa;
        base_se.k[d] = delta(&at, &[-1.0 / (kappa * kappa), 0.0, 0.0]);
        base_se.m[d] = delta(&at, &[-mu / (kappa * kappa), 1.0 / kappa, 0.0]);
        base_se.c[d] = delta(&at, &[-gamma / (kappa * kappa), 0.0, 1.0 / kappa]);
        if mu > 0.0 {
            base_frequency_hz[d] = 1.0 / (TAU * mu.sqrt());
        }
        // A mode inside the range whose frequency the Fisher information
        // does not pin down (μ = 1/Ω_B² uncertain by more than a third) is
        // no full identification: say what is determined on its side.
        let pinned = se(o + 1) < MODE_REL_SE * mu.abs();
        if ident[d] == BaseIdentifiability::Full && !pinned {
            ident[d] = if mu > 0.0 && mu.sqrt() * w_mid < 1.0 {
                BaseIdentifiability::QuasiStatic {
                    compliance_m_per_n: kappa,
                    std_err: f64::NAN,
                }
            } else {
                BaseIdentifiability::MassLine {
                    mass_kg: mu / kappa,
                    std_err: f64::NAN,
                }
            };
        }
        match &mut ident[d] {
            BaseIdentifiability::QuasiStatic {
                compliance_m_per_n,
                std_err,
            } => {
                *compliance_m_per_n = kappa;
                *std_err = se(o);
            }
            BaseIdentifiability::MassLine { mass_kg, std_err } => {
                *mass_kg = base.m[d];
                *std_err = base_se.m[d];
            }
            _ => {}
        }
    }
    Ok(BaseFitResult {
        pedestals: (0..n)
            .map(|i| std::array::from_fn(|k| p[5 * i + k]))
            .collect(),
        pedestal_covariance: (0..n)
            .map(|i| std::array::from_fn(|a| std::array::from_fn(|b| cov[(5 * i + a, 5 * i + b)])))
            .collect(),
        pedestal_std_err: (0..n)
            .map(|i| std::array::from_fn(|k| se(5 * i + k)))
            .collect(),
        split_unresolved: vec![[false; 3]; n],
        base_unresolved: [[false; 3]; 2],
        base,
        base_std_err: base_se,
        base_frequency_hz,
        identifiability: ident,
        chi2: fin.cost,
        dof: n_eq - n_free,
        chi2_rigid: rigid.cost,
        pedestal_residual_rms: (0..n)
            .map(|i| {
                let ss: f64 = (0..eq.speeds())
                    .map(|s| eq.residual(s, &p).0.rows(4 * i, 4).norm_squared())
                    .sum();
                (ss / (4 * eq.speeds()) as f64).sqrt()
            })
            .collect(),
        condition_number: gh::condition_number(&f),
        converged: fin.converged,
        iterations: fin.iterations,
        speeds_hz: eq.speeds.iter().map(|s| s.omega / TAU).collect(),
    })
}

/// Whether a fitted μ = M_B/K_B [s²] is a negative base mass that matters
/// at the top speed `w_hi` [rad/s]: |μ|·Ω_max² ≥ [`NEGATIVE_MASS_EFFECT`].
/// The base's receptance is G = κ/(1 − Ω²μ + iΩγ); with μ < 0 it has no
/// mode at all, and only where |μ|Ω² is small is it the quasi-static
/// compliance κ the `quasi_static` reading reports. Beyond that the fit
/// has used a negative mass to shape G over the range: non-physical.
pub(crate) fn negative_mass_matters(mu: f64, w_hi: f64) -> bool {
    mu < 0.0 && -mu * w_hi * w_hi >= NEGATIVE_MASS_EFFECT
}

/// The Fisher covariance of a group's fit at `p` (model units, full size:
/// zero rows and columns for the parameters not `free`; `scale` as for
/// [`gh::fisher`]) and the information of the free parameters it inverts
/// (for the condition number). `None` when J cannot be evaluated.
fn covariance(
    eq: &Unmeasured,
    p: &[f64],
    scale: &[f64],
    free: &[bool],
) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
    let idx: Vec<usize> = (0..p.len()).filter(|&k| free[k]).collect();
    let f_all = gh::fisher(eq, p, scale)?;
    let f = DMatrix::from_fn(idx.len(), idx.len(), |r, c| f_all[(idx[r], idx[c])]);
    let mut cov = DMatrix::from_element(p.len(), p.len(), 0.0);
    let inv = gh::inverse_psd(&f);
    for (r, &a) in idx.iter().enumerate() {
        for (c, &b) in idx.iter().enumerate() {
            cov[(a, b)] = inv[(r, c)];
        }
    }
    Some((cov, f))
}

/// Scale of every parameter of a group's fit (model units: the pedestals'
/// θ, then κ, μ, γ of y and z) for pedestal values `theta` (group order)
/// and the range's geometric-mean speed `w_mid` [rad/s]: the steps and the
/// information are taken relative to these.
fn scales(theta: &[[f64; 5]], w_mid: f64) -> Vec<f64> {
    let n = theta.len();
    let mut scale = vec![1.0; 5 * n + 6];
    let mut k_sum = 0.0;
    for (i, th) in theta.iter().enumerate() {
        let k = th[0].abs().max(th[1].abs()).max(1.0);
        k_sum += k;
        scale[5 * i] = th[0].abs().max(1e-3 * k);
        scale[5 * i + 1] = th[1].abs().max(1e-3 * k);
        scale[5 * i + 2] = th[2].abs().max(1e-3 * k / (w_mid * w_mid));
        scale[5 * i + 3] = th[3].abs().max(1e-3 * k / w_mid);
        scale[5 * i + 4] = th[4].abs().max(1e-3 * k / w_mid);
    }
    for d in 0..2 {
        let o = base_at(n, d);
        scale[o] = 1.0 / k_sum;
        scale[o + 1] = 1.0 / (w_mid * w_mid);
        scale[o + 2] = 1.0 / w_mid;
    }
    scale
}

/// A final fit that stopped short of its convergence test, run on once
/// from where it stopped with the parameters scaled to their values there
/// (the scale made from the rigid-ground start can be a decade off when the
/// fit moved a pedestal's stiffness and mass into a base, and the search
/// then crawls along the valley between them). Kept when it lowers J.
fn polish(eq: &Unmeasured, fit: gh::Minimum, scale: &[f64], free: &[bool]) -> gh::Minimum {
    if fit.converged {
        return fit;
    }
    let rescaled: Vec<f64> = fit
        .p
        .iter()
        .zip(scale)
        .map(|(p, s)| p.abs().max(*s))
        .collect();
    match gh::fit(eq, &fit.p, &rescaled, free, None, FINAL_ITERATIONS) {
        Some(m) if m.cost <= fit.cost => m,
        _ => fit,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_complex::Complex;

    /// Two bearings at 20 speeds with arbitrary rel and bearing stiffness;
    /// ped left at zero (set by the caller).
    fn observations() -> Vec<Vec<Observation>> {
        (0..2)
            .map(|b| {
                (0..20)
                    .map(|j| {
                        let f = 10.0 + 5.0 * j as f64;
                        let w = TAU * f;
                        let s = 1.0 + 0.3 * b as f64;
                        Observation {
                            speed_hz: f,
                            rel: [
                                Complex::from_polar(1e-5 * s, 0.05 * f),
                                Complex::from_polar(8e-6, 1.0 - 0.03 * f * s),
                            ],
                            ped: [Complex::new(0.0, 0.0); 2],
                            kstar: [
                                [Complex::new(3e7 * s, w * 2e3), Complex::new(8e6, w * 1e2)],
                                [Complex::new(-6e6, -w * 1e2), Complex::new(2.5e7, w * 1.5e3)],
                            ],
                            var: [1e-20; 8],
                        }
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn predicted_motion_satisfies_the_equations() {
        let mut obs = observations();
        let group = BaseGroup {
            bearings: vec![0, 1],
        };
        let theta = [
            [1e7, 8e6, 80.0, 300.0, 250.0],
            [6e6, 9e6, 60.0, 200.0, 350.0],
        ];
        let base = BaseParams {
            k: [1e7, 8e6],
            c: [3e3, 2.5e3],
            m: [300.0, 250.0],
        };
        let pred = predict(&obs, &group, &theta, &base).unwrap();
        for (s, p) in pred.iter().enumerate() {
            for (b, o) in obs.iter_mut().enumerate() {
                o[s].ped = p.ped[b];
            }
        }
        let j = chi2(&obs, &group, &theta, &base).unwrap();
        let rigid = chi2(&obs, &group, &theta, &BaseParams::RIGID).unwrap();
        assert!(j < 1e-12 * rigid, "χ² {j:e} (rigid ground {rigid:e})");
    }

    #[test]
    fn a_negative_base_mass_that_shapes_the_receptance_is_not_quasi_static() {
        let w_hi = TAU * 110.0;
        // Session 29's fit end on the bedplate: |μ|Ω² = 2.5 at the top speed.
        assert!(negative_mass_matters(-2.5 / (w_hi * w_hi), w_hi));
        assert!(!negative_mass_matters(-0.05 / (w_hi * w_hi), w_hi));
        assert!(!negative_mass_matters(1.0 / (w_hi * w_hi), w_hi));
        assert!(!negative_mass_matters(0.0, w_hi));
    }

    #[test]
    fn bad_groups_are_errors() {
        let obs = observations();
        let start = [[1e7, 1e7, 50.0, 0.0, 0.0]; 2];
        let fit = |b: Vec<usize>| fit_on_unmeasured_base(&obs, &BaseGroup { bearings: b }, &start);
        assert!(matches!(
            fit(vec![0, 2]),
            Err(BaseFitError::NoSuchBearing { index: 2, .. })
        ));
        assert!(matches!(fit(vec![0, 0]), Err(BaseFitError::BadGroup(_))));
        assert!(matches!(fit(vec![]), Err(BaseFitError::BadGroup(_))));
        let few: Vec<Vec<Observation>> = obs.iter().map(|o| o[..2].to_vec()).collect();
        assert!(matches!(
            fit_on_unmeasured_base(
                &few,
                &BaseGroup {
                    bearings: vec![0, 1]
                },
                &start
            ),
            Err(BaseFitError::TooFewEquations { .. })
        ));
    }
}
