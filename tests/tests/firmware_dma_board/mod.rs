//! The simulated board of `plinth-box` for the acquisition tests: a CONVST
//! timer at the rate its settings really give, an SPI DMA filling a double
//! buffer one conversion at a time, a transfer-complete count, a 32-bit
//! capture timer latching keyphasor edges, and a consumer slowed down on
//! demand (each read of a vector lets time pass).
#![allow(dead_code)]

use crate::firmware_support::{Scenario, VOLTS_PER_CODE};
use plinth_firmware::acquisition::dma_source::{AcquisitionHardware, DmaSource};
use plinth_firmware::acquisition::handover::{DoubleBuffer, HalfCompletions};
use plinth_firmware::acquisition::pacing::ConvstTiming;
use plinth_firmware::ad7606::Range;
use plinth_firmware::source::{SampleBuffer, BUFFER_VECTORS, CHANNELS};
use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;

/// Timer clock of TIM3 (CONVST) and TIM5 (capture) on the box [Hz]:
/// APB1 at 42 MHz, timer clocks doubled.
pub const TIMER_HZ: u32 = 84_000_000;
/// Sample vectors per DMA half (as in plinth-box).
pub const HALF: usize = BUFFER_VECTORS;

/// The simulated board's state, shared by the DMA, the timers and the test.
pub struct State {
    pub scenario: Scenario,
    /// Capture ticks per sample.
    pub p: u64,
    /// Capture count at sample 0 (the 32-bit count wraps during the run).
    pub origin: u32,
    /// Ticks since power-up (the first start is at tick 0).
    pub now: u64,
    /// Tick of the current acquisition's sample 0.
    pub run_start: u64,
    /// Conversions of the current acquisition.
    pub run_converted: u64,
    /// Conversions since power-up (each one's number is in its codes).
    pub converted: u64,
    /// Tick of each conversion since power-up.
    pub ticks: Vec<u64>,
    /// Ticks of the scenario's run: conversions stop after it.
    pub end_tick: u64,
    /// Conversions in the run, if nothing restarts it.
    pub total: u64,
    /// A conversion that BUSY's interrupt misses (its words are never
    /// read: the later ones land one slot early), by number since power-up.
    pub skip: Option<u64>,
    /// Sequence faults so far.
    pub faults: u32,
    /// The DMA's two halves.
    pub memory: [[[i16; CHANNELS]; HALF]; 2],
    /// Half and vector the DMA writes next.
    pub half: usize,
    pub index: usize,
    pub completions: HalfCompletions,
    /// Ticks each read of a vector by the consumer lets pass (a consumer
    /// preempted by other work while copying).
    pub read_cost: u64,
    /// Captured, not yet taken keyphasor counts.
    pub captures: VecDeque<u32>,
    pub next_pulse: usize,
    /// Keyphasor edge times [s].
    pub pulses: Vec<f64>,
    pub running: bool,
}

impl State {
    pub fn rate(&self) -> f64 {
        f64::from(TIMER_HZ) / self.p as f64
    }

    /// Time passes: conversions land in the DMA halves, edges are captured.
    pub fn advance(&mut self, ticks: u64) {
        self.now += ticks;
        if !self.running {
            return;
        }
        loop {
            let tick = self.run_start + self.run_converted * self.p;
            if tick > self.now || tick > self.end_tick {
                break;
            }
            let k = self.converted;
            self.ticks.push(tick);
            self.converted += 1;
            self.run_converted += 1;
            if self.skip == Some(k) {
                self.faults += 1;
                continue;
            }
            self.memory[self.half][self.index] = codes(&self.scenario, k, tick);
            self.index += 1;
            if self.index == HALF {
                self.index = 0;
                self.half ^= 1;
                self.completions.complete();
            }
        }
        let tick_s = 1.0 / f64::from(TIMER_HZ);
        while let Some(&t) = self.pulses.get(self.next_pulse) {
            let tick = (t / tick_s).floor() as u64;
            if tick > self.now {
                break;
            }
            self.captures
                .push_back(self.origin.wrapping_add(tick as u32));
            self.next_pulse += 1;
        }
    }
}

