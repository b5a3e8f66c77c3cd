//! The scatter between neighbouring speeds: local polynomial fits in speed,
//! their residuals, robust spreads, and the scatter law they give.

use super::*;

/// The median of `v` [units of `v`] by selection (reorders `v`; NaN when
/// empty; order by `f64::total_cmp`): the one median of the estimators.
pub fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    // Selection, not a sort: O(n) on the long series of fine sweeps.
    let n = v.len();
    let (below, &mut upper, _) = v.select_nth_unstable_by(n / 2, f64::total_cmp);
    if n % 2 == 1 {
        upper
    } else {
        let lower = below.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        0.5 * (lower + upper)
    }
}

/// Rejection threshold of [`robust_sd`] [sd].
pub(super) const REJECT: f64 = 3.5;
/// sd of a standard normal truncated to ±[`REJECT`].
pub(super) const TRUNCATED_SD: f64 = 0.996_940;

/// The sd of zero-mean normal samples given as |x|, some of which are
/// contaminated by large values (points a local fit cannot follow): start
/// from the median, then drop samples beyond 3.5 sd and take the RMS of the
/// rest (corrected for the truncation), until the set settles.
pub(super) fn robust_sd(abs: &mut [f64]) -> f64 {
    let mut sd = median(abs) / MEDIAN_ABS_NORMAL;
    for _ in 0..10 {
        let (mut kept, mut sum_sq) = (0usize, 0.0);
        for &x in abs.iter().filter(|&&x| x <= REJECT * sd) {
            kept += 1;
            sum_sq += x * x;
        }
        if kept < 4 {
            break;
        }
        let next = (sum_sq / kept as f64).sqrt() / TRUNCATED_SD;
        if (next - sd).abs() <= 1e-9 * sd {
            sd = next;
            break;
        }
        sd = next;
    }
    sd
}

/// Interquartile range of log|u|: how homogeneous standardised samples are,
/// robust to the few points a local fit cannot follow.
pub(super) fn log_spread(u: &[f64]) -> f64 {
    let mut logs: Vec<f64> = u.iter().filter(|x| **x > 0.0).map(|x| x.ln()).collect();
    if logs.len() < 4 {
        return f64::INFINITY;
    }
    let mut q = |f: f64| {
        let k = ((logs.len() - 1) as f64 * f).round() as usize;
        *logs.select_nth_unstable_by(k, f64::total_cmp).1
    };
    q(0.75) - q(0.25)
}

/// The local cubic fit (module docs) at one point of a series, as weights:
/// the smooth value there is Σ weights[r]·y[start + r] over its window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalFit {
    /// Index of the window's first point.
    pub start: usize,
    /// Points in the window.
    pub len: usize,
    /// Weight of each window point in the smooth value [-].
    pub weights: [f64; WINDOW],
    /// The point's leverage h₀ in its own fit [-].
    pub leverage: f64,
}

/// The local cubic fits of a series sampled at increasing `speeds` [Hz], one
/// per point (`None` where the fit is singular or the point determines it):
/// they depend on the speeds only, so one set serves every channel. Empty
/// with fewer than `DEGREE + 3` points.
pub fn local_fits(speeds: &[f64]) -> Vec<Option<LocalFit>> {
    let n = speeds.len();
    let w = WINDOW.min(n);
    if w < DEGREE + 3 {
        return Vec::new();
    }
    (0..n)
        .map(|j| {
            let start = j.saturating_sub(w / 2).min(n - w);
            let window = &speeds[start..start + w];
            let f0 = speeds[j];
            let span = (window[w - 1] - window[0]).abs().max(f64::MIN_POSITIVE);
            // Powers (1, x, x², x³) of each window point's offset, and XᵀX.
            let powers = |f: f64| {
                let x = (f - f0) / span;
                nalgebra::Vector4::new(1.0, x, x * x, x * x * x)
            };
            let mut xtx = nalgebra::Matrix4::<f64>::zeros();
            for f in window {
                let v = powers(*f);
                xtx += v * v.transpose();
            }
            // The smooth value at f0 is e₀ᵀ(XᵀX)⁻¹Xᵀy = Σ (x_r·h) y_r with
            // h = (XᵀX)⁻¹e₀, and its leverage is h₀.
            let h = xtx.cholesky().map(|c| c.solve(&nalgebra::Vector4::x()))?;
            let leverage = h[0];
            if leverage.is_nan() || leverage >= 1.0 - 1e-9 {
                return None;
            }
            let mut weights = [0.0; WINDOW];
            for (wr, f) in weights.iter_mut().zip(window) {
                *wr = powers(*f).dot(&h);
            }
            Some(LocalFit {
                start,
                len: w,
                weights,
                leverage,
            })
        })
        .collect()
}

