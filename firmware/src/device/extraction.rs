//! The extraction state: the session's configuration, the pipeline of the
//! current run and the sample buffer. On the board it belongs to the
//! extraction task (`plinth-box`'s `extract`, priority 2), which runs
//! [`Extraction::run`] on every completed DMA half; the protocol task only
//! borrows it for short sections (a configuration command, `Start`,
//! `Stop`, a status snapshot).

use super::outbox::Outbox;
use super::shared::Lock;
use super::REPLY_RESERVE;
use crate::config::Configuration;
use crate::pipeline::Pipeline;
use crate::source::{SampleBuffer, SampleSource, CHANNELS};
use plinth_shared::protocol::{DeviceCounters, DeviceMessage, NackReason, MAX_CHANNELS};

/// Configuration, pipeline and sample buffer of a session.
pub struct Extraction {
    /// The session's configuration (kept across Stop/Start).
    pub(super) config: Configuration,
    pipeline: Option<Pipeline>,
    buffer: SampleBuffer,
    /// Samples at the ADC's limits this session, per ADC channel.
    saturation: heapless::Vec<u32, MAX_CHANNELS>,
    running: bool,
}

impl Default for Extraction {
    fn default() -> Self {
        Self::new()
    }
}

impl Extraction {
    /// No session: empty configuration, no pipeline.
    pub fn new() -> Self {
        Self {
            config: Configuration::new(),
            pipeline: None,
            buffer: SampleBuffer::default(),
            saturation: heapless::Vec::new(),
            running: false,
        }
    }

    /// A new session: configuration and counts back to their defaults.
    pub(super) fn open_session(&mut self) {
        self.pipeline = None;
        self.running = false;
        self.config = Configuration::new();
        self.saturation.clear();
        for _ in 0..CHANNELS {
            let _ = self.saturation.push(0);
        }
    }

    /// No session (a host of another protocol version).
    pub(super) fn close_session(&mut self) {
        self.pipeline = None;
        self.running = false;
    }

    /// Builds the run's pipeline for `sample_rate_hz` [Hz] and starts
    /// `source`, if the configuration is complete.
    pub(super) fn start<S: SampleSource>(
        &mut self,
        source: &mut S,
        sample_rate_hz: f32,
    ) -> Result<(), NackReason> {
        if !self.config.ready() {
            return Err(NackReason::WrongState);
        }
        let pipeline =
            Pipeline::new(&self.config, sample_rate_hz).map_err(|_| NackReason::BadValue)?;
        source.start()?;
        self.pipeline = Some(pipeline);
        self.running = true;
        Ok(())
    }

    /// Stops `source`; returns the run's final estimates (if any).
    pub(super) fn stop<S: SampleSource>(
        &mut self,
        source: &mut S,
    ) -> Option<plinth_shared::protocol::EstimateFrame> {
        source.stop();
        self.running = false;
        self.pipeline
            .as_ref()
            .map(|p| p.estimates())
            .filter(|e| !e.pedestals.is_empty())
    }

    /// Adds this state's counts to the session's `counters`.
    pub(super) fn fold_counters(&self, counters: &mut DeviceCounters) {
        counters.adc_saturation = self.saturation.clone();
        if let Some(p) = &self.pipeline {
            p.counters.fold_into(counters);
        }
    }

    /// Whether a run is on (between an accepted `Start` and `Stop`).
    pub fn running(&self) -> bool {
        self.running
    }

    /// The buffer the last [`Extraction::run`] filled (what a board model
    /// checks against the conversions' truth).
    pub fn buffer(&self) -> &SampleBuffer {
        &self.buffer
    }

    /// The extraction step: whatever `source` has, through the pipeline;
    /// each phasor or estimate frame goes into the outbox under its own
    /// short lock. Returns the sample vectors taken (0 when no run is on).
    pub fn run<S: SampleSource>(
        &mut self,
        source: &mut S,
        outbox: &mut impl Lock<Target = Outbox>,
    ) -> usize {
        if !self.running {
            return 0;
        }
        self.buffer.clear();
        source.poll(&mut self.buffer);
        let n = self.buffer.samples.len();
        if n == 0 && self.buffer.lost_before == 0 {
            return 0;
        }
        for (total, add) in self.saturation.iter_mut().zip(self.buffer.saturated) {
            *total = total.saturating_add(add);
        }
        if let Some(pipeline) = &mut self.pipeline {
            let mut out = |m: DeviceMessage| outbox.lock(|o| o.push(&m, REPLY_RESERVE));
            pipeline.process(&self.buffer, &self.config.tables, &mut out);
        }
        n
    }
}
