//! The replay source: sample blocks and keyphasor edges sent by the host over
//! the link ([`HostMessage::Samples`](plinth_shared::protocol::HostMessage)),
//! processed as if the ADC had produced them.

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
        }
    }
}

impl SampleSource for ReplaySource {
    fn start(&mut self) {
        self.pending.clear();
        self.carry = None;
        self.next_sample = 0;
        self.running = true;
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
        let buf = &mut self.pending;
        buf.clear();
        if block.first_sample != self.next_sample {
            // A block went missing (or came twice): the time base is broken.
            buf.lost_before = block.first_sample.wrapping_sub(self.next_sample);
            self.carry = None;
        }
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
                return Err(NackReason::BadBlock);
            }
        }
        self.next_sample = block.first_sample.wrapping_add(k as u32);
        Ok(())
    }
}
