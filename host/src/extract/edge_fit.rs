//! Keyphasor edge times smoothed over their neighbours, and the timing
//! jitter measured from them.
//!
//! An edge timed by linear interpolation between the two samples around the
//! threshold is exact only if the keyphasor's transition spans a sample.
//! A transition shorter than a sample (a square pulse; a notch with 2°
//! edges at 80 samples per revolution) interpolates to the same fraction
//! whatever the true time: a timing error uniform over ±0.5 sample
//! (sd 0.29 sample, 1.2° of shaft angle at 85 samples per revolution), the
//! same phase error on every channel of that revolution.
//!
//! The shaft angle of a heavy rotor is smooth over a few revolutions, so each
//! edge time is replaced by the time at which a local quadratic of the
//! revolution count in time, fitted through the edge and its
//! ±[`HALF_WINDOW`] neighbours (within one run of regular periods: a missing
//! or extra pulse starts a new run), reaches the edge's count. A constant
//! acceleration makes the count exactly quadratic in time, at any rate, so
//! a run-down's speed change is kept; the jitter's variance is cut to the
//! window's leverage h (0.11 for ±10 edges: the sd by 3). The jitter itself
//! is the residual of each edge against its fit, sd = sqrt(Σr²/Σ(1 − h)).

/// Edges each side of the fitted one.
pub const HALF_WINDOW: usize = 10;

/// Fewest edges in a run of regular periods for it to be smoothed.
pub const MIN_RUN: usize = 5;

/// Largest relative change of the period from one revolution to the next
/// inside one run (a missing pulse doubles it, an extra one halves it).
pub const RUN_BREAK: f64 = 0.2;

/// Jitter [samples] below which the edges are left as timed: a transition
/// spanning samples times its edges far better (the 8° notch edges of
/// scripts/ross_recording.py at 77 samples per revolution: 0.0013 sample),
/// and the extractor then sees the box's own edges.
pub const SMOOTH_ABOVE: f64 = 0.01;

/// The smoothed edges of a recording.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EdgeFit {
    /// Edge times, smoothed [samples, frame index of the sample at or after
    /// which the edge ends, minus 1, plus the fraction: the detector's time].
    pub times: Vec<f64>,
    /// The edge timing jitter's standard deviation before smoothing
    /// [samples] (0 with no run long enough to measure it).
    pub jitter_samples: f64,
    /// Leverage of a fit with a full window: the smoothed times' error
    /// variance is `jitter_samples`² times it.
    pub leverage: f64,
    /// Median edge period [samples] (0 with fewer than two edges).
    pub median_period: f64,
    /// Whether `times` are smoothed (the jitter above [`SMOOTH_ABOVE`]).
    pub smoothed: bool,
}

impl EdgeFit {
    /// The timing jitter in degrees of shaft angle at the median period.
    pub fn jitter_deg(&self) -> f64 {
        if self.median_period > 0.0 {
            360.0 * self.jitter_samples / self.median_period
        } else {
            0.0
        }
    }

    /// The sd of the smoothed edges' phase error [rad] at `period` samples
    /// per revolution.
    pub fn residual_phase_rad(&self, period: f64) -> f64 {
        if period > 0.0 && self.smoothed {
            std::f64::consts::TAU * self.jitter_samples * self.leverage.sqrt() / period
        } else {
            0.0
        }
    }
}

/// Quadratic least squares y = c0 + c1 u + c2 u² through (u, y); returns
/// the coefficients and the leverage of a point at u = 0.
fn fit_at_zero(points: impl Iterator<Item = (f64, f64)>) -> Option<([f64; 3], f64)> {
    // Normal equations in the basis 1, u, u².
    let mut s = [0.0f64; 5];
    let mut b = [0.0f64; 3];
    for (u, y) in points {
        let mut p = 1.0;
        for (k, sk) in s.iter_mut().enumerate() {
            *sk += p;
            if k < 3 {
                b[k] += p * y;
            }
            p *= u;
        }
    }
    let m = [[s[0], s[1], s[2]], [s[1], s[2], s[3]], [s[2], s[3], s[4]]];
    let inv = invert3(&m)?;
    // The leverage of a point at u = 0 is inv[0][0].
    let c = inv.map(|row| row[0] * b[0] + row[1] * b[1] + row[2] * b[2]);
    Some((c, inv[0][0]))
}

fn invert3(m: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if det.abs() < 1e-12 {
        return None;
    }
    let c =
        |r0: usize, r1: usize, c0: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    let adj = [
        [c(1, 2, 1, 2), -c(0, 2, 1, 2), c(0, 1, 1, 2)],
        [-c(1, 2, 0, 2), c(0, 2, 0, 2), -c(0, 1, 0, 2)],
        [c(1, 2, 0, 1), -c(0, 2, 0, 1), c(0, 1, 0, 1)],
    ];
    Some(adj.map(|row| row.map(|v| v / det)))
}

