//! The replay source: sample blocks and keyphasor edges sent by the host over
//! the link ([`HostMessage::Samples`](plinth_shared::protocol::HostMessage)),
//! processed as if the ADC had produced them.
//!
//! Blocks are taken strictly in order (go-back-N on the host): only the block
//! whose `first_sample` is the next expected sample index is processed. A
//! block that lies wholly before it (a resend after a lost `Ack`) is a
//! duplicate: acknowledged again, not processed. A block after it (one went
//! missing on the way) or overlapping it is refused with
//! [`NackReason::BadBlock`], so the host rewinds to its oldest
//! unacknowledged block and the time base never breaks.

use crate::source::{ChannelLayout, SampleBuffer, SampleSource, CHANNELS};
use plinth_shared::extractor::KeyphasorEdge;
use plinth_shared::protocol::{NackReason, SampleBlock, Samples};

/// Holds one replayed block (converted to volts) until the pipeline takes it.
#[derive(Debug)]
pub struct ReplaySource {
    /// ADC step [V per code] for blocks of raw codes.
    volts_per_code: f32,
    /// The converted block waiting for `poll`.
    pending: SampleBuffer,
    /// An edge after the last sample vector of the previous block (it belongs
    /// to the next block's first interval), as its fraction.
    carry: Option<f32>,
    /// Index of the next expected sample vector since start.
    next_sample: u32,
    /// Whether acquisition runs.
    running: bool,
    /// Ordering decisions since boot.
    counters: ReplayCounters,
}

/// How the replay source sorted the blocks it was offered (since boot;
/// they are not on the wire: the status frame's `commands_rejected` counts
/// the refusals together with every other `Nack`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ReplayCounters {
    /// Blocks processed (in order).
    pub accepted: u32,
    /// Blocks wholly before the next expected sample, acknowledged again
    /// without being processed.
    pub duplicates: u32,
    /// Blocks refused because they start after the next expected sample
    /// (a block before them is missing) or overlap it.
    pub out_of_order: u32,
}

/// Where a block's `first_sample` lies relative to the next expected sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Position {
    /// Exactly the next block.
    Next,
    /// Wholly before it: already processed.
    Duplicate,
    /// After it (a gap) or overlapping it.
    OutOfOrder,
}

/// Classifies a block of `k` sample vectors starting at `first` when `next`
/// is the next expected sample index (indices wrap at 2^32: a block is
/// "before" when it starts less than 2^31 samples back).
fn position(first: u32, k: usize, next: u32) -> Position {
    if first == next {
        return Position::Next;
    }
    let behind = next.wrapping_sub(first);
    if behind < 1 << 31 && u64::from(behind) >= k as u64 {
        Position::Duplicate
    } else {
        Position::OutOfOrder
    }
}

impl ReplaySource {
    /// A replay source whose raw codes are `volts_per_code` [V] each.
    pub fn new(volts_per_code: f32) -> Self {
        Self {
            volts_per_code,
            pending: SampleBuffer::default(),
            carry: None,
            next_sample: 0,
            running: false,
            counters: ReplayCounters::default(),
        }
    }

    /// How the blocks offered since boot were sorted.
    pub fn counters(&self) -> ReplayCounters {
        self.counters
    }
}

impl SampleSource for ReplaySource {
    fn start(&mut self) -> Result<(), NackReason> {
        self.pending.clear();
        self.carry = None;
        self.next_sample = 0;
        self.running = true;
        Ok(())
    }

    fn stop(&mut self) {
        self.pending.clear();
        self.carry = None;
        self.running = false;
    }

    fn poll(&mut self, out: &mut SampleBuffer) {
        if !self.pending.is_empty() {
            core::mem::swap(out, &mut self.pending);
            self.pending.clear();
        }
    }

