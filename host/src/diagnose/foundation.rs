//! The `foundation_coupling` candidate: the pedestals stand on a shared,
//! unmeasured base (`crate::estimate::base`, the one physical model and its
//! maximum-likelihood fit, called here, never copied), tried on all
//! bearings, with the test that is valid for it.
//!
//! **Which pedestals share a base.** Every measured pedestal on one base is
//! tried; with up to [`MAX_SEARCH_BEARINGS`] bearings also every other
//! grouping into bases of two or more pedestals (the rest on rigid ground).
//! The grouping the data favour is the one with the largest penalised
//! likelihood ratio LR − q·ln N (q = 6 base parameters per base, N real
//! equations).
//!
//! **The test.** Under "rigid base" the base's frequency and damping are not
//! identified (the base compliance κ = 0 leaves them undefined), so the
//! likelihood ratio does not follow χ² and a Bonferroni correction over
//! candidates has no basis. The statistic is the penalised likelihood ratio
//! of the favoured grouping, LR = J_rigid − J_base (whitened residual sums of
//! squares of `estimate::base`, the same equations with and without the
//! base); its null distribution is calibrated by a **parametric bootstrap**:
//! [`REPLICATES`] data sets simulated from the rigid-ground fit (each
//! measured rel as the true rotor motion, the pedestal motion the rigid fit
//! predicts from its force, plus Gaussian noise of each number's own standard
//! deviation), each refitted with and without bases *including the search
//! over groupings*, with a fixed seed ([`SEED`]). The p-value reported is
//! the bootstrap's own (1 + #{T* ≥ T})/(R + 1) and, for the tail beyond the
//! replicates, that of a scaled χ² a·χ²(ν) matched to the replicates' mean
//! and variance; the effect is significant when T exceeds every replicate
//! and the calibrated tail probability is below the significance level.
//!
//! Cost: each replicate refits the bases, so the bootstrap is run only when
//! the candidate could be chosen at all (the rigid model's gap, over the
//! machine or on any one pedestal channel against that channel's own floor
//! ([`Prediction::above_floor`]), is above [`TRY_ABOVE_FLOOR`] times its
//! noise floor, the penalised ratio is positive and
//! the base model brings the gap down), and it stops early when the decision
//! can no longer change: at the first replicate that reaches T (the effect
//! is then not significant; the p-value shown is that of the replicates
//! run), or, after [`MIN_REPLICATES`], when T is beyond every replicate and
//! the calibrated p-value is below 1/1000 of the significance level. The
//! test's name gives the replicates actually run. The replicates refit the favoured grouping
//! only; the search over groupings is allowed for by a Bonferroni factor
//! (the number of groupings tried) on the calibrated p-value.

use super::criterion::Evidence;
use super::data::Prepared;
use super::gap::{Gap, Prediction};
use super::report::FoundationTest;

/// The rigid model's gap must exceed this multiple of its noise floor for
/// the base to be tried: below it there is nothing a base could explain. It
/// is lower than the verdict's [`super::trust::AT_THE_FLOOR`] (3×): a gap
/// twice its floor is no failure of the model, but it may still hold a base
/// the likelihood-ratio test can find (0.5 % noise on a stiff base: gap 2.3×
/// its floor).
pub const TRY_ABOVE_FLOOR: f64 = 1.5;
use crate::estimate::base::{
    fit_on_unmeasured_base, widen_by_profile, BaseFitResult, BaseGroup, BaseIdentifiability, Misfit,
};
use crate::estimate::Observation;
use anyhow::Result;
use prediction::prediction;

/// Bootstrap replicates of the likelihood-ratio test (fixed: the test's
/// resolution is 1/(R + 1) empirically, the scaled-χ² tail beyond).
pub const REPLICATES: usize = 40;

/// Replicates always run before the bootstrap may stop on an overwhelming
/// statistic (module docs).
pub const MIN_REPLICATES: usize = 10;

/// Seed of the bootstrap's random numbers (same data, same answer).
pub const SEED: u64 = 0x0f0_0da7;

/// Up to this many bearings every grouping into bases is tried; beyond it,
/// every pedestal on one base only.
pub const MAX_SEARCH_BEARINGS: usize = 4;

/// Base parameters per base (k, c, m in y and z).
const BASE_PARAMETERS: usize = 6;

