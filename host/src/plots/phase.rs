//! Phase conventions of the plots: peak-to-peak amplitude and phase lag of a
//! phasor, the lag of a response behind its force, wrapping and unwrapping.

use num_complex::Complex;

/// Peak-to-peak amplitude [unit of Q] and phase lag [deg, 0-360] of a phasor.
pub fn peak_to_peak_and_lag(q: Complex<f64>) -> (f64, f64) {
    plinth_shared::phasor::peak_to_peak_and_lag_deg(q)
}

/// Phase lag of `response` behind `force` [deg], wrapped to [−180, 180).
///
/// For a pedestal (−Ω²m + iΩc + k)·X = F this is atan2(Ωc, k − Ω²m): 0 below
/// the pedestal's resonance, 180 above, 90 at it (the paper's Figs. 5 and 9).
pub fn phase_lag_deg(response: Complex<f64>, force: Complex<f64>) -> f64 {
    wrap_deg_pm180((force.arg() - response.arg()).to_degrees())
}

/// Wraps an angle [deg] to [−180, 180).
pub fn wrap_deg_pm180(deg: f64) -> f64 {
    (deg + 180.0).rem_euclid(360.0) - 180.0
}

/// Makes a sequence of angles [deg] continuous: each value is moved by a
/// multiple of 360 to lie within 180 of its predecessor.
pub fn unwrap_deg(angles: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(angles.len());
    let mut prev: Option<f64> = None;
    for &a in angles {
        let v = match prev {
            None => a,
            Some(p) => a - 360.0 * ((a - p) / 360.0).round(),
        };
        out.push(v);
        prev = Some(v);
    }
    out
}

/// Splits a curve where consecutive wrapped angles differ by more than 180°.
pub(super) fn split_at_wraps(values: Vec<(f64, f64)>, wrapped: bool) -> Vec<Vec<(f64, f64)>> {
    if !wrapped {
        return vec![values];
    }
    let mut segments: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    for v in values {
        if let Some(last) = segments.last().and_then(|s| s.last()) {
            if (v.1 - last.1).abs() > 180.0 {
                segments.push(Vec::new());
            }
        }
        if let Some(seg) = segments.last_mut() {
            seg.push(v);
        }
    }
    segments
}
