//! The averaging window's curvature: an output of R revolutions is the mean
//! of R phasors at consecutive revolutions, not the phasor at its middle.
//!
//! The extractor's run-down correction makes each revolution's phasor the
//! response in the middle of that revolution; the output is their mean over
//! R revolutions. Where the response Q(n) curves along the revolution
//! number n (a lightly damped resonance passed in a run-down), that mean is
//! Q(n̄) + Q''·(R² − 1)/24 + …: the variance of R equally spaced
//! positions, (R² − 1)/12, times Q''/2. It is a bias, not noise: measured
//! on ROSS-made run-downs of unseen-five (`scripts/ross_recording.py`, 4
//! revolutions per phasor, docs/field-data.md ("Session 39")) it made the
//! phasor at a pedestal resonance 6 % off at 1 Hz/s while its noise column
//! said 0.23 %: mean |error|²/sd² up to 3.9 per channel at 1 Hz/s and 21 at
//! 2 Hz/s (1.0-1.15 with one revolution per phasor).
//!
//! Consecutive outputs with no revolution between them are R revolutions
//! apart, so their second difference Δ² = Q_{k+1} − 2Q_k + Q_{k−1} is
//! Q''·R² (exactly for a quadratic, whose window means are a quadratic of
//! the same curvature), and [`mid_window`] subtracts c·Δ² with
//! c = (R² − 1)/(24R²). Its noise is (1 + 2c)·n_k − c·(n_{k−1} + n_{k+1}):
//! the variance gain (1 + 2c)² + 2c² (1.165 for R = 4) with independent
//! neighbours. Where the window is as wide as the peak (2 Hz/s through a
//! 0.2 Hz wide resonance at 18 Hz: 0.44 Hz per output) the next terms are
//! not small; the size of the correction, |c·Δ²|, stands for them in the
//! noise: sd² = gain·sd² + |c·Δ²|² (for noise alone |c·Δ²|² is about
//! 6c²·sd², 1 % of it at R = 4). On the same runs the mean |error|²/sd²
//! is then 0.94-1.04, no channel above 1.14.

use super::phasors::Output;

/// How far from R revolutions [revolutions] the time between consecutive
/// outputs may be for them to count as neighbours (a keyphasor fault drops
/// at least three revolutions: re-acquiring takes them).
const CONTIGUOUS_REVOLUTIONS: f64 = 0.5;

/// The curvature coefficient c = (R² − 1)/(24R²) [-] of R revolutions per
/// output (0 for one revolution: nothing is averaged).
pub fn curvature_coefficient(revolutions: u16) -> f64 {
    let r = f64::from(revolutions);
    (r * r - 1.0) / (24.0 * r * r)
}

/// Whether outputs `a` and `b` (b after a) are R revolutions apart: the
/// time between their closing edges [s] times b's speed [Hz].
fn contiguous(a: &Output, b: &Output, revolutions: u16) -> bool {
    let turns = (b.time_s - a.time_s) * b.speed_hz;
    (turns - f64::from(revolutions)).abs() <= CONTIGUOUS_REVOLUTIONS
}

/// The outputs with each one that has a contiguous neighbour on both sides
/// moved from its window's mean to the response in the window's middle
/// (module doc), its noise sd [m] widened by the correction's noise gain
/// and its size. The first and last output of a contiguous stretch are
/// left as they are. With one revolution per output nothing changes.
pub fn mid_window(outputs: &[Output], revolutions: u16) -> Vec<Output> {
    let c = curvature_coefficient(revolutions);
    let mut out = outputs.to_vec();
    if c == 0.0 {
        return out;
    }
    let gain = (1.0 + 2.0 * c).powi(2) + 2.0 * c * c;
    for k in 1..outputs.len().saturating_sub(1) {
        let (before, here, after) = (&outputs[k - 1], &outputs[k], &outputs[k + 1]);
        if !contiguous(before, here, revolutions) || !contiguous(here, after, revolutions) {
            continue;
        }
        for (i, q) in here.displacement.iter().enumerate() {
            let (Some(a), Some(b)) = (before.displacement.get(i), after.displacement.get(i)) else {
                continue;
            };
            let bias = (*a - *q * 2.0 + *b) * c as f32;
            let Some(target) = out[k].displacement.get_mut(i) else {
                continue;
            };
            *target = *q - bias;
            if let Some(Some(sd)) = out[k].noise_sd.get_mut(i) {
                *sd = (gain * *sd * *sd + f64::from(bias.norm_sqr())).sqrt();
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use plinth_shared::phasor::Phasor;

    /// The mean of a response `q` along the revolution number over the
    /// `revolutions` revolutions from `first`.
    fn window_mean(q: impl Fn(f64) -> Phasor, first: f64, revolutions: u16) -> Phasor {
        let n = f32::from(revolutions);
        (0..revolutions)
            .map(|j| q(first + f64::from(j)))
            .fold(Phasor::new(0.0, 0.0), |s, v| s + v)
            / n
    }

    fn output(k: usize, q: Phasor, revolutions: u16) -> Output {
        // 20 Hz, R revolutions per output, no gap.
        Output {
            speed_hz: 20.0,
            time_s: (k as f64 + 1.0) * f64::from(revolutions) / 20.0,
            displacement: vec![q],
            noise_sd: vec![Some(1e-3)],
        }
    }

    /// A response quadratic in the revolution number: the window means are
    /// off by Q''(R² − 1)/24 and come back exactly to the middle's value.
    #[test]
    fn a_quadratic_response_comes_back_to_the_window_middle() {
        let r = 4u16;
        let q = |n: f64| Phasor::new((0.3 * n * n) as f32, (1.0 - 0.2 * n * n) as f32);
        let outs: Vec<Output> = (0..5)
            .map(|k| output(k, window_mean(q, (k * 4) as f64, r), r))
            .collect();
        let fixed = mid_window(&outs, r);
        for k in 1..4 {
            let middle = q((k * 4) as f64 + 1.5);
            assert!(
                (outs[k].displacement[0] - middle).norm() > 0.1,
                "the mean is biased"
            );
            assert!(
                (fixed[k].displacement[0] - middle).norm() < 1e-4,
                "{k}: {} vs {middle}",
                fixed[k].displacement[0]
            );
            // The sd: the noise gain (1.165) and the correction's size.
            let sd = fixed[k].noise_sd[0].unwrap_or(0.0);
            assert!(sd > 1e-3 * 1.165f64.sqrt() && sd > 0.1, "{sd}");
        }
        // The ends have one neighbour only.
        assert_eq!(fixed[0], outs[0]);
        assert_eq!(fixed[4], outs[4]);
    }

    /// Outputs with revolutions missing between them (a keyphasor fault)
    /// are not neighbours; one revolution per output is left alone.
    #[test]
    fn gaps_and_single_revolutions_are_left_alone() {
        let q = Phasor::new(1.0, 0.0);
        let mut outs: Vec<Output> = (0..3).map(|k| output(k, q * k as f32, 4)).collect();
        outs[2].time_s += 4.0 / 20.0;
        assert_eq!(mid_window(&outs, 4), outs);
        let ones: Vec<Output> = (0..3).map(|k| output(k, q * (k * k) as f32, 1)).collect();
        assert_eq!(mid_window(&ones, 1), ones);
        assert_eq!(curvature_coefficient(4), 15.0 / 384.0);
    }
}
