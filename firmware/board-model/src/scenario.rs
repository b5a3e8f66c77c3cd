//! One acquisition on the model board with the firmware's real code: the
//! interrupt handlers of `plinth_firmware::acquisition::adc_dma` on their
//! IRQs and priorities, `DmaSource` over `AdcDma` in the idle thread, one
//! injected fault; every delivered sample checked against the model's
//! truth (which conversion, which channel), every loss against the
//! counters.

use crate::check::{Checker, Outcome};
use crate::hw::{filtered_captures, Hw, RAM_BASE};
use crate::sim::{Board, Handler, HandlerStats, Port};
use heapless::spsc::Queue;
use plinth_firmware::acquisition::adc_dma::{
    self, AdcDma, AdcShared, RestartPath, KEYPHASOR_FILTER_N, KEYPHASOR_FILTER_STEP,
};
use plinth_firmware::acquisition::dma_source::DmaSource;
use plinth_firmware::acquisition::read_plan::ReadPlan;
use plinth_firmware::acquisition::rm0090::nvic;
use plinth_firmware::ad7606::Range;
use plinth_firmware::revert::Revert;
use plinth_firmware::source::{SampleBuffer, SampleSource};
use plinth_firmware::watchdog::ProgressWatch;
use std::rc::Rc;

/// Capture queue slots (as on the box).
pub const CAPTURE_SLOTS: usize = 32;
/// Where the transmit DMA's dummy word lives in model RAM.
const DUMMY: usize = RAM_BASE;
/// Where the two ADC halves live in model RAM.
const ADC_MEMORY: usize = RAM_BASE + 0x100;
/// Idle-thread cycles per delivered sample vector besides the copy: the
/// scaling (QEMU-measured consumer 146.4 less the modelled reads) and the
/// extractor (77.7), firmware/README.md's budget.
pub const IDLE_CYCLES_PER_VECTOR: u64 = 220;
/// The idle loop's progress limit in the model [µs]: the box's 200 ms
/// scaled to the model's short halves (2.4 halves of 32 vectors; the
/// box's is 100 halves of 96).
pub const NO_PROGRESS_US: u32 = 1_500;
/// The model's independent watchdog timeout [µs] (the box's 500 ms,
/// scaled alike).
pub const WATCHDOG_US: u64 = 1_000;

/// The board's clocks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClockSetup {
    /// Core clock [Hz].
    pub sysclk_hz: u32,
    /// APB1 [Hz] (SPI2; timers at twice it when divided).
    pub pclk1_hz: u32,
}

impl ClockSetup {
    /// The PLL at 168 MHz, APB1 42 MHz (crystal or RC input alike).
    pub const PLL: ClockSetup = ClockSetup {
        sysclk_hz: 168_000_000,
        pclk1_hz: 42_000_000,
    };
    /// The 16 MHz RC alone (the PLL did not lock).
    pub const HSI: ClockSetup = ClockSetup {
        sysclk_hz: 16_000_000,
        pclk1_hz: 16_000_000,
    };

    /// The timers' clock [Hz].
    pub fn timer_hz(&self) -> u32 {
        plinth_firmware::acquisition::pacing::apb_timer_clock_hz(self.sysclk_hz, self.pclk1_hz)
    }
}

/// What goes wrong in a scenario.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fault {
    /// Nothing.
    None,
    /// Interrupts masked for `ticks` from `at`.
    Masked { at: u64, ticks: u64 },
    /// The host stops and starts acquisition at `at` (after `pause` ticks
    /// stopped).
    Restart { at: u64, pause: u64 },
    /// DMA requests not served for `ticks` from `at` (SPI overrun).
    DmaStall { at: u64, ticks: u64 },
    /// The host stops and starts acquisition 8 ticks into a DMA stall of
    /// `stall` ticks from `at` (a word the DMA did not take is in SPI2's
    /// DR when `stop` disables the requests).
    RestartInDmaStall { at: u64, stall: u64 },
    /// A transfer error on the receive stream at `at`.
    TransferError { at: u64 },
    /// BUSY stuck at `high` from `at`.
    BusyStuck { at: u64, high: bool },
    /// The keyphasor's pulses missing for `revolutions` from the second.
    KeyphasorMissing { revolutions: u32 },
    /// Each keyphasor edge bounces `bounces` times within 0.5 µs.
    KeyphasorBouncing { bounces: u32 },
    /// A keyphasor `hz` [Hz] fast (more edges than a buffer holds).
    KeyphasorFast { hz: f64 },
}