/// Smooths `times` (the detector's edge times [samples], increasing).
pub fn smooth(times: &[f64]) -> EdgeFit {
    let n = times.len();
    let mut out = EdgeFit {
        times: times.to_vec(),
        ..EdgeFit::default()
    };
    if n < 2 {
        return out;
    }
    let mut periods: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    // Runs of regular periods: edges [start, end).
    let mut runs = Vec::new();
    let mut start = 0;
    for i in 1..periods.len() {
        if (periods[i] / periods[i - 1] - 1.0).abs() > RUN_BREAK {
            // Edge i + 1 closes an irregular period: edges ..=i are one run.
            runs.push((start, i + 1));
            start = i + 1;
        }
    }
    runs.push((start, n));
    let (mut r2, mut dof) = (0.0f64, 0.0f64);
    let mut full_leverage = None;
    for (a, b) in runs {
        if b - a < MIN_RUN {
            continue;
        }
        let len = b - a;
        let w = (2 * HALF_WINDOW + 1).min(len);
        for i in a..b {
            let lo = (i.saturating_sub(w / 2)).max(a).min(b - w);
            // The revolution count as a quadratic in time (exact for a
            // constant acceleration, whatever its rate), time in units of
            // the window's mean period.
            let period = (times[lo + w - 1] - times[lo]) / (w - 1) as f64;
            let points =
                (lo..lo + w).map(|j| ((times[j] - times[i]) / period, j as f64 - i as f64));
            let Some((c, h)) = fit_at_zero(points) else {
                continue;
            };
            // The fitted count is c0 at edge i's time: the smoothed edge is
            // where it reaches 0 (a Newton step from the linear solution).
            if c[1] <= 0.0 {
                continue;
            }
            let mut d = -c[0] / c[1];
            d -= (c[0] + c[1] * d + c[2] * d * d) / (c[1] + 2.0 * c[2] * d);
            let shift = d * period;
            out.times[i] = times[i] + shift;
            // The residual of edge i against its own fit: E r² = σ²(1 − h).
            r2 += shift * shift;
            dof += 1.0 - h;
            if w == 2 * HALF_WINDOW + 1 && lo + HALF_WINDOW == i {
                full_leverage.get_or_insert(h);
            }
        }
    }
    if dof > 0.0 {
        out.jitter_samples = (r2 / dof).sqrt();
    }
    out.leverage = full_leverage.unwrap_or(1.0);
    out.smoothed = out.jitter_samples > SMOOTH_ABOVE;
    if !out.smoothed {
        out.times = times.to_vec();
    }
    periods.sort_by(f64::total_cmp);
    out.median_period = periods[periods.len() / 2];
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Edges of a run-down from `f0` at `rate` Hz/s sampled at `fs`, each
    /// timed by the detector on a square pulse: the crossing at the half of
    /// the sample interval the true edge falls in.
    fn square_edges(fs: f64, f0: f64, rate: f64, count: usize) -> (Vec<f64>, Vec<f64>) {
        // θ(t) = f0 t − rate t²/2 revolutions; edge k at θ = k + 0.37.
        let (mut truth, mut timed) = (Vec::new(), Vec::new());
        for k in 0..count {
            let th = k as f64 + 0.37;
            let t = if rate == 0.0 {
                th / f0
            } else {
                (f0 - (f0 * f0 - 2.0 * rate * th).sqrt()) / rate
            };
            let s = t * fs;
            truth.push(s);
            // The detector's time: (frame − 1) + 0.5 for the sample after s.
            timed.push(s.floor() + 0.5);
        }
        (truth, timed)
    }

    #[test]
    fn square_pulse_jitter_is_measured_and_cut_and_a_run_down_kept() {
        let fs = 4000.0;
        for rate in [0.0, 1.0, 4.0, 10.0] {
            let (truth, timed) = square_edges(
                fs,
                50.3,
                rate,
                // Down to about 20 Hz.
                if rate > 0.0 {
                    ((50.3f64.powi(2) - 400.0) / (2.0 * rate)) as usize
                } else {
                    200
                },
            );
            let fit = smooth(&timed);
            // Uniform over one sample: sd 1/√12 = 0.289 sample.
            assert!(
                (fit.jitter_samples - 0.289).abs() < 0.03,
                "{rate}: {}",
                fit.jitter_samples
            );
            let rms = |t: &[f64]| {
                (t.iter()
                    .zip(&truth)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    / t.len() as f64)
                    .sqrt()
            };
            assert!(fit.smoothed);
            let (raw, smoothed) = (rms(&timed), rms(&fit.times));
            assert!(smoothed < 0.5 * raw, "{rate}: {raw} -> {smoothed}");
            let predicted = fit.jitter_samples * fit.leverage.sqrt();
            assert!(
                smoothed < 1.5 * predicted && smoothed > 0.6 * predicted,
                "{rate}: {smoothed} vs {predicted}"
            );
        }
    }

    #[test]
    fn exact_edges_stay_and_a_missing_pulse_breaks_the_run() {
        let mut times: Vec<f64> = (0..60)
            .map(|k| 10.0 + 80.0 * k as f64 + 1e-3 * (k * k) as f64)
            .collect();
        times.remove(30);
        let fit = smooth(&times);
        for (a, b) in fit.times.iter().zip(&times) {
            assert!((a - b).abs() < 1e-3, "{a} {b}");
        }
        assert!(fit.jitter_samples < 1e-3 && !fit.smoothed);
        assert_eq!(fit.times, times);
        assert!(
            (fit.median_period - 80.06).abs() < 0.1,
            "{}",
            fit.median_period
        );
    }
}
