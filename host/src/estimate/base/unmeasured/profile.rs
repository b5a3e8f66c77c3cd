//! The ± of a pedestal on an unmeasured base from the profile likelihood.
//!
//! When a pedestal is much stiffer than the base it stands on (a massive
//! block on a bedplate), the data fix the sum of its mass and the base's
//! well but their split only weakly, along a nearly flat valley of J. The
//! Fisher information of the fit (the Gauss–Newton curvature, the
//! weights held) can understate how far that valley reaches: on the
//! flexible roll's bedplate (seed 1) J rose by 0.054 at one Fisher ± of the
//! block's mass, not by 1, and quadratically (0.22 at 2 ±, 0.67 at 3.5 ±),
//! so the likelihood's own ± was 4.3 times the Fisher one. The profile
//! likelihood does not rest on that curvature: one parameter (a pedestal's
//! k_y, k_z or m) is held at values stepped out from its estimate on both
//! sides and everything else refitted; the points with ΔJ ≤ 1 (ΔJ divided
//! by χ²/dof when that is above 1: the noise may be understated) are the
//! one-standard-error set along it, and the largest distance of each
//! parameter from its estimate over the sets (the crossing ΔJ = 1
//! interpolated between the last point inside and the first outside) is
//! its ± along them.

use super::equations::{base_at, common_speeds, Unmeasured};
use super::{covariance, scales};
use crate::estimate::base::{BaseFitResult, BaseGroup, BaseIdentifiability};
use crate::estimate::gauss_helmert as gh;
use crate::estimate::Observation;

/// How the profile reads a misfit (χ²/dof above 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Misfit {
    /// ΔJ is divided by χ²/dof when above 1 (the noise may be
    /// understated): for a caller that reports the ± as they come.
    Scaled,
    /// ΔJ as it is: for a caller that scales every ± by √(χ²/dof) itself
    /// (`plinth identify`), which would otherwise count the misfit twice.
    AsIs,
}

