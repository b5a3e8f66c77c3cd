//! The scatter between neighbouring speeds: local polynomial fits in speed,
//! their residuals, robust spreads, and the scatter law they give.

mod law;
mod windows;

use super::*;
pub use law::TERM_LR;
use law::{fit_law, Law};
use windows::{adequate, windows_of, Window};
pub use windows::{ADEQUACY_P, ADEQUACY_WINDOW};

/// Most rounds of (windows judged, law fitted) [-].
const MAX_ROUNDS: usize = 40;

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

/// The local polynomial fit (module docs) at one point of a series, as
/// weights: the smooth value there is Σ weights[r]·y[start + r] over its
/// window.
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

impl LocalFit {
    /// The residual's weight c_r [-] on window point r: the residual at
    /// point `j` is Σ c_r·y[start + r], c_r = δ(start + r = j) − weights[r].
    fn residual_weight(&self, j: usize, r: usize) -> f64 {
        f64::from(u8::from(self.start + r == j)) - self.weights[r]
    }
}

/// The powers of one speed's offset in a local fit (module docs).
type Terms = nalgebra::SVector<f64, { DEGREE + 1 }>;

/// The local polynomial fits of a series sampled at increasing `speeds`
/// [Hz], one per point (`None` where the fit is singular or the point
/// determines it): they depend on the speeds only, so one set serves every
/// channel. The degree is `DEGREE`, or one less for a run of `WINDOW` − 1
/// speeds (two residual degrees of freedom per fit at least). Empty with
/// fewer than `WINDOW` − 1 points.
pub fn local_fits(speeds: &[f64]) -> Vec<Option<LocalFit>> {
    let n = speeds.len();
    let w = WINDOW.min(n);
    if w + 1 < WINDOW {
        return Vec::new();
    }
    let terms = (DEGREE + 1).min(w - 2);
    (0..n)
        .map(|j| {
            let start = j.saturating_sub(w / 2).min(n - w);
            let window = &speeds[start..start + w];
            let f0 = speeds[j];
            let span = (window[w - 1] - window[0]).abs().max(f64::MIN_POSITIVE);
            // Powers 1, x, …, x^(terms−1) of each window point's offset, in
            // fixed-size vectors (no allocation per point: the local fits of
            // a 20 001-speed run are a hot path, docs/trust-noise-law.md "Session 27");
            // a term left out of a reduced fit is 0 here and 1 on XᵀX's
            // diagonal, a block of its own that leaves the fit's block as
            // it is.
            let mut powers = [Terms::zeros(); WINDOW];
            for (v, f) in powers.iter_mut().zip(window) {
                let x = (f - f0) / span;
                for t in 0..terms {
                    v[t] = x.powi(t as i32);
                }
            }
            let mut xtx = nalgebra::SMatrix::<f64, { DEGREE + 1 }, { DEGREE + 1 }>::zeros();
            for v in &powers[..w] {
                xtx += v * v.transpose();
            }
            for t in terms..=DEGREE {
                xtx[(t, t)] = 1.0;
            }
            // The smooth value at f0 is e₀ᵀ(XᵀX)⁻¹Xᵀy = Σ (x_r·h) y_r with
            // h = (XᵀX)⁻¹e₀, and its leverage is h₀.
            let h = xtx.cholesky().map(|c| c.solve(&Terms::x()))?;
            let leverage = h[0];
            if leverage.is_nan() || leverage >= 1.0 - 1e-9 {
                return None;
            }
            let mut weights = [0.0; WINDOW];
            for (wr, v) in weights.iter_mut().zip(&powers[..w]) {
                *wr = v.dot(&h);
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

/// Standardised residuals of a local polynomial fit (module docs) of a complex
/// series sampled at increasing speeds [Hz]: per point (residual, smooth
/// value), the residual divided by sqrt(1 − leverage) so that its real and
/// imaginary parts have the sd of that point's noise. Empty with fewer than
/// `WINDOW` − 1 points.
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

/// [`scatter_law`] of `values` with their series' [`local_fits`]
/// (module docs of [`super`]: windows the local fits cannot follow left
/// out, the law v = α·|X|² + β fitted to the rest).
pub(super) fn scatter_law_of(
    fits: &[Option<LocalFit>],
    values: &[Complex<f64>],
) -> Option<Scatter> {
    scatter_law_with(fits, values, &mut WindowCache::default()).0
}

/// The windows of one series' samples ([`windows_of`]) and the points those
/// samples are at: the windows depend on the local fits and on which points
/// have a sample only (a sample's `floor` is its fit's), so every channel of
/// a bearing whose samples are at the same points shares them.
#[derive(Default)]
pub(super) struct WindowCache {
    /// The points of the samples the windows were made for, and the windows.
    made: Option<(Vec<usize>, Vec<Window>)>,
}

/// [`scatter_law_of`] with the windows taken from `cache` when the samples
/// are at the points they were made for (the same `fits`), else made and
/// kept there; and how many of the series' samples its windows left out
/// (the law carried to them from the rest: not measured there).
pub(super) fn scatter_law_with(
    fits: &[Option<LocalFit>],
    values: &[Complex<f64>],
    cache: &mut WindowCache,
) -> (Option<Scatter>, usize) {
    let samples = samples_of(fits, values);
    if samples.len() < 2 {
        return (None, 0);
    }
    let points: Vec<usize> = samples.iter().map(|s| s.point).collect();
    let windows = match cache.made.take() {
        Some((p, w)) if p == points => (p, w),
        _ => {
            let w = windows_of(fits, &samples);
            (points, w)
        }
    };
    let windows = &cache.made.insert(windows).1;
    // Start: one sd at every speed, from the median of the standardised
    // samples. From there a resonance's model error (residuals that grow
    // with |X|) is left out before a fraction of |X| is ever fitted; a
    // start that admits it lets α take it up (branch `mixedlaw`, session
    // 25). Measured, a relative start chosen by likelihood on the points
    // both starts keep did worse on mixed noise (docs/trust-noise-law.md "Session 26").
    let mut u: Vec<f64> = samples
        .iter()
        .flat_map(|s| [s.e.re.abs(), s.e.im.abs()].map(|x| x / s.floor.sqrt()))
        .collect();
    let sd = robust_sd(&mut u);
    if !(sd > 0.0 && sd.is_finite()) {
        return (sd.is_finite().then_some(Scatter::Absolute(sd.max(0.0))), 0);
    }
    let start = Law {
        alpha: 0.0,
        beta: sd * sd,
    };
    let (law, kept) = settle(&samples, windows, start, LawTerms::Both);
    // A law with no floor that left out the low-|X| end of the series is
    // not a law of these data's noise (`disowns_low_end`): the law of a
    // floor alone instead.
    let left_out = |kept: &[bool]| kept.iter().filter(|k| !**k).count();
    if law.alpha > 0.0 && law.beta <= 0.0 && disowns_low_end(&samples, &kept) {
        let (law, kept) = settle(&samples, windows, start, LawTerms::FloorOnly);
        return (Some(law.scatter()), left_out(&kept));
    }
    (Some(law.scatter()), left_out(&kept))
}

/// Whether a law keeps its fraction term when the likelihood needs it
/// ([`fit_law`]) or is the floor alone.
#[derive(Clone, Copy, Debug, PartialEq)]
enum LawTerms {
    /// v = α·|X|² + β, the fraction kept by its test.
    Both,
    /// v = β.
    FloorOnly,
}

/// Whether at least [`ADEQUACY_WINDOW`] samples whose |X| is below that of
/// every sample `kept` were left out: the law was fitted only above the
/// series' low-|X| end and judged every window there inadequate.
///
/// Windows are left out where the local fits cannot follow the response
/// (a resonance: residuals that grow with |X|). Under a law with no floor,
/// v = α·|X|², white noise at the small |X| of a series' quiet end looks
/// like such a misfit (its residuals are many times α·|X|²), while a
/// resonance's misfit, which grows with |X|, looks like noise: the rounds
/// of [`settle`] can end there, with the low end left out and the law
/// extrapolated to it, where it makes the readings nearly exact. Measured
/// (docs/trust.md, Session 45 (before17)): bench_trust's three-bearing machine at
/// 0.3 % white noise, seed 2521, `outboard` rel_y: 35 of 79 samples kept,
/// √along 4.1e-7 to 7.2e-6 m (the resonance's peak kept, all 23 samples
/// below it left out), law 0.22 % of |X| with no floor; the same channel
/// at seeds 2522 and 2523 keeps √along from 2.4e-9 m and 2.8e-9 m and a
/// floor of 8.0e-9 and 9.5e-9 m (true sd 8.9e-9).
fn disowns_low_end(samples: &[Sample], kept: &[bool]) -> bool {
    // |X|² of a sample: its window's Σ c_r²·m_r² per unit Σ c_r².
    let x2 = |s: &Sample| s.along / s.floor;
    let lowest_kept = samples
        .iter()
        .zip(kept)
        .filter(|(_, k)| **k)
        .map(|(s, _)| x2(s))
        .fold(f64::INFINITY, f64::min);
    samples
        .iter()
        .zip(kept)
        .filter(|(s, k)| !**k && x2(s) < lowest_kept)
        .count()
        >= ADEQUACY_WINDOW
}

/// From `law`, rounds of (windows judged under the law, law fitted to the
/// points kept) until the points kept and the law settle: the law and the
/// points it keeps.
fn settle(
    samples: &[Sample],
    windows: &[Window],
    mut law: Law,
    terms: LawTerms,
) -> (Law, Vec<bool>) {
    let mut kept_before: Vec<bool> = Vec::new();
    // The previous round's fit: the start it read (`None`: it read none,
    // [`two_terms`] reads it only with both terms positive) and its law.
    let mut fitted_before: Option<(Option<Law>, Law)> = None;
    for _ in 0..MAX_ROUNDS {
        let kept = adequate(samples, windows, law);
        let chosen: Vec<&Sample> = samples
            .iter()
            .zip(&kept)
            .filter_map(|(s, k)| k.then_some(s))
            .collect();
        if chosen.len() < 2 {
            return (law, kept);
        }
        let start = (law.alpha > 0.0 && law.beta > 0.0).then_some(law);
        // The same points and the same start: the previous round's fit,
        // which [`fit_law`] would repeat exactly.
        let next = match fitted_before {
            Some((read, fitted)) if kept == kept_before && read == start => fitted,
            _ => match fit_law(&chosen, law, terms == LawTerms::Both) {
                Some(next) => next,
                None => return (law, kept),
            },
        };
        fitted_before = Some((start, next));
        let settled = kept == kept_before && next.close_to(law);
        law = next;
        kept_before = kept;
        if settled {
            break;
        }
    }
    (law, kept_before)
}

/// One point's local-fit residual (module docs of [`super`]) and what its
/// variance is made of under the law v = α·m² + β of every point of its
/// window: each real part's variance is α·`along` + β·`floor`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Sample {
    /// Index of the point in the series.
    point: usize,
    /// The residual y − smooth [m] (not standardised).
    e: Complex<f64>,
    /// |e|² [m²].
    nsq: f64,
    /// Σ c_r²·m_r² over the window [m²] (c_r: the residual's weight on
    /// point r, m_r its smooth magnitude).
    along: f64,
    /// Σ c_r² = 1 − leverage [-].
    floor: f64,
}

/// True when |z| = hypot(re, im) is positive, as `z.norm() > 0.0` says
/// (an infinite part makes it +∞, else a NaN part NaN), without the hypot.
pub(super) fn magnitude_positive(z: Complex<f64>) -> bool {
    z.re.is_infinite()
        || z.im.is_infinite()
        || (!z.re.is_nan() && !z.im.is_nan() && (z.re != 0.0 || z.im != 0.0))
}

/// The samples of a series (one per point with a local fit and a finite,
/// nonzero smooth value), in order of speed.
fn samples_of(fits: &[Option<LocalFit>], values: &[Complex<f64>]) -> Vec<Sample> {
    let smooth: Vec<Option<Complex<f64>>> = fits
        .iter()
        .map(|fit| {
            let fit = fit.as_ref()?;
            let window = &values[fit.start..fit.start + fit.len];
            Some(window.iter().zip(&fit.weights).map(|(z, w)| z * *w).sum())
        })
        .collect();
    // |X|² of each point: the smooth value's, the reading's where none.
    let m2: Vec<f64> = smooth
        .iter()
        .zip(values)
        .map(|(s, v)| s.unwrap_or(*v).norm_sqr())
        .collect();
    fits.iter()
        .zip(&smooth)
        .enumerate()
        .filter_map(|(j, (fit, s))| {
            let (fit, s) = (fit.as_ref()?, (*s)?);
            let along: f64 = (0..fit.len)
                .map(|r| fit.residual_weight(j, r).powi(2) * m2[fit.start + r])
                .sum();
            let e = values[j] - s;
            let ok = magnitude_positive(s)
                && along > 0.0
                && along.is_finite()
                && e.re.is_finite()
                && e.im.is_finite();
            ok.then_some(Sample {
                point: j,
                e,
                nsq: e.norm_sqr(),
                along,
                floor: 1.0 - fit.leverage,
            })
        })
        .collect()
}
