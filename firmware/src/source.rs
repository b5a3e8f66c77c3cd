//! Where samples come from: the ADC on the box, or blocks replayed by the
//! host (under QEMU, where there are no sensors). Both fill the same
//! [`SampleBuffer`] that the pipeline consumes.

use plinth_shared::extractor::KeyphasorEdge;
use plinth_shared::protocol::{NackReason, SampleBlock};

/// ADC channels of the box (one AD7606: 8 simultaneously sampled inputs).
pub const CHANNELS: usize = 8;

/// Most sample vectors one [`SampleBuffer`] holds.
pub const BUFFER_VECTORS: usize = plinth_shared::protocol::MAX_BLOCK_VALUES;

/// Most keyphasor edges one [`SampleBuffer`] holds (a replayed block's, plus one carried over from the block before).
pub const BUFFER_EDGES: usize = plinth_shared::protocol::MAX_KEYPHASOR_EDGES + 1;

/// Consecutive sample vectors [V] with the keyphasor edges that fell among
/// them, as the phasor extractor takes them.
#[derive(Clone, Debug, Default)]
pub struct SampleBuffer {
    /// Sample vectors, every ADC channel [V].
    pub samples: heapless::Vec<[f32; CHANNELS], BUFFER_VECTORS>,
    /// Keyphasor edges, sorted, indices into `samples`.
    pub edges: heapless::Vec<KeyphasorEdge, BUFFER_EDGES>,
    /// Samples at the ADC's limits in this buffer, per ADC channel.
    pub saturated: [u32; CHANNELS],
    /// Sample vectors lost just before this buffer (ADC overrun, missing
    /// replay block): the time base is broken there.
    pub lost_before: u32,
}

impl SampleBuffer {
    /// Empties the buffer.
    pub fn clear(&mut self) {
        self.samples.clear();
        self.edges.clear();
        self.saturated = [0; CHANNELS];
        self.lost_before = 0;
    }

    /// True when no sample vector is waiting.
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// True when no further sample vector fits.
    pub fn is_full(&self) -> bool {
        self.samples.is_full()
    }
}

/// Where each value of a replayed block goes: `adc_channel[n]` is the ADC
/// channel of the n-th configured channel (the order of the channel set).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ChannelLayout {
    /// ADC channel index of each configured channel, in channel-set order.
    pub adc_channel: heapless::Vec<u8, CHANNELS>,
}

/// A producer of sample vectors and keyphasor edges.
pub trait SampleSource {
    /// Starts acquisition (a new sample count from zero).
    fn start(&mut self);
    /// Stops acquisition and drops anything not yet delivered.
    fn stop(&mut self);
    /// Moves what has been acquired into `out` (which the caller has emptied);
    /// does a bounded amount of work and never waits for new data.
    fn poll(&mut self, out: &mut SampleBuffer);
    /// Accepts a block the host replays instead of the ADC; only a replay
    /// source does ([`NackReason::WrongState`] otherwise).
    fn replay(&mut self, block: &SampleBlock, layout: &ChannelLayout) -> Result<(), NackReason> {
        let _ = (block, layout);
        Err(NackReason::WrongState)
    }
}
