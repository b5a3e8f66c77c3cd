//! The parametric bootstrap of a base candidate's likelihood-ratio test
//! (the parent module's docs): null data simulated from the rigid-ground
//! fit, the favoured grouping refitted on each, the p-value from the
//! replicates and a scaled χ² tail.

use super::{best_grouping, Fitted, FoundationFit, MIN_REPLICATES};
use crate::diagnose::report::FoundationTest;
use crate::estimate::Observation;
use num_complex::Complex;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use statrs::distribution::{ChiSquared, ContinuousCDF};

impl Fitted {
    /// The candidate with its bootstrap test (module docs): `replicates`
    /// at most, seed `seed`, early stop against level `alpha`.
    pub fn tested(self, alpha: f64, replicates: usize, seed: u64) -> FoundationFit {
        let statistic = self.grouping.score;
        let not_run = if statistic <= 0.0 {
            Some("the likelihood ratio does not pay for the base's parameters")
        } else if self.gap.gap >= self.base_gap.gap {
            Some("the base model does not bring the gap down")
        } else {
            None
        };
        if let Some(reason) = not_run {
            return self.untested(reason);
        }
        let (obs, start, grouping) = (&self.obs, &self.start, &self.grouping);
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let favoured = [grouping.groups.clone()];
        let mut null = Vec::with_capacity(replicates);
        let mut ticker = crate::progress::Ticker::new(
            "diagnose: foundation bootstrap replicates",
            replicates,
            true,
        );
        for done in 0..replicates {
            ticker.tick(done);
            let data = null_replicate(obs, start, &mut rng);
            if let Some(g) = best_grouping(&data, start, &favoured, self.n_eq, None) {
                null.push(g.score);
                if g.score >= statistic {
                    break;
                }
            }
            if null.len() >= MIN_REPLICATES {
                let so_far =
                    FoundationTest::from_replicates(statistic, grouping.lr, &null, self.groupings);
                if so_far.exceedances == 0 && so_far.p_calibrated < 1e-3 * alpha {
                    break;
                }
            }
        }
        let test = FoundationTest::from_replicates(statistic, grouping.lr, &null, self.groupings);
        self.with_test(test)
    }
}

/// Data simulated from the rigid-ground fit `theta` under the noise of each
/// number (module docs).
fn null_replicate(
    obs: &[Vec<Observation>],
    theta: &[[f64; 5]],
    rng: &mut rand::rngs::StdRng,
) -> Vec<Vec<Observation>> {
    let mut normal = || -> f64 { StandardNormal.sample(rng) };
    obs.iter()
        .zip(theta)
        .map(|(row, th)| {
            row.iter()
                .map(|o| {
                    let w = o.omega();
                    let f = o.force();
                    let mut r = *o;
                    for d in 0..2 {
                        let h = Complex::new(th[d] - w * w * th[2], w * th[3 + d]);
                        r.ped[d] = f[d] / h;
                    }
                    for d in 0..2 {
                        r.rel[d] += Complex::new(
                            o.var[2 * d].sqrt() * normal(),
                            o.var[2 * d + 1].sqrt() * normal(),
                        );
                        r.ped[d] += Complex::new(
                            o.var[4 + 2 * d].sqrt() * normal(),
                            o.var[5 + 2 * d].sqrt() * normal(),
                        );
                    }
                    r
                })
                .collect()
        })
        .collect()
}

impl FoundationTest {
    /// The test not run (module docs: it could not change the decision),
    /// with the reason.
    pub fn not_run(t: f64, lr: f64, reason: &str) -> Self {
        Self {
            test: format!("likelihood-ratio, parametric bootstrap (0): not run, {reason}"),
            likelihood_ratio: lr,
            statistic: t,
            replicates: 0,
            exceedances: 0,
            critical_value_95: f64::NAN,
            p_empirical: 1.0,
            p_value: 1.0,
            groupings: 0,
            p_calibrated: 1.0,
        }
    }

    /// The test from the observed statistic `t` (penalised LR), the LR, the
    /// bootstrap replicates of `t` under the null and the number of
    /// groupings searched (the Bonferroni factor).
    pub fn from_replicates(t: f64, lr: f64, null: &[f64], groupings: usize) -> Self {
        let r = null.len();
        let exceed = null.iter().filter(|&&x| x >= t).count();
        let p_empirical = (1 + exceed) as f64 / (r + 1) as f64;
        // Scaled χ² a·χ²(ν) through the replicates' mean and variance, on the
        // statistic shifted to be non-negative (the penalty is a constant).
        let lo = null.iter().copied().fold(f64::INFINITY, f64::min).min(t);
        let shift = if lo.is_finite() { -lo } else { 0.0 };
        let mean = null.iter().map(|x| x + shift).sum::<f64>() / r.max(1) as f64;
        let var =
            null.iter().map(|x| (x + shift - mean).powi(2)).sum::<f64>() / (r.max(2) - 1) as f64;
        let p_tail = if r >= 2 && mean > 0.0 && var > 0.0 {
            let a = var / (2.0 * mean);
            let nu = 2.0 * mean * mean / var;
            ChiSquared::new(nu).map_or(f64::NAN, |d| d.sf((t + shift) / a))
        } else {
            f64::NAN
        };
        let critical = quantile(null, 0.95);
        // Beyond every replicate the scaled-χ² tail; otherwise the
        // replicates themselves.
        let p_value = if exceed == 0 && p_tail.is_finite() {
            p_tail.min(p_empirical)
        } else {
            p_empirical
        };
        Self {
            test: format!("likelihood-ratio, parametric bootstrap ({r})"),
            likelihood_ratio: lr,
            statistic: t,
            replicates: r,
            exceedances: exceed,
            critical_value_95: critical,
            p_empirical,
            p_value,
            groupings,
            p_calibrated: (p_value * groupings.max(1) as f64).min(1.0),
        }
    }

    /// The smallest p-value the replicates can show, 1/(R + 1).
    pub fn p_empirical_floor(&self) -> f64 {
        1.0 / (self.replicates + 1) as f64
    }

    /// Significant at level `alpha`: beyond every replicate, and the
    /// calibrated tail below `alpha`.
    pub fn significant(&self, alpha: f64) -> bool {
        self.replicates > 0 && self.exceedances == 0 && self.p_calibrated < alpha
    }
}

/// The `q`-quantile of `x` (linear interpolation), NaN when empty.
fn quantile(x: &[f64], q: f64) -> f64 {
    if x.is_empty() {
        return f64::NAN;
    }
    let mut v = x.to_vec();
    v.sort_by(f64::total_cmp);
    let pos = q * (v.len() - 1) as f64;
    let (i, f) = (pos.floor() as usize, pos.fract());
    let j = (i + 1).min(v.len() - 1);
    v[i] + f * (v[j] - v[i])
}
