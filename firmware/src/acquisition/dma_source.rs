//! The box's sample source on the board: DMA halves of AD7606 conversions
//! and keyphasor captures, turned into the [`SampleBuffer`]s the pipeline
//! takes (volts, sample-fractional edges, losses marked).

use super::handover::{DoubleBuffer, HandOver, Taken};
use super::scaling;
use super::timebase::CaptureTimebase;
use crate::ad7606::Range;
use crate::source::{SampleBuffer, SampleSource, BUFFER_VECTORS};
use plinth_shared::extractor::KeyphasorEdge;
use plinth_shared::protocol::{BoxHealth, NackReason};

/// The acquisition hardware: CONVST timer, capture timer, SPI DMA.
pub trait AcquisitionHardware: DoubleBuffer {
    /// Starts conversions from a clean state (half 0, completion count 0)
    /// and returns the capture timer's count at sample 0 [ticks].
    fn start(&mut self) -> u32;
    /// Stops conversions and the DMA.
    fn stop(&mut self);
    /// The oldest keyphasor capture not yet taken [capture ticks].
    fn take_capture(&mut self) -> Option<u32>;
    /// Faults since power-up that broke the sample sequence: conversions
    /// not read (BUSY came while the previous read still ran) and DMA
    /// transfer errors (wrapping). When it changes the source restarts the
    /// hardware rather than deliver samples one conversion out of place.
    fn sequence_faults(&self) -> u32 {
        0
    }
    /// Adds the hardware's fault counters to `health` (nothing by default).
    fn health(&self, health: &mut BoxHealth) {
        let _ = health;
    }
}

/// What the source lost or dropped since start.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct DmaSourceCounters {
    /// Halves not delivered because the consumer came too late (overruns;
    /// samples lost to a restart after a sequence fault are not in here).
    pub overrun_halves: u32,
    /// Of those, halves overrun while being copied (copy discarded).
    pub torn_halves: u32,
    /// Keyphasor edges dropped: before the start, in lost samples, or more
    /// than a buffer holds.
    pub dropped_edges: u32,
    /// Restarts after a sequence fault ([`AcquisitionHardware::sequence_faults`]).
    pub resyncs: u32,
}

/// DMA-fed AD7606 samples with keyphasor captures.
#[derive(Debug)]
pub struct DmaSource<H> {
    hardware: H,
    handover: HandOver,
    timebase: CaptureTimebase,
    range: Range,
    /// A capture belonging to a later half.
    held: Option<u32>,
    /// Vectors lost since the last delivered half.
    lost: u64,
    /// Sample count since the (re)start that the next half should begin at.
    expected: u64,
    /// The hardware's fault count when last looked at.
    faults_seen: u32,
    /// Halves lost before the last restart.
    lost_halves_before: u64,
    running: bool,
    counters: DmaSourceCounters,
    /// Sample count since the (re)start of the last delivered half's first vector.
    delivered_first: u64,
}

impl<H: AcquisitionHardware> DmaSource<H> {
    /// A source over `hardware` whose halves hold `vectors_per_half` sample
    /// vectors (at most [`BUFFER_VECTORS`]), converted `ticks_per_sample`
    /// capture ticks apart, on the ADC input `range`.
    pub fn new(hardware: H, vectors_per_half: usize, ticks_per_sample: u32, range: Range) -> Self {
        Self {
            hardware,
            handover: HandOver::new(vectors_per_half.clamp(1, BUFFER_VECTORS)),
            timebase: CaptureTimebase::new(ticks_per_sample, 0),
            range,
            held: None,
            lost: 0,
            expected: 0,
            faults_seen: 0,
            lost_halves_before: 0,
            running: false,
            counters: DmaSourceCounters::default(),
            delivered_first: 0,
        }
    }

    /// Starts the hardware from a clean state: sample count 0, no stale
    /// captures.
    fn restart(&mut self) {
        self.hardware.stop();
        while self.hardware.take_capture().is_some() {}
        self.lost_halves_before += self.handover.lost_halves();
        self.handover.reset();
        self.held = None;
        self.expected = 0;
        self.faults_seen = self.hardware.sequence_faults();
        let origin = self.hardware.start();
        self.timebase = CaptureTimebase::new(self.timebase.ticks_per_sample(), origin);
    }

