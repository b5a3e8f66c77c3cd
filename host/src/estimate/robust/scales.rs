//! Robust scales for the outlier test: the median of a speed's
//! neighbours, never below the run's own, so a noise level that varies
//! slowly with speed sets the scale where it is and a few bad speeds do
//! not.

/// The median of the finite entries of `v` (NaN when none).
pub(super) fn median(v: &[f64]) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    crate::estimate::noise::median(&mut s)
}

/// Speeds on each side of a speed whose median sets its local scale in the
/// outlier test.
pub const OUTLIER_WINDOW: usize = 7;

/// Per entry of `v` (one per speed, in speed order; non-finite entries
/// ignored), max(median of all, [`window_medians`]) divided by
/// `null_median`: a robust scale that follows a level varying slowly with
/// speed and never falls below the run's own [-].
pub fn local_scales(v: &[f64], null_median: f64, half_window: usize) -> Vec<f64> {
    let global = median(v);
    window_medians(v, half_window)
        .into_iter()
        .map(|m| m.max(global) / null_median)
        .collect()
}

/// Per entry of `v` (one per speed, in speed order; non-finite entries
/// ignored), the median of the entries within `half_window` speeds on each
/// side [units of `v`].
pub fn window_medians(v: &[f64], half_window: usize) -> Vec<f64> {
    // The window's finite entries kept sorted as it slides (one insertion
    // and one removal per speed instead of a selection over the window):
    // the same order statistics as [`median`], so the same figures.
    let n = v.len();
    let mut sorted: Vec<f64> = Vec::with_capacity(2 * half_window + 1);
    let (mut lo, mut hi) = (0, 0);
    (0..n)
        .map(|i| {
            let (start, end) = (i.saturating_sub(half_window), (i + half_window + 1).min(n));
            for &x in &v[hi..end] {
                if x.is_finite() {
                    let at = sorted.partition_point(|y| y.total_cmp(&x).is_lt());
                    sorted.insert(at, x);
                }
            }
            for &x in &v[lo..start] {
                if x.is_finite() {
                    let at = sorted.partition_point(|y| y.total_cmp(&x).is_lt());
                    sorted.remove(at);
                }
            }
            (lo, hi) = (start, end.max(hi));
            sorted_median(&sorted)
        })
        .collect()
}

/// The median of `sorted` (ascending in [`f64::total_cmp`], finite; NaN
/// when empty): the middle entry, or the mean of the two middle ones, as
/// [`median`] gives for the same entries in any order.
fn sorted_median(sorted: &[f64]) -> f64 {
    let k = sorted.len();
    match k {
        0 => f64::NAN,
        _ if k % 2 == 1 => sorted[k / 2],
        _ => 0.5 * (sorted[k / 2 - 1] + sorted[k / 2]),
    }
}
