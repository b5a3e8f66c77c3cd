//! The board's peripherals, tick by tick (one tick = one period of the
//! timer clock, 84 MHz on the PLL): TIM3 (PWM CONVST, TRGO), TIM5 (32-bit
//! input capture behind the digital filter, overcapture), EXTI0, GPIOB (CS,
//! BUSY), SPI2 (TX buffer, shift register, RXNE/OVR/BSY), DMA1 streams 3-6
//! (double-buffer and circular modes, NDTR, HT/TC/TE flags), USART2 and an
//! AD7606 (CONVST → BUSY, conversion, 128-bit serial output on DOUTA
//! restarted by each CS falling edge). Register semantics follow RM0090
//! for the bits the firmware uses; an access to anything else panics (the
//! model does not silently accept what it does not model).

use plinth_firmware::acquisition::rm0090::{dma1, exti, gpiob, nvic, spi2, tim, usart2};
use plinth_firmware::source::CHANNELS;

/// Model RAM: where the firmware's DMA buffers live.
pub const RAM_BASE: usize = 0x2000_0000;
/// Model RAM size [bytes].
pub const RAM_BYTES: usize = 0x1_0000;
/// Ticks from a DMA request to its transfer (arbitration, bus).
pub const DMA_LATENCY: u64 = 3;
/// Conversions whose tags are unique (tag = 1 + channel + 8 · (g mod this)).
pub const TAG_PERIOD: u64 = 4000;

/// The code the AD7606 gives channel `c` of conversion `g` (since power-up):
/// the conversion and channel, recoverable from any delivered sample.
pub fn tag(g: u64, c: usize) -> i16 {
    (1 + c as u64 + 8 * (g % TAG_PERIOD)) as i16
}

/// (conversion mod [`TAG_PERIOD`], channel) of a code, if it is a tag.
pub fn untag(code: i16) -> Option<(u64, usize)> {
    if code < 1 || i64::from(code) > (8 * TAG_PERIOD) as i64 {
        return None;
    }
    let v = code as u64 - 1;
    Some((v / 8, (v % 8) as usize))
}

/// One conversion the AD7606 made.
#[derive(Clone, Copy, Debug)]
pub struct Conversion {
    /// Tick of its CONVST rising edge.
    pub tick: u64,
    /// TIM3 run (enables since power-up, from 1).
    pub run: u32,
    /// CONVST edges of that run before it (its sample index in the run).
    pub index: u64,
}

/// A general-purpose timer (the parts of TIM3/TIM5 the firmware uses).
#[derive(Clone, Debug, Default)]
pub struct Timer {
    pub cr1: u32,
    pub cr2: u32,
    pub smcr: u32,
    pub dier: u32,
    pub sr: u32,
    pub ccmr1: u32,
    pub ccer: u32,
    pub psc: u32,
    pub arr: u32,
    pub ccr1: u32,
    pub ccr2: u32,
    /// Counter at `since` (when running).
    cnt: u32,
    since: u64,
    /// Tick of the next compare match (TIM3: CONVST rising edge).
    pub next_compare: Option<u64>,
    /// CONVST edges since the last enable.
    pub edges: u64,
}

impl Timer {
    fn running(&self) -> bool {
        self.cr1 & tim::CR1_CEN != 0
    }
    fn period(&self) -> u64 {
        u64::from(self.arr) + 1
    }
    /// The counter at `now`.
    pub fn count(&self, now: u64) -> u32 {
        if !self.running() {
            return self.cnt;
        }
        let n = u64::from(self.cnt) + (now - self.since) / (u64::from(self.psc) + 1);
        if self.arr == u32::MAX {
            n as u32
        } else {
            (n % self.period()) as u32
        }
    }
    fn rebase(&mut self, now: u64, cnt: u32) {
        self.cnt = cnt;
        self.since = now;
    }
    /// Schedules the next compare match of channel 1 (PWM mode 2: CONVST
    /// rises when the counter reaches CCR1).
    fn schedule_compare(&mut self, now: u64) {
        if !self.running() {
            self.next_compare = None;
            return;
        }
        let c = u64::from(self.count(now));
        let p = self.period();
        let mut d = (u64::from(self.ccr1) + p - c % p) % p;
        if d == 0 {
            d = p;
        }
        self.next_compare = Some(now + d * (u64::from(self.psc) + 1));
    }
}

