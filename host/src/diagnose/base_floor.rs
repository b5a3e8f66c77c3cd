//! A chosen base's own uncertainty in the machine-level floor
//! (`--machine`, [`super::machine::machine_floor`]).
//!
//! The re-simulation stands the pedestals of a chosen base on a base
//! element with the fitted pedestals θ = (k_y, k_z, m, c_y, c_z) and base
//! (K_B, C_B, M_B per direction). Their covariance is that of the base's
//! maximum-likelihood fit (`crate::estimate::base`), whose cost
//! J = Σ eᵀΣ⁻¹e is public ([`chi2`]): the covariance is 2·H⁻¹, H the
//! Hessian of J by central differences, on the very observations and
//! variances the fit minimised J over (`FoundationFit::obs`: after a
//! pedestal cross-coupling, a correction that mixes the channels, the
//! variances the correction carries into each residual,
//! `super::correct::carrying_noise`, not the measured numbers' own, which
//! would make the base look better known than its fit says), in the fit's
//! own parametrisation
//! (θ of every pedestal of the group, then κ = 1/K_B, μ = M_B/K_B,
//! γ = C_B/K_B of each direction where base motion was detected), in
//! relative units. The readings' variance then follows by the delta method
//! (gradients by forward differences of 1 % of each parameter's ±, through
//! the re-simulation), Σ_o g_oᵀ·C·g_o. Correlations between a base and
//! the state's corrections (runout, delays) are not carried.

use super::data::Prepared;
use super::foundation::FoundationFit;
use super::machine::{flat, resimulate, Readings};
use super::state::State;
use crate::estimate::base::{chi2, BaseGroup, BaseIdentifiability};
use crate::estimate::gauss_helmert::inverse_psd;
use crate::estimate::Observation;
use crate::sim::Machine;
use anyhow::Result;
use nalgebra::DMatrix;

/// A parameter of a base fit: pedestal `i`'s θ entry `k`, or base
/// direction `d`'s κ (0), μ (1) or γ (2), of group `g`.
#[derive(Clone, Copy, Debug)]
enum Slot {
    Pedestal { i: usize, k: usize },
    Base { d: usize, which: usize },
}

/// The base-fit parameters of one group in the fit's parametrisation.
fn get(fit: &crate::estimate::base::BaseFitResult, s: Slot) -> f64 {
    match s {
        Slot::Pedestal { i, k } => fit.pedestals[i][k],
        Slot::Base { d, which } => {
            let kappa = 1.0 / fit.base.k[d];
            match which {
                0 => kappa,
                1 => fit.base.m[d] * kappa,
                _ => fit.base.c[d] * kappa,
            }
        }
    }
}

/// Sets one parameter of `fit` (κ, μ, γ moved together through K, M, C).
fn set(fit: &mut crate::estimate::base::BaseFitResult, s: Slot, v: f64) {
    match s {
        Slot::Pedestal { i, k } => fit.pedestals[i][k] = v,
        Slot::Base { d, which } => {
            let (mut kappa, mut mu, mut gamma) = (
                get(fit, Slot::Base { d, which: 0 }),
                get(fit, Slot::Base { d, which: 1 }),
                get(fit, Slot::Base { d, which: 2 }),
            );
            match which {
                0 => kappa = v,
                1 => mu = v,
                _ => gamma = v,
            }
            fit.base.k[d] = 1.0 / kappa;
            fit.base.m[d] = mu / kappa;
            fit.base.c[d] = gamma / kappa;
        }
    }
}

/// The free parameters of a group's fit: every pedestal entry with a
/// positive standard error, and κ, μ, γ of each direction where the base
/// moves; only non-zero values (the relative steps need a scale).
fn slots(fit: &crate::estimate::base::BaseFitResult) -> Vec<Slot> {
    let mut out = Vec::new();
    for (i, se) in fit.pedestal_std_err.iter().enumerate() {
        for (k, s) in se.iter().enumerate() {
            if *s > 0.0 && s.is_finite() {
                out.push(Slot::Pedestal { i, k });
            }
        }
    }
    for d in 0..2 {
        if fit.identifiability[d] != BaseIdentifiability::NotDetected && fit.base.k[d].is_finite() {
            for which in 0..3 {
                out.push(Slot::Base { d, which });
            }
        }
    }
    out.retain(|&s| {
        let v = get(fit, s);
        v.is_finite() && v != 0.0
    });
    out
}

