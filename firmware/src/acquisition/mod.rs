//! Acquisition on the board, as plain Rust that the host tests drive with
//! simulated hardware: the `plinth-box` image supplies the registers.
//!
//! - [`pacing`]: timer prescaler, period and CONVST pulse for a sample rate.
//! - [`handover`]: the SPI DMA double buffer handed from the DMA to the
//!   extractor task; overruns counted, torn halves never delivered.
//! - [`timebase`]: keyphasor capture counts to sample-fractional edges.
//! - [`scaling`]: codes to volts, saturation counts.
//! - [`dma_source`]: all of it as a [`crate::source::SampleSource`].
//! - [`adc_dma`]: the reference board's registers and interrupt handlers
//!   ([`rm0090`]: the register map), [`read_plan`]: whether a read fits.

pub mod adc_dma;
pub mod dma_source;
pub mod handover;
pub mod pacing;
pub mod read_plan;
pub mod rm0090;
pub mod scaling;
pub mod timebase;
