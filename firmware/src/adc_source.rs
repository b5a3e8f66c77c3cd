//! The ADC sample source: paces AD7606 conversions from a free-running
//! capture timer and attaches the keyphasor edges that the same timer
//! captured, with their sub-sample position.

use crate::ad7606::{Ad7606, ADC_CHANNELS};
use crate::source::{SampleBuffer, SampleSource, CHANNELS};
use embedded_hal::digital::{InputPin, OutputPin};
use embedded_hal::spi::SpiDevice;
use plinth_shared::extractor::KeyphasorEdge;
use plinth_shared::protocol::NackReason;

const _: () = assert!(ADC_CHANNELS == CHANNELS);

/// A free-running 32-bit timer whose input capture timestamps the
/// keyphasor pulses (e.g. TIM2 on an STM32F4).
pub trait CaptureTimer {
    /// The timer's current count [ticks].
    fn now(&mut self) -> u32;
    /// The oldest captured keyphasor edge not yet taken [ticks], if any.
    fn take_edge(&mut self) -> Option<u32>;
}

/// Counts of what the ADC source could not deliver.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AdcSourceCounters {
    /// Conversions that failed (SPI, pin or BUSY timeout).
    pub conversion_errors: u32,
    /// Sample slots missed because the loop came too late.
    pub missed_samples: u32,
    /// Keyphasor edges dropped (before the first sample or out of order).
    pub dropped_edges: u32,
}

/// Samples the AD7606 every `ticks_per_sample` timer ticks.
#[derive(Debug)]
pub struct AdcSource<SPI, CONVST, BUSY, TIM> {
    adc: Ad7606<SPI, CONVST, BUSY>,
    timer: TIM,
    ticks_per_sample: u32,
    next_due: u32,
    /// Timer count at the previous conversion.
    last_stamp: Option<u32>,
    /// An edge captured after the latest conversion: for the next sample.
    held_edge: Option<u32>,
    /// Sample slots skipped since the last delivered buffer.
    lost: u32,
    running: bool,
    /// What went wrong so far.
    pub counters: AdcSourceCounters,
}

impl<SPI, CONVST, BUSY, TIM, P> AdcSource<SPI, CONVST, BUSY, TIM>
where
    SPI: SpiDevice,
    CONVST: OutputPin<Error = P>,
    BUSY: InputPin<Error = P>,
    TIM: CaptureTimer,
{
    /// A source converting every `ticks_per_sample` ticks of `timer`
    /// (timer clock / sample rate, e.g. 84 MHz / 51.2 kHz ≈ 1641).
    pub fn new(adc: Ad7606<SPI, CONVST, BUSY>, timer: TIM, ticks_per_sample: u32) -> Self {
        Self {
            adc,
            timer,
            ticks_per_sample: ticks_per_sample.max(1),
            next_due: 0,
            last_stamp: None,
            held_edge: None,
            lost: 0,
            running: false,
            counters: AdcSourceCounters::default(),
        }
    }

    /// The ADC (for its range).
    pub fn adc(&self) -> &Ad7606<SPI, CONVST, BUSY> {
        &self.adc
    }

    /// Attaches the edges up to the conversion at `stamp` to sample `index`.
    fn attach_edges(&mut self, out: &mut SampleBuffer, index: usize, stamp: u32) {
        loop {
            let Some(edge) = self.held_edge.take().or_else(|| self.timer.take_edge()) else {
                return;
            };
            if stamp.wrapping_sub(edge) as i32 <= 0 {
                // At or after this conversion: belongs to the next interval.
                self.held_edge = Some(edge);
                return;
            }
            let Some(last) = self.last_stamp else {
                // Before the first sample (or a gap): no interval to place it in.
                self.counters.dropped_edges += 1;
                continue;
            };
            let from_last = edge.wrapping_sub(last) as i32;
            if from_last < 0 {
                self.counters.dropped_edges += 1;
                continue;
            }
            let span = stamp.wrapping_sub(last) as f32;
            let fraction = (from_last as f32 / span).clamp(0.0, 0.999_999);
            if out.edges.push(KeyphasorEdge { index, fraction }).is_err() {
                self.counters.dropped_edges += 1;
            }
        }
    }
}