/// The groupings tried for `n` bearings: lists of bases, each a list of
/// bearing indices (two or more); bearings in no base stand on rigid ground.
pub fn groupings(n: usize) -> Vec<Vec<Vec<usize>>> {
    if n < 2 {
        return Vec::new();
    }
    let all: Vec<usize> = (0..n).collect();
    let mut out = vec![vec![all]];
    if n > MAX_SEARCH_BEARINGS {
        return out;
    }
    // Every proper subset of two or more on one base.
    let subsets: Vec<Vec<usize>> = (1u32..(1 << n) - 1)
        .map(|mask| (0..n).filter(|b| mask & (1 << b) != 0).collect::<Vec<_>>())
        .filter(|s| s.len() >= 2)
        .collect();
    for s in &subsets {
        out.push(vec![s.clone()]);
    }
    // Two disjoint bases of two or more each.
    for a in &subsets {
        for b in &subsets {
            if a.iter().all(|x| !b.contains(x)) && a[0] < b[0] {
                out.push(vec![a.clone(), b.clone()]);
            }
        }
    }
    out
}

/// Which base model: a base shared by two or more pedestals
/// (`foundation_coupling`, every grouping of [`groupings`]) or one
/// pedestal on its own sub-base (`pedestal_sub_base`: the same physical
/// model, `crate::estimate::base`, on a group of one, a two-degree-of-freedom
/// pedestal per direction), tried on every bearing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Pedestals on a shared base.
    Shared,
    /// One pedestal on its own sub-base.
    SubBase,
}

impl Kind {
    /// The effect name (`crate::effects`).
    pub fn effect(self) -> &'static str {
        match self {
            Kind::Shared => crate::effects::EffectKind::FoundationCoupling.name(),
            Kind::SubBase => super::candidates::PEDESTAL_SUB_BASE,
        }
    }

    /// The groupings tried for `n` bearings.
    pub fn groupings(self, n: usize) -> Vec<Vec<Vec<usize>>> {
        match self {
            Kind::Shared => groupings(n),
            Kind::SubBase => (0..n).map(|b| vec![vec![b]]).collect(),
        }
    }

    /// Prefix of the base parameters' names in the report.
    fn prefix(self) -> &'static str {
        match self {
            Kind::Shared => "base",
            Kind::SubBase => "sub",
        }
    }
}

/// Whether a joint fit is physical: every pedestal's k and m positive, and
/// whatever the data determine of the base (its stiffness and mass, its
/// quasi-static compliance or its mass) positive. A fit that ends with a
/// negative base stiffness or mass is rejected, not kept.
///
/// A sub-base ([`Kind::SubBase`]) must moreover be one the data constrain:
/// a pedestal on its own sub-base is a two-degree-of-freedom pedestal, and
/// a sub-base whose mode lies outside the speed range (quasi-static or
/// mass line) is indistinguishable from a changed pedestal stiffness or
/// mass (it would "explain" a mass anisotropy with a pedestal of 10⁹ N/m on
/// a spring). So every direction the data detect must be fully determined
/// (its mode inside the speed range, `BaseIdentifiability::Full`) with
/// stiffness and mass each known to better than [`SUB_BASE_REL_SE`] (the
/// ± excludes both zero and infinity), and at least one direction detected.
pub fn physical(fit: &BaseFitResult, kind: Kind) -> bool {
    let pedestals = fit
        .pedestals
        .iter()
        .all(|t| t[0] > 0.0 && t[1] > 0.0 && t[2] > 0.0);
    let base = (0..2).all(|d| match fit.identifiability[d] {
        BaseIdentifiability::Full => fit.base.k[d] > 0.0 && fit.base.m[d] > 0.0,
        BaseIdentifiability::QuasiStatic {
            compliance_m_per_n, ..
        } => kind == Kind::Shared && compliance_m_per_n > 0.0,
        BaseIdentifiability::MassLine { mass_kg, .. } => kind == Kind::Shared && mass_kg > 0.0,
        BaseIdentifiability::NotDetected => true,
    });
    let constrained = |d: usize| {
        fit.base_std_err.k[d] < SUB_BASE_REL_SE * fit.base.k[d]
            && fit.base_std_err.m[d] < SUB_BASE_REL_SE * fit.base.m[d]
    };
    let sub_base = kind == Kind::Shared
        || ((0..2).any(|d| fit.identifiability[d] == BaseIdentifiability::Full)
            && (0..2)
                .all(|d| fit.identifiability[d] != BaseIdentifiability::Full || constrained(d)));
    pedestals && base && sub_base
}

