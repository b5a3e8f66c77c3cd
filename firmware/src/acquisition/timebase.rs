//! Keyphasor capture timestamps to sample-fractional edge positions.
//!
//! The capture timer (32 bits, unprescaled) is started by the CONVST timer's
//! enable (master/slave trigger), so both count the same clock and sample
//! `k` is taken at capture count `origin + k · ticks_per_sample` exactly. A
//! capture `c` then lies `(c − origin) / ticks_per_sample` samples after
//! sample 0: no interpolation, no drift, whatever the shaft speed does. The
//! capture latches the tick in which the edge came, so the edge is placed
//! at the middle of that tick: the error is at most half a tick
//! (1 / (2 · 1641) ≈ 3.0e-4 sample at 51.2 kHz from an 84 MHz clock).
//!
//! The 32-bit count wraps every 2³² ticks (51 s at 84 MHz); a capture is
//! unwrapped against an upper bound of the current time, so it is exact as
//! long as it is taken from the queue within one wrap of being captured.

/// Sample position of one keyphasor edge, as the extractor takes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgePosition {
    /// Sample count since acquisition start of the first sample after the edge.
    pub next_sample: u64,
    /// Where in the interval before `next_sample` the edge came, in (0, 1).
    pub fraction: f32,
}

/// The capture timer's relation to the sample clock.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CaptureTimebase {
    /// Capture-timer ticks per sample period (> 0).
    ticks_per_sample: u32,
    /// Capture count at sample 0.
    origin: u32,
}

impl CaptureTimebase {
    /// A time base whose sample 0 is at capture count `origin` and whose
    /// samples are `ticks_per_sample` capture ticks apart (at least 1).
    pub fn new(ticks_per_sample: u32, origin: u32) -> Self {
        Self {
            ticks_per_sample: ticks_per_sample.max(1),
            origin,
        }
    }

    /// Capture-timer ticks per sample period.
    pub fn ticks_per_sample(&self) -> u32 {
        self.ticks_per_sample
    }

    /// Where the edge captured at count `capture` lies, given that no more
    /// than `now_samples` sample periods have passed since sample 0 (an upper
    /// bound of the current time). `None` for an edge before sample 0.
    pub fn locate(&self, capture: u32, now_samples: u64) -> Option<EdgePosition> {
        let p = u64::from(self.ticks_per_sample);
        let now_ticks = now_samples.saturating_mul(p);
        // Ticks since sample 0, unwrapped as the latest count ≤ now.
        let since_origin = capture.wrapping_sub(self.origin);
        let age = u64::from((now_ticks as u32).wrapping_sub(since_origin));
        let ticks = now_ticks.checked_sub(age)?;
        let whole = ticks / p;
        let rest = ticks % p;
        // Middle of the capturing tick: (rest + ½) / p, never 0 or 1.
        let fraction = ((2 * rest + 1) as f64 / (2 * p) as f64) as f32;
        Some(EdgePosition {
            next_sample: whole + 1,
            fraction: fraction.clamp(f32::MIN_POSITIVE, 1.0 - f32::EPSILON),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_worked_positions() {
        let tb = CaptureTimebase::new(1000, 500);
        // 2.25 samples after sample 0, tick 250 of the interval: (250.5)/1000.
        let e = tb.locate(500 + 2250, 10).unwrap();
        assert_eq!(e.next_sample, 3);
        assert!((e.fraction - 0.2505).abs() < 1e-7);
        // On a sample's own tick: just after it.
        let e = tb.locate(500 + 3000, 10).unwrap();
        assert_eq!(e.next_sample, 4);
        assert!((e.fraction - 0.0005).abs() < 1e-7);
        // Before sample 0.
        assert_eq!(tb.locate(499, 10), None);
    }

    #[test]
    fn unwraps_across_the_32_bit_count() {
        // Origin just below the wrap; an edge 5 000 000.5 samples later
        // (the count has wrapped once).
        let p = 1641u32;
        let origin = u32::MAX - 10;
        let tb = CaptureTimebase::new(p, origin);
        let ticks: u64 = 5_000_000 * u64::from(p) + 820;
        let capture = origin.wrapping_add(ticks as u32);
        let e = tb.locate(capture, 5_000_100).unwrap();
        assert_eq!(e.next_sample, 5_000_001);
        assert!((e.fraction - 820.5 / 1641.0).abs() < 1e-6);
    }
}