/// A DMA1 stream.
#[derive(Clone, Debug, Default)]
pub struct Stream {
    pub cr: u32,
    pub ndtr: u32,
    reload: u32,
    pub par: u32,
    pub m0ar: u32,
    pub m1ar: u32,
    pub fcr: u32,
    /// Flags, unshifted (FEIF, DMEIF, TEIF, HTIF, TCIF).
    pub flags: u32,
    /// When a pending request will be served.
    due: Option<u64>,
}

impl Stream {
    fn enabled(&self) -> bool {
        self.cr & dma1::CR_EN != 0
    }
    fn irq_line(&self) -> bool {
        let f = self.flags;
        let c = self.cr;
        (f & dma1::TCIF != 0 && c & dma1::CR_TCIE != 0)
            || (f & dma1::HTIF != 0 && c & dma1::CR_HTIE != 0)
            || (f & dma1::TEIF != 0 && c & dma1::CR_TEIE != 0)
            || (f & dma1::DMEIF != 0 && c & dma1::CR_DMEIE != 0)
    }
    /// One item moved: NDTR, flags, circular/double-buffer reload.
    /// Returns the item's address.
    fn advance(&mut self, size: u32) -> u32 {
        let base = if self.cr & dma1::CR_CT != 0 {
            self.m1ar
        } else {
            self.m0ar
        };
        let addr = if self.cr & dma1::CR_MINC != 0 {
            base + (self.reload - self.ndtr) * size
        } else {
            base
        };
        self.ndtr -= 1;
        if self.ndtr == self.reload / 2 {
            self.flags |= dma1::HTIF;
        }
        if self.ndtr == 0 {
            self.flags |= dma1::TCIF;
            if self.cr & dma1::CR_DBM != 0 {
                self.cr ^= dma1::CR_CT;
                self.ndtr = self.reload;
            } else if self.cr & dma1::CR_CIRC != 0 {
                self.ndtr = self.reload;
            } else {
                self.cr &= !dma1::CR_EN;
            }
        }
        addr
    }
}

/// SPI2 as a master.
#[derive(Clone, Debug, Default)]
pub struct Spi {
    pub cr1: u32,
    pub cr2: u32,
    rxne: bool,
    ovr: bool,
    ovr_dr_read: bool,
    rx: u16,
    tx: Option<u16>,
    /// The frame being shifted: start tick, end tick.
    shift: Option<(u64, u64)>,
}

/// The AD7606 in serial mode, DOUTA only, CONVST A and B tied.
#[derive(Clone, Debug, Default)]
pub struct Adc {
    /// BUSY pin level.
    pub busy: bool,
    pub fall_at: Option<u64>,
    converting: u64,
    /// Output register: conversion whose results are shifted out, and the
    /// tick it was loaded (the previous one before that).
    output: Option<(u64, u64)>,
    previous: Option<u64>,
    /// CS pin level (high = deselected).
    pub cs_high: bool,
    /// Ticks of the recent CS falling edges.
    cs_falls: Vec<u64>,
    /// Ticks of the recent CS rising edges.
    cs_rises: Vec<u64>,
    /// SCLK bits shifted since power-up, at the start of the frame in flight.
    bits: u64,
    /// Bits shifted since power-up at each recent CS falling edge.
    bits_at_fall: Vec<u64>,
}