/// One scenario.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scenario {
    /// Name (in failure messages).
    pub name: &'static str,
    /// Index in its matrix.
    pub index: usize,
    /// Clocks.
    pub clocks: ClockSetup,
    /// AD7606 conversion time [ns].
    pub conversion_ns: u32,
    /// Sample vectors per DMA half.
    pub vectors_per_half: usize,
    /// Halves of run time.
    pub halves: u64,
    /// Keyphasor rate [Hz].
    pub keyphasor_hz: f64,
    /// The fault.
    pub fault: Fault,
    /// The restart path of `AdcDma`.
    pub path: RestartPath,
    /// The fix switched off (tests that show the matrix catches it).
    pub revert: Revert,
}

impl Scenario {
    /// A clean run of the reference board.
    pub fn clean(name: &'static str) -> Self {
        Self {
            name,
            index: 0,
            clocks: ClockSetup::PLL,
            conversion_ns: 4_000,
            vectors_per_half: 32,
            halves: 8,
            keyphasor_hz: 2_000.0,
            fault: Fault::None,
            path: RestartPath::Clean,
            revert: Revert::None,
        }
    }

    /// Whether the fault leaves the board unable to sample for good (only
    /// a watchdog reset gets it out).
    pub fn permanent(&self) -> bool {
        matches!(self.fault, Fault::BusyStuck { .. })
    }

    /// Ticks per sample at these clocks.
    pub fn ticks_per_sample(&self) -> u64 {
        ReadPlan::new(self.clocks.timer_hz(), self.clocks.pclk1_hz, 51_200.0)
            .map(|p| u64::from(p.timing.timer_ticks_per_sample))
            .unwrap_or(1641)
    }
}

/// The keyphasor input's transitions (tick, level) and its true rising
/// edges [ticks].
fn keyphasor(s: &Scenario, end: u64, timer_hz: u32) -> (Vec<(u64, bool)>, Vec<u64>) {
    let hz = match s.fault {
        Fault::KeyphasorFast { hz } => hz,
        _ => s.keyphasor_hz,
    };
    let period = (f64::from(timer_hz) / hz) as u64;
    let width = (period / 2).max(400);
    let (mut tr, mut edges) = (Vec::new(), Vec::new());
    let mut t = period / 3 + 1000;
    let mut n = 0u32;
    while t + width < end {
        n += 1;
        let skip = matches!(s.fault, Fault::KeyphasorMissing { revolutions } if n >= 2 && n < 2 + revolutions);
        if !skip {
            edges.push(t);
            tr.push((t, true));
            if let Fault::KeyphasorBouncing { bounces } = s.fault {
                // Toggles 2-6 ticks apart, within 0.5 µs.
                let mut b = t;
                for k in 0..bounces.min(20) {
                    b += 2 + u64::from(k % 5);
                    tr.push((b, k % 2 == 1));
                }
                if bounces % 2 == 1 {
                    b += 3;
                    tr.push((b, true));
                }
            }
            tr.push((t + width, false));
        }
        t += period;
    }
    (tr, edges)
}

/// Per-handler figures of a clean run (the budget table's source).
pub fn handler_stats(s: &Scenario) -> Vec<HandlerStats> {
    run_inner(s).1
}

/// Runs a scenario and checks it.
pub fn run(s: &Scenario) -> Outcome {
    run_inner(s).0
}

/// The box's acquisition side on a model board: the firmware's interrupt
/// handlers on their IRQs and priorities, `DmaSource` over `AdcDma` (not
/// yet started), the injected fault and the truth checker.
pub struct Rig {
    /// The board.
    pub board: Rc<Board>,
    /// What the handlers share with `AdcDma`.
    pub shared: &'static AdcShared,
    /// The source over the board.
    pub source: BoardSource,
    /// The truth checker.
    pub checker: Checker,
    /// Ticks per sample.
    pub p: u64,
    /// Ticks of run time.
    pub end: u64,
    /// The timers' clock [Hz].
    pub timer_hz: u32,
}

/// The box's sample source on the model board.
pub type BoardSource = DmaSource<AdcDma<Port, CAPTURE_SLOTS>>;