/// The ADC codes of conversion k (since power-up) taken at `tick`: the
/// scenario's four probes quantised, then channels that make every vector
/// unique (k itself, split in two).
pub fn codes(scenario: &Scenario, k: u64, tick: u64) -> [i16; CHANNELS] {
    let v = scenario.volts(tick as f64 / f64::from(TIMER_HZ));
    let q = |x: f64| (x / VOLTS_PER_CODE).round().clamp(-32768.0, 32767.0) as i16;
    [
        q(v[0]),
        q(v[1]),
        q(v[2]),
        q(v[3]),
        (k % 30_000) as i16,
        (k / 30_000) as i16,
        -((k % 1000) as i16),
        0,
    ]
}

/// The board as the firmware sees it.
#[derive(Clone)]
pub struct Board(pub Rc<RefCell<State>>);

impl Board {
    pub fn new(scenario: Scenario, origin: u32) -> Self {
        let timing = ConvstTiming::for_rate(TIMER_HZ, 51_200.0, 16).unwrap();
        let p = u64::from(timing.timer_ticks_per_sample);
        let rate = f64::from(TIMER_HZ) / p as f64;
        Board(Rc::new(RefCell::new(State {
            scenario,
            p,
            origin,
            now: 0,
            run_start: 0,
            run_converted: 0,
            converted: 0,
            ticks: Vec::new(),
            end_tick: (scenario.duration_s * f64::from(TIMER_HZ)) as u64,
            total: (scenario.duration_s * rate) as u64 + 1,
            skip: None,
            faults: 0,
            memory: [[[0; CHANNELS]; HALF]; 2],
            half: 0,
            index: 0,
            completions: HalfCompletions::new(),
            read_cost: 0,
            captures: VecDeque::new(),
            next_pulse: 0,
            pulses: scenario.keyphasor_times(),
            running: false,
        })))
    }

    pub fn advance(&self, ticks: u64) {
        self.0.borrow_mut().advance(ticks);
    }
}

impl DoubleBuffer for Board {
    fn completed(&self) -> u32 {
        self.0.borrow().completions.count()
    }
    fn read(&self, half: usize, vector: usize) -> [i16; CHANNELS] {
        let mut s = self.0.borrow_mut();
        let cost = s.read_cost;
        s.advance(cost);
        s.memory[half][vector]
    }
}

impl AcquisitionHardware for Board {
    fn start(&mut self) -> u32 {
        let mut s = self.0.borrow_mut();
        s.running = true;
        s.completions.reset();
        // The DMA restarts at half 0.
        s.half = 0;
        s.index = 0;
        s.run_start = s.now;
        s.run_converted = 0;
        s.origin.wrapping_add(s.run_start as u32)
    }
    fn stop(&mut self) {
        self.0.borrow_mut().running = false;
    }
    fn take_capture(&mut self) -> Option<u32> {
        self.0.borrow_mut().captures.pop_front()
    }
    fn sequence_faults(&self) -> u32 {
        self.0.borrow().faults
    }
}

pub fn source(board: &Board) -> DmaSource<Board> {
    let p = board.0.borrow().p as u32;
    DmaSource::new(board.clone(), HALF, p, Range::PlusMinus10V)
}

/// Checks a delivered buffer against the conversions it claims to hold
/// (starting at `first`) and returns its edges' absolute sample positions.
pub fn check_buffer(board: &Board, buf: &SampleBuffer, first: u64) -> Vec<f64> {
    let s = board.0.borrow();
    let step = Range::PlusMinus10V.volts_per_code();
    for (i, v) in buf.samples.iter().enumerate() {
        let k = first + i as u64;
        let want = codes(&s.scenario, k, s.ticks[k as usize]).map(|c| f32::from(c) * step);
        assert_eq!(
            *v,
            want,
            "vector {i} of the buffer from sample {first}: not conversion {}",
            first + i as u64
        );
    }
    buf.edges
        .iter()
        .map(|e| {
            assert!(e.index < buf.samples.len());
            assert!(e.fraction > 0.0 && e.fraction < 1.0);
            (first + e.index as u64) as f64 - 1.0 + f64::from(e.fraction)
        })
        .collect()
}
