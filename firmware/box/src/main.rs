#![no_std]
#![no_main]
use defmt_rtt as _;
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {}
}
#[cortex_m_rt::entry]
fn main() -> ! {
    loop {}
}
