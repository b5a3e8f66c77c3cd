//! The box's health as `HelloAck` and every `Status` frame report it
//! (protocol version 3): where its sample clock comes from, how its last
//! boot ended, and the acquisition faults it counted. The box never hides
//! these in a log nobody reads in the field.

use serde::{Deserialize, Serialize};

/// Where the box's sample clock comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SampleClock {
    /// The PLL from the crystal (timing as accurate as the crystal).
    #[default]
    Crystal,
    /// The PLL from the internal RC: the crystal did not start; the sample
    /// rate is only as accurate as the RC (±1 %).
    RcOscillator,
    /// The internal 16 MHz RC alone: the PLL did not lock; a conversion's
    /// read does not fit the sample period, so the box refuses to sample.
    RcOscillatorNoPll,
    /// An emulator's fixed clock, or samples replayed by the host.
    Emulated,
}

/// How the box's previous boot ended.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PreviousReset {
    /// Power-up, reset pin or a requested reset.
    #[default]
    Normal,
    /// A panic (the box logs its file and line at boot).
    Panic,
    /// A hard fault (the box logs the faulting address at boot).
    HardFault,
    /// The watchdog: the main loop hung, or acquisition stopped progressing.
    Watchdog,
}

/// The box's health.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BoxHealth {
    /// Where the sample clock comes from.
    pub sample_clock: SampleClock,
    /// How the previous boot ended.
    pub previous_reset: PreviousReset,
    /// The box cannot sample at its clock (`Start` is refused).
    pub sampling_refused: bool,
    /// Acquisition restarts after a fault since `Start` (each one a gap
    /// reported in `overruns`).
    pub restarts: u32,
    /// Conversions whose BUSY edges merged while interrupts were masked
    /// (since power-up).
    pub slips: u32,
    /// Conversions not read because the previous read still ran (since
    /// power-up).
    pub late_reads: u32,
    /// Times no DMA half completed long after one was due (since power-up).
    pub stalls: u32,
    /// SPI overruns and mode faults (since power-up).
    pub spi_errors: u32,
    /// DMA transfer and direct-mode errors (since power-up).
    pub dma_errors: u32,
    /// Keyphasor edges lost in the capture hardware (since power-up).
    pub lost_captures: u32,
}

impl BoxHealth {
    /// True when something is worth a look: a clock or a reset that is not
    /// the normal one, or any fault counted.
    pub fn needs_attention(&self) -> bool {
        self.sample_clock == SampleClock::RcOscillator
            || self.sample_clock == SampleClock::RcOscillatorNoPll
            || self.previous_reset != PreviousReset::Normal
            || self.sampling_refused
            || self.restarts
                | self.slips
                | self.late_reads
                | self.stalls
                | self.spi_errors
                | self.dma_errors
                | self.lost_captures
                != 0
    }
}
