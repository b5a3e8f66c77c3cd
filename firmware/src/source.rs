//! Where samples come from: the ADC on the box, or blocks replayed by the
//! host (under QEMU, where there are no sensors). Both fill the same
//! [`SampleBuffer`] that the pipeline consumes.

use plinth_shared::extractor::KeyphasorEdge;
use plinth_shared::protocol::{BoxHealth, NackReason, SampleBlock};

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
    /// Starts acquisition (a new sample count from zero), or says why it
    /// cannot ([`NackReason::SamplingUnavailable`]).
    fn start(&mut self) -> Result<(), NackReason>;
    /// Stops acquisition and drops anything not yet delivered.
    fn stop(&mut self);
    /// Moves what has been acquired into `out` (which the caller has emptied);
    /// does a bounded amount of work and never waits for new data.
    fn poll(&mut self, out: &mut SampleBuffer);
    /// Adds the source's fault counters to `health` (nothing by default).
    fn health(&self, health: &mut BoxHealth) {
        let _ = health;
    }
    /// Accepts a block the host replays instead of the ADC; only a replay
    /// source does ([`NackReason::WrongState`] otherwise).
    fn replay(&mut self, block: &SampleBlock, layout: &ChannelLayout) -> Result<(), NackReason> {
        let _ = (block, layout);
        Err(NackReason::WrongState)
    }
}

/// A source that may be unavailable: the board's ADC when a read does not
/// fit the sample period at the clock the box runs on (`Start` is then
/// refused with [`NackReason::SamplingUnavailable`]).
#[derive(Debug)]
pub struct Refusable<S>(pub Option<S>);

impl<S: SampleSource> SampleSource for Refusable<S> {
    fn start(&mut self) -> Result<(), NackReason> {
        match &mut self.0 {
            Some(s) => s.start(),
            None => Err(NackReason::SamplingUnavailable),
        }
    }
    fn stop(&mut self) {
        if let Some(s) = &mut self.0 {
            s.stop();
        }
    }
    fn poll(&mut self, out: &mut SampleBuffer) {
        if let Some(s) = &mut self.0 {
            s.poll(out);
        }
    }
    fn health(&self, health: &mut BoxHealth) {
        match &self.0 {
            Some(s) => s.health(health),
            None => health.sampling_refused = true,
        }
    }
}
