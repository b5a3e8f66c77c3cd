//! Keyphasor events from a recorded keyphasor waveform: a threshold crossing
//! in the configured direction, armed again only after the signal has come
//! back `hysteresis` past the threshold (noise on a slow edge gives one event,
//! not a burst), timed to a fraction of a sample by linear interpolation
//! between the two samples around the crossing: the same sub-sample edge the
//! box's timer capture gives its extractor.

use super::channels::{Edge, KeyphasorConfig};

/// Fewest samples per revolution the shared extractor accepts
/// (`ExtractorConfig::max_speed_hz` ≤ sample rate / 64).
pub const MIN_SAMPLES_PER_REVOLUTION: f64 = 64.0;

/// A streaming edge detector over one channel.
#[derive(Clone, Debug)]
pub struct EdgeDetector {
    threshold: f64,
    hysteresis: f64,
    edge: Edge,
    armed: bool,
    previous: Option<f64>,
    /// Edges found so far.
    pub edges: u64,
    /// Lowest and highest sample seen [V].
    pub range: (f64, f64),
}

impl EdgeDetector {
    /// A detector for `config`.
    pub fn new(config: &KeyphasorConfig) -> Self {
        Self {
            threshold: config.threshold_v,
            hysteresis: config.hysteresis_v,
            edge: config.edge,
            armed: false,
            previous: None,
            edges: 0,
            range: (f64::INFINITY, f64::NEG_INFINITY),
        }
    }

    /// Feeds the next sample [V]; returns the edge's position within the
    /// interval since the previous sample, in [0, 1), when one ends in it.
    pub fn push(&mut self, v: f64) -> Option<f32> {
        self.range = (self.range.0.min(v), self.range.1.max(v));
        // Work on a signal whose edge of interest is a fall.
        let (x, t) = match self.edge {
            Edge::Falling => (v, self.threshold),
            Edge::Rising => (-v, -self.threshold),
        };
        let previous = self.previous.replace(x);
        if x >= t + self.hysteresis {
            self.armed = true;
        }
        if self.armed && x < t {
            self.armed = false;
            let p = previous?;
            if p < t {
                // Armed by a sample at or above t + hysteresis that is not
                // the previous one? Only possible with zero hysteresis; the
                // crossing is between p and x all the same.
                return None;
            }
            self.edges += 1;
            let fraction = ((p - t) / (p - x)).clamp(0.0, 1.0);
            // [0, 1): an edge exactly at the sample counts just before it.
            return Some((fraction as f32).min(1.0 - f32::EPSILON));
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn detector(edge: Edge, hysteresis_v: f64) -> EdgeDetector {
        EdgeDetector::new(&KeyphasorConfig {
            channel: 0,
            threshold_v: -5.0,
            edge,
            hysteresis_v,
        })
    }

    #[test]
    fn falling_edge_with_fraction_and_hysteresis() {
        let mut d = detector(Edge::Falling, 0.5);
        assert_eq!(d.push(-1.0), None);
        // −1 → −9 crosses −5 halfway.
        assert_eq!(d.push(-9.0), Some(0.5));
        // Noise around the threshold below −4.5 re-arms nothing.
        for v in [-4.8, -5.2, -4.9, -5.1] {
            assert_eq!(d.push(v), None);
        }
        assert_eq!(d.push(-2.0), None);
        // −2 → −6: crossing at 3/4.
        assert_eq!(d.push(-6.0), Some(0.75));
        assert_eq!(d.edges, 2);
    }

    #[test]
    fn rising_edge() {
        let mut d = detector(Edge::Rising, 0.5);
        assert_eq!(d.push(-9.0), None);
        assert_eq!(d.push(-1.0), Some(0.5));
        assert_eq!(d.push(-9.0), None);
        assert_eq!(d.push(-4.0), Some(0.8));
    }
}