/// Builds the board for `s` (None: the box refuses to sample). `after_half`
/// runs in the `adc_half` interrupt after the firmware's handler (the box
/// pends its extraction task there).
pub fn rig(s: &Scenario, after_half: Option<Handler>) -> Option<Rig> {
    let timer_hz = s.clocks.timer_hz();
    let plan = ReadPlan::with_revert(timer_hz, s.clocks.pclk1_hz, 51_200.0, s.revert).ok()?;
    let p = u64::from(plan.timing.timer_ticks_per_sample);
    let half = p * s.vectors_per_half as u64;
    let end = half * s.halves + p;
    let hw = Hw::new(timer_hz, s.clocks.pclk1_hz, s.conversion_ns);
    let board = Board::new(hw, u64::from(s.clocks.sysclk_hz / timer_hz));
    let (transitions, pulses) = keyphasor(s, end + 10 * half + 1_000_000, timer_hz);
    {
        let mut hw = board.hw.borrow_mut();
        hw.capture_ticks = filtered_captures(
            &transitions,
            u64::from(KEYPHASOR_FILTER_STEP),
            u64::from(KEYPHASOR_FILTER_N),
        );
        match s.fault {
            Fault::DmaStall { at, ticks } => hw.faults.dma_stall = Some((at, at + ticks)),
            Fault::RestartInDmaStall { at, stall } => hw.faults.dma_stall = Some((at, at + stall)),
            Fault::TransferError { at } => hw.faults.transfer_error = Some(at),
            Fault::BusyStuck { at, high } => hw.faults.busy_stuck = Some((at, high)),
            _ => {}
        }
    }
    if let Fault::Masked { at, ticks } = s.fault {
        board.mask(at, ticks);
    }
    let shared: &'static AdcShared = Box::leak(Box::new(AdcShared::new()));
    let queue: &'static mut Queue<u32, CAPTURE_SLOTS> = Box::leak(Box::new(Queue::new()));
    let (mut producer, consumer) = queue.split();
    if s.path == RestartPath::Legacy {
        board.attach(
            nvic::IRQ_EXTI0,
            4,
            "busy_fell",
            Box::new(move |r| busy_fell_legacy(r, shared)),
        );
    } else {
        board.attach(
            nvic::IRQ_EXTI0,
            4,
            "busy_fell",
            Box::new(move |r| adc_dma::busy_fell(r, shared)),
        );
    }
    board.attach(
        nvic::IRQ_SPI2,
        4,
        "spi_error",
        Box::new(move |r| adc_dma::spi_error(r, shared)),
    );
    let mut after_half = after_half;
    board.attach(
        nvic::IRQ_DMA1_STREAM3,
        3,
        "adc_half",
        Box::new(move |r| {
            adc_dma::adc_half(r, shared);
            if let Some(h) = after_half.as_mut() {
                h(r);
            }
        }),
    );
    board.attach(
        nvic::IRQ_TIM5,
        3,
        "keyphasor",
        Box::new(move |r| adc_dma::keyphasor(r, shared, &mut producer)),
    );
    let mut dma = AdcDma::new(
        Port(board.clone()),
        shared,
        plan,
        ADC_MEMORY as u32,
        DUMMY as u32,
        s.vectors_per_half,
        consumer,
        s.path,
    );
    dma.revert(s.revert);
    let source = DmaSource::new(dma, s.vectors_per_half, p as u32, Range::PlusMinus10V);
    Some(Rig {
        board,
        shared,
        source,
        checker: Checker::new(p as f64, pulses),
        p,
        end,
        timer_hz,
    })
}

