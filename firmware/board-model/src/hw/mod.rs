//! The board's peripherals, tick by tick (one tick = one period of the
//! timer clock, 84 MHz on the PLL): TIM3 (PWM CONVST, TRGO), TIM5 (32-bit
//! input capture behind the digital filter, overcapture), EXTI0, GPIOB (CS,
//! BUSY), SPI2 (TX buffer, shift register, RXNE/OVR/BSY), DMA1 streams 3-6
//! (double-buffer and circular modes, NDTR, HT/TC/TE flags), USART2 and an
//! AD7606 (CONVST → BUSY, conversion, 128-bit serial output on DOUTA
//! restarted by each CS falling edge). Register semantics follow RM0090
//! for the bits the firmware uses; an access to anything else panics (the
//! model does not silently accept what it does not model).

//!
//! - [`timer`]: TIM3, TIM5, the keyphasor's capture filter;
//! - [`dma`]: DMA1 streams;
//! - [`spi`]: SPI2; [`usart`]: USART2; [`ad7606`]: the ADC and its tags;
//! - `registers`: the CPU's accesses by address.

pub mod ad7606;
pub mod dma;
mod registers;
pub mod spi;
pub mod timer;
pub mod usart;

pub use ad7606::{tag, untag, Adc, Conversion, TAG_PERIOD};
pub use dma::{Stream, DMA_LATENCY};
pub use spi::Spi;
pub use timer::{filtered_captures, Timer};
pub use usart::Usart;

use plinth_firmware::acquisition::rm0090::{dma1, exti, nvic, spi2, tim};
use plinth_firmware::source::CHANNELS;

/// Model RAM: where the firmware's DMA buffers live.
pub const RAM_BASE: usize = 0x2000_0000;
/// Model RAM size [bytes].
pub const RAM_BYTES: usize = 0x1_0000;

/// Faults the hardware itself shows.
#[derive(Clone, Debug, Default)]
pub struct HwFaults {
    /// From this tick on BUSY stays at this level.
    pub busy_stuck: Option<(u64, bool)>,
    /// DMA requests are not served in [from, to) (bus contention).
    pub dma_stall: Option<(u64, u64)>,
    /// A transfer error on stream 3 at this tick.
    pub transfer_error: Option<u64>,
}

/// The board's hardware.
#[derive(Clone, Debug)]
pub struct Hw {
    /// Current tick.
    pub now: u64,
    /// Timer ticks per SPI2 bus (APB1) clock cycle.
    pub pclk1_ticks: u64,
    /// AD7606 conversion time [ticks].
    pub conversion_ticks: u64,
    pub tim3: Timer,
    pub tim5: Timer,
    /// TIM5 starts (TRGO) at this tick.
    tim5_start: Option<u64>,
    /// TIM3 enables since power-up.
    pub runs: u32,
    pub adc: Adc,
    pub spi: Spi,
    pub dma: [Stream; 8],
    pub exti_imr: u32,
    pub exti_ftsr: u32,
    pub exti_pr: u32,
    pub usart: Usart,
    /// NVIC clear-pending writes not yet taken by the CPU model.
    pub nvic_clear: u64,
    /// Every conversion since power-up (index = g).
    pub conversions: Vec<Conversion>,
    /// Tick of each run's first CONVST rising edge (its sample 0).
    pub run_starts: Vec<u64>,
    /// Captures TIM5 will latch (ticks, after the filter), in order.
    pub capture_ticks: Vec<u64>,
    next_capture: usize,
    /// Bytes arriving on USART2 RX: (tick, byte, with a noise/framing error).
    pub rx_bytes: Vec<(u64, u8, bool)>,
    next_rx: usize,
    /// Bytes lost in the USART (overrun: the DMA came too late).
    pub rx_overruns: u32,
    /// Indices (in `rx_bytes`) of the bytes lost to those overruns.
    pub rx_lost: Vec<usize>,
    /// Times SPI2's OVR was set (an overrun began).
    pub spi_overruns: u32,
    pub faults: HwFaults,
    ram: Vec<u8>,
}

impl Hw {
    /// The board at power-up: timer clock `timer_hz`, APB1 at `pclk1_hz`,
    /// AD7606 conversions of `conversion_ns`.
    pub fn new(timer_hz: u32, pclk1_hz: u32, conversion_ns: u32) -> Self {
        Self {
            now: 0,
            pclk1_ticks: u64::from(timer_hz / pclk1_hz).max(1),
            conversion_ticks: u64::from(conversion_ns) * u64::from(timer_hz) / 1_000_000_000,
            tim3: Timer::default(),
            tim5: Timer::default(),
            tim5_start: None,
            runs: 0,
            adc: Adc {
                cs_high: true,
                ..Adc::default()
            },
            spi: Spi::default(),
            dma: Default::default(),
            exti_imr: 0,
            exti_ftsr: 0,
            exti_pr: 0,
            usart: Usart::default(),
            nvic_clear: 0,
            conversions: Vec::new(),
            run_starts: Vec::new(),
            capture_ticks: Vec::new(),
            next_capture: 0,
            rx_bytes: Vec::new(),
            next_rx: 0,
            rx_overruns: 0,
            rx_lost: Vec::new(),
            spi_overruns: 0,
            faults: HwFaults::default(),
            ram: vec![0; RAM_BYTES],
        }
    }