/// Largest relative standard error of a sub-base's stiffness and mass for
/// the sub-base to count as determined: 2σ then excludes zero, and the
/// reciprocal (compliance, 1/mass) excludes zero too (no infinite value).
pub const SUB_BASE_REL_SE: f64 = 0.5;

/// One grouping fitted: the bases and their joint fits.
#[derive(Clone, Debug)]
pub struct GroupingFit {
    /// Bearing indices of each base.
    pub groups: Vec<Vec<usize>>,
    /// The joint fit of each base's pedestals and the base.
    pub fits: Vec<BaseFitResult>,
    /// Likelihood ratio Σ (J_rigid − J) over the bases [-].
    pub lr: f64,
    /// Base parameters added (q).
    pub q: usize,
    /// LR − q·ln N: what the grouping search maximises [-].
    pub score: f64,
}

/// The foundation candidate fitted and tested.
#[derive(Clone, Debug)]
pub struct FoundationFit {
    /// Shared base or sub-base.
    pub kind: Kind,
    /// The favoured grouping.
    pub grouping: GroupingFit,
    /// The bootstrap test.
    pub test: FoundationTest,
    /// The evidence in the library's terms (statistic = LR).
    pub evidence: Evidence,
    /// The pedestal-level prediction of every bearing.
    pub prediction: Prediction,
    /// Its gap.
    pub gap: Gap,
    /// The observations the bases were fitted to, with the variances the
    /// fit weighted them by (the noise a channel-mixing correction carries
    /// into them included, `super::correct::carrying_noise`): the cost
    /// whose curvature is the fit's covariance
    /// ([`super::base_floor::base_variance`]).
    pub obs: Vec<Vec<Observation>>,
}

/// The measurements as the estimation core's observations, per bearing,
/// with the variances the diagnosis uses (`Observation::var`).
pub fn observations(prep: &Prepared) -> Vec<Vec<Observation>> {
    prep.points
        .iter()
        .map(|row| row.iter().flatten().copied().collect())
        .collect()
}

/// The rigid-ground fit θ of every bearing (`plinth identify`'s ML fit),
/// when all are finite.
pub fn rigid_start(prep: &Prepared) -> Option<Vec<[f64; 5]>> {
    let start: Vec<[f64; 5]> = prep.base_fits.iter().map(|f| f.pedestal.theta()).collect();
    (start.len() == prep.bearings.len() && start.iter().flatten().all(|v| v.is_finite()))
        .then_some(start)
}

/// Fits every grouping and returns the favoured one (largest score); `None`
/// when no grouping could be fitted. With `kind`, only groupings whose fits
/// are [`physical`] for that kind count; the bootstrap's null replicates
/// pass `None` (the unrestricted statistic, which is larger than the
/// restricted one: a conservative null).
fn best_grouping(
    obs: &[Vec<Observation>],
    start: &[[f64; 5]],
    groupings: &[Vec<Vec<usize>>],
    n_eq: usize,
    kind: Option<Kind>,
) -> Option<GroupingFit> {
    let ln_n = (n_eq.max(2) as f64).ln();
    let mut best: Option<GroupingFit> = None;
    // Each base group is fitted once: a group recurs in several groupings
    // (a pair alone and beside another pair), and its fit depends on the
    // group, `obs` and `start` only.
    let mut fitted: Vec<(&[usize], Option<BaseFitResult>)> = Vec::new();
    for groups in groupings {
        let fits: Option<Vec<BaseFitResult>> = groups
            .iter()
            .map(|g| {
                if let Some((_, f)) = fitted.iter().find(|(h, _)| *h == g.as_slice()) {
                    return f.clone();
                }
                let f = fit_group(obs, g, start, kind);
                fitted.push((g, f.clone()));
                f
            })
            .collect();
        let Some(fits) = fits else { continue };
        if kind.is_some_and(|k| !fits.iter().all(|f| physical(f, k))) {
            continue;
        }
        let lr: f64 = fits.iter().map(|f| (f.chi2_rigid - f.chi2).max(0.0)).sum();
        let q = BASE_PARAMETERS * groups.len();
        let score = lr - q as f64 * ln_n;
        if !score.is_finite() {
            continue;
        }
        if best.as_ref().is_none_or(|b| score > b.score) {
            best = Some(GroupingFit {
                groups: groups.clone(),
                fits,
                lr,
                q,
                score,
            });
        }
    }
    best
}