    /// A conversion went unread, two merged, the DMA or the SPI failed:
    /// what follows in the buffer is out of place. Everything since the
    /// last delivered half is lost; start again from a clean state.
    fn resync(&mut self) {
        let converted = self.handover.now_bound(&self.hardware);
        // (Halves already counted lost all lie after `expected`.)
        self.lost = self
            .lost
            .max(converted.saturating_sub(self.expected))
            .max(1);
        self.counters.resyncs = self.counters.resyncs.saturating_add(1);
        self.restart();
    }

    /// What was lost since start.
    pub fn counters(&self) -> DmaSourceCounters {
        self.counters
    }

    /// Where the last delivered buffer's first vector lies: its sample
    /// count since the hardware's last (re)start (what a board model checks
    /// against the conversions' own times).
    pub fn delivered_first_sample(&self) -> u64 {
        self.delivered_first
    }

    /// The hardware (for its own counters).
    pub fn hardware(&self) -> &H {
        &self.hardware
    }

    /// The hardware, mutably (benches and simulations drive it).
    pub fn hardware_mut(&mut self) -> &mut H {
        &mut self.hardware
    }

    /// Whether acquisition runs.
    pub fn running(&self) -> bool {
        self.running
    }

    /// Attaches the captures up to the end of the half `[first, end)`.
    fn attach_edges(&mut self, out: &mut SampleBuffer, first: u64, end: u64) {
        let now = self.handover.now_bound(&self.hardware);
        loop {
            let Some(capture) = self.held.take().or_else(|| self.hardware.take_capture()) else {
                return;
            };
            let Some(edge) = self.timebase.locate(capture, now) else {
                self.counters.dropped_edges = self.counters.dropped_edges.saturating_add(1);
                continue;
            };
            if edge.next_sample >= end {
                self.held = Some(capture); // for a later half
                return;
            }
            if edge.next_sample < first || (edge.next_sample == first && out.lost_before > 0) {
                // In samples that were lost (the interval before a half
                // that follows a gap is not one sample period of data).
                self.counters.dropped_edges = self.counters.dropped_edges.saturating_add(1);
                continue;
            }
            let index = (edge.next_sample - first) as usize;
            if out
                .edges
                .push(KeyphasorEdge {
                    index,
                    fraction: edge.fraction,
                })
                .is_err()
            {
                self.counters.dropped_edges = self.counters.dropped_edges.saturating_add(1);
            }
        }
    }
}

impl<H: AcquisitionHardware> SampleSource for DmaSource<H> {
    fn start(&mut self) -> Result<(), NackReason> {
        self.lost = 0;
        self.counters = DmaSourceCounters::default();
        self.restart();
        self.lost_halves_before = 0;
        self.running = true;
        Ok(())
    }

    fn health(&self, health: &mut BoxHealth) {
        health.restarts = self.counters.resyncs;
        self.hardware.health(health);
    }

    fn stop(&mut self) {
        self.hardware.stop();
        self.running = false;
    }

