//! Plinth field box: acquisition pipeline and drivers, target independent so
//! that the host runs them against simulated hardware.
//!
//! Only [`stm32`] touches hardware registers (and is only built for the MCU).
#![no_std]
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod link;
#[cfg(target_os = "none")]
pub mod stm32;
