//! Plinth field box image (thumbv7em-none-eabihf).
//!
//! Runs on an STM32F405/407 and unchanged under
//! `qemu-system-arm -M netduinoplus2` (see `.cargo/config.toml`). The host
//! link is USART1; with no sensors attached the samples come from the host
//! (replay). Under QEMU (the default `semihosting` feature) the image exits
//! with status 0 through semihosting once a `Stop` has been acknowledged and
//! every queued frame has been sent, so a test can run it to completion.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("plinth-firmware is an MCU image: build it with --target thumbv7em-none-eabihf");
    std::process::exit(2);
}

#[cfg(target_os = "none")]
mod image {
    #[cfg(all(feature = "rtt", feature = "semihosting"))]
    compile_error!(
        "choose one log transport: `semihosting` (default) or `rtt` (--no-default-features --features rtt)"
    );

    #[cfg(feature = "rtt")]
    use defmt_rtt as _;
    #[cfg(feature = "semihosting")]
    use defmt_semihosting as _;

    use cortex_m_rt::entry;
    use plinth_firmware::ad7606::Range;
    use plinth_firmware::device::Device;
    use plinth_firmware::replay::ReplaySource;
    use plinth_firmware::stm32::{configure_clocks, Iwdg, Usart1};
    use plinth_firmware::uptime::Uptime;
    use plinth_firmware::watchdog::Watchdog;

    /// The board's crystal [Hz] (8 MHz, as on most STM32F4 boards; `None`
    /// for a board without one: the PLL then runs from the HSI).
    const HSE_HZ: Option<u32> = Some(8_000_000);
    /// Host link speed [bit/s].
    const BAUD: u32 = 115_200;
    /// Watchdog timeout [ms]: far above one bounded main-loop pass.
    const WATCHDOG_MS: u32 = 500;

    /// Logs the panic over defmt (no `core::fmt`: it would cost ~4 KiB of
    /// flash), then exits with failure under semihosting (QEMU: the test
    /// sees it) or stops on an undefined instruction (hardware: the watchdog
    /// resets the box).
    #[panic_handler]
    fn panic(info: &core::panic::PanicInfo) -> ! {
        let message = info.message().as_str().unwrap_or("(formatted message)");
        match info.location() {
            Some(l) => defmt::error!(
                "panic at {=str}:{=u32}: {=str}",
                l.file(),
                l.line(),
                message
            ),
            None => defmt::error!("panic: {=str}", message),
        }
        #[cfg(feature = "semihosting")]
        cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_FAILURE);
        cortex_m::asm::udf()
    }

    #[entry]
    fn main() -> ! {
        let Some(cp) = cortex_m::Peripherals::take() else {
            // Only reachable if something took the core peripherals before
            // main, which nothing does.
            cortex_m::asm::udf()
        };
        let clocks = configure_clocks(HSE_HZ);
        let mut link = Usart1::init(clocks.pclk2_hz, BAUD);
        let mut watchdog = Iwdg::start(WATCHDOG_MS);
        let mut uptime = Uptime::new(cp.SYST, clocks.sysclk_hz);
        // Statics (counted by `size`), not stack: the device is ~20 KiB.
        let device =
            cortex_m::singleton!(: Device = Device::new(Range::PlusMinus10V.volts_per_code()));
        let source = cortex_m::singleton!(: ReplaySource = ReplaySource::new(Range::PlusMinus10V.volts_per_code()));
        let (Some(device), Some(source)) = (device, source) else {
            cortex_m::asm::udf()
        };
        // Samples come from the host: no sample clock of its own.
        device.set_platform(
            plinth_shared::protocol::SampleClock::Emulated,
            plinth_shared::protocol::PreviousReset::Normal,
        );
        defmt::info!(
            "plinth-firmware {=str} up, clocks {}",
            env!("CARGO_PKG_VERSION"),
            clocks
        );
        let mut stopping = false;
        loop {
            watchdog.feed();
            let now = uptime.now_ms();
            device.poll(&mut link, source, now);
            if device.take_stopped() {
                defmt::info!("stop: counters {}", device.counters());
                stopping = true;
            }
            if stopping && device.tx_idle() {
                stopping = false;
                finish();
            }
        }
    }

    /// Ends the run after a `Stop`: under semihosting (QEMU) the process
    /// exits with status 0; on hardware the box keeps serving the link.
    #[cfg(feature = "semihosting")]
    fn finish() {
        defmt::info!("exit");
        cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_SUCCESS);
    }

    /// Hardware build: a `Stop` just returns to idle.
    #[cfg(not(feature = "semihosting"))]
    fn finish() {}
}
