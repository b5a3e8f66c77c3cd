//! What the interrupt handlers share with the idle task: the fault
//! counters (one writer each, read as [`AdcFaults`]) and the set-up of the
//! running acquisition the BUSY handler checks against.

use super::super::handover::HalfCompletions;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

/// What the interrupt handlers share with the idle task (a `static` on
/// the board): counters written by one handler each, and the set-up of
/// the running acquisition, written by the idle task while EXTI0 is masked.
#[derive(Debug)]
pub struct AdcShared {
    /// Halves the receive DMA completed ([`adc_half`]).
    pub completions: HalfCompletions,
    /// The counters of [`AdcFaults`], one writer each.
    pub(super) late_reads: AtomicU32,
    pub(super) slips: AtomicU32,
    pub(super) dma_errors: AtomicU32,
    pub(super) spi_errors: AtomicU32,
    pub(super) lost_captures: AtomicU32,
    pub(super) stalls: AtomicU32,
    /// TIM5 count before which this conversion's BUSY cannot fall.
    pub(super) next_fall: AtomicU32,
    /// TIM5 ticks per sample.
    pub(super) ticks_per_sample: AtomicU32,
    /// Whether [`busy_fell`] checks for slips (off only when a test
    /// reverts the slip detector).
    pub(super) slip_check: AtomicBool,
}

impl Default for AdcShared {
    fn default() -> Self {
        Self::new()
    }
}

/// Adds one to a counter with a single writer (load and store).
#[inline]
pub(super) fn bump(counter: &AtomicU32) {
    counter.store(
        counter.load(Ordering::Relaxed).wrapping_add(1),
        Ordering::Relaxed,
    );
}

/// The acquisition's fault counters since power-up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct AdcFaults {
    /// BUSY fell while the previous read still ran (conversion not read).
    pub late_reads: u32,
    /// BUSY edges merged while interrupts were masked (a conversion lost).
    pub slips: u32,
    /// No half completed long after one was due (BUSY stuck, DMA stopped).
    pub stalls: u32,
    /// DMA transfer or direct-mode errors on streams 3 and 4.
    pub dma_errors: u32,
    /// SPI2 overruns and mode faults.
    pub spi_errors: u32,
    /// Keyphasor edges lost to overcapture or a full capture queue.
    pub lost_captures: u32,
}

impl AdcFaults {
    /// Faults that broke the sample sequence (wrapping sum).
    pub fn sequence(&self) -> u32 {
        self.late_reads
            .wrapping_add(self.slips)
            .wrapping_add(self.stalls)
            .wrapping_add(self.dma_errors)
            .wrapping_add(self.spi_errors)
    }
}

impl AdcShared {
    /// Nothing counted.
    pub const fn new() -> Self {
        Self {
            completions: HalfCompletions::new(),
            late_reads: AtomicU32::new(0),
            slips: AtomicU32::new(0),
            dma_errors: AtomicU32::new(0),
            spi_errors: AtomicU32::new(0),
            lost_captures: AtomicU32::new(0),
            stalls: AtomicU32::new(0),
            next_fall: AtomicU32::new(0),
            ticks_per_sample: AtomicU32::new(1),
            slip_check: AtomicBool::new(true),
        }
    }

    /// Counts a late read (for a replacement BUSY handler in a model).
    pub fn count_late_read(&self) {
        bump(&self.late_reads);
    }

    /// The fault counters.
    pub fn faults(&self) -> AdcFaults {
        let l = |a: &AtomicU32| a.load(Ordering::Relaxed);
        AdcFaults {
            late_reads: l(&self.late_reads),
            slips: l(&self.slips),
            stalls: l(&self.stalls),
            dma_errors: l(&self.dma_errors),
            spi_errors: l(&self.spi_errors),
            lost_captures: l(&self.lost_captures),
        }
    }
}
