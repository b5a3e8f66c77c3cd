//! Plinth field box image (thumbv7em-none-eabihf).
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("plinth-firmware is an MCU image: build it with --target thumbv7em-none-eabihf");
    std::process::exit(2);
}