    /// Interrupt lines (level) by IRQ number.
    pub fn irq_line(&self, irq: u32) -> bool {
        match irq {
            nvic::IRQ_EXTI0 => self.exti_pr & self.exti_imr & exti::LINE_BUSY != 0,
            nvic::IRQ_DMA1_STREAM3 => self.dma[3].irq_line(),
            nvic::IRQ_DMA1_STREAM5 => self.dma[5].irq_line(),
            nvic::IRQ_SPI2 => self.spi.cr2 & spi2::CR2_ERRIE != 0 && self.spi.ovr,
            nvic::IRQ_TIM5 => {
                self.tim5.sr & tim::SR_CC2IF != 0 && self.tim5.dier & tim::DIER_CC2IE != 0
            }
            _ => false,
        }
    }

    fn dma_stalled(&self, t: u64) -> bool {
        matches!(self.faults.dma_stall, Some((a, b)) if t >= a && t < b)
    }

    /// Whether stream `n` has a request from its peripheral now.
    fn request(&self, n: usize) -> bool {
        if !self.dma[n].enabled() {
            return false;
        }
        match n {
            3 => self.spi.rxne && self.spi.cr2 & spi2::CR2_RXDMAEN != 0,
            4 => self.spi.tx.is_none() && self.spi.cr2 & spi2::CR2_TXDMAEN != 0,
            5 => self.usart.rxne && self.usart.cr3 & (1 << 6) != 0,
            6 => self.usart.cr3 & (1 << 7) != 0,
            _ => false,
        }
    }

    /// Schedules the service of new DMA requests and drops withdrawn ones.
    fn update_requests(&mut self) {
        for n in 3..7 {
            if self.request(n) {
                if self.dma[n].due.is_none() {
                    self.dma[n].due = Some(self.now + DMA_LATENCY);
                }
            } else {
                self.dma[n].due = None;
            }
        }
        // The SPI master starts the next frame as soon as its TX buffer
        // holds one.
        if self.spi.shift.is_none() && self.spi.tx.is_some() && self.spi.cr1 & spi2::CR1_SPE != 0 {
            self.spi.tx = None;
            let end = self.now + 16 * self.bit_ticks();
            self.spi.shift = Some((self.now, end));
            self.update_requests();
        }
    }

    /// The earliest tick after `now` at which something happens, if any.
    pub fn next_event(&self) -> Option<u64> {
        let mut t: Option<u64> = None;
        let mut take = |x: Option<u64>| {
            if let Some(x) = x {
                t = Some(t.map_or(x, |t| t.min(x)));
            }
        };
        take(self.tim3.next_compare);
        take(self.tim5_start);
        take(self.adc.fall_at);
        take(self.spi.shift.map(|s| s.1));
        for n in 3..7 {
            take(self.dma[n].due.map(|d| match self.faults.dma_stall {
                Some((a, b)) if d >= a && d < b => b,
                _ => d,
            }));
        }
        take(self.capture_ticks.get(self.next_capture).copied());
        take(self.rx_bytes.get(self.next_rx).map(|b| b.0));
        take(self.faults.transfer_error);
        t.map(|t| t.max(self.now))
    }

    /// Processes everything due at `t` (≥ now) and moves to it.
    pub fn process(&mut self, t: u64) {
        self.now = t;
        if self.faults.transfer_error == Some(t) {
            self.faults.transfer_error = None;
            if self.dma[3].enabled() {
                self.dma[3].flags |= dma1::TEIF;
                self.dma[3].cr &= !dma1::CR_EN;
            }
        }
        if self.tim5_start == Some(t) {
            self.tim5_start = None;
            if self.tim5.smcr & 0b111 == tim::SMCR_SMS_TRIGGER && !self.tim5.running() {
                let c = self.tim5.count(t);
                self.tim5.cr1 |= tim::CR1_CEN;
                self.tim5.rebase(t, c);
            }
        }
        if self.tim3.next_compare == Some(t) {
            self.tim3.schedule_compare(t);
            self.convst(t);
        }
        if self.adc.fall_at == Some(t) {
            self.adc.fall_at = None;
            self.busy_falls(t);
        }
        if matches!(self.spi.shift, Some((_, end)) if end == t) {
            self.frame_done(t);
        }
        for n in 3..7 {
            if self.dma[n].due.is_some_and(|d| d <= t) && !self.dma_stalled(t) {
                self.dma[n].due = None;
                if self.request(n) {
                    self.dma_transfer(n);
                }
            }
        }
        if self.capture_ticks.get(self.next_capture) == Some(&t) {
            self.next_capture += 1;
            self.capture(t);
        }
        if let Some(&(bt, byte, noisy)) = self.rx_bytes.get(self.next_rx) {
            if bt == t {
                self.next_rx += 1;
                self.usart_receive(byte, noisy);
            }
        }
        self.update_requests();
    }

    fn ram_read16(&self, addr: u32) -> u16 {
        let i = addr as usize - RAM_BASE;
        u16::from_le_bytes([self.ram[i], self.ram[i + 1]])
    }

    fn ram_write16(&mut self, addr: u32, v: u16) {
        let i = addr as usize - RAM_BASE;
        self.ram[i..i + 2].copy_from_slice(&v.to_le_bytes());
    }

    /// Writes bytes into model RAM (the firmware's buffers).
    pub fn ram_fill(&mut self, addr: usize, bytes: &[u8]) {
        let i = addr - RAM_BASE;
        self.ram[i..i + bytes.len()].copy_from_slice(bytes);
    }

    /// CHANNELS (for users of the tag helpers).
    pub const CHANNELS: usize = CHANNELS;
}
