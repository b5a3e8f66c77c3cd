//! Plinth field box image (thumbv7em-none-eabihf).
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
        "choose one log transport: `semihosting` (default) or `rtt` (--no-default-features)"
    );

    #[cfg(feature = "rtt")]
    use defmt_rtt as _;
    #[cfg(feature = "semihosting")]
    use defmt_semihosting as _;
    #[cfg(feature = "semihosting")]
    use panic_semihosting as _;

    use cortex_m_rt::entry;
    use cortex_m_semihosting::debug;
    use plinth_firmware::link::ByteLink;
    use plinth_firmware::stm32::Usart1;

    /// APB2 clock after reset (HSI) [Hz].
    const PCLK2_HZ: u32 = 16_000_000;
    /// Host link speed [bit/s].
    const BAUD: u32 = 115_200;

    #[entry]
    fn main() -> ! {
        let mut usart = Usart1::init(PCLK2_HZ, BAUD);
        defmt::info!("plinth-firmware up");
        loop {
            if let Some(b) = usart.read_byte() {
                if b == b'q' {
                    defmt::info!("bye");
                    debug::exit(debug::EXIT_SUCCESS);
                }
                while !usart.write_byte(b) {}
            }
        }
    }
}
