//! Time since boot from SysTick running free as a 24-bit down-counter,
//! polled from the main loop (no interrupt).

/// Extends a 24-bit down-counter to a 64-bit tick count; correct as long as
/// it is updated at least once per counter period (2²⁴ ticks, 99.9 ms at
/// 168 MHz), which the bounded main loop guarantees.
#[derive(Clone, Copy, Debug)]
pub struct TickExtender {
    last: u32,
    ticks: u64,
}

/// SysTick's counter mask (24 bits).
pub const SYSTICK_MASK: u32 = 0x00FF_FFFF;

impl TickExtender {
    /// Starts from the counter value `now`.
    pub fn new(now: u32) -> Self {
        Self {
            last: now & SYSTICK_MASK,
            ticks: 0,
        }
    }

    /// Folds in the counter value `now` and returns the ticks elapsed since
    /// [`TickExtender::new`].
    pub fn update(&mut self, now: u32) -> u64 {
        let now = now & SYSTICK_MASK;
        // Down-counter: elapsed = last − now, modulo 2²⁴.
        let elapsed = self.last.wrapping_sub(now) & SYSTICK_MASK;
        self.ticks += u64::from(elapsed);
        self.last = now;
        self.ticks
    }
}

/// Milliseconds since boot from SysTick (MCU only).
#[cfg(target_os = "none")]
pub struct Uptime {
    syst: cortex_m::peripheral::SYST,
    extender: TickExtender,
    ticks_per_ms: u64,
}

#[cfg(target_os = "none")]
impl Uptime {
    /// Starts SysTick free-running on the core clock of `core_hz` [Hz].
    pub fn new(mut syst: cortex_m::peripheral::SYST, core_hz: u32) -> Self {
        use cortex_m::peripheral::syst::SystClkSource;
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(SYSTICK_MASK);
        syst.clear_current();
        syst.enable_counter();
        let extender = TickExtender::new(cortex_m::peripheral::SYST::get_current());
        Self {
            syst,
            extender,
            ticks_per_ms: u64::from(core_hz / 1000).max(1),
        }
    }

    /// Time since [`Uptime::new`] [ms], wrapping at 2³² ms (49.7 days).
    pub fn now_ms(&mut self) -> u32 {
        let _ = &self.syst;
        let ticks = self
            .extender
            .update(cortex_m::peripheral::SYST::get_current());
        (ticks / self.ticks_per_ms) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extends_across_wraps() {
        let mut t = TickExtender::new(100);
        assert_eq!(t.update(40), 60);
        // Wrap: 40 → 0 → 0xFF_FFFF → 0xFF_FF00.
        assert_eq!(t.update(0x00FF_FF00), 60 + 40 + 0x100);
        assert_eq!(t.update(0x00FF_FF00), 60 + 40 + 0x100);
    }
}