fn run_inner(s: &Scenario) -> (Outcome, Vec<HandlerStats>) {
    // The box refuses to sample (and says so): nothing delivered,
    // nothing lost unseen.
    let Some(rig) = rig(s, None) else {
        return (Outcome::refused(), Vec::new());
    };
    let Rig {
        board,
        shared,
        mut source,
        mut checker,
        p,
        end,
        timer_hz,
    } = rig;
    let mut buf = SampleBuffer::default();
    let _ = source.start();
    checker.started(board.hw.borrow().runs);
    let t0 = board.now();
    let mut restart = match s.fault {
        Fault::Restart { at, pause } => Some((t0 + at, pause)),
        Fault::RestartInDmaStall { at, .. } => Some((at + 8, 0)),
        _ => None,
    };
    let mut seen = shared.completions.count();
    let step = p / 2;
    // The idle loop's watchdog (model time in µs) and the model's IWDG.
    let us = |tick: u64| (tick as u128 * 1_000_000 / u128::from(timer_hz)) as u64;
    let mut watch = ProgressWatch::new(NO_PROGRESS_US).with_revert(s.revert);
    let mut fed = board.now();
    let mut last_delivery = board.now();
    let mut watchdog_reset = false;
    while board.now() < t0 + end {
        if watch.should_feed(true, shared.completions.count(), us(board.now()) as u32) {
            fed = board.now();
        }
        if us(board.now() - fed) > WATCHDOG_US {
            watchdog_reset = true;
            break;
        }
        if let Some((at, pause)) = restart {
            if board.now() + step >= at {
                board.run_until(at);
                source.stop();
                board.spend(pause * u64::from(s.clocks.sysclk_hz / timer_hz));
                let _ = source.start();
                checker.started(board.hw.borrow().runs);
                restart = None;
                last_delivery = board.now();
                seen = shared.completions.count();
                continue;
            }
        }
        board.spend(step * u64::from(s.clocks.sysclk_hz / timer_hz));
        // The idle loop wakes on every interrupt; it works when a half
        // completed (and looks for faults every pass).
        let done = shared.completions.count();
        buf.clear();
        source.poll(&mut buf);
        let counters = source.counters();
        if !buf.is_empty() {
            last_delivery = board.now();
            let hw = board.hw.borrow();
            checker.delivered(&hw, &buf, source.delivered_first_sample(), counters);
            drop(hw);
            board.spend(IDLE_CYCLES_PER_VECTOR * buf.samples.len() as u64);
        } else {
            checker.counters(counters);
        }
        if done != seen {
            seen = done;
        }
    }
    let hw = board.hw.borrow();
    let mut outcome = checker.finish(
        &hw,
        source.counters(),
        shared.faults(),
        p * (3 * s.vectors_per_half as u64 + 2),
        watchdog_reset,
    );
    drop(hw);
    // Recovery: a passing fault must not need the watchdog; a permanent
    // one must get it (the next boot reports it), never leave the box
    // running without samples.
    let silent_us = us(board.now() - last_delivery);
    if watchdog_reset && !s.permanent() {
        outcome.unrecovered += 1;
        outcome.problem(|| {
            format!(
                "reset by the watchdog after {silent_us} µs without a sample: the box neither recovered nor refused"
            )
        });
    } else if !watchdog_reset && silent_us > u64::from(NO_PROGRESS_US) + WATCHDOG_US {
        outcome.unrecovered += 1;
        outcome.problem(|| {
            format!("no sample for {silent_us} µs while acquiring, and no watchdog reset")
        });
    }
    outcome.watchdog_reset = watchdog_reset;
    if let Fault::Restart { .. } = s.fault {
        let n = shared.faults().sequence();
        if n > 0 {
            outcome.unclean += u64::from(n);
            outcome.problem(|| {
                format!("the commanded stop/restart was not clean: {n} sequence faults counted")
            });
        }
    }
    let stats = board.stats();
    drop(source);
    (outcome, stats)
}

/// The BUSY handler before issue 18, for [`RestartPath::Legacy`] runs: its
/// only check was "the transmit stream still runs"; no pending-bit check,
/// no slip or partial-read detector. Kept here (not in the firmware) so
/// that a test shows what the old restart path corrupts.
pub fn busy_fell_legacy(r: &mut Port, s: &AdcShared) {
    use plinth_firmware::acquisition::rm0090::{dma1, exti, gpiob};
    use plinth_firmware::clock::Registers;
    r.write(exti::PR, exti::LINE_BUSY);
    if r.read(dma1::cr(adc_dma::TX_STREAM)) & dma1::CR_EN != 0 {
        s.count_late_read();
        return;
    }
    let (_, ifcr, shift) = dma1::flags(adc_dma::TX_STREAM);
    r.write(ifcr, dma1::ALL_FLAGS << shift);
    r.write(gpiob::BSRR, gpiob::CS);
    let _ = r.read(gpiob::IDR);
    r.write(gpiob::BSRR, gpiob::CS << 16);
    r.write(dma1::ndtr(adc_dma::TX_STREAM), 8);
    let cr = r.read(dma1::cr(adc_dma::TX_STREAM));
    r.write(dma1::cr(adc_dma::TX_STREAM), cr | dma1::CR_EN);
}
