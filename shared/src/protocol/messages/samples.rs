//! Replayed sample blocks: sample values and keyphasor edges sent to the box.

use super::*;

/// The sample values of a replayed block, interleaved by sample vector:
/// value `k · channels + n` is sample vector k of channel n.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Samples {
    /// Raw ADC codes; volts = code · [`Capabilities::adc_volts_per_code`].
    AdcCodes(heapless::Vec<i16, MAX_BLOCK_VALUES>),
    /// Transducer output voltages \[V] (the channel's sensitivity still applies).
    Volts(heapless::Vec<f32, MAX_BLOCK_VALUES>),
}

impl Samples {
    /// Number of values (sample vectors × channels).
    pub fn len(&self) -> usize {
        match self {
            Samples::AdcCodes(v) => v.len(),
            Samples::Volts(v) => v.len(),
        }
    }

    /// True when the block holds no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A keyphasor (once-per-revolution) pulse inside a replayed block.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct KeyphasorEdge {
    /// Time of the edge from the block's first sample vector, in sample
    /// periods (fractional: sub-sample timing), in [0, sample vectors).
    pub offset_samples: f32,
}

/// Host → box: K sample vectors of N channels to process as if the ADC had
/// produced them, with the keyphasor edges that fall inside the block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SampleBlock {
    /// Index of the block's first sample vector since `Start` (wrapping), so
    /// that the box can detect a missing block.
    pub first_sample: u32,
    /// Channels per sample vector (N ≥ 1), in the order of the channel set.
    pub channels: u8,
    /// The K · N values.
    pub samples: Samples,
    /// Keyphasor edges inside the block, in increasing time.
    pub keyphasor_edges: heapless::Vec<KeyphasorEdge, MAX_KEYPHASOR_EDGES>,
}

/// Why a [`SampleBlock`] is malformed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SampleBlockError {
    /// `channels` is zero.
    NoChannels,
    /// The number of values is not a multiple of `channels`.
    Ragged,
    /// Keyphasor edge `index` is not finite, outside [0, K) or not after the
    /// previous one.
    BadEdge {
        /// Position of the edge in `keyphasor_edges`.
        index: u8,
    },
}

impl SampleBlock {
    /// Checks the block's shape and returns K, the number of sample vectors.
    pub fn sample_vectors(&self) -> Result<usize, SampleBlockError> {
        let n = self.channels as usize;
        if n == 0 {
            return Err(SampleBlockError::NoChannels);
        }
        let len = self.samples.len();
        if !len.is_multiple_of(n) {
            return Err(SampleBlockError::Ragged);
        }
        let k = len / n;
        let mut prev = f32::NEG_INFINITY;
        for (i, e) in self.keyphasor_edges.iter().enumerate() {
            let t = e.offset_samples;
            if !t.is_finite() || t < 0.0 || t >= k as f32 || t <= prev {
                return Err(SampleBlockError::BadEdge { index: i as u8 });
            }
            prev = t;
        }
        Ok(k)
    }
}