/// Widens the ± of `fit`, a fit of `group` on `obs` by
/// [`super::fit_on_unmeasured_base`], to the profile likelihood's (module
/// docs): each pedestal's k_y, k_z and m is profiled, and the base's own
/// κ = 1/K_B, μ = M_B/K_B and γ = C_B/K_B in each direction where it
/// moves; every pedestal parameter's ± and the base's K_B, M_B, C_B ±
/// become the larger of their Fisher ± and their largest distance from the
/// estimate over all these one-standard-error sets (each set lies inside
/// the joint ΔJ ≤ 1 region, so its spread is a lower bound of the
/// quantity's own profile interval); the pedestal covariance is widened
/// with its ± (correlations kept), and `split_unresolved` and
/// `base_unresolved` are set where a profile stayed open. Costs up to
/// 2 × 7 refits per profile (3 per pedestal, 3 per moving direction),
/// seconds on a long run: call it once, on the fit that is reported, not
/// on every candidate fit. A fit that does not belong to `group` and `obs`
/// is left as it is.
pub fn widen_by_profile(
    obs: &[Vec<Observation>],
    group: &BaseGroup,
    fit: &mut BaseFitResult,
    misfit: Misfit,
) {
    let n = group.bearings.len();
    let Ok(speeds) = common_speeds(obs, group) else {
        return;
    };
    if fit.pedestals.len() != n || fit.pedestal_std_err.len() != n || speeds.is_empty() {
        return;
    }
    let w_mid = (speeds[0].omega * speeds[speeds.len() - 1].omega).sqrt();
    let n_eq = 4 * n * speeds.len();
    let eq = Unmeasured { speeds };
    // The fit's end in model units: θ per pedestal, then κ = 1/K,
    // μ = M/K, γ = C/K per direction where the base moves.
    let mut p: Vec<f64> = fit.pedestals.iter().flatten().copied().collect();
    let mut free = vec![true; 5 * n];
    for d in 0..2 {
        let moves = fit.identifiability[d] != BaseIdentifiability::NotDetected;
        let kappa = 1.0 / fit.base.k[d];
        let at = if moves && kappa.is_finite() {
            [kappa, fit.base.m[d] * kappa, fit.base.c[d] * kappa]
        } else {
            [0.0; 3]
        };
        p.extend(at);
        free.extend([moves && kappa.is_finite(); 3]);
    }
    debug_assert_eq!(p.len(), base_at(n, 1) + 3);
    let Some(j) = gh::cost(&eq, &p) else {
        return;
    };
    let dof = n_eq
        .saturating_sub(free.iter().filter(|f| **f).count())
        .max(1);
    let chi2_per_dof = match misfit {
        Misfit::Scaled => j / dof as f64,
        Misfit::AsIs => 1.0,
    };
    let scale: Vec<f64> = p
        .iter()
        .zip(scales(&fit.pedestals, w_mid))
        .map(|(v, s)| v.abs().max(s))
        .collect();
    // The Fisher ± of every parameter in model units: the steps of the
    // base's own profiles (a pedestal's are its reported Fisher ±).
    let Some((cov, _)) = covariance(&eq, &p, &scale, &free) else {
        return;
    };
    let end = End {
        p: &p,
        j,
        scale: &scale,
        free: &free,
        chi2_per_dof,
    };
    let fisher = fit.pedestal_std_err.clone();
    let mut sets = Vec::new();
    for (i, fisher_i) in fisher.iter().enumerate() {
        // k_y, k_z and m: the values a pedestal is judged by.
        for (k, se) in fisher_i.iter().take(3).enumerate() {
            if let Some(prof) = along(&eq, &end, 5 * i + k, *se) {
                if let Some(open) = fit.split_unresolved.get_mut(i) {
                    open[k] |= prof.open;
                }
                sets.push(prof);
            }
        }
    }
    for d in 0..2 {
        let o = base_at(n, d);
        for w in 0..3 {
            let se = cov[(o + w, o + w)].max(0.0).sqrt();
            if let Some(prof) = along(&eq, &end, o + w, se) {
                fit.base_unresolved[d][w] |= prof.open;
                sets.push(prof);
            }
        }
    }
    let spread =
        |g: &dyn Fn(&[f64]) -> f64| sets.iter().map(|s| s.spread(&p, g)).fold(0.0, f64::max);
    for (i, fisher_i) in fisher.iter().enumerate() {
        for (a, v) in fit.pedestal_std_err[i].iter_mut().enumerate() {
            *v = v.max(spread(&|q| q[5 * i + a]));
        }
        let widen: [f64; 5] = std::array::from_fn(|a| {
            if fisher_i[a] > 0.0 {
                fit.pedestal_std_err[i][a] / fisher_i[a]
            } else {
                1.0
            }
        });
        if let Some(c) = fit.pedestal_covariance.get_mut(i) {
            for (a, row) in c.iter_mut().enumerate() {
                for (b, v) in row.iter_mut().enumerate() {
                    *v *= widen[a] * widen[b];
                }
            }
        }
    }
    for d in (0..2).filter(|&d| free[base_at(n, d)]) {
        let o = base_at(n, d);
        let e = &mut fit.base_std_err;
        e.k[d] = e.k[d].max(spread(&|q| 1.0 / q[o]));
        e.m[d] = e.m[d].max(spread(&|q| q[o + 1] / q[o]));
        e.c[d] = e.c[d].max(spread(&|q| q[o + 2] / q[o]));
        match &mut fit.identifiability[d] {
            BaseIdentifiability::QuasiStatic { std_err, .. } => {
                *std_err = std_err.max(spread(&|q| q[o]));
            }
            BaseIdentifiability::MassLine { std_err, .. } => *std_err = e.m[d],
            _ => {}
        }
    }
}

/// Steps of the profile on each side of the estimate, in Fisher standard
/// errors of the profiled parameter [-].
const STEPS: [f64; 7] = [1.0, 2.0, 3.5, 5.0, 7.5, 11.0, 16.0];
/// Most iterations of each profile fit (warm-started from its neighbour).
const ITERATIONS: usize = 80;

