#![cfg_attr(not(feature = "bench"), allow(dead_code))]
//! DWT cycle accounting of the box's tasks for the `bench` feature: each
//! task's body is timed with the cycle counter and summed here; the idle
//! loop prints the sums once a second (format in firmware/README.md,
//! "Cycle budget on the board"). Without the feature nothing is measured
//! and nothing is printed.

use core::sync::atomic::{AtomicU32, Ordering};

/// Calls, cycles and the longest call of one task.
pub struct Meter {
    /// Name printed in the report.
    pub name: &'static str,
    calls: AtomicU32,
    cycles: AtomicU32,
    max: AtomicU32,
}

impl Meter {
    /// A meter at zero.
    pub const fn new(name: &'static str) -> Self {
        Self {
            name,
            calls: AtomicU32::new(0),
            cycles: AtomicU32::new(0),
            max: AtomicU32::new(0),
        }
    }

    /// Runs `f`, timing it when the `bench` feature is on. Only one task
    /// (one priority) uses a given meter, so loads and stores suffice.
    #[inline(always)]
    pub fn measure<R>(&self, f: impl FnOnce() -> R) -> R {
        #[cfg(feature = "bench")]
        {
            let start = cortex_m::peripheral::DWT::cycle_count();
            let r = f();
            let spent = cortex_m::peripheral::DWT::cycle_count().wrapping_sub(start);
            self.calls.store(
                self.calls.load(Ordering::Relaxed).wrapping_add(1),
                Ordering::Relaxed,
            );
            self.cycles.store(
                self.cycles.load(Ordering::Relaxed).wrapping_add(spent),
                Ordering::Relaxed,
            );
            if spent > self.max.load(Ordering::Relaxed) {
                self.max.store(spent, Ordering::Relaxed);
            }
            r
        }
        #[cfg(not(feature = "bench"))]
        f()
    }

    /// (calls, cycles, longest call) since the last take; resets them.
    /// A task may add between the loads and the resets: the report is off by
    /// at most one call, never corrupt.
    pub fn take(&self) -> (u32, u32, u32) {
        (
            self.calls.swap_or_load(),
            self.cycles.swap_or_load(),
            self.max.swap_or_load(),
        )
    }
}

/// `swap(0)` without the read-modify-write instructions (fine on
/// thumbv7em, but kept to loads and stores like the rest).
trait SwapOrLoad {
    fn swap_or_load(&self) -> u32;
}

impl SwapOrLoad for AtomicU32 {
    fn swap_or_load(&self) -> u32 {
        let v = self.load(Ordering::Relaxed);
        self.store(0, Ordering::Relaxed);
        v
    }
}

/// The BUSY (end of conversion) interrupt: re-arms the SPI read.
pub static BUSY: Meter = Meter::new("busy_exti");
/// The SPI receive DMA's half-complete interrupt.
pub static HALF: Meter = Meter::new("adc_half_dma");
/// The keyphasor capture interrupt.
pub static KEYPHASOR: Meter = Meter::new("keyphasor_capture");
/// One `Device::extract` of the `extract` task (a DMA half through the
/// extractor and the pipeline).
pub static EXTRACT: Meter = Meter::new("extract");
/// One `Device::poll` of the `process` task (protocol, status, and any
/// samples `extract` has not taken yet).
pub static POLL: Meter = Meter::new("device_poll");
/// The millisecond tick.
pub static TICK: Meter = Meter::new("systick");

/// Every meter, in report order.
pub static ALL: [&Meter; 6] = [&BUSY, &HALF, &KEYPHASOR, &EXTRACT, &POLL, &TICK];
