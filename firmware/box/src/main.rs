//! `plinth-box`: the Plinth field box on a real board, sampling real
//! sensors.
//!
//! Reference hardware: an STM32F407G-DISC1 ("STM32F4DISCOVERY": STM32F407VG,
//! 8 MHz crystal, ST-LINK/V2-A on board for probe-rs) and a common AD7606
//! module in serial mode. Wiring, flashing and the hardware-in-the-loop
//! procedure: firmware/README.md.
//!
//! | signal | MCU pin | peripheral |
//! | --- | --- | --- |
//! | AD7606 CONVST A+B | PC6 | TIM3_CH1 (AF2), PWM mode 2 |
//! | AD7606 BUSY | PB0 | EXTI0, falling edge |
//! | AD7606 SCLK (RD) | PB13 | SPI2_SCK (AF5) |
//! | AD7606 DOUTA (DB7) | PB14 | SPI2_MISO (AF5) |
//! | (unused MOSI) | PB15 | SPI2_MOSI (AF5) |
//! | AD7606 CS | PB12 | GPIO output |
//! | AD7606 RESET | PB1 | GPIO output |
//! | keyphasor (3.3 V logic) | PA1 | TIM5_CH2 (AF2), rising edge |
//! | host TX / RX | PA2 / PA3 | USART2 (AF7) |
//! | LEDs | PD12 green, PD14 red | GPIO |
//!
//! Real-time structure (RTIC 2, priorities high to low; the handler bodies
//! are the library's, `plinth_firmware::acquisition::adc_dma` and
//! `plinth_firmware::uart_dma`, which the host's board model runs):
//! - 4: `busy_fell` (EXTI0: starts each 8-word SPI DMA read, slip and
//!   late-read detectors) and `spi_error` (SPI2 overrun);
//! - 3: `adc_half` (SPI receive DMA: a half is complete), `keyphasor`
//!   (TIM5 capture), `host_rx_half` (host-link receive DMA) and `tick`
//!   (1 ms): each a few dozen cycles, above the device's lock so that a
//!   long protocol pass never delays the millisecond count;
//! - 2: `extract` (pended by each completed half: the phasor extractor
//!   and the pipeline, on its own state, `plinth_firmware::device::Extraction`);
//! - 1: `process` (pended by received bytes and the tick): the protocol
//!   (`Session`, its own), status frames and the link. It shares the
//!   extraction state, the source and the outbox with `extract` (ceiling 2)
//!   and takes each for one short section only (a command, a status
//!   snapshot, one frame, one 64-byte chunk to the link), so `extract` waits
//!   for at most one such section, never for a protocol pass
//!   (firmware/README.md, "Who waits for whom").
//! - idle: the watchdog (fed only while acquisition progresses or is
//!   stopped on purpose), the LEDs and the once-a-second log.
//!
//! Logging: the field image (default features) has a logger that writes
//! nowhere and masks nothing. The `log` feature (and `bench`) logs over
//! defmt-rtt, which masks interrupts while it writes a frame: a mask long
//! enough to merge two BUSY edges is caught by the slip detector and
//! becomes a counted restart (the board model's fault matrix covers masks
//! up to 100 µs), never a shifted sample.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("plinth-box is an MCU image: build it with `bash scripts/build-box.sh`");
    std::process::exit(2);
}

#[cfg(target_os = "none")]
mod adc_dma;
#[cfg(target_os = "none")]
mod cycles;
#[cfg(target_os = "none")]
mod panic_record;
#[cfg(target_os = "none")]
mod serial;

#[cfg(all(target_os = "none", feature = "log"))]
use defmt_rtt as _;

/// The field image's logger (no `log` feature): takes no critical section
/// and writes nowhere, so logging can never hold BUSY's interrupt off.
#[cfg(all(target_os = "none", not(feature = "log")))]
mod silent_log {
    #[defmt::global_logger]
    struct Silent;

    // SAFETY: nothing is shared: every method does nothing.
    unsafe impl defmt::Logger for Silent {
        fn acquire() {}
        unsafe fn flush() {}
        unsafe fn release() {}
        unsafe fn write(_bytes: &[u8]) {}
    }
}