/// The fit of one base group `g` (`estimate::base`) from `start`. A
/// sub-base ([`Kind::SubBase`]) whose fit ends non-physical is fitted again
/// from the chain its receptance shows ([`sub_base::fit_from_receptance`]:
/// that fit's profile starts from the rigid-ground pedestal, the two
/// springs in series, and can end in a non-physical optimum from any θ
/// start), kept when that is physical.
fn fit_group(
    obs: &[Vec<Observation>],
    g: &[usize],
    start: &[[f64; 5]],
    kind: Option<Kind>,
) -> Option<BaseFitResult> {
    let group = BaseGroup {
        bearings: g.to_vec(),
    };
    let fit = fit_on_unmeasured_base(obs, &group, start).ok()?;
    if kind != Some(Kind::SubBase) || physical(&fit, Kind::SubBase) {
        return Some(fit);
    }
    let [b] = g else { return Some(fit) };
    match sub_base::fit_from_receptance(obs, *b, &fit) {
        Some(f) if physical(&f, Kind::SubBase) => Some(f),
        _ => Some(fit),
    }
}

/// The start of a sub-base fit from the rigid-ground fit `theta`: the
/// rigid fit sees the pedestal and its sub-base as two springs in series,
/// so its stiffness is about half the pedestal's own when the two are
/// alike (the sub-base fit of `estimate::base` starts its base as compliant
/// as the pedestal). Starting the pedestal at the rigid stiffness puts the
/// search in the basin of a non-physical optimum (a negative sub-base mass
/// and stiffness, seen on the skid machine's right pedestal); starting it at
/// twice the rigid stiffness and damping does not.
fn series_start(theta: &[[f64; 5]]) -> Vec<[f64; 5]> {
    theta
        .iter()
        .map(|t| [2.0 * t[0], 2.0 * t[1], t[2], 2.0 * t[3], 2.0 * t[4]])
        .collect()
}

/// A base candidate fitted, its bootstrap test not yet run: the test is
/// run ([`Fitted::tested`]) only for a candidate that could be chosen.
#[derive(Clone, Debug)]
pub struct Fitted {
    /// Shared base or sub-base.
    pub kind: Kind,
    /// The favoured grouping.
    pub grouping: GroupingFit,
    /// The pedestal-level prediction of every bearing.
    pub prediction: Prediction,
    /// Its gap.
    pub gap: Gap,
    /// The rigid model's gap.
    base_gap: Gap,
    /// The observations fitted.
    obs: Vec<Vec<Observation>>,
    /// The rigid-ground θ the bootstrap simulates from.
    start: Vec<[f64; 5]>,
    /// Real equations.
    n_eq: usize,
    /// Groupings searched (the Bonferroni factor).
    groupings: usize,
}

/// Fits the foundation candidate on `prep` (module docs). `base_prediction`
/// is the rigid model's prediction (kept for bearings on no base),
/// `base_gap` its gap; `None` when there are fewer than two bearings, the
/// rigid model already fits to the noise floor (nothing to explain), or no
/// grouping can be fitted.
///
/// `kind` chooses shared bases or sub-bases; `start` is the rigid-ground
/// fit θ of every bearing the base fits start from and the bootstrap
/// simulates from (`None`: `plinth identify`'s fits, [`rigid_start`]).
/// Groupings whose fit ends non-physical ([`physical`]) are rejected.
pub fn fit(
    prep: &Prepared,
    base_prediction: &Prediction,
    base_gap: Gap,
    kind: Kind,
    start: Option<Vec<[f64; 5]>>,
) -> Result<Option<Fitted>> {
    let nb = prep.bearings.len();
    let candidates = kind.groupings(nb);
    let Some(start) = start.or_else(|| rigid_start(prep)) else {
        return Ok(None);
    };
    // Nothing to explain: the rigid model already fits to the noise floor,
    // so the candidate could not be chosen (and its fits cost seconds).
    if candidates.is_empty() || !base_prediction.above_floor(prep, TRY_ABOVE_FLOOR) {
        return Ok(None);
    }
    let obs = observations(prep);
    let n_eq: usize = obs.iter().map(|o| 4 * o.len()).sum();
    // A sub-base's fit also starts from the series reading of the rigid
    // fit ([`series_start`]); the better of the two is kept.
    let starts = match kind {
        Kind::Shared => vec![start.clone()],
        Kind::SubBase => vec![start.clone(), series_start(&start)],
    };
    let Some(grouping) = starts
        .iter()
        .filter_map(|s| best_grouping(&obs, s, &candidates, n_eq, Some(kind)))
        .max_by(|a, b| a.score.total_cmp(&b.score))
    else {
        return Ok(None);
    };
    let prediction = prediction(prep, &obs, base_prediction, &grouping)?;
    let gap = prediction.gap(prep, None);
    Ok(Some(Fitted {
        kind,
        grouping,
        prediction,
        gap,
        base_gap,
        obs,
        start,
        n_eq,
        groupings: candidates.len(),
    }))
}

