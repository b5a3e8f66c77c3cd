//! Whether one AD7606 read fits a sample period, and the SPI clock for it.
//!
//! Each sample period holds a conversion (CONVST → BUSY falls, at most
//! [`CONVERSION_MAX_NS`]) and the read of its 8 × 16 bits on DOUTA at the
//! SPI clock, plus the BUSY interrupt's entry and CS pulse
//! ([`READ_OVERHEAD_NS`]). SPI2 runs at f_PCLK1 / 2^(BR+1); the fastest
//! clock at or below [`SCLK_MAX_HZ`] is taken. When the read cannot fit
//! (the 16 MHz RC fallback: /2 gives 8 MHz, a 16 µs read in a 19.5 µs
//! period) the box refuses to sample instead of restarting forever.

use super::pacing::{ConvstTiming, PacingError};
use crate::revert::Revert;

/// AD7606 conversion time without oversampling, data-sheet maximum [ns].
pub const CONVERSION_MAX_NS: u32 = 4_150;
/// A lower bound of the conversion time the slip detector assumes [ns]
/// (data sheet: 3.45 µs typical; a margin below it).
pub const CONVERSION_MIN_NS: u32 = 3_000;
/// Fastest serial clock the box drives the AD7606 at [Hz] (data sheet
/// allows 23.5 MHz; margin for a module's wiring).
pub const SCLK_MAX_HZ: u32 = 20_000_000;
/// Bits of one read: 8 channels of 16 bits on DOUTA.
pub const READ_BITS: u32 = 128;
/// Interrupt entry, the BUSY handler's checks and the CS pulse before the
/// first SCLK edge, with margin [ns].
pub const READ_OVERHEAD_NS: u32 = 1_000;

/// The SPI read of a conversion at one clock setting.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct ReadPlan {
    /// CONVST timing (timer settings, rate achieved).
    pub timing: ConvstTiming,
    /// SPI CR1.BR: SCLK = f_PCLK1 / 2^(br+1).
    pub spi_br: u32,
    /// SCLK [Hz].
    pub sclk_hz: u32,
    /// Conversion + read + overhead [ns].
    pub busy_ns: u32,
    /// The sample period [ns].
    pub period_ns: u32,
    /// Timer ticks the conversion takes at least ([`CONVERSION_MIN_NS`]).
    pub conversion_min_ticks: u32,
    /// Timer ticks from CONVST to the end of the read, at most.
    pub read_end_ticks: u32,
}

/// Why the box cannot sample at a clock setting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum ReadPlanError {
    /// No timer setting for the rate.
    Pacing(PacingError),
    /// The conversion and its read take `busy_ns` [ns] of a `period_ns`
    /// [ns] period.
    ReadDoesNotFit {
        /// Conversion + read + overhead [ns].
        busy_ns: u32,
        /// Sample period [ns].
        period_ns: u32,
    },
}

/// Nanoseconds of `cycles` at `hz` (rounded up).
fn ns(cycles: u64, hz: u32) -> u32 {
    (cycles * 1_000_000_000).div_ceil(u64::from(hz.max(1))) as u32
}

/// Timer ticks of `ns` nanoseconds at `hz` (rounded `up` or down).
pub fn ticks(ns: u32, hz: u32, up: bool) -> u32 {
    let t = u64::from(ns) * u64::from(hz);
    (if up {
        t.div_ceil(1_000_000_000)
    } else {
        t / 1_000_000_000
    }) as u32
}

impl ReadPlan {
    /// The plan for `rate_hz` [Hz] with TIM3 on `timer_hz` [Hz] (16-bit
    /// counter) and SPI2 on the APB1 clock `pclk1_hz` [Hz].
    pub fn new(timer_hz: u32, pclk1_hz: u32, rate_hz: f64) -> Result<Self, ReadPlanError> {
        Self::with_revert(timer_hz, pclk1_hz, rate_hz, Revert::None)
    }

    /// [`ReadPlan::new`] with `revert` applied: [`Revert::PrescalerRefusal`]
    /// fixes the divider at /4 and never refuses (the plan before issue
    /// 18; tests only).
    pub fn with_revert(
        timer_hz: u32,
        pclk1_hz: u32,
        rate_hz: f64,
        revert: Revert,
    ) -> Result<Self, ReadPlanError> {
        let timing =
            ConvstTiming::for_rate(timer_hz, rate_hz, 16).map_err(ReadPlanError::Pacing)?;
        // Smallest divider 2^(br+1) with pclk1 / divider ≤ SCLK_MAX_HZ.
        let mut br = 0;
        while br < 7 && pclk1_hz >> (br + 1) > SCLK_MAX_HZ {
            br += 1;
        }
        let old = revert == Revert::PrescalerRefusal;
        if old {
            br = 1;
        }
        let sclk_hz = pclk1_hz >> (br + 1);
        let period_ns = ns(u64::from(timing.timer_ticks_per_sample), timer_hz);
        let read_ns = ns(u64::from(READ_BITS), sclk_hz);
        let busy_ns = CONVERSION_MAX_NS + read_ns + READ_OVERHEAD_NS;
        if busy_ns > period_ns && !old {
            return Err(ReadPlanError::ReadDoesNotFit { busy_ns, period_ns });
        }
        Ok(Self {
            timing,
            spi_br: br,
            sclk_hz,
            busy_ns,
            period_ns,
            conversion_min_ticks: ticks(CONVERSION_MIN_NS, timer_hz, false),
            read_end_ticks: ticks(busy_ns, timer_hz, true),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pll_clock_reads_at_10_5_mhz_with_time_to_spare() {
        let p = ReadPlan::new(84_000_000, 42_000_000, 51_200.0).unwrap();
        assert_eq!((p.spi_br, p.sclk_hz), (1, 10_500_000));
        // 4.15 µs + 12.19 µs + 1 µs of 19.54 µs.
        assert_eq!(p.busy_ns, 4_150 + 12_191 + 1_000);
        assert_eq!(p.period_ns, 19_536);
        assert_eq!(p.conversion_min_ticks, 252);
    }

    #[test]
    fn the_rc_fallback_is_refused_with_its_figures() {
        // HSI 16 MHz, APB1 undivided: /2 = 8 MHz, 16 µs per read; 313
        // ticks per sample.
        assert_eq!(
            ReadPlan::new(16_000_000, 16_000_000, 51_200.0),
            Err(ReadPlanError::ReadDoesNotFit {
                busy_ns: 4_150 + 16_000 + 1_000,
                period_ns: 19_563
            })
        );
        // At a quarter of the rate it fits.
        let p = ReadPlan::new(16_000_000, 16_000_000, 12_800.0).unwrap();
        assert_eq!(p.sclk_hz, 8_000_000);
    }
}
