//! The scatter law v = α·|X|² + β of a series' local-fit residuals
//! ([`super`]): its pseudo-likelihood fit and the test that keeps the
//! fraction term.

use super::*;

/// The scatter law v = α·m² + β of each real part (α [-], β [m²]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Law {
    /// Fraction term α [-]: the variance's part proportional to |X|².
    pub(super) alpha: f64,
    /// Floor term β [m²].
    pub(super) beta: f64,
}

impl Law {
    /// Variance [m²] of each real part of a sample's residual.
    pub(super) fn variance(&self, s: &Sample) -> f64 {
        self.variance_at(s.along, s.floor)
    }

    /// Variance [m²] of each real part of a residual whose `along` [m²] and
    /// `floor` [-] are given ([`Sample`]).
    fn variance_at(&self, along: f64, floor: f64) -> f64 {
        (self.alpha * along + self.beta * floor).max(f64::MIN_POSITIVE)
    }

    /// True when both terms moved by less than 1e-9 of their size.
    pub(super) fn close_to(&self, other: Law) -> bool {
        let near = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
        near(self.alpha, other.alpha) && near(self.beta, other.beta)
    }

    /// −2·log-likelihood (constants dropped) of the samples' residuals,
    /// each real part N(0, v).
    fn deviance(&self, samples: &[&Sample]) -> f64 {
        samples
            .iter()
            .map(|s| {
                let v = self.variance(s);
                2.0 * v.ln() + s.nsq / v
            })
            .sum()
    }

    /// The law as a [`Scatter`].
    pub(super) fn scatter(&self) -> Scatter {
        match (self.alpha > 0.0, self.beta > 0.0) {
            (false, _) => Scatter::Absolute(self.beta.max(0.0).sqrt()),
            (true, false) => Scatter::Relative(self.alpha.sqrt()),
            (true, true) => Scatter::Mixed {
                fraction: self.alpha.sqrt(),
                floor: self.beta.sqrt(),
            },
        }
    }
}

/// Likelihood-ratio statistic a term of the law must exceed to be kept [-]:
/// twice χ²(1)'s 1e-3 point, since the residuals of overlapping local fits
/// are correlated and their pseudo-likelihood ratio is dispersed about
/// 2.5 times a χ²(1) (measured: 99th percentile 16.5 on 300 runs of pure
/// white noise on a 120-speed geometric grid).
pub const TERM_LR: f64 = 2.0 * 10.828;

/// Most iterations of the two-term fit [-].
const LAW_ITERATIONS: usize = 200;

/// The law of `samples` (module docs of [`super`]): the Gaussian
/// pseudo-likelihood's maximum over α, β ≥ 0 (Carroll & Ruppert 1988,
/// ch. 3: iteratively reweighted least squares of |e|²/2 on (along, floor)
/// with weights 1/v²), the fraction dropped when the likelihood ratio does
/// not need it ([`TERM_LR`]: a resonance the local fits follow only roughly
/// leaves residuals that grow with |X|, which α would take up). The floor
/// is never dropped by the test (only where the maximum puts it at zero):
/// a law without it makes the readings of small |X| nearly exact (the
/// session-23 failure, docs/trust-noise-law.md). `start` seeds the iteration;
/// without `fraction` the floor-only law is given. `None` when nothing is
/// finite.
pub(super) fn fit_law(samples: &[&Sample], start: Law, fraction: bool) -> Option<Law> {
    let n = samples.len() as f64;
    let floor_only = Law {
        alpha: 0.0,
        beta: samples.iter().map(|s| s.nsq / (2.0 * s.floor)).sum::<f64>() / n,
    };
    if !(floor_only.beta.is_finite()) {
        return None;
    }
    if !fraction {
        return Some(floor_only);
    }
    let fraction_only = Law {
        alpha: samples.iter().map(|s| s.nsq / (2.0 * s.along)).sum::<f64>() / n,
        beta: 0.0,
    };
    match two_terms(samples, start, floor_only, fraction_only) {
        Some(both) if floor_only.deviance(samples) - both.deviance(samples) >= TERM_LR => {
            Some(both)
        }
        _ => Some(floor_only),
    }
}

/// The two-term maximum of [`fit_law`] by IRLS, α, β ≥ 0 (a negative term
/// set to zero and the other refitted alone); `None` when it leaves the
/// finite numbers.
fn two_terms(samples: &[&Sample], start: Law, floor_only: Law, fraction_only: Law) -> Option<Law> {
    // `along` in units of its mean: α and β of one order.
    let a_ref = samples.iter().map(|s| s.along).sum::<f64>() / samples.len() as f64;
    if !(a_ref > 0.0 && a_ref.is_finite()) {
        return None;
    }
    let mut law = if start.alpha > 0.0 && start.beta > 0.0 {
        start
    } else {
        Law {
            alpha: 0.5 * fraction_only.alpha,
            beta: 0.5 * floor_only.beta,
        }
    };
    if !(law.alpha.is_finite() && law.beta.is_finite()) {
        return None;
    }
    // What every iteration reads of each sample, made once: along, floor,
    // q = along/a_ref and y = |e|²/2 (the least-squares target).
    let terms: Vec<[f64; 4]> = samples
        .iter()
        .map(|s| [s.along, s.floor, s.along / a_ref, 0.5 * s.nsq])
        .collect();
    for _ in 0..LAW_ITERATIONS {
        let (mut saa, mut sab, mut sbb, mut ta, mut tb) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for &[along, floor, q, y] in &terms {
            let v = law.variance_at(along, floor);
            let w = 1.0 / (v * v);
            saa += w * q * q;
            sab += w * q * floor;
            sbb += w * floor * floor;
            ta += w * q * y;
            tb += w * floor * y;
        }
        let det = saa * sbb - sab * sab;
        let floor_alone = (0.0, tb / sbb);
        let mut next = if det > 1e-12 * saa * sbb {
            ((ta * sbb - tb * sab) / det, (saa * tb - sab * ta) / det)
        } else {
            floor_alone
        };
        if next.0 < 0.0 {
            next = floor_alone;
        } else if next.1 < 0.0 {
            next = (ta / saa, 0.0);
        }
        if !(next.0.is_finite() && next.1.is_finite()) || next.0 + next.1 <= 0.0 {
            return None;
        }
        let next = Law {
            alpha: next.0 / a_ref,
            beta: next.1,
        };
        let settled = next.close_to(law);
        law = next;
        if settled {
            break;
        }
    }
    Some(law)
}
