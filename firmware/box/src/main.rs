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
//! Real-time structure (RTIC 2, priorities high to low): BUSY interrupt
//! (starts each 8-word SPI DMA read) 4; SPI receive DMA half complete and
//! keyphasor capture 3; host-link receive DMA and the millisecond tick 2;
//! the idle loop runs the protocol, the extractor and the pipeline on each
//! full half ([`plinth_firmware::acquisition`]) and feeds the watchdog.
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

#[cfg(target_os = "none")]
use defmt_rtt as _;

/// Logs, records and resets: the next boot reports the record.
#[cfg(target_os = "none")]
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    cortex_m::interrupt::disable();
    panic_record::write(info);
    defmt::error!(
        "panic: {=str}",
        info.message().as_str().unwrap_or("(formatted message)")
    );
    cortex_m::peripheral::SCB::sys_reset()
}

#[cfg(target_os = "none")]
#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use crate::adc_dma::{self, AdcDma, CAPTURE_SLOTS, HALF_VECTORS};
    use crate::serial::{self, DmaSerial};
    use crate::{cycles, panic_record};
    use core::sync::atomic::{AtomicU32, Ordering};
    use heapless::spsc::{Producer, Queue};
    use plinth_firmware::acquisition::dma_source::DmaSource;
    use plinth_firmware::acquisition::pacing::{apb_timer_clock_hz, ConvstTiming};
    use plinth_firmware::ad7606::Range;
    use plinth_firmware::device::{Device, SAMPLE_RATE_HZ};
    use plinth_firmware::stm32::configure_clocks;
    use stm32f4xx_hal::gpio::{Edge, ExtiPin, Input, Output, PushPull, PB0, PB12, PD12, PD14};
    use stm32f4xx_hal::pac;
    use stm32f4xx_hal::prelude::*;
    use stm32f4xx_hal::rcc::{Enable, Reset};
    use stm32f4xx_hal::watchdog::IndependentWatchdog;

    /// The board's crystal [Hz].
    const HSE_HZ: u32 = 8_000_000;
    /// Host link speed [bit/s] (as `plinth stream --baud`).
    const BAUD: u32 = 115_200;
    /// Watchdog timeout [ms]: far above one idle-loop pass.
    const WATCHDOG_MS: u32 = 500;
    /// The AD7606 module's RANGE jumper (±10 V).
    const RANGE: Range = Range::PlusMinus10V;

    /// TIMx_SR: channel 2 overcapture (RM0090 18.4.5).
    const TIM_SR_CC2OF: u32 = 1 << 10;

    /// Milliseconds since boot (the SysTick task).
    static UPTIME_MS: AtomicU32 = AtomicU32::new(0);

    #[shared]
    struct Shared {}

    #[local]
    struct Local {
        busy: PB0<Input>,
        cs: PB12<Output<PushPull>>,
        tim5: pac::TIM5,
        captures: Producer<'static, u32, CAPTURE_SLOTS>,
        device: &'static mut Device,
        source: DmaSource<AdcDma>,
        link: DmaSerial,
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
        if let Some(r) = panic_record::take() {
            defmt::error!(
                "the previous boot panicked at {=str}:{=u32}: {=str}",
                r.file(),
                r.line(),
                r.message()
            );
        }
        if reset_by_watchdog {
            defmt::error!("the previous boot was reset by the watchdog");
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
        let mut cs = gpiob.pb12.into_push_pull_output();
        cs.set_high();
        let _convst = gpioc.pc6.into_alternate::<2>();
        let _sck = gpiob.pb13.into_alternate::<5>();
        let _miso = gpiob.pb14.into_alternate::<5>();
        let _mosi = gpiob.pb15.into_alternate::<5>();
        let _keyphasor = gpioa.pa1.into_alternate::<2>();
        let _host_tx = gpioa.pa2.into_alternate::<7>();
        let _host_rx = gpioa.pa3.into_alternate::<7>();
        let mut busy = gpiob.pb0.into_pull_down_input();
        busy.make_interrupt_source(&mut syscfg);
        busy.trigger_on_edge(&mut dp.EXTI, Edge::Falling);
        busy.enable_interrupt(&mut dp.EXTI);

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
        let timing = match ConvstTiming::for_rate(timer_hz, f64::from(SAMPLE_RATE_HZ), 16) {
            Ok(t) => t,
            // 51.2 kHz fits any clock this board can run at (16-168 MHz).
            Err(e) => defmt::panic!("no CONVST timing at {=u32} Hz: {}", timer_hz, e),
        };
        let rate = timing.achieved_rate_hz as f32;
        let (producer, consumer) = cx.local.queue.split();
        // SAFETY: TIM5's capture registers belong to the keyphasor task from
        // here on; `AdcDma` only starts and stops its counter.
        let tim5_capture = unsafe { pac::TIM5::steal() };
        let hardware = AdcDma::new(dp.TIM3, dp.TIM5, dp.SPI2, timing, consumer);
        let source = DmaSource::new(hardware, HALF_VECTORS, timing.timer_ticks_per_sample, RANGE);
        let link = DmaSerial::new(dp.USART2, clocks.pclk1_hz, BAUD);
        let Some(device) =
            cortex_m::singleton!(: Device = Device::with_sample_rate(RANGE.volts_per_code(), rate))
        else {
            defmt::panic!("device taken twice")
        };

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
            "plinth-box {=str} up: clocks {}, CONVST {} ({=f32} Hz)",
            env!("CARGO_PKG_VERSION"),
            clocks,
            timing,
            rate
        );
        (
            Shared {},
            Local {
                busy,
                cs,
                tim5: tim5_capture,
                captures: producer,
                device,
                source,
                link,
                watchdog,
                green: gpiod.pd12.into_push_pull_output(),
                red: gpiod.pd14.into_push_pull_output(),
            },
        )
    }

    /// The protocol, the extractor and the pipeline, on whatever the
    /// interrupts handed over; sleeps when a pass did nothing (the
    /// millisecond tick wakes it at the latest).
    #[idle(local = [device, source, link, watchdog, green, red])]
    fn idle(cx: idle::Context) -> ! {
        let idle::LocalResources {
            device,
            source,
            link,
            watchdog,
            green,
            red,
            ..
        } = cx.local;
        let mut last_report_ms = 0u32;
        let mut reported = (0u32, 0u32, 0u32, 0u32);
        let mut last_look = serial::Look::default();
        let mut busy = true;
        loop {
            watchdog.feed();
            let now = UPTIME_MS.load(Ordering::Relaxed);
            // Every BUSY interrupt (51.2 kHz) wakes the core from WFI: when
            // no half completed, no byte came in and no millisecond passed
            // since an idle pass, go straight back to sleep.
            let look = serial::Look::now(now);
            if !busy && look == last_look {
                cortex_m::asm::wfi();
                continue;
            }
            last_look = look;
            let activity = cycles::POLL.measure(|| device.poll(link, source, now));
            link.kick();
            if now.wrapping_sub(last_report_ms) >= 1000 {
                last_report_ms = now;
                let faults = (
                    source.counters().overrun_halves,
                    adc_dma::LATE_READS.load(Ordering::Relaxed),
                    adc_dma::DMA_ERRORS.load(Ordering::Relaxed),
                    adc_dma::LOST_CAPTURES.load(Ordering::Relaxed),
                );
                if faults != reported {
                    reported = faults;
                    defmt::warn!(
                        "overrun halves {=u32}, late reads {=u32}, DMA errors {=u32}, lost keyphasor captures {=u32}",
                        faults.0,
                        faults.1,
                        faults.2,
                        faults.3
                    );
                }
                red.set_state((faults.1 | faults.2 | faults.3 != 0).into());
                if source.running() {
                    green.toggle();
                } else {
                    green.set_low();
                }
                #[cfg(feature = "bench")]
                report_cycles(now);
            }
            busy = activity.received != 0 || activity.sent != 0 || activity.samples != 0;
            if !busy {
                cortex_m::asm::wfi();
            }
        }
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
    #[task(binds = EXTI0, priority = 4, local = [busy, cs])]
    fn busy_fell(cx: busy_fell::Context) {
        cycles::BUSY.measure(|| {
            cx.local.busy.clear_interrupt_pending_bit();
            let tx = adc_dma::dma1().st(adc_dma::TX_STREAM);
            if tx.cr().read().en().is_enabled() {
                // The previous read is still running: this conversion is
                // lost and the buffer's time base with it.
                adc_dma::bump(&adc_dma::LATE_READS);
                return;
            }
            AdcDma::clear_stream_flags(adc_dma::TX_STREAM);
            // A CS falling edge starts the AD7606's serial output (≥ 50 ns
            // high before it).
            cx.local.cs.set_high();
            cortex_m::asm::delay(10);
            cx.local.cs.set_low();
            tx.ndtr()
                .write(|w| w.ndt().set(plinth_firmware::source::CHANNELS as u16));
            tx.cr().modify(|_, w| w.en().enabled());
        });
    }

    /// The SPI receive DMA filled a half.
    #[task(binds = DMA1_STREAM3, priority = 3)]
    fn adc_half(_: adc_half::Context) {
        cycles::HALF.measure(|| {
            let isr = adc_dma::dma1().lisr().read();
            if isr.teif3().bit_is_set() {
                adc_dma::bump(&adc_dma::DMA_ERRORS);
            }
            AdcDma::clear_stream_flags(adc_dma::RX_STREAM);
            if isr.tcif3().bit_is_set() {
                adc_dma::COMPLETIONS.complete();
            }
        });
    }

    /// A keyphasor edge was captured.
    #[task(binds = TIM5, priority = 3, local = [tim5, captures])]
    fn keyphasor(cx: keyphasor::Context) {
        cycles::KEYPHASOR.measure(|| {
            let sr = cx.local.tim5.sr().read();
            if sr.cc2of().bit_is_set() {
                // A second edge came before the first was read.
                adc_dma::bump(&adc_dma::LOST_CAPTURES);
                // SR's flags clear by writing 0 and ignore a 1: clear CC2OF
                // alone (a read-modify-write could clear a capture flag
                // raised meanwhile).
                // SAFETY: writes 1 to every other flag, which changes nothing.
                cx.local
                    .tim5
                    .sr()
                    .write(|w| unsafe { w.bits(!TIM_SR_CC2OF) });
            }
            if sr.cc2if().bit_is_set() {
                // Reading CCR2 clears CC2IF.
                let count = cx.local.tim5.ccr2().read().bits();
                if cx.local.captures.enqueue(count).is_err() {
                    adc_dma::bump(&adc_dma::LOST_CAPTURES);
                }
            }
        });
    }

    /// The host link's receive DMA passed half its ring.
    #[task(binds = DMA1_STREAM5, priority = 2)]
    fn host_rx_half(_: host_rx_half::Context) {
        AdcDma::clear_stream_flags(serial::RX_STREAM);
        adc_dma::bump(&serial::RX_HALVES);
    }

    /// Milliseconds since boot.
    #[task(binds = SysTick, priority = 2)]
    fn tick(_: tick::Context) {
        cycles::TICK.measure(|| adc_dma::bump(&UPTIME_MS));
    }
}
