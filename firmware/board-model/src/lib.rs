//! A tick-level model of the `plinth-box` board (STM32F407 + AD7606) that
//! runs the firmware's own acquisition code on the host: the interrupt
//! handlers and `AdcDma` of `plinth_firmware::acquisition::adc_dma`, and
//! `DmaSource` above them, with interrupt latency and priorities.
//!
//! - [`hw`]: the peripherals, tick by tick, behind the register map.
//! - [`sim`]: the NVIC, priorities, masking, the cost of code; [`sim::Port`]
//!   is the firmware's `Registers`.
//! - [`scenario`]: one acquisition with one injected fault.
//! - [`check`]: every delivered sample and edge against the model's truth.
//! - [`tasks`]: the box's `extract` and `process` tasks (the library's
//!   extraction and protocol pass) with their shared parts locked as RTIC
//!   locks them, under a flooded host link.
//! - [`uart`]: the host link's receive path under line noise and overflow.
//! - [`matrix`]: the fault matrix (`bash scripts/bench-board-faults.sh`).

pub mod check;
pub mod hw;
pub mod matrix;
pub mod scenario;
pub mod sim;
pub mod tasks;
pub mod uart;
