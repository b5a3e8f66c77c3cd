//! The unit list (the common unit factors of vibration transducers and the
//! window within which a factor counts as one of them) and the search of a
//! factor over log10 s: a grid, then a golden-section refinement.

use super::evidence;

/// Common unit factors of vibration transducers [-] and the mistakes they
/// stand for (each also read as its inverse).
pub(crate) const COMMON: [(f64, &str); 7] = [
    (25.4, "mil against µm"),
    (1000.0 / 25.4, "mil against mm"),
    (1000.0, "mm against µm"),
    (1.0e6, "m against µm"),
    (2.0, "0-peak against peak-to-peak"),
    (std::f64::consts::SQRT_2, "rms against peak"),
    (2.0 * std::f64::consts::SQRT_2, "rms against peak-to-peak"),
];

/// The search range of s: 10^±LOG_RANGE [-] (beyond m against µm).
pub(crate) const LOG_RANGE: f64 = 6.5;

/// The search range of one bearing's s: 10^±LOG_RANGE_ONE [-] (beyond mm
/// against µm; m against µm on one bearing alone puts its |ped|/|rel|
/// beyond what machines give, and the reader names it:
/// docs/identify.md "Physical plausibility").
pub(crate) const LOG_RANGE_ONE: f64 = 3.5;

/// Grid step of log10 s before the golden-section refinement [-]: 0.93 %
/// in s. The open-loop re-simulation makes the gap's valley around the
/// right s narrow where a lightly damped resonance lies in the run
/// (unseen-train: a pedestal scale 5 % off gives a gap of about 1, as wrong
/// as no model; docs/robustness-hostile.md ("Session 39")): a step of 0.1 (26 %) missed
/// √2 there. About 3 250 re-simulations per kind, 0.6 ms each on that
/// machine.
const LOG_STEP: f64 = 0.004;

/// The factor 10^l, |l| ≤ `range`, that minimises the gap `g(l)` [-], with
/// that gap: a grid of l in steps of [`LOG_STEP`], then a golden-section
/// search within a step either side of the grid's best. `None` when the
/// unscaled model (l = 0) cannot be simulated.
pub(crate) fn minimise(g: impl Fn(f64) -> Option<f64>, range: f64) -> Option<(f64, f64)> {
    let n = (2.0 * range / LOG_STEP).round() as i32;
    let (mut best_l, mut best_g) = (0.0, g(0.0)?);
    for i in 0..=n {
        let l = -range + LOG_STEP * f64::from(i);
        if let Some(v) = g(l) {
            if v < best_g {
                (best_l, best_g) = (l, v);
            }
        }
    }
    Some(refine(&g, best_l, best_g, LOG_STEP))
}

/// The factor 10^l and its gap after a golden-section search of `g(l)`
/// within `half` either side of `best_l` (whose gap is `best_g`): the
/// better of the two.
pub(crate) fn refine(
    g: &impl Fn(f64) -> Option<f64>,
    best_l: f64,
    best_g: f64,
    half: f64,
) -> (f64, f64) {
    let (mut a, mut b) = (best_l - half, best_l + half);
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..30 {
        let (c, d) = (b - phi * (b - a), a + phi * (b - a));
        let (gc, gd) = (g(c).unwrap_or(f64::INFINITY), g(d).unwrap_or(f64::INFINITY));
        if gc < gd {
            b = d;
        } else {
            a = c;
        }
    }
    let l = 0.5 * (a + b);
    match g(l) {
        Some(v) if v < best_g => (10f64.powf(l), v),
        _ => (10f64.powf(best_l), best_g),
    }
}

/// The common unit factor nearest `s` when within [`evidence::TOLERANCE`]
/// (10 %) of it, either way: that factor as `s` reads it (f, or 1/f when
/// `s` < 1) [-], and the mistake it stands for. The one definition of the
/// unit list's window ([`nearest_common`], [`super::channel::window`]).
pub fn nearest_listed(s: f64) -> Option<(f64, &'static str)> {
    let (f, what) = COMMON
        .iter()
        .min_by(|a, b| {
            let da = (s.ln().abs() - a.0.ln()).abs();
            let db = (s.ln().abs() - b.0.ln()).abs();
            da.total_cmp(&db)
        })
        .copied()?;
    ((s.ln().abs() - f.ln()).abs() < evidence::TOLERANCE.ln())
        .then_some((if s >= 1.0 { f } else { 1.0 / f }, what))
}

/// The common unit factor within [`evidence::TOLERANCE`] (10 %) of `s` (or
/// of 1/s), named.
pub fn nearest_common(s: f64) -> Option<String> {
    let (f, what) = nearest_listed(s)?;
    let g = if s >= 1.0 { f } else { 1.0 / f };
    let shown = if g == std::f64::consts::SQRT_2 {
        "√2".to_string()
    } else if g == 2.0 * std::f64::consts::SQRT_2 {
        "2√2".to_string()
    } else {
        format!("{g}")
    };
    Some(if s >= 1.0 {
        format!("×{shown} ({what})")
    } else {
        format!("×1/{shown} ({what})")
    })
}

#[cfg(test)]
mod tests {
    use super::nearest_common;

    #[test]
    fn the_nearest_common_factor_is_named_within_ten_percent() {
        assert_eq!(
            nearest_common(25.9).as_deref(),
            Some("×25.4 (mil against µm)")
        );
        assert_eq!(
            nearest_common(1.0 / 25.0).as_deref(),
            Some("×1/25.4 (mil against µm)")
        );
        assert_eq!(
            nearest_common(0.70).as_deref(),
            Some("×1/√2 (rms against peak)")
        );
        assert_eq!(
            nearest_common(1980.0).as_deref(),
            None,
            "2 × 1000 is no common factor"
        );
        assert_eq!(nearest_common(1.7), None);
    }
}