/// Covariance (relative units: Δp/|p|) of the parameters `slots` of the
/// fit of group `group` on `obs`: 2·H⁻¹ (module docs); `None` when J
/// cannot be evaluated or H is not positive.
fn covariance(
    obs: &[Vec<Observation>],
    group: &[usize],
    fit: &crate::estimate::base::BaseFitResult,
    slots: &[Slot],
) -> Option<DMatrix<f64>> {
    let g = BaseGroup {
        bearings: group.to_vec(),
    };
    let n = slots.len();
    let scale: Vec<f64> = slots.iter().map(|&s| get(fit, s).abs()).collect();
    let cost = |moves: &[(usize, f64)]| -> Option<f64> {
        let mut f = fit.clone();
        for &(k, u) in moves {
            let v = get(fit, slots[k]) + u * scale[k];
            set(&mut f, slots[k], v);
        }
        chi2(obs, &g, &f.pedestals, &f.base)
            .ok()
            .filter(|v| v.is_finite())
    };
    let f0 = cost(&[])?;
    // Steps: a first diagonal at 1e-4, then 0.3 of each parameter's ±
    // (within [1e-6, 0.05]) for the whole Hessian.
    let mut h = vec![1e-4; n];
    for (k, hk) in h.iter_mut().enumerate() {
        let d2 = (cost(&[(k, *hk)])? - 2.0 * f0 + cost(&[(k, -*hk)])?) / (*hk * *hk);
        *hk = if d2 > 0.0 {
            (0.3 * (2.0 / d2).sqrt()).clamp(1e-6, 0.05)
        } else {
            0.05
        };
    }
    let mut hess = DMatrix::zeros(n, n);
    for a in 0..n {
        hess[(a, a)] = (cost(&[(a, h[a])])? - 2.0 * f0 + cost(&[(a, -h[a])])?) / (h[a] * h[a]);
        for b in 0..a {
            let v = (cost(&[(a, h[a]), (b, h[b])])?
                - cost(&[(a, h[a]), (b, -h[b])])?
                - cost(&[(a, -h[a]), (b, h[b])])?
                + cost(&[(a, -h[a]), (b, -h[b])])?)
                / (4.0 * h[a] * h[b]);
            hess[(a, b)] = v;
            hess[(b, a)] = v;
        }
    }
    let inv = inverse_psd(&(hess * 0.5));
    inv.iter().all(|v| v.is_finite()).then_some(inv)
}

/// Σ Var X̂ [m²] of the re-simulated readings `readings` from the
/// covariance of the chosen base's fits (module docs); 0 without a base.
/// A group whose covariance cannot be formed (J not evaluable, H singular)
/// adds an infinite variance: a floor that cannot be bounded judges
/// nothing.
pub fn base_variance(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    foundation: Option<&FoundationFit>,
    readings: &Readings,
) -> Result<f64> {
    let Some(f) = foundation else {
        return Ok(0.0);
    };
    let obs = &f.obs;
    let x0 = flat(readings);
    let mut total = 0.0;
    for (gi, (group, fit)) in f.grouping.groups.iter().zip(&f.grouping.fits).enumerate() {
        let slots = slots(fit);
        if slots.is_empty() {
            continue;
        }
        let Some(cov) = covariance(obs, group, fit, &slots) else {
            return Ok(f64::INFINITY);
        };
        let mut grads: Vec<Vec<f64>> = Vec::with_capacity(slots.len());
        for (k, &s) in slots.iter().enumerate() {
            let h = 0.01 * cov[(k, k)].max(0.0).sqrt();
            if !(h.is_finite() && h > 0.0) {
                grads.push(vec![0.0; x0.len()]);
                continue;
            }
            let mut shifted = f.clone();
            let v = get(fit, s);
            set(&mut shifted.grouping.fits[gi], s, v + h * v.abs());
            let x = flat(&resimulate(machine, prep, state, Some(&shifted))?);
            grads.push(x.iter().zip(&x0).map(|(a, b)| (a - b) / h).collect());
        }
        for o in 0..x0.len() {
            let g: Vec<f64> = grads.iter().map(|gr| gr[o]).collect();
            let mut v = 0.0;
            for (a, ga) in g.iter().enumerate() {
                for (b, gb) in g.iter().enumerate() {
                    v += ga * cov[(a, b)] * gb;
                }
            }
            total += v.max(0.0);
        }
    }
    Ok(total)
}