    fn replay(&mut self, block: &SampleBlock, layout: &ChannelLayout) -> Result<(), NackReason> {
        if !self.running {
            return Err(NackReason::WrongState);
        }
        if !self.pending.is_empty() {
            return Err(NackReason::QueueFull);
        }
        let k = block.sample_vectors().map_err(|_| NackReason::BadBlock)?;
        let n = block.channels as usize;
        if n != layout.adc_channel.len() || k > self.pending.samples.capacity() {
            return Err(NackReason::BadBlock);
        }
        match position(block.first_sample, k, self.next_sample) {
            Position::Next => {}
            Position::Duplicate => {
                self.counters.duplicates = self.counters.duplicates.saturating_add(1);
                return Ok(());
            }
            Position::OutOfOrder => {
                self.counters.out_of_order = self.counters.out_of_order.saturating_add(1);
                return Err(NackReason::BadBlock);
            }
        }
        let buf = &mut self.pending;
        buf.clear();
        for v in 0..k {
            let mut vector = [0.0f32; CHANNELS];
            for (i, &adc) in layout.adc_channel.iter().enumerate() {
                let slot = adc as usize % CHANNELS;
                vector[slot] = match &block.samples {
                    Samples::AdcCodes(codes) => {
                        let c = codes[v * n + i];
                        if c == i16::MAX || c == i16::MIN {
                            buf.saturated[slot] += 1;
                        }
                        f32::from(c) * self.volts_per_code
                    }
                    Samples::Volts(volts) => volts[v * n + i],
                };
            }
            // Cannot fail: k ≤ capacity was checked above.
            let _ = buf.samples.push(vector);
        }
        // Edge at t samples after the first vector: the first sample after it
        // is floor(t) + 1, at fraction t − floor(t) of the interval before.
        if let Some(fraction) = self.carry.take() {
            let _ = buf.edges.push(KeyphasorEdge { index: 0, fraction });
        }
        for e in &block.keyphasor_edges {
            let t = e.offset_samples;
            let whole = libm::floorf(t);
            let fraction = t - whole;
            let index = whole as usize + 1;
            if index >= k {
                self.carry = Some(fraction);
            } else if buf.edges.push(KeyphasorEdge { index, fraction }).is_err() {
                // Cannot happen (room for a block's edges plus a carried
                // one); refuse the whole block rather than process part of it.
                buf.clear();
                return Err(NackReason::BadBlock);
            }
        }
        self.next_sample = block.first_sample.wrapping_add(k as u32);
        self.counters.accepted = self.counters.accepted.saturating_add(1);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plinth_shared::protocol::KeyphasorEdge as WireEdge;

    /// Two channels on ADC inputs 0 and 1.
    fn layout() -> ChannelLayout {
        let mut l = ChannelLayout::default();
        l.adc_channel.extend_from_slice(&[0, 1]).unwrap();
        l
    }

    /// A block of `k` two-channel vectors starting at `first`, value
    /// (first + v) on channel 0 and −(first + v) on channel 1, with a
    /// keyphasor edge at 2.5 samples and one at `k` − 0.25 (carried over).
    fn block(first: u32, k: usize) -> SampleBlock {
        let mut volts = heapless::Vec::new();
        for v in 0..k {
            let x = (first as usize + v) as f32;
            volts.extend_from_slice(&[x, -x]).unwrap();
        }
        let mut edges = heapless::Vec::new();
        edges
            .push(WireEdge {
                offset_samples: 2.5,
            })
            .unwrap();
        edges
            .push(WireEdge {
                offset_samples: k as f32 - 0.25,
            })
            .unwrap();
        SampleBlock {
            first_sample: first,
            channels: 2,
            samples: Samples::Volts(volts),
            keyphasor_edges: edges,
        }
    }

    fn running() -> ReplaySource {
        let mut s = ReplaySource::new(1.0);
        s.start().unwrap();
        s
    }

    fn take(s: &mut ReplaySource) -> SampleBuffer {
        let mut out = SampleBuffer::default();
        s.poll(&mut out);
        out
    }

    #[test]
    fn blocks_in_order_are_processed_with_the_edge_carried_over() {
        let mut s = running();
        let l = layout();
        assert_eq!(s.replay(&block(0, 10), &l), Ok(()));
        let a = take(&mut s);
        assert_eq!(a.samples.len(), 10);
        assert_eq!(a.samples[9][0], 9.0);
        assert_eq!(a.samples[9][1], -9.0);
        assert_eq!(a.lost_before, 0);
        assert_eq!(a.edges.len(), 1);
        assert_eq!((a.edges[0].index, a.edges[0].fraction), (3, 0.5));
        assert_eq!(s.replay(&block(10, 10), &l), Ok(()));
        let b = take(&mut s);
        assert_eq!(b.samples[0][0], 10.0);
        assert_eq!(b.lost_before, 0);
        // The edge at 9.75 of the first block opens the second one.
        assert_eq!((b.edges[0].index, b.edges[0].fraction), (0, 0.75));
        assert_eq!((b.edges[1].index, b.edges[1].fraction), (3, 0.5));
        assert_eq!(
            s.counters(),
            ReplayCounters {
                accepted: 2,
                duplicates: 0,
                out_of_order: 0
            }
        );
    }

    #[test]
    fn a_repeated_block_is_acknowledged_but_not_processed() {
        let mut s = running();
        let l = layout();
        for first in [0, 10, 20] {
            assert_eq!(s.replay(&block(first, 10), &l), Ok(()));
            take(&mut s);
        }
        // The last block again (its Ack was lost), and an older one.
        for first in [20, 0] {
            assert_eq!(s.replay(&block(first, 10), &l), Ok(()));
            assert!(
                take(&mut s).is_empty(),
                "block at {first} was processed twice"
            );
        }
        assert_eq!(s.counters().duplicates, 2);
        // The expected block is still the next one, and the carried edge
        // of the block at 20 survived the duplicates.
        assert_eq!(s.replay(&block(30, 10), &l), Ok(()));
        let b = take(&mut s);
        assert_eq!(b.samples[0][0], 30.0);
        assert_eq!(b.lost_before, 0);
        assert_eq!((b.edges[0].index, b.edges[0].fraction), (0, 0.75));
        assert_eq!(s.counters().accepted, 4);
    }

    #[test]
    fn a_block_after_a_gap_is_refused_until_the_missing_one_comes() {
        let mut s = running();
        let l = layout();
        assert_eq!(s.replay(&block(0, 10), &l), Ok(()));
        take(&mut s);
        // The block at 10 was lost on the way: 20 and 30 are refused.
        for first in [20, 30] {
            assert_eq!(s.replay(&block(first, 10), &l), Err(NackReason::BadBlock));
            assert!(take(&mut s).is_empty());
        }
        // A block overlapping the expected index is refused too.
        assert_eq!(s.replay(&block(5, 10), &l), Err(NackReason::BadBlock));
        assert_eq!(s.counters().out_of_order, 3);
        // The resend from the missing block on goes through in order.
        for first in [10, 20, 30] {
            assert_eq!(s.replay(&block(first, 10), &l), Ok(()));
            let b = take(&mut s);
            assert_eq!(b.samples[0][0], first as f32);
            assert_eq!(b.lost_before, 0);
            assert_eq!(b.edges[0].index, 0, "carried edge before {first}");
        }
        assert_eq!(s.counters().accepted, 4);
    }

    #[test]
    fn sample_indices_wrap_at_two_to_the_32() {
        assert_eq!(position(u32::MAX - 4, 10, u32::MAX - 4), Position::Next);
        // 10 samples before 5 (across the wrap) is a duplicate.
        assert_eq!(position(u32::MAX - 4, 10, 5), Position::Duplicate);
        assert_eq!(position(u32::MAX - 3, 10, 5), Position::OutOfOrder);
        assert_eq!(position(15, 10, 5), Position::OutOfOrder);
        // Half the index range ahead is ahead, not behind.
        assert_eq!(
            position(5u32.wrapping_add(1 << 31), 10, 5),
            Position::OutOfOrder
        );
    }

    #[test]
    fn a_block_while_stopped_or_with_another_channel_count_is_refused() {
        let mut s = ReplaySource::new(1.0);
        assert_eq!(
            s.replay(&block(0, 10), &layout()),
            Err(NackReason::WrongState)
        );
        s.start().unwrap();
        let mut three = layout();
        three.adc_channel.push(2).unwrap();
        assert_eq!(s.replay(&block(0, 10), &three), Err(NackReason::BadBlock));
        // Not an ordering decision: the block at 0 is still the next one.
        assert_eq!(s.counters(), ReplayCounters::default());
        assert_eq!(s.replay(&block(0, 10), &layout()), Ok(()));
    }
}
