//! CONVST pacing: the prescaler, period and compare value that make a timer's
//! PWM output start one AD7606 conversion per sample period.
//!
//! PWM mode 2 holds the output low while the counter is below the compare
//! value and high from it to the end of the period, so CONVST rises at
//! count `compare` of every period (the sampling instant of all eight
//! channels) and falls at the update event. Mode 2 rather than mode 1: the
//! output stays low until the counter runs, so the first rising edge is
//! the first sample. The counter clock is the timer clock divided by
//! `prescaler + 1`; the period is `auto_reload + 1` counter ticks.

/// The AD7606's fastest throughput [samples/s per channel] (200 kSPS).
pub const AD7606_MAX_RATE_HZ: f64 = 200_000.0;

/// CONVST high time the box asks for [ns]: the AD7606 needs ≥ 25 ns (t2);
/// 100 ns leaves margin for a module's wiring.
pub const CONVST_HIGH_NS: u32 = 100;

/// Why no timer setting gives the requested sample rate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum PacingError {
    /// The sample rate or the timer clock is not finite and positive.
    NotPositive,
    /// The sample rate is above the AD7606's 200 kSPS.
    AboveAdcThroughput,
    /// The period would be shorter than the CONVST pulse plus one tick.
    PeriodTooShort,
    /// The period does not fit the counter even at the largest prescaler.
    PeriodTooLong,
}

/// A timer's settings for a sample rate, and the rate they really give.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct ConvstTiming {
    /// PSC: counter clock = timer clock / (prescaler + 1).
    pub prescaler: u16,
    /// ARR: period = auto_reload + 1 counter ticks.
    pub auto_reload: u32,
    /// CCR of the CONVST channel (PWM mode 2): CONVST rises at this count
    /// and stays high to the end of the period (≥ [`CONVST_HIGH_NS`]).
    pub compare: u32,
    /// Timer-clock ticks from the counter's start to the first CONVST
    /// rising edge (sample 0): compare · (prescaler + 1).
    pub first_rise_ticks: u32,
    /// Timer-clock ticks per sample period: (prescaler + 1) · (auto_reload + 1).
    /// An unprescaled capture timer on the same clock counts this many ticks
    /// between samples.
    pub timer_ticks_per_sample: u32,
    /// The sample rate these settings give [Hz] (the request rounded to a
    /// whole number of ticks).
    pub achieved_rate_hz: f64,
}

impl ConvstTiming {
    /// Settings for `rate_hz` [Hz] on a timer clocked at `timer_clock_hz`
    /// [Hz] whose counter has `counter_bits` bits (16, or 32 for TIM2/TIM5).
    /// The period is the nearest whole number of counter ticks, at the
    /// smallest prescaler that fits (finest rate step).
    pub fn for_rate(
        timer_clock_hz: u32,
        rate_hz: f64,
        counter_bits: u32,
    ) -> Result<Self, PacingError> {
        if timer_clock_hz == 0 || !rate_hz.is_finite() || rate_hz <= 0.0 {
            return Err(PacingError::NotPositive);
        }
        if rate_hz > AD7606_MAX_RATE_HZ {
            return Err(PacingError::AboveAdcThroughput);
        }
        let clock = f64::from(timer_clock_hz);
        let total = clock / rate_hz; // timer-clock ticks per sample, unrounded
        let counter_span = if counter_bits >= 32 {
            4_294_967_296.0
        } else {
            f64::from(1u32 << counter_bits.max(1))
        };
        // Smallest prescaler whose counter holds the period.
        let prescale = libm::ceil(total / counter_span).max(1.0);
        if prescale > 65_536.0 {
            return Err(PacingError::PeriodTooLong);
        }
        let counter_clock = clock / prescale;
        let period = libm::round(counter_clock / rate_hz);
        if period > counter_span {
            return Err(PacingError::PeriodTooLong);
        }
        let high = libm::ceil(f64::from(CONVST_HIGH_NS) * 1e-9 * counter_clock).max(1.0);
        if period < high + 1.0 {
            return Err(PacingError::PeriodTooShort);
        }
        let prescaler = prescale as u32 - 1;
        let period = period as u64;
        let timer_ticks = u64::from(prescaler + 1) * period;
        let Ok(timer_ticks_per_sample) = u32::try_from(timer_ticks) else {
            return Err(PacingError::PeriodTooLong);
        };
        let compare = (period - high as u64) as u32;
        Ok(Self {
            prescaler: prescaler as u16,
            auto_reload: (period - 1) as u32,
            compare,
            first_rise_ticks: compare * (prescaler + 1),
            timer_ticks_per_sample,
            achieved_rate_hz: clock / timer_ticks as f64,
        })
    }