/// The one-standard-error set of the fit along one parameter.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Profile {
    /// Parameter vectors of the set (the estimate excluded), the ends
    /// interpolated at ΔJ = 1 (model units, like the fit's p).
    pub(crate) points: Vec<Vec<f64>>,
    /// True when ΔJ stayed below 1 to the last step on a side, or the
    /// parameter reached zero first: the set reaches past the profile, and
    /// its spreads are lower bounds.
    pub(crate) open: bool,
}

impl Profile {
    /// Largest |g(p) − g(p̂)| over the set for a quantity g of the
    /// parameters (in g's units; 0 for an empty set).
    pub(crate) fn spread(&self, p_hat: &[f64], g: impl Fn(&[f64]) -> f64) -> f64 {
        let at = g(p_hat);
        self.points
            .iter()
            .map(|p| (g(p) - at).abs())
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max)
    }
}

/// Where a profile starts: the fit's end `p` (its J `j`, its free
/// parameters `free`, the scale of its parameters `scale`) and its
/// χ²/dof, which scales ΔJ when above 1 (module docs).
pub(super) struct End<'a> {
    /// Parameters at the fit's end (model units).
    pub(super) p: &'a [f64],
    /// J there [-].
    pub(super) j: f64,
    /// Scale of each parameter for the refits (model units).
    pub(super) scale: &'a [f64],
    /// The fit's free parameters.
    pub(super) free: &'a [bool],
    /// J/dof at the end [-].
    pub(super) chi2_per_dof: f64,
}

/// Profile of J along parameter `k` from the fit's `end`, stepped in units
/// of `se` (its Fisher standard error, model units). `None` when the
/// parameter was not free or `se` is not a positive number.
pub(super) fn along(eq: &Unmeasured, end: &End, k: usize, se: f64) -> Option<Profile> {
    let (p_hat, j_hat) = (end.p, end.j);
    if !(end.free.get(k).copied().unwrap_or(false) && se > 0.0 && se.is_finite()) {
        return None;
    }
    let se_m = se;
    let (scale, free, chi2_per_dof) = (end.scale, end.free, end.chi2_per_dof);
    let s = chi2_per_dof.max(1.0);
    let mut held = free.to_vec();
    held[k] = false;
    let mut out = Profile {
        points: Vec::new(),
        open: false,
    };
    for side in [-1.0, 1.0] {
        let (mut prev, mut prev_dj) = (p_hat.to_vec(), 0.0);
        let mut closed = false;
        for t in STEPS {
            let m = p_hat[k] + side * t * se_m;
            if m <= 0.0 && p_hat[k] > 0.0 {
                break;
            }
            let mut start = prev.clone();
            start[k] = m;
            let Some(fit) = gh::fit(eq, &start, scale, &held, None, ITERATIONS) else {
                break;
            };
            let dj = ((fit.cost - j_hat) / s).max(0.0);
            if dj >= 1.0 {
                // Interpolate the crossing between the last point inside
                // and this one.
                let a = ((1.0 - prev_dj) / (dj - prev_dj)).clamp(0.0, 1.0);
                out.points.push(
                    prev.iter()
                        .zip(&fit.p)
                        .map(|(x, y)| x + a * (y - x))
                        .collect(),
                );
                closed = true;
                break;
            }
            out.points.push(fit.p.clone());
            (prev, prev_dj) = (fit.p, dj);
        }
        out.open |= !closed;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spread_is_the_largest_distance_over_the_set() {
        let set = Profile {
            points: vec![vec![1.0, 5.0], vec![4.0, 1.0], vec![f64::NAN, 2.0]],
            open: false,
        };
        let hat = [2.0, 2.0];
        assert_eq!(set.spread(&hat, |p| p[0]), 2.0);
        assert_eq!(set.spread(&hat, |p| p[1]), 3.0);
        assert_eq!(set.spread(&hat, |p| p[0] + p[1]), 2.0);
        let empty = Profile {
            points: vec![],
            open: true,
        };
        assert_eq!(empty.spread(&hat, |p| p[0]), 0.0);
    }
}
