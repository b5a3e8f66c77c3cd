//! The acquisition hardware of the reference board: the library's
//! [`AdcDma`] (registers, interrupt handlers, clean stop/restart, slip
//! detectors: `plinth_firmware::acquisition::adc_dma`, which the host's
//! board model runs tick by tick) on the MCU's memory map, with the
//! memory its DMA streams own.
//!
//! Ownership (module doc of `adc_dma` in the library): stream 4 and CS
//! belong to `busy_fell` while EXTI0 is unmasked and to the idle task while
//! it is masked; stream 3's flags and [`SHARED`]'s completion count to
//! `adc_half`; TIM5's capture registers and the capture queue's producer to
//! `keyphasor`; everything else to the idle task.

use core::cell::UnsafeCell;
use heapless::spsc::Consumer;
use plinth_firmware::acquisition::adc_dma::{AdcDma, AdcShared, RestartPath};
use plinth_firmware::acquisition::read_plan::ReadPlan;
use plinth_firmware::source::{BUFFER_VECTORS, CHANNELS};
use plinth_firmware::stm32::Mmio;

/// Sample vectors per DMA half: one pipeline buffer (96 vectors, 1.9 ms at
/// 51.2 kHz; two halves are 3 KiB).
pub const HALF_VECTORS: usize = BUFFER_VECTORS;
/// Capture queue slots (a heapless spsc queue holds one fewer).
pub const CAPTURE_SLOTS: usize = 32;

/// The two halves the SPI receive DMA writes (16-bit words, 4-aligned).
#[repr(C, align(4))]
pub struct AdcMemory(UnsafeCell<[[[i16; CHANNELS]; HALF_VECTORS]; 2]>);

// SAFETY: written only by the DMA, read only by the idle task through
// volatile reads (`Mmio`); the hand-over protocol decides which half may
// be read.
unsafe impl Sync for AdcMemory {}

/// The DMA's target.
pub static ADC_MEMORY: AdcMemory = AdcMemory(UnsafeCell::new([[[0; CHANNELS]; HALF_VECTORS]; 2]));

/// The word the SPI2 transmit DMA clocks out (the AD7606 ignores DIN in
/// serial read mode).
pub static TX_DUMMY: u32 = 0;

/// What the acquisition interrupts share with the idle task.
pub static SHARED: AdcShared = AdcShared::new();

/// The board's acquisition hardware.
pub type BoxAdc = AdcDma<Mmio, CAPTURE_SLOTS>;

/// Configures TIM3, TIM5, SPI2 for `plan` (clocks on, pins set up, EXTI0
/// routed to PB0 and masked); nothing runs until `start`.
pub fn new(plan: ReadPlan, captures: Consumer<'static, u32, CAPTURE_SLOTS>) -> BoxAdc {
    AdcDma::new(
        Mmio,
        &SHARED,
        plan,
        ADC_MEMORY.0.get() as u32,
        core::ptr::addr_of!(TX_DUMMY) as u32,
        HALF_VECTORS,
        captures,
        RestartPath::Clean,
    )
}