    /// Delivers at most one half: the newest complete one.
    fn poll(&mut self, out: &mut SampleBuffer) {
        if !self.running {
            return;
        }
        out.clear();
        if self.hardware.sequence_faults() != self.faults_seen {
            self.resync();
            return;
        }
        let range = self.range;
        let mut saturated = [0u32; crate::source::CHANNELS];
        let taken = self.handover.take(&self.hardware, |_, codes| {
            // Cannot fail: a half holds at most BUFFER_VECTORS vectors.
            let _ = out
                .samples
                .push(scaling::to_volts(range, &codes, &mut saturated));
        });
        // A fault raised during the copy may lie in the half just copied
        // (a late read completes its half after it was counted).
        if self.hardware.sequence_faults() != self.faults_seen {
            out.clear();
            self.resync();
            return;
        }
        match taken {
            Taken::Nothing => {}
            Taken::Torn { lost } => {
                out.clear();
                self.lost = self.lost.saturating_add(lost);
                self.counters.overrun_halves =
                    (self.lost_halves_before + self.handover.lost_halves()) as u32;
                self.counters.torn_halves = self.counters.torn_halves.saturating_add(1);
            }
            Taken::Half {
                first_sample,
                lost_before,
            } => {
                out.saturated = saturated;
                let lost = self.lost.saturating_add(lost_before);
                self.lost = 0;
                out.lost_before = u32::try_from(lost).unwrap_or(u32::MAX);
                self.counters.overrun_halves =
                    (self.lost_halves_before + self.handover.lost_halves()) as u32;
                self.delivered_first = first_sample;
                let end = first_sample + out.samples.len() as u64;
                self.expected = end;
                self.attach_edges(out, first_sample, end);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::acquisition::handover::HalfCompletions;
    use crate::source::CHANNELS;
    use std::collections::VecDeque;

    /// Halves of 4 vectors whose codes are their sample number, captures
    /// queued by hand, 100 capture ticks per sample from origin 1000.
    struct Fake {
        done: HalfCompletions,
        captures: VecDeque<u32>,
        faults: u32,
    }

    impl DoubleBuffer for Fake {
        fn completed(&self) -> u32 {
            self.done.count()
        }
        fn read(&self, half: usize, vector: usize) -> [i16; CHANNELS] {
            // The newest half of a count n is n − 1; this fake is only read
            // for that one.
            let seq = self.done.count() as usize - 1;
            assert_eq!(seq % 2, half);
            [(seq * 4 + vector) as i16; CHANNELS]
        }
    }

    impl AcquisitionHardware for Fake {
        fn start(&mut self) -> u32 {
            self.done.reset();
            1000
        }
        fn stop(&mut self) {}
        fn take_capture(&mut self) -> Option<u32> {
            self.captures.pop_front()
        }
        fn sequence_faults(&self) -> u32 {
            self.faults
        }
    }

    fn source() -> DmaSource<Fake> {
        let fake = Fake {
            done: HalfCompletions::new(),
            captures: VecDeque::new(),
            faults: 0,
        };
        let mut s = DmaSource::new(fake, 4, 100, Range::PlusMinus10V);
        s.start().unwrap();
        s
    }

    #[test]
    fn edges_go_to_the_half_that_holds_the_sample_after_them() {
        let mut s = source();
        // 2.5 samples in (half 0), and 3.5 (after its last sample: half 1's
        // index 0).
        s.hardware.captures.extend([1250, 1350]);
        s.hardware.done.complete();
        let mut out = SampleBuffer::default();
        s.poll(&mut out);
        assert_eq!(out.samples.len(), 4);
        assert_eq!(out.edges.len(), 1);
        assert_eq!(out.edges[0].index, 3);
        assert!((out.edges[0].fraction - 0.505).abs() < 1e-6);
        s.hardware.done.complete();
        s.poll(&mut out);
        assert_eq!(
            out.samples[0][0],
            4.0 * Range::PlusMinus10V.volts_per_code()
        );
        assert_eq!(out.edges.len(), 1);
        assert_eq!(out.edges[0].index, 0);
        assert_eq!(s.counters(), DmaSourceCounters::default());
    }

    #[test]
    fn after_a_gap_the_interval_before_the_first_sample_is_not_data() {
        let mut s = source();
        s.hardware.done.complete();
        let mut out = SampleBuffer::default();
        s.poll(&mut out);
        // Halves 1 and 2 complete; 1 is lost. An edge in half 1, one in the
        // interval before half 2's first sample (8), one inside half 2.
        s.hardware
            .captures
            .extend([1000 + 550, 1000 + 750, 1000 + 920]);
        s.hardware.done.complete();
        s.hardware.done.complete();
        s.poll(&mut out);
        assert_eq!(out.lost_before, 4);
        assert_eq!(
            out.samples[0][0],
            8.0 * Range::PlusMinus10V.volts_per_code()
        );
        assert_eq!(out.edges.len(), 1);
        assert_eq!(out.edges[0].index, 2);
        assert_eq!(s.counters().dropped_edges, 2);
        assert_eq!(s.counters().overrun_halves, 1);
    }

    #[test]
    fn a_sequence_fault_restarts_and_reports_a_gap() {
        let mut s = source();
        s.hardware.done.complete();
        let mut out = SampleBuffer::default();
        s.poll(&mut out);
        s.hardware.faults = 1;
        s.poll(&mut out);
        assert!(out.is_empty());
        assert_eq!(s.counters().resyncs, 1);
        // Sample numbering starts again after the restart.
        s.hardware.done.complete();
        s.poll(&mut out);
        assert_eq!(out.samples.len(), 4);
        assert_eq!(out.samples[0][0], 0.0);
        assert!(out.lost_before >= 1);
    }
}
