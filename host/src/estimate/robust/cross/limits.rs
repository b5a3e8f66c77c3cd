//! The χ² figures of the test across bearings ([`super::cross_bearing_flips`])
//! and its judgement of one hypothesis: the limits of Σ r/s (with the run's
//! end speeds, whose subspace is an extrapolation, on χ²([`EDGE_DOF`])), the
//! conditions on the negated reading, and the likelihood margin by which one
//! bearing is named when two bearings' negations pass.

use super::super::flips::{CONSISTENT_QUANTILE, FLIP_BLOCK, FLIP_RATIO, SCREEN_QUANTILE};
use super::super::OUTLIER_FAMILY_RATE;
use super::{signed, surrounded, Subspace, EDGE_DOF};
use num_complex::Complex;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// The χ² figures of the test across bearings for B bearings and n speeds
/// ([`super::cross_bearing_flips`]).
pub(in crate::estimate::robust) struct Limits {
    /// Degrees of freedom of a good reading's r/s, 2(C − D) [-].
    dof: f64,
    /// Median of χ²(dof) [-].
    pub(in crate::estimate::robust) null_median: f64,
    /// Its [`SCREEN_QUANTILE`] [-].
    pub(in crate::estimate::robust) screen: f64,
    /// Its [`CONSISTENT_QUANTILE`] [-].
    consistent: f64,
    /// Per block length L and number e of its speeds at the run's ends
    /// ([`surrounded`]) (indices), the χ²(dof·(L − e) + [`EDGE_DOF`]·e)
    /// quantile at [`OUTLIER_FAMILY_RATE`]/n [-]: the limit of the block's
    /// Σ r/s, each end speed's r/s over [`Limits::edge_scale`].
    edge_limit: Vec<Vec<f64>>,
    /// The median of χ²(dof) over that of χ²([`EDGE_DOF`]) [-]: at an end
    /// speed r/s over it is taken as χ²([`EDGE_DOF`]).
    edge_scale: f64,
    /// The least gain of −2 ln L of the best bearing's negation over the
    /// second best's for the best to be named when both pass,
    /// 2 ln(n/[`OUTLIER_FAMILY_RATE`]) [-].
    margin: f64,
}

impl Limits {
    /// The figures for `nb` bearings and `n` speeds; `None` when they
    /// leave no degree of freedom.
    pub(in crate::estimate::robust) fn new(nb: usize, n: usize) -> Option<Self> {
        let dof = (2 * (4 * nb).saturating_sub(2 * nb)) as f64;
        let chi2 = ChiSquared::new(dof).ok()?;
        let rate = OUTLIER_FAMILY_RATE / n.max(1) as f64;
        let quantile =
            |k: f64| ChiSquared::new(k).map_or(f64::INFINITY, |d| d.inverse_cdf(1.0 - rate));
        let null_median = chi2.inverse_cdf(0.5);
        Some(Limits {
            dof,
            null_median,
            screen: chi2.inverse_cdf(SCREEN_QUANTILE),
            consistent: chi2.inverse_cdf(CONSISTENT_QUANTILE),
            edge_limit: (0..=FLIP_BLOCK)
                .map(|l| {
                    let l = l.max(1);
                    (0..=l)
                        .map(|e| quantile(dof * (l - e) as f64 + EDGE_DOF * e as f64))
                        .collect()
                })
                .collect(),
            edge_scale: null_median / ChiSquared::new(EDGE_DOF).ok()?.inverse_cdf(0.5),
            margin: -2.0 * rate.ln(),
        })
    }

