//! The adequacy windows of the scatter law ([`super`]): runs of
//! [`ADEQUACY_WINDOW`] consecutive local-fit residuals whose sum under the
//! law is judged against its scaled χ² limit, so that points the local fits
//! cannot follow (a resonance) are left out of the law.

use super::*;

/// Consecutive samples a window holds (module docs of [`super`]) [-].
pub const ADEQUACY_WINDOW: usize = 6;

/// p-value below which a window's residuals are judged too large for the
/// current law (the local fits do not follow the response there) [-].
pub const ADEQUACY_P: f64 = 1e-4;

/// Standard normal quantile of 1 − [`ADEQUACY_P`] [-].
const ADEQUACY_Z: f64 = 3.719_016;

/// A window of consecutive samples and the largest sum of its samples'
/// |e|²/v the law allows.
pub(super) struct Window {
    /// First sample.
    first: usize,
    /// Samples held.
    len: usize,
    /// Critical value of Σ |e|²/v over the window [-].
    limit: f64,
}

/// The windows of the samples ([`ADEQUACY_WINDOW`] consecutive ones, one
/// per start) and the limit of each: under the law, Σ|e|²/v of a window is
/// a sum of 2K squares of unit variance (K samples, re and im) that the
/// overlap of neighbouring local fits correlates (corr = Σ c_r·c'_r /
/// sqrt(floor·floor'), the law taken constant over a window). Its mean 2K
/// and variance 4·Σ corr² give a scaled χ² (Satterthwaite), whose upper
/// [`ADEQUACY_P`] point is the limit (Wilson–Hilferty).
pub(super) fn windows_of(fits: &[Option<LocalFit>], samples: &[Sample]) -> Vec<Window> {
    let n = samples.len();
    let k = ADEQUACY_WINDOW.min(n);
    // corr² of each sample with the next ADEQUACY_WINDOW − 1 samples.
    let corr2: Vec<[f64; ADEQUACY_WINDOW]> = (0..n)
        .map(|a| {
            let mut out = [0.0; ADEQUACY_WINDOW];
            let sa = &samples[a];
            let Some(fa) = fits[sa.point].as_ref() else {
                return out;
            };
            for (d, slot) in out.iter_mut().enumerate().skip(1) {
                let Some(sb) = samples.get(a + d) else {
                    break;
                };
                let Some(fb) = fits[sb.point].as_ref() else {
                    continue;
                };
                let lo = fa.start.max(fb.start);
                let hi = (fa.start + fa.len).min(fb.start + fb.len);
                let cov: f64 = (lo..hi)
                    .map(|i| {
                        fa.residual_weight(sa.point, i - fa.start)
                            * fb.residual_weight(sb.point, i - fb.start)
                    })
                    .sum();
                *slot = cov * cov / (sa.floor * sb.floor);
            }
            out
        })
        .collect();
    (0..=n - k)
        .map(|first| {
            // Σ corr² over the pairs within the window.
            let pairs: f64 = corr2[first..first + k]
                .iter()
                .enumerate()
                .map(|(i, row)| row[1..k - i].iter().sum::<f64>())
                .sum();
            let mean = 2.0 * k as f64;
            let var = 4.0 * (k as f64 + 2.0 * pairs);
            let g = var / (2.0 * mean);
            let h = 2.0 * mean * mean / var;
            let c = 2.0 / (9.0 * h);
            let limit = g * h * (1.0 - c + ADEQUACY_Z * c.sqrt()).powi(3);
            Window {
                first,
                len: k,
                limit,
            }
        })
        .collect()
}

/// Per sample, whether every window that holds it is within its limit
/// under `law` (a point of a window the local fits cannot follow is left
/// out, and so is every other point of that window).
pub(super) fn adequate(samples: &[Sample], windows: &[Window], law: Law) -> Vec<bool> {
    let mut prefix = Vec::with_capacity(samples.len() + 1);
    prefix.push(0.0);
    let mut sum = 0.0;
    for s in samples {
        sum += s.nsq / law.variance(s);
        prefix.push(sum);
    }
    // +1 where a rejected window starts, −1 past its end.
    let mut marks = vec![0i64; samples.len() + 1];
    for w in windows {
        if prefix[w.first + w.len] - prefix[w.first] > w.limit {
            marks[w.first] += 1;
            marks[w.first + w.len] -= 1;
        }
    }
    let mut open = 0;
    marks[..samples.len()]
        .iter()
        .map(|m| {
            open += m;
            open == 0
        })
        .collect()
}