    /// (achieved − requested) / requested for the request `rate_hz` [Hz].
    pub fn relative_error(&self, rate_hz: f64) -> f64 {
        (self.achieved_rate_hz - rate_hz) / rate_hz
    }
}

/// The clock of a timer on an APB bus [Hz]: the bus clock, doubled when the
/// bus runs divided from HCLK (RM0090 §6.2).
pub fn apb_timer_clock_hz(hclk_hz: u32, pclk_hz: u32) -> u32 {
    if pclk_hz < hclk_hz {
        pclk_hz.saturating_mul(2)
    } else {
        pclk_hz
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_rate_on_an_84_mhz_timer() {
        // TIM3 on APB1 (42 MHz, timer clock doubled): 84 MHz / 51.2 kHz =
        // 1640.625 ticks → 1641.
        let t = ConvstTiming::for_rate(84_000_000, 51_200.0, 16).unwrap();
        assert_eq!(t.prescaler, 0);
        assert_eq!(t.auto_reload, 1640);
        assert_eq!(t.timer_ticks_per_sample, 1641);
        // 100 ns at 84 MHz = 8.4 → 9 ticks high at the end of the period.
        assert_eq!(t.compare, 1632);
        assert_eq!(t.first_rise_ticks, 1632);
        assert!((t.achieved_rate_hz - 84e6 / 1641.0).abs() < 1e-9);
        assert!(t.relative_error(51_200.0).abs() < 2.3e-4);
    }

    #[test]
    fn slow_rates_take_a_prescaler_on_a_16_bit_counter() {
        // 84 MHz / 1 kHz = 84 000 ticks > 65 536: prescale by 2.
        let t = ConvstTiming::for_rate(84_000_000, 1_000.0, 16).unwrap();
        assert_eq!(t.prescaler, 1);
        assert_eq!(t.auto_reload, 41_999);
        assert_eq!(t.timer_ticks_per_sample, 84_000);
        assert_eq!(t.achieved_rate_hz, 1_000.0);
        // 100 ns at 42 MHz: 4.2 → 5 counter ticks high, rising at 41 995.
        assert_eq!((t.compare, t.first_rise_ticks), (41_995, 83_990));
        // A 32-bit counter needs none.
        let t = ConvstTiming::for_rate(84_000_000, 1_000.0, 32).unwrap();
        assert_eq!((t.prescaler, t.auto_reload), (0, 83_999));
    }

    #[test]
    fn apb_timers_run_at_twice_a_divided_bus() {
        assert_eq!(apb_timer_clock_hz(168_000_000, 42_000_000), 84_000_000);
        assert_eq!(apb_timer_clock_hz(16_000_000, 16_000_000), 16_000_000);
    }

    #[test]
    fn impossible_rates_are_refused() {
        use PacingError::*;
        assert_eq!(
            ConvstTiming::for_rate(84_000_000, 0.0, 16),
            Err(NotPositive)
        );
        assert_eq!(
            ConvstTiming::for_rate(84_000_000, f64::NAN, 16),
            Err(NotPositive)
        );
        assert_eq!(ConvstTiming::for_rate(0, 1e3, 16), Err(NotPositive));
        assert_eq!(
            ConvstTiming::for_rate(84_000_000, 250e3, 16),
            Err(AboveAdcThroughput)
        );
        assert_eq!(
            ConvstTiming::for_rate(200_000, 150e3, 16),
            Err(PeriodTooShort)
        );
        assert_eq!(
            ConvstTiming::for_rate(84_000_000, 0.001, 16),
            Err(PeriodTooLong)
        );
    }
}