    /// The bearing (and its gain) [`super::cross_bearing_flips`] names among
    /// those whose negation passes every condition (`passing`: bearing,
    /// gain of −2 ln L): the one when one passes; the best when its gain
    /// beats every other's by [`Limits::margin`]; else none. The margin is
    /// the universal bound on a likelihood ratio: when bearing c is the
    /// one flipped, the odds of "b flipped" against it reach k with
    /// probability at most 1/k, k = n/[`OUTLIER_FAMILY_RATE`].
    pub(in crate::estimate::robust) fn named(
        &self,
        passing: &[(usize, f64)],
    ) -> Option<(usize, f64)> {
        let best = passing.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1))?;
        passing
            .iter()
            .filter(|(b, _)| *b != best.0)
            .all(|(_, g)| best.1 - g >= self.margin)
            .then_some(best)
    }

    /// Whether the weighted phasors `y` of one speed agree with the
    /// subspace `u` as they are and not with the bearings `which` negated:
    /// as they are, the studentised r/((1 + ℓ)·s′) (`scale_s` the scale s′
    /// of that speed) is within the χ²(2(C − D)) quantile
    /// [`CONSISTENT_QUANTILE`], and their −2 ln L ([`Limits::judge`]) is
    /// lower than negated: the mirror of the conditions that name a flip.
    pub(in crate::estimate::robust) fn agrees_unnegated(
        &self,
        u: &Subspace,
        y: &[Complex<f64>],
        which: &[usize],
        scale_s: f64,
    ) -> bool {
        let studentised = |(r, l): (f64, f64)| r / ((1.0 + l) * scale_s);
        let nll = |(r, l): (f64, f64)| studentised((r, l)) + self.dof * l.ln_1p();
        let (read, negated) = (u.residual(y), u.residual(&signed(y, which)));
        studentised(read) <= self.consistent && nll(read) < nll(negated)
    }

    /// The hypothesis "the bearings `which` are negated at the speeds
    /// `block`" against the subspace `u` of the window around the block,
    /// the weighted phasors `y` (per speed), the scales `scale` of r and
    /// `scale_s` of the studentised r (per speed): `Some(gain)` (the gain
    /// of −2 ln L) when it is named by [`super::cross_bearing_flips`]'s three
    /// conditions, else `None`.
    pub(in crate::estimate::robust) fn judge(
        &self,
        u: &Subspace,
        y: &[Vec<Complex<f64>>],
        block: std::ops::Range<usize>,
        which: &[usize],
        scale: &[f64],
        scale_s: &[f64],
    ) -> Option<f64> {
        // −2 ln L of a reading (r, ℓ) at speed j, up to a constant.
        let nll =
            |(r, l): (f64, f64), j: usize| r / ((1.0 + l) * scale_s[j]) + self.dof * l.ln_1p();
        // Σ r/s as read (against the limit; where the subspace is
        // extrapolated, [`surrounded`], over the edge scale), as read and
        // negated (for the halving).
        let (mut beyond, mut before, mut after, mut gain) = (0.0, 0.0, 0.0, 0.0);
        let mut edges = 0;
        let mut agrees = true;
        for j in block.clone() {
            let read = u.residual(&y[j]);
            let flipped = u.residual(&signed(&y[j], which));
            before += read.0 / scale[j];
            after += flipped.0 / scale[j];
            beyond += if surrounded(y.len(), j) {
                read.0 / scale[j]
            } else {
                // An extrapolated subspace: r/s taken as χ²(EDGE_DOF) at
                // the median of χ²(2(C − D)) ([`super::cross_bearing_flips`]).
                edges += 1;
                read.0 / (scale[j] * self.edge_scale)
            };
            let (l_read, l_flipped) = (nll(read, j), nll(flipped, j));
            agrees &= flipped.0 / ((1.0 + flipped.1) * scale_s[j]) <= self.consistent
                && l_flipped < l_read;
            gain += l_read - l_flipped;
        }
        let named = beyond > self.edge_limit[block.len()][edges]
            && agrees
            && after < FLIP_RATIO * before
            && gain.is_finite();
        named.then_some(gain)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_best_bearing_is_named_only_by_the_margin_and_the_ends_by_chi2_2() {
        // 79 speeds (the three-bearing machine's run): margin 2 ln(n/α).
        let limits = Limits::new(3, 79).expect("limits");
        let margin = 2.0 * (79.0 / OUTLIER_FAMILY_RATE).ln();
        assert!((limits.margin - margin).abs() < 1e-9, "{}", limits.margin);
        assert_eq!(limits.named(&[]), None);
        assert_eq!(limits.named(&[(2, 5.0)]), Some((2, 5.0)));
        // Session 37's ambiguous clean blocks: margins 3.3-11.9, none named;
        // a flip at the run's last speed: ahead by 74 or more.
        assert_eq!(limits.named(&[(0, 71.2), (1, 59.4), (2, 54.0)]), None);
        assert_eq!(limits.named(&[(0, 26.9), (1, 117.3)]), Some((1, 117.3)));
        assert_eq!(limits.named(&[(0, 100.0), (1, 100.0 - margin + 0.1)]), None);
        // One end speed alone: r/s over the edge scale against χ²(2)'s
        // quantile at α/n, which is −2 ln(α/n); a block of an interior and
        // an end speed against χ²(12 + 2).
        let one = limits.edge_limit[1][1];
        assert!((one - margin).abs() < 1e-6, "{one} against {margin}");
        let chi2_2_median = 2.0 * 2f64.ln();
        assert!((limits.edge_scale - limits.null_median / chi2_2_median).abs() < 1e-9);
        let mixed = ChiSquared::new(14.0)
            .expect("χ²")
            .inverse_cdf(1.0 - OUTLIER_FAMILY_RATE / 79.0);
        assert!((limits.edge_limit[2][1] - mixed).abs() < 1e-6);
    }
}