/// Fits the foundation candidate on `prep` and tests it against rigid
/// ground ([`fit`], then [`Fitted::tested`]).
#[allow(clippy::too_many_arguments)]
pub fn evaluate(
    prep: &Prepared,
    base_prediction: &Prediction,
    base_gap: Gap,
    alpha: f64,
    replicates: usize,
    seed: u64,
    kind: Kind,
    start: Option<Vec<[f64; 5]>>,
) -> Result<Option<FoundationFit>> {
    Ok(fit(prep, base_prediction, base_gap, kind, start)?
        .map(|f| f.tested(alpha, replicates, seed)))
}

impl Fitted {
    /// The penalised likelihood ratio LR − q·ln N [-].
    pub fn score(&self) -> f64 {
        self.grouping.score
    }

    /// The candidate with its test not run, for `reason`.
    pub fn untested(self, reason: &str) -> FoundationFit {
        let test = FoundationTest::not_run(self.grouping.score, self.grouping.lr, reason);
        self.with_test(test)
    }

    fn with_test(self, test: FoundationTest) -> FoundationFit {
        let ln_n = (self.n_eq.max(2) as f64).ln();
        let grouping = self.grouping;
        let evidence = Evidence {
            wald_floor: grouping.lr,
            wald_robust: grouping.lr,
            wald: grouping.lr,
            extra_parameters: grouping.q,
            delta_bic: grouping.lr - grouping.q as f64 * ln_n,
            p_value: test.p_value,
            p_adjusted: test.p_calibrated,
        };
        FoundationFit {
            kind: self.kind,
            grouping,
            test,
            evidence,
            prediction: self.prediction,
            gap: self.gap,
            obs: self.obs,
        }
    }
}

impl FoundationFit {
    /// The same bases (grouping and kind) refitted on other data `prep`
    /// (the data a further correction changes), starting from this fit's
    /// pedestals, with `rigid` the rigid-ground prediction of bearings on no
    /// base. The bootstrap test is not repeated (the base's own test
    /// stands). `None` when the fit fails or ends non-physical
    /// ([`physical`]).
    pub fn refit(&self, prep: &Prepared, rigid: &Prediction) -> Option<FoundationFit> {
        let obs = observations(prep);
        let n_eq: usize = obs.iter().map(|o| 4 * o.len()).sum();
        let mut start = rigid_start(prep)?;
        for (g, f) in self.grouping.groups.iter().zip(&self.grouping.fits) {
            for (i, &b) in g.iter().enumerate() {
                start[b] = f.pedestals[i];
            }
        }
        let favoured = [self.grouping.groups.clone()];
        let grouping = best_grouping(&obs, &start, &favoured, n_eq, Some(self.kind))?;
        let prediction = prediction(prep, &obs, rigid, &grouping).ok()?;
        let gap = prediction.gap(prep, None);
        Some(FoundationFit {
            kind: self.kind,
            grouping,
            test: self.test.clone(),
            evidence: self.evidence,
            prediction,
            gap,
            obs,
        })
    }
}

impl FoundationFit {
    /// This fit with every pedestal's ± widened to the profile likelihood's
    /// along its mass split with the base ([`widen_by_profile`]; ΔJ read
    /// against χ²/dof where the misfit is above 1). Run on the fit the
    /// diagnosis reports only: it refits each base up to 42 times per
    /// pedestal, and no choice of effects depends on the pedestals' ±.
    pub fn with_profile_errors(mut self) -> FoundationFit {
        for (g, f) in self
            .grouping
            .groups
            .iter()
            .zip(self.grouping.fits.iter_mut())
        {
            let group = BaseGroup {
                bearings: g.clone(),
            };
            widen_by_profile(&self.obs, &group, f, Misfit::Scaled);
        }
        self
    }
}

mod bootstrap;
mod prediction;
mod report;
pub mod sub_base;
#[cfg(test)]
mod tests;