/// USART2 with its receive and transmit data registers.
#[derive(Clone, Debug, Default)]
pub struct Usart {
    pub cr1: u32,
    pub cr3: u32,
    pub brr: u32,
    rxne: bool,
    errors: u32,
    sr_read: bool,
    rx: u8,
    /// Bytes the box sent.
    pub sent: Vec<u8>,
}

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
            spi_overruns: 0,
            faults: HwFaults::default(),
            ram: vec![0; RAM_BYTES],
        }
    }

    /// Ticks per SCLK bit.
    fn bit_ticks(&self) -> u64 {
        (2u64 << ((self.spi.cr1 & spi2::CR1_BR_MASK) >> 3)) * self.pclk1_ticks
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

    /// CONVST rose: the AD7606 starts converting unless it is busy.
    fn convst(&mut self, t: u64) {
        let index = self.tim3.edges;
        self.tim3.edges += 1;
        if index == 0 {
            self.run_starts.push(t);
        }
        if let Some((from, level)) = self.faults.busy_stuck {
            if t >= from {
                self.adc.busy = level;
                return;
            }
        }
        if self.adc.busy {
            return; // ignored during a conversion
        }
        self.adc.busy = true;
        self.adc.fall_at = Some(t + self.conversion_ticks);
        self.adc.converting = self.conversions.len() as u64;
        self.conversions.push(Conversion {
            tick: t,
            run: self.runs,
            index,
        });
    }

    /// BUSY fell: the results are in the output register; EXTI sees the edge.
    fn busy_falls(&mut self, t: u64) {
        if let Some((from, _)) = self.faults.busy_stuck {
            if t >= from {
                return;
            }
        }
        self.adc.busy = false;
        self.adc.previous = self.adc.output.map(|o| o.0);
        self.adc.output = Some((self.adc.converting, t));
        if self.exti_ftsr & exti::LINE_BUSY != 0 {
            self.exti_pr |= exti::LINE_BUSY;
        }
    }

    /// The AD7606's DOUTA bit at tick `t`, SCLK bit number `bit` since
    /// power-up: bit (bits since the last CS fall) of the 128-bit output,
    /// 0 when CS is high or past the end.
    fn douta(&self, t: u64, bit: u64) -> u16 {
        let Some(i) = self.adc.cs_falls.iter().rposition(|&f| f <= t) else {
            return 0;
        };
        let fall = self.adc.cs_falls[i];
        if self.adc.cs_rises.iter().any(|&r| r > fall && r <= t) {
            return 0;
        }
        let pos = bit - self.adc.bits_at_fall[i];
        if pos >= 128 {
            return 0;
        }
        let g = match self.adc.output {
            Some((g, at)) if at <= t => Some(g),
            _ => self.adc.previous,
        };
        let Some(g) = g else { return 0 };
        let code = tag(g, (pos / 16) as usize) as u16;
        (code >> (15 - pos % 16)) & 1
    }

    /// A frame finished shifting: its bits, sampled at each SCLK's falling
    /// edge (mode 2: CPOL = 1, CPHA = 0), go to the RX buffer.
    fn frame_done(&mut self, t: u64) {
        let Some((start, _)) = self.spi.shift.take() else {
            return;
        };
        let b = self.bit_ticks();
        let mut word = 0u16;
        for i in 0..16 {
            let at = start + i * b + b / 2;
            word = word << 1 | self.douta(at, self.adc.bits + i);
        }
        self.adc.bits += 16;
        if self.spi.ovr {
            // RM0090 28.4.8: while OVR is set, every received frame is
            // lost (DR keeps the old one).
        } else if self.spi.rxne {
            self.spi.ovr = true; // the new frame is lost
            self.spi_overruns += 1;
        } else {
            self.spi.rx = word;
            self.spi.rxne = true;
        }
        let _ = t;
    }

    /// DMA stream `n` moves one item.
    fn dma_transfer(&mut self, n: usize) {
        match n {
            3 => {
                let w = self.spi.rx;
                self.spi_dr_read();
                let addr = self.dma[3].advance(2);
                self.ram_write16(addr, w);
            }
            4 => {
                let addr = self.dma[4].advance(2);
                let w = self.ram_read16(addr);
                self.spi.tx = Some(w);
            }
            5 => {
                let b = self.usart.rx;
                self.usart_dr_read();
                let addr = self.dma[5].advance(1);
                let i = addr as usize - RAM_BASE;
                self.ram[i] = b;
            }
            6 => {
                let addr = self.dma[6].advance(1);
                let b = self.ram[addr as usize - RAM_BASE];
                self.usart.sent.push(b);
            }
            _ => {}
        }
    }

    fn spi_dr_read(&mut self) {
        self.spi.rxne = false;
        if self.spi.ovr {
            self.spi.ovr_dr_read = true;
        }
    }

    fn usart_dr_read(&mut self) {
        self.usart.rxne = false;
        if self.usart.sr_read {
            self.usart.errors = 0;
            self.usart.sr_read = false;
        }
    }

    fn usart_receive(&mut self, byte: u8, noisy: bool) {
        if self.usart.cr1 & (1 << 2) == 0 {
            return;
        }
        if self.usart.rxne {
            // ORE: this byte is lost; the flag clears by a read of SR
            // that sees it, then of DR.
            self.usart.errors |= 1 << 3;
            self.usart.sr_read = false;
            self.rx_overruns += 1;
            return;
        }
        self.usart.rx = byte;
        self.usart.rxne = true;
        if noisy {
            self.usart.sr_read = false;
            self.usart.errors |= 1 << 2 | 1 << 1; // NF, FE
        }
    }

    /// TIM5 latches a (filtered, resynchronised) keyphasor edge.
    fn capture(&mut self, t: u64) {
        if self.tim5.ccer & tim::CCER_CC2E == 0 {
            return;
        }
        if self.tim5.sr & tim::SR_CC2IF != 0 {
            self.tim5.sr |= tim::SR_CC2OF;
        }
        self.tim5.ccr2 = self.tim5.count(t);
        self.tim5.sr |= tim::SR_CC2IF;
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

    fn timer(&mut self, addr: usize) -> (&mut Timer, usize, bool) {
        if (tim::TIM3..tim::TIM3 + 0x400).contains(&addr) {
            (&mut self.tim3, addr - tim::TIM3, true)
        } else {
            (&mut self.tim5, addr - tim::TIM5, false)
        }
    }

    /// A 32-bit read by the CPU.
    pub fn read(&mut self, addr: usize) -> u32 {
        let now = self.now;
        let v = match addr {
            a if (RAM_BASE..RAM_BASE + RAM_BYTES).contains(&a) => {
                let i = a - RAM_BASE;
                u32::from_le_bytes([
                    self.ram[i],
                    self.ram[i + 1],
                    self.ram[i + 2],
                    self.ram[i + 3],
                ])
            }
            a if (tim::TIM3..tim::TIM3 + 0x400).contains(&a)
                || (tim::TIM5..tim::TIM5 + 0x400).contains(&a) =>
            {
                let (t, off, _) = self.timer(a);
                match off {
                    tim::CR1 => t.cr1,
                    tim::SR => t.sr,
                    tim::CNT => t.count(now),
                    tim::CCR2 => {
                        t.sr &= !tim::SR_CC2IF;
                        t.ccr2
                    }
                    tim::DIER => t.dier,
                    _ => panic!("model: read of timer register {a:#x}"),
                }
            }
            spi2::SR => {
                let s = &mut self.spi;
                if s.ovr && s.ovr_dr_read {
                    s.ovr = false;
                    s.ovr_dr_read = false;
                    // (this read still shows OVR)
                    return u32::from(s.rxne)
                        | (u32::from(s.tx.is_none()) << 1)
                        | spi2::SR_OVR
                        | (u32::from(s.shift.is_some()) << 7);
                }
                u32::from(s.rxne)
                    | (u32::from(s.tx.is_none()) << 1)
                    | if s.ovr { spi2::SR_OVR } else { 0 }
                    | (u32::from(s.shift.is_some() || s.tx.is_some()) << 7)
            }
            spi2::DR => {
                let w = self.spi.rx;
                self.spi_dr_read();
                u32::from(w)
            }
            spi2::CR1 => self.spi.cr1,
            spi2::CR2 => self.spi.cr2,
            dma1::LISR | dma1::HISR => {
                let streams = if addr == dma1::LISR { 0..4 } else { 4..8 };
                streams
                    .map(|n| self.dma[n].flags << dma1::flags(n).2)
                    .fold(0, |a, b| a | b)
            }
            a if (dma1::cr(0)..dma1::cr(8)).contains(&a) => {
                let n = (a - dma1::cr(0)) / 0x18;
                let s = &self.dma[n];
                match (a - dma1::cr(0)) % 0x18 {
                    0x00 => s.cr,
                    0x04 => s.ndtr,
                    _ => panic!("model: read of DMA register {a:#x}"),
                }
            }
            exti::IMR => self.exti_imr,
            exti::PR => self.exti_pr,
            exti::FTSR => self.exti_ftsr,
            gpiob::IDR => u32::from(self.adc.busy) | (u32::from(self.adc.cs_high) << 12),
            usart2::SR => {
                self.usart.sr_read = true;
                self.usart.errors | (u32::from(self.usart.rxne) << 5) | 1 << 7 | 1 << 6
            }
            usart2::DR => {
                let b = self.usart.rx;
                self.usart_dr_read();
                u32::from(b)
            }
            _ => panic!("model: read of unmodelled register {addr:#x}"),
        };
        self.update_requests();
        v
    }

    /// A 32-bit write by the CPU.
    pub fn write(&mut self, addr: usize, v: u32) {
        let now = self.now;
        match addr {
            a if (RAM_BASE..RAM_BASE + RAM_BYTES).contains(&a) => {
                let i = a - RAM_BASE;
                self.ram[i..i + 4].copy_from_slice(&v.to_le_bytes());
            }
            a if (tim::TIM3..tim::TIM3 + 0x400).contains(&a)
                || (tim::TIM5..tim::TIM5 + 0x400).contains(&a) =>
            {
                let trigger = self.tim5.smcr & 0b111 == tim::SMCR_SMS_TRIGGER;
                let (t, off, is_tim3) = self.timer(a);
                let was = t.running();
                let mut started = false;
                match off {
                    tim::CR1 => {
                        let c = t.count(now);
                        t.cr1 = v;
                        t.rebase(now, c);
                        if is_tim3 {
                            if !was && t.running() {
                                t.edges = 0;
                                t.schedule_compare(now);
                                started = true;
                            } else if !t.running() {
                                t.next_compare = None;
                            }
                        }
                    }
                    tim::CR2 => t.cr2 = v,
                    tim::SMCR => t.smcr = v,
                    tim::DIER => t.dier = v,
                    tim::SR => t.sr &= v,
                    tim::EGR => {
                        if v & tim::EGR_UG != 0 {
                            t.rebase(now, 0);
                            if is_tim3 {
                                t.schedule_compare(now);
                            }
                        }
                    }
                    tim::CCMR1 => t.ccmr1 = v,
                    tim::CCER => t.ccer = v,
                    tim::CNT => {
                        t.rebase(now, v);
                        if is_tim3 {
                            t.schedule_compare(now);
                        }
                    }
                    tim::PSC => t.psc = v,
                    tim::ARR => t.arr = v,
                    tim::CCR1 => t.ccr1 = v,
                    _ => panic!("model: write of timer register {a:#x}"),
                }
                if started {
                    self.runs += 1;
                    if trigger {
                        self.tim5_start = Some(now + 1);
                    }
                }
            }
            spi2::CR1 => self.spi.cr1 = v,
            spi2::CR2 => self.spi.cr2 = v,
            spi2::DR => self.spi.tx = Some(v as u16),
            dma1::LIFCR | dma1::HIFCR => {
                let streams = if addr == dma1::LIFCR { 0..4 } else { 4..8 };
                for n in streams {
                    self.dma[n].flags &= !((v >> dma1::flags(n).2) & dma1::ALL_FLAGS);
                }
            }
            a if (dma1::cr(0)..dma1::cr(8)).contains(&a) => {
                let n = (a - dma1::cr(0)) / 0x18;
                let s = &mut self.dma[n];
                match (a - dma1::cr(0)) % 0x18 {
                    0x00 => {
                        if s.cr & dma1::CR_EN == 0 && v & dma1::CR_EN != 0 {
                            s.reload = s.ndtr;
                        }
                        if s.cr & dma1::CR_EN != 0 {
                            // Only EN can change while enabled.
                            s.cr = (s.cr & !dma1::CR_EN) | (v & dma1::CR_EN);
                        } else {
                            s.cr = v;
                        }
                    }
                    0x04 if s.cr & dma1::CR_EN == 0 => s.ndtr = v & 0xFFFF,
                    0x08 if s.cr & dma1::CR_EN == 0 => s.par = v,
                    0x0C if s.cr & dma1::CR_EN == 0 => s.m0ar = v,
                    0x10 if s.cr & dma1::CR_EN == 0 => s.m1ar = v,
                    0x14 if s.cr & dma1::CR_EN == 0 => s.fcr = v,
                    _ => {} // ignored while the stream runs, as on silicon
                }
            }
            exti::IMR => self.exti_imr = v,
            exti::FTSR => self.exti_ftsr = v,
            exti::PR => self.exti_pr &= !v,
            gpiob::BSRR => {
                if v & gpiob::CS != 0 && !self.adc.cs_high {
                    self.adc.cs_high = true;
                    push_recent(&mut self.adc.cs_rises, now);
                }
                if v & (gpiob::CS << 16) != 0 && self.adc.cs_high {
                    self.adc.cs_high = false;
                    // Bits shifted by now: those of the frame in flight
                    // that have passed.
                    let bits = match self.spi.shift {
                        Some((start, _)) => self.adc.bits + (now - start) / self.bit_ticks().max(1),
                        None => self.adc.bits,
                    };
                    push_recent(&mut self.adc.cs_falls, now);
                    push_recent(&mut self.adc.bits_at_fall, bits);
                }
            }
            nvic::ICPR0 => self.nvic_clear |= u64::from(v),
            0xE000_E284 => self.nvic_clear |= u64::from(v) << 32,
            usart2::BRR => self.usart.brr = v,
            usart2::CR1 => self.usart.cr1 = v,
            usart2::CR3 => self.usart.cr3 = v,
            usart2::DR => self.usart.sent.push(v as u8),
            _ => panic!("model: write of unmodelled register {addr:#x} = {v:#x}"),
        }
        self.update_requests();
    }

    /// CHANNELS (for users of the tag helpers).
    pub const CHANNELS: usize = CHANNELS;
}

/// Keeps the last few entries of an edge history.
fn push_recent(v: &mut Vec<u64>, x: u64) {
    if v.len() >= 8 {
        v.remove(0);
    }
    v.push(x);
}

/// Ticks at which TIM5's channel 2 latches the rising edges of an input
/// with `transitions` (tick, level) through the digital filter (f_DTS/32,
/// N = 8: the output changes after 8 equal samples taken every 32 ticks)
/// and 2 ticks of resynchronisation.
pub fn filtered_captures(transitions: &[(u64, bool)], step: u64, n: u64) -> Vec<u64> {
    let mut out = Vec::new();
    let (mut run_level, mut run_count, mut output) = (false, 0u64, false);
    for (i, &(t, level)) in transitions.iter().enumerate() {
        let end = transitions.get(i + 1).map_or(t + 1_000_000, |x| x.0);
        let first = t.div_ceil(step) * step;
        if first >= end {
            continue; // no sample sees this level
        }
        let samples = (end - 1 - first) / step + 1;
        let before = if level == run_level { run_count } else { 0 };
        run_level = level;
        run_count = before + samples;
        if run_count >= n && output != level {
            output = level;
            if level {
                let k = n.saturating_sub(before + 1);
                out.push(first + k * step + 2);
            }
        }
    }
    out
}