/// Records, logs and resets: the next boot reports the record. A panic
/// while panicking resets at once.
#[cfg(target_os = "none")]
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    if panic_record::begin() {
        panic_record::write_panic(info);
        defmt::error!(
            "panic: {=str}",
            info.message().as_str().unwrap_or("(formatted message)")
        );
    }
    cortex_m::peripheral::SCB::sys_reset()
}

/// A hard fault: records the faulting PC and resets.
#[cfg(target_os = "none")]
#[cortex_m_rt::exception]
unsafe fn HardFault(frame: &cortex_m_rt::ExceptionFrame) -> ! {
    if panic_record::begin() {
        panic_record::write(panic_record::Kind::HardFault, "", frame.pc(), "hard fault");
    }
    cortex_m::peripheral::SCB::sys_reset()
}

#[cfg(target_os = "none")]
#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use crate::adc_dma::{self, BoxAdc, CAPTURE_SLOTS, HALF_VECTORS, SHARED};
    use crate::serial::{self, BoxSerial};
    use crate::{cycles, panic_record};
    use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};
    use heapless::spsc::{Producer, Queue};
    use plinth_firmware::acquisition::adc_dma as acq;
    use plinth_firmware::acquisition::dma_source::DmaSource;
    use plinth_firmware::acquisition::pacing::apb_timer_clock_hz;
    use plinth_firmware::acquisition::read_plan::ReadPlan;
    use plinth_firmware::ad7606::Range;
    use plinth_firmware::device::{
        capabilities_at, Extraction, Lock, Outbox, Session, Shared as ProtocolShared,
        SAMPLE_RATE_HZ,
    };
    use plinth_firmware::source::Refusable;
    use plinth_firmware::stm32::{configure_clocks, Mmio};
    use plinth_firmware::uart_dma;
    use plinth_firmware::watchdog::ProgressWatch;
    use plinth_shared::protocol::PreviousReset;
    use stm32f4xx_hal::gpio::{Edge, ExtiPin, Output, PushPull, Speed, PD12, PD14};
    use stm32f4xx_hal::pac;
    use stm32f4xx_hal::prelude::*;
    use stm32f4xx_hal::rcc::{Enable, Reset};
    use stm32f4xx_hal::watchdog::IndependentWatchdog;

    /// The board's crystal [Hz].
    const HSE_HZ: u32 = 8_000_000;
    /// Host link speed [bit/s] (as `plinth stream --baud`).
    const BAUD: u32 = 115_200;
    /// Watchdog timeout [ms]: far above one pass of any task.
    const WATCHDOG_MS: u32 = 500;
    /// Running acquisition may go this long without a completed half
    /// before the watchdog is starved [ms] (a half is 1.9 ms; restarts
    /// after a fault take ≤ 10 ms).
    const NO_PROGRESS_MS: u32 = 200;
    /// The AD7606 module's RANGE jumper (±10 V).
    const RANGE: Range = Range::PlusMinus10V;

    /// Milliseconds since boot (the SysTick task).
    static UPTIME_MS: AtomicU32 = AtomicU32::new(0);
    /// Whether acquisition runs (written by `process`).
    static RUNNING: AtomicBool = AtomicBool::new(false);

    /// The board's sample source.
    type Source = Refusable<DmaSource<BoxAdc>>;

    #[shared]
    struct Shared {
        extraction: &'static mut Extraction,
        source: Source,
        outbox: &'static mut Outbox,
    }

    #[local]
    struct Local {
        captures: Producer<'static, u32, CAPTURE_SLOTS>,
        session: &'static mut Session,
        link: BoxSerial,
        watchdog: IndependentWatchdog,
        green: PD12<Output<PushPull>>,
        red: PD14<Output<PushPull>>,
    }

    #[init(local = [queue: Queue<u32, CAPTURE_SLOTS> = Queue::new()])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let mut cp = cx.core;
        let mut dp = cx.device;
        // The project's clock bring-up (bounded waits, HSI fallback; tested
        // on a simulated RCC): the HAL's `freeze` waits for the crystal
        // without a bound.
        let clocks = configure_clocks(Some(HSE_HZ));
        let reset_by_watchdog = dp.RCC.csr().read().wdgrstf().bit_is_set();
        dp.RCC.csr().modify(|_, w| w.rmvf().set_bit());
        let mut rcc = dp.RCC.constrain();
        let mut previous = PreviousReset::Normal;
        if let Some(r) = panic_record::take() {
            r.with_text(|file, message| {
                defmt::error!(
                    "the previous boot ended in a {}: {=str}:{=u32}: {=str}",
                    r.kind(),
                    file,
                    r.line(),
                    message
                )
            });
            previous = match r.kind() {
                panic_record::Kind::Panic => PreviousReset::Panic,
                panic_record::Kind::HardFault => PreviousReset::HardFault,
            };
        } else if reset_by_watchdog {
            defmt::error!("the previous boot was reset by the watchdog");
            previous = PreviousReset::Watchdog;
        }
        #[cfg(feature = "bench")]
        {
            cp.DCB.enable_trace();
            cp.DWT.enable_cycle_counter();
        }
        let mut syscfg = dp.SYSCFG.constrain(&mut rcc);
        let gpioa = dp.GPIOA.split(&mut rcc);
        let gpiob = dp.GPIOB.split(&mut rcc);
        let gpioc = dp.GPIOC.split(&mut rcc);
        let gpiod = dp.GPIOD.split(&mut rcc);

        // AD7606: reset pulse (≥ 50 ns) after power-up, CS idle high.
        let mut reset = gpiob.pb1.into_push_pull_output();
        reset.set_high();
        cortex_m::asm::delay(100);
        reset.set_low();
        // SCK at up to 21 MHz and the 107 ns CONVST pulse need fast edges
        // (the reset speed, Low, is specified to 2-8 MHz).
        let mut cs = gpiob.pb12.into_push_pull_output().speed(Speed::VeryHigh);
        cs.set_high();
        let _convst = gpioc.pc6.into_alternate::<2>().speed(Speed::VeryHigh);
        let _sck = gpiob.pb13.into_alternate::<5>().speed(Speed::VeryHigh);
        let _miso = gpiob.pb14.into_alternate::<5>();
        let _mosi = gpiob.pb15.into_alternate::<5>();
        let _keyphasor = gpioa.pa1.into_alternate::<2>();
        let _host_tx = gpioa.pa2.into_alternate::<7>();
        let _host_rx = gpioa.pa3.into_alternate::<7>();
        // BUSY on EXTI0, falling edge; `AdcDma` unmasks it in `start`.
        let mut busy = gpiob.pb0.into_pull_down_input();
        busy.make_interrupt_source(&mut syscfg);
        busy.trigger_on_edge(&mut dp.EXTI, Edge::Falling);

        for enable in [
            <pac::TIM3 as Enable>::enable,
            <pac::TIM5 as Enable>::enable,
            <pac::SPI2 as Enable>::enable,
            <pac::USART2 as Enable>::enable,
            <pac::DMA1 as Enable>::enable,
        ] {
            enable(&mut rcc);
        }
        <pac::TIM3 as Reset>::reset(&mut rcc);
        <pac::TIM5 as Reset>::reset(&mut rcc);
        <pac::SPI2 as Reset>::reset(&mut rcc);

        let timer_hz = apb_timer_clock_hz(clocks.sysclk_hz, clocks.pclk1_hz);
        let (producer, consumer) = cx.local.queue.split();
        let (source, rate) =
            match ReadPlan::new(timer_hz, clocks.pclk1_hz, f64::from(SAMPLE_RATE_HZ)) {
                Ok(plan) => {
                    let p = plan.timing.timer_ticks_per_sample;
                    let rate = plan.timing.achieved_rate_hz as f32;
                    let hardware = adc_dma::new(plan, consumer);
                    defmt::info!("acquisition: {}", plan);
                    (
                        Refusable(Some(DmaSource::new(hardware, HALF_VECTORS, p, RANGE))),
                        rate,
                    )
                }
                Err(e) => {
                    defmt::error!(
                        "cannot sample at {=u32} Hz on {}: {} (Start is refused)",
                        SAMPLE_RATE_HZ as u32,
                        clocks.source,
                        e
                    );
                    (Refusable(None), SAMPLE_RATE_HZ)
                }
            };
        let link = serial::new(clocks.pclk1_hz, BAUD);
        // Statics (counted by `size`), not stack.
        let session = cortex_m::singleton!(: Session =
            Session::new(capabilities_at(RANGE.volts_per_code(), rate)));
        let extraction = cortex_m::singleton!(: Extraction = Extraction::new());
        let outbox = cortex_m::singleton!(: Outbox = Outbox::new());
        let (Some(session), Some(extraction), Some(outbox)) = (session, extraction, outbox) else {
            defmt::panic!("device parts taken twice")
        };
        session.set_platform(clocks.source.sample_clock(), previous);

        // 1 kHz tick.
        cp.SYST
            .set_clock_source(cortex_m::peripheral::syst::SystClkSource::Core);
        cp.SYST.set_reload(clocks.sysclk_hz / 1000 - 1);
        cp.SYST.clear_current();
        cp.SYST.enable_interrupt();
        cp.SYST.enable_counter();

        // Keep the debug port (RTT, probe-rs) alive while idle sleeps in WFI.
        dp.DBGMCU.cr().modify(|_, w| w.dbg_sleep().set_bit());
        let mut watchdog = IndependentWatchdog::new(dp.IWDG);
        watchdog.stop_on_debug(&dp.DBGMCU, true);
        watchdog.start(WATCHDOG_MS.millis());

        defmt::info!(
            "plinth-box {=str} up: clocks {} ({=f32} Hz)",
            env!("CARGO_PKG_VERSION"),
            clocks,
            rate
        );
        (
            Shared {
                extraction,
                source,
                outbox,
            },
            Local {
                captures: producer,
                session,
                link,
                watchdog,
                green: gpiod.pd12.into_push_pull_output(),
                red: gpiod.pd14.into_push_pull_output(),
            },
        )
    }

    /// The watchdog (fed only while acquisition progresses or is stopped
    /// on purpose), the LEDs and the once-a-second fault log; sleeps
    /// between interrupts.
    #[idle(local = [watchdog, green, red])]
    fn idle(cx: idle::Context) -> ! {
        let mut watch = ProgressWatch::new(NO_PROGRESS_MS);
        let mut last_report_ms = 0u32;
        let mut reported = acq::AdcFaults::default();
        loop {
            let now = UPTIME_MS.load(Ordering::Relaxed);
            let running = RUNNING.load(Ordering::Relaxed);
            if watch.should_feed(running, SHARED.completions.count(), now) {
                cx.local.watchdog.feed();
            }
            if now.wrapping_sub(last_report_ms) >= 1000 {
                last_report_ms = now;
                let faults = SHARED.faults();
                if faults != reported {
                    reported = faults;
                    defmt::warn!("acquisition faults: {}", faults);
                }
                cx.local.red.set_state((faults.sequence() != 0).into());
                if running {
                    cx.local.green.toggle();
                } else {
                    cx.local.green.set_low();
                }
                #[cfg(feature = "bench")]
                report_cycles(now);
            }
            cortex_m::asm::wfi();
        }
    }

    /// The extraction: each completed DMA half through the phasor
    /// extractor and the pipeline (priority 2: above the protocol and idle,
    /// below every acquisition interrupt; pended by `adc_half`).
    /// (At priority 2 every lock below is free: `extract` is the highest
    /// priority that uses these resources.)
    #[task(binds = USART3, priority = 2, shared = [extraction, source, outbox])]
    fn extract(cx: extract::Context) {
        let extract::SharedResources {
            mut extraction,
            mut source,
            outbox,
            ..
        } = cx.shared;
        let mut outbox = Held(outbox);
        extraction.lock(|extraction| {
            source.lock(|source| {
                cycles::EXTRACT.measure(|| extraction.run(source, &mut outbox));
            })
        });
    }

    /// The protocol (commands, status frames, the link) on whatever the
    /// interrupts handed over (priority 1: above idle, below the
    /// extraction and every acquisition interrupt). Its own state is
    /// local; what it shares with `extract` it locks one short section at
    /// a time (`ProtocolShared for BoxShared`).
    #[task(binds = USART1, priority = 1, shared = [extraction, source, outbox], local = [session, link])]
    fn process(cx: process::Context) {
        let link = cx.local.link;
        let now = UPTIME_MS.load(Ordering::Relaxed);
        let process::SharedResources {
            extraction,
            source,
            outbox,
            ..
        } = cx.shared;
        let mut shared = BoxShared {
            extraction,
            source,
            outbox,
        };
        cycles::POLL.measure(|| cx.local.session.poll(link, &mut shared, now));
        let running = shared.acquisition(|e, _| e.running());
        RUNNING.store(running, Ordering::Relaxed);
        link.kick();
    }

    /// An RTIC resource as the library's [`Lock`].
    struct Held<M>(M);

    impl<T: 'static, M: rtic::Mutex<T = &'static mut T>> Lock for Held<M> {
        type Target = T;
        fn lock<R>(&mut self, f: impl FnOnce(&mut T) -> R) -> R {
            self.0.lock(|t| f(t))
        }
    }

    /// What `process` shares with `extract`, each access one RTIC lock
    /// (raises the priority to the ceiling, 2, for the closure only).
    struct BoxShared<E, S, O> {
        extraction: E,
        source: S,
        outbox: O,
    }

    impl<E, S, O> ProtocolShared for BoxShared<E, S, O>
    where
        E: rtic::Mutex<T = &'static mut Extraction>,
        S: rtic::Mutex<T = Source>,
        O: rtic::Mutex<T = &'static mut Outbox>,
    {
        type Source = Source;
        fn acquisition<R>(&mut self, f: impl FnOnce(&mut Extraction, &mut Source) -> R) -> R {
            let source = &mut self.source;
            self.extraction
                .lock(|extraction| source.lock(|source| f(extraction, source)))
        }
        fn outbox<R>(&mut self, f: impl FnOnce(&mut Outbox) -> R) -> R {
            self.outbox.lock(|o| f(o))
        }
        /// `extract` runs the extraction in its own task.
        fn extract_inline(&mut self) -> usize {
            0
        }
    }

    /// Runs `process` (after the pending interrupts above it).
    fn pend_process() {
        rtic::pend(pac::Interrupt::USART1);
    }

    /// Runs `extract` (after the pending interrupts above it).
    fn pend_extract() {
        rtic::pend(pac::Interrupt::USART3);
    }

    /// One line per task and second: `BENCH <task> calls <n> cycles <sum>
    /// max <longest>` (firmware/README.md, "Cycle budget on the board").
    #[cfg(feature = "bench")]
    fn report_cycles(now_ms: u32) {
        defmt::println!("BENCH t_ms {=u32}", now_ms);
        for m in cycles::ALL {
            let (calls, sum, max) = m.take();
            defmt::println!(
                "BENCH {=str} calls {=u32} cycles {=u32} max {=u32}",
                m.name,
                calls,
                sum,
                max
            );
        }
    }

    /// BUSY fell: the conversion is done; clock its 8 words out by DMA.
    #[task(binds = EXTI0, priority = 4)]
    fn busy_fell(_: busy_fell::Context) {
        cycles::BUSY.measure(|| acq::busy_fell(&mut Mmio, &SHARED));
    }

    /// SPI2 overran (or a mode fault).
    #[task(binds = SPI2, priority = 4)]
    fn spi_error(_: spi_error::Context) {
        acq::spi_error(&mut Mmio, &SHARED);
    }

    /// The SPI receive DMA filled a half (or failed).
    #[task(binds = DMA1_STREAM3, priority = 3)]
    fn adc_half(_: adc_half::Context) {
        cycles::HALF.measure(|| acq::adc_half(&mut Mmio, &SHARED));
        pend_extract();
    }

    /// A keyphasor edge was captured.
    #[task(binds = TIM5, priority = 3, local = [captures])]
    fn keyphasor(cx: keyphasor::Context) {
        cycles::KEYPHASOR.measure(|| acq::keyphasor(&mut Mmio, &SHARED, cx.local.captures));
    }

    /// The host link's receive DMA passed half its ring.
    #[task(binds = DMA1_STREAM5, priority = 3)]
    fn host_rx_half(_: host_rx_half::Context) {
        uart_dma::host_rx_half(&mut Mmio, &serial::RX_HALVES);
        pend_process();
    }

    /// Milliseconds since boot; the protocol's pass every millisecond.
    #[task(binds = SysTick, priority = 3)]
    fn tick(_: tick::Context) {
        cycles::TICK.measure(|| {
            UPTIME_MS.store(
                UPTIME_MS.load(Ordering::Relaxed).wrapping_add(1),
                Ordering::Relaxed,
            )
        });
        pend_process();
    }
}