/// Standardised residuals of a local cubic fit (module docs) of a complex
/// series sampled at increasing speeds [Hz]: per point (residual, smooth
/// value), the residual divided by sqrt(1 − leverage) so that its real and
/// imaginary parts have the sd of that point's noise. Empty with fewer than
/// `DEGREE + 3` points.
pub fn local_residuals(series: &[(f64, Complex<f64>)]) -> Vec<(Complex<f64>, Complex<f64>)> {
    let speeds: Vec<f64> = series.iter().map(|s| s.0).collect();
    let values: Vec<Complex<f64>> = series.iter().map(|s| s.1).collect();
    residuals_of(&local_fits(&speeds), &values).collect()
}

/// [`local_residuals`] of `values` with their series' [`local_fits`].
pub(super) fn residuals_of<'a>(
    fits: &'a [Option<LocalFit>],
    values: &'a [Complex<f64>],
) -> impl Iterator<Item = (Complex<f64>, Complex<f64>)> + 'a {
    fits.iter().enumerate().filter_map(move |(j, fit)| {
        let fit = fit.as_ref()?;
        let window = &values[fit.start..fit.start + fit.len];
        let smooth: Complex<f64> = window.iter().zip(&fit.weights).map(|(z, wr)| z * *wr).sum();
        Some(((values[j] - smooth) / (1.0 - fit.leverage).sqrt(), smooth))
    })
}

/// The robust scatter law (module docs) of a complex series at increasing
/// speeds [Hz]; `None` with too few points or no signal.
pub fn scatter_law(series: &[(f64, Complex<f64>)]) -> Option<Scatter> {
    let speeds: Vec<f64> = series.iter().map(|s| s.0).collect();
    let values: Vec<Complex<f64>> = series.iter().map(|s| s.1).collect();
    scatter_law_of(&local_fits(&speeds), &values)
}

/// [`scatter_law`] of `values` with their series' [`local_fits`].
pub(super) fn scatter_law_of(
    fits: &[Option<LocalFit>],
    values: &[Complex<f64>],
) -> Option<Scatter> {
    // (|component of the standardised residual|, local magnitude)
    let samples: Vec<(f64, f64)> = residuals_of(fits, values)
        .filter_map(|(r, s)| {
            let m = s.norm();
            (m > 0.0 && m.is_finite()).then_some([(r.re.abs(), m), (r.im.abs(), m)])
        })
        .flatten()
        .collect();
    if samples.len() < 4 {
        return None;
    }
    let mut abs: Vec<f64> = samples.iter().map(|s| s.0).collect();
    let mut rel: Vec<f64> = samples.iter().map(|s| s.0 / s.1).collect();
    let sigma = robust_sd(&mut abs);
    let fraction = robust_sd(&mut rel);
    let u_abs: Vec<f64> = samples
        .iter()
        .map(|s| s.0 / sigma.max(f64::MIN_POSITIVE))
        .collect();
    let u_rel: Vec<f64> = samples
        .iter()
        .map(|s| s.0 / (fraction * s.1).max(f64::MIN_POSITIVE))
        .collect();
    if log_spread(&u_abs) <= log_spread(&u_rel) {
        Some(Scatter::Absolute(sigma))
    } else {
        Some(Scatter::Relative(fraction))
    }
}
