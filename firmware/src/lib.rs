//! Plinth field box: acquisition pipeline and drivers, target independent so
//! that the host runs them against simulated hardware.
//!
//! - [`device`]: the protocol endpoint: [`device::Session`] (protocol),
//!   [`device::Extraction`] (pipeline), [`device::Outbox`] (frame queue), and
//!   [`device::Device`], all three in one thread (the main-loop step).
//! - [`config`]: the host's configuration commands, validated.
//! - [`pipeline`]: samples → phasors → bearing forces → pedestal RLS → frames.
//! - [`source`]: the [`source::SampleSource`] trait; [`replay`] (host-fed
//!   blocks, used under QEMU) and [`adc_source`] (the [`ad7606`] ADC with
//!   keyphasor capture) implement it.
//! - [`link`], [`watchdog`], [`uptime`]: the loop's I/O, feed hook and time.
//! - [`acquisition`]: the board's DMA-paced ADC and keyphasor capture
//!   (`plinth-box`), target independent.
//! - [`uart_dma`]: the board's DMA-fed UART receive ring (`plinth-box`).
//! - [`revert`]: test-only knobs that switch one fix of issue 18 off.
//! - [`clock`]: the STM32F4 clock tree the box programs (PLL to 168 MHz).
//! - `stm32` (MCU only): the one module with register access.
#![no_std]
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod acquisition;
pub mod ad7606;
pub mod adc_source;
pub mod clock;
pub mod config;
pub mod device;
pub mod link;
pub mod pipeline;
pub mod replay;
pub mod revert;
pub mod source;
#[cfg(target_os = "none")]
pub mod stm32;
pub mod uart_dma;
pub mod uptime;
pub mod watchdog;