impl<SPI, CONVST, BUSY, TIM, P> SampleSource for AdcSource<SPI, CONVST, BUSY, TIM>
where
    SPI: SpiDevice,
    CONVST: OutputPin<Error = P>,
    BUSY: InputPin<Error = P>,
    TIM: CaptureTimer,
{
    fn start(&mut self) -> Result<(), NackReason> {
        self.next_due = self.timer.now();
        self.last_stamp = None;
        self.held_edge = None;
        self.lost = 0;
        // Edges captured while stopped are stale.
        while self.timer.take_edge().is_some() {}
        self.running = true;
        Ok(())
    }

    fn stop(&mut self) {
        self.running = false;
    }

    fn poll(&mut self, out: &mut SampleBuffer) {
        if !self.running {
            return;
        }
        while !out.is_full() {
            let now = self.timer.now();
            let late = now.wrapping_sub(self.next_due);
            if (late as i32) < 0 {
                return; // next conversion not due yet
            }
            if late >= self.ticks_per_sample {
                if !out.is_empty() {
                    return; // deliver what is consistent; the gap starts the next buffer
                }
                let missed = late / self.ticks_per_sample;
                self.lost = self.lost.saturating_add(missed);
                self.counters.missed_samples = self.counters.missed_samples.saturating_add(missed);
                self.next_due = self
                    .next_due
                    .wrapping_add(missed.wrapping_mul(self.ticks_per_sample));
                // The time base broke: the interval before the next sample
                // is not one sample period.
                self.last_stamp = None;
            }
            let stamp = now;
            self.next_due = self.next_due.wrapping_add(self.ticks_per_sample);
            match self.adc.convert() {
                Ok(codes) => {
                    if out.is_empty() {
                        out.lost_before = core::mem::take(&mut self.lost);
                    }
                    for (n, &c) in codes.iter().enumerate() {
                        if c == i16::MAX || c == i16::MIN {
                            out.saturated[n] += 1;
                        }
                    }
                    let volts = self.adc.to_volts(&codes);
                    let index = out.samples.len();
                    // Cannot fail: the loop runs only while not full.
                    let _ = out.samples.push(volts);
                    self.attach_edges(out, index, stamp);
                    self.last_stamp = Some(stamp);
                }
                Err(_) => {
                    self.counters.conversion_errors += 1;
                    self.lost = self.lost.saturating_add(1);
                    self.last_stamp = None;
                    if !out.is_empty() {
                        return;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::ad7606::Range;
    use embedded_hal_mock::eh1::digital::{
        Mock as PinMock, State as PinState, Transaction as PinTransaction,
    };
    use embedded_hal_mock::eh1::spi::{Mock as SpiMock, Transaction as SpiTransaction};
    use std::collections::VecDeque;
    use std::vec::Vec;

    /// A timer whose count advances by a script, with queued captures.
    struct ScriptedTimer {
        counts: VecDeque<u32>,
        edges: VecDeque<u32>,
    }

    impl CaptureTimer for ScriptedTimer {
        fn now(&mut self) -> u32 {
            self.counts
                .pop_front()
                .expect("timer read more often than scripted")
        }
        fn take_edge(&mut self) -> Option<u32> {
            self.edges.pop_front()
        }
    }

    /// Mocks for `n` conversions returning channel k = sample index + k.
    fn adc_for(n: usize) -> (SpiMock<u8>, PinMock, PinMock) {
        let mut spi = Vec::new();
        let mut convst = std::vec![PinTransaction::set(PinState::Low)];
        let mut busy = Vec::new();
        for i in 0..n {
            let codes: Vec<u8> = (0..8)
                .flat_map(|k| ((i * 10 + k) as i16).to_be_bytes())
                .collect();
            spi.extend([
                SpiTransaction::transaction_start(),
                SpiTransaction::read_vec(codes),
                SpiTransaction::transaction_end(),
            ]);
            convst.extend([
                PinTransaction::set(PinState::Low),
                PinTransaction::set(PinState::High),
                PinTransaction::set(PinState::Low),
            ]);
            busy.push(PinTransaction::get(PinState::Low));
        }
        (
            SpiMock::new(&spi),
            PinMock::new(&convst),
            PinMock::new(&busy),
        )
    }

    #[test]
    fn paces_conversions_and_places_keyphasor_edges_between_samples() {
        let (mut spi, mut convst, mut busy) = adc_for(3);
        let adc = Ad7606::new(
            spi.clone(),
            convst.clone(),
            busy.clone(),
            Range::PlusMinus10V,
            10,
        )
        .unwrap();
        // 100 ticks per sample from t = 1000. Reads: start, then per loop
        // pass one `now`: 1000 (due), 1100 (due), 1150 (not yet), then in a
        // second poll 1200 (due), 1250 (not yet).
        let timer = ScriptedTimer {
            counts: [1000, 1000, 1100, 1150, 1200, 1250].into(),
            // Stale: captured while stopped, drained by start().
            edges: [500, 700].into(),
        };
        let mut source = AdcSource::new(adc, timer, 100);
        source.start().unwrap();
        assert!(source.timer.edges.is_empty());
        // An edge 30 % into the first interval, one exactly on the third
        // sample (it belongs to the interval after it).
        source.timer.edges = [1030, 1200].into();
        let mut out = SampleBuffer::default();
        source.poll(&mut out);
        assert_eq!(out.samples.len(), 2);
        assert_eq!(
            out.samples[1][2],
            12.0 * Range::PlusMinus10V.volts_per_code()
        );
        assert_eq!(out.edges.len(), 1);
        assert_eq!(out.edges[0].index, 1);
        assert!((out.edges[0].fraction - 0.3).abs() < 1e-6);
        out.clear();
        source.poll(&mut out);
        assert_eq!(out.samples.len(), 1);
        // The edge at the third conversion's stamp waits for the next interval.
        assert!(out.edges.is_empty());
        assert_eq!(source.held_edge, Some(1200));
        assert_eq!(source.counters, AdcSourceCounters::default());
        spi.done();
        convst.done();
        busy.done();
    }

    #[test]
    fn a_late_loop_counts_missed_samples_and_marks_the_gap() {
        let (mut spi, mut convst, mut busy) = adc_for(1);
        let adc = Ad7606::new(
            spi.clone(),
            convst.clone(),
            busy.clone(),
            Range::PlusMinus10V,
            10,
        )
        .unwrap();
        // Start at 0; the loop comes back at 350: slots 0, 100, 200 missed,
        // the conversion at 350 stands for slot 300; then 390 is not due.
        let timer = ScriptedTimer {
            counts: [0, 350, 390].into(),
            edges: VecDeque::new(),
        };
        let mut source = AdcSource::new(adc, timer, 100);
        source.start().unwrap();
        let mut out = SampleBuffer::default();
        source.poll(&mut out);
        assert_eq!(out.samples.len(), 1);
        assert_eq!(out.lost_before, 3);
        assert_eq!(source.counters.missed_samples, 3);
        spi.done();
        convst.done();
        busy.done();
    }
}
