//! The reference board's acquisition hardware and its interrupt handlers,
//! written against [`Registers`] (address access) so that the same code
//! runs on the STM32F407 (`plinth-box` passes the memory map) and on the
//! host's tick-level board model (crate `plinth-board-model`).
//!
//! TIM3 paces CONVST; BUSY's falling edge (EXTI0) runs [`busy_fell`],
//! which pulses CS and arms SPI2's transmit DMA (DMA1 stream 4) for 8
//! dummy words; the receive DMA (stream 3, double-buffer mode) fills two
//! halves; [`adc_half`] counts completed halves; TIM5 timestamps the
//! keyphasor ([`keyphasor`]); [`spi_error`] counts SPI overruns.
//!
//! Ownership (one owner per resource at any time):
//! - stream 4 (SPI TX) and CS: [`busy_fell`] while EXTI0 is unmasked; the
//!   idle task ([`AdcDma`]) while it is masked (`stop` masks it first and
//!   waits until the last read has finished, `start` unmasks it last);
//! - stream 3's flags and the completion count: [`adc_half`];
//! - TIM5's capture registers and the capture queue's producer:
//!   [`keyphasor`]; SPI2's SR/DR after an error: [`spi_error`];
//! - everything else (timers, stream set-up, SPI CR1/CR2, EXTI mask):
//!   [`AdcDma`] in the idle task.
//!
//! Sequence faults (the sample sequence broke; the source restarts from a
//! clean state and reports a gap, never samples out of place):
//! - a late read: BUSY fell while the previous read still ran (the receive
//!   stream's count is not a multiple of 8, or the transmit stream still
//!   runs): pulsing CS would restart the AD7606's output mid-read;
//! - a slip: two BUSY edges merged while interrupts were masked (EXTI
//!   remembers one): TIM5's count is a period or more past where this
//!   conversion's BUSY could fall;
//! - a stall: no half completed long after one was due (BUSY stuck);
//! - DMA transfer/direct-mode errors and SPI overruns.
//!
//! This module is the idle task's driver ([`AdcDma`]) and the DMA set-up
//! both sides use; `interrupts` holds the handlers, `state` what they share
//! with the idle task.

use super::dma_source::AcquisitionHardware;
use super::handover::DoubleBuffer;
use super::read_plan::ReadPlan;
use super::rm0090::{dma1, exti, gpiob, nvic, spi2, tim};
use crate::clock::Registers;
use crate::revert::Revert;
use crate::source::CHANNELS;
use core::sync::atomic::Ordering;
use heapless::spsc::Consumer;
use plinth_shared::protocol::BoxHealth;

mod interrupts;
mod state;

pub use interrupts::{adc_half, busy_fell, keyphasor, spi_error};
use state::bump;
pub use state::{AdcFaults, AdcShared};

/// SPI2 receive stream (DMA1, channel 0).
pub const RX_STREAM: usize = 3;
/// SPI2 transmit stream (DMA1, channel 0).
pub const TX_STREAM: usize = 4;
/// 16-bit words per conversion.
const WORDS: u32 = CHANNELS as u32;

/// TIM5 input filter on the keyphasor: f_DTS/32, N = 8 (IC2F = 1111): an
/// edge must hold for 8 samples 32 ticks apart (≈ 3 µs at 84 MHz), which
/// debounces a comparator.
pub const KEYPHASOR_FILTER: u32 = 0b1111;
/// Timer ticks between the filter's samples (f_DTS/32).
pub const KEYPHASOR_FILTER_STEP: u32 = 32;
/// Samples the filter needs to see high.
pub const KEYPHASOR_FILTER_N: u32 = 8;
/// TIM5 starts one tick after TIM3 (TRGO → slave trigger).
pub const TIM5_START_LAG_TICKS: u32 = 1;
/// Capture ticks between a keyphasor edge and the count TIM5 latches:
/// the filter's 7 further samples after the first one that sees the edge
/// (which comes 0-31 ticks after it: 15.5 on average), and 2 ticks of
/// resynchronisation. An estimate from RM0090's description (the board
/// model implements that description); the hardware-in-the-loop procedure
/// measures it.
pub const CAPTURE_DELAY_TICKS: u32 =
    (KEYPHASOR_FILTER_N - 1) * KEYPHASOR_FILTER_STEP + KEYPHASOR_FILTER_STEP / 2 + 2;
/// Polls of a status bit before a wait in `stop` gives up (≥ 25 µs at
/// 168 MHz: a conversion plus a read).
pub const STOP_POLLS: u32 = 2_048;

/// Clears every flag of DMA1 stream `n`.
fn clear_stream_flags(r: &mut impl Registers, n: usize) {
    let (_, ifcr, shift) = dma1::flags(n);
    r.write(ifcr, dma1::ALL_FLAGS << shift);
}

/// The flags of DMA1 stream `n` (unshifted).
fn stream_flags(r: &mut impl Registers, n: usize) -> u32 {
    let (isr, _, shift) = dma1::flags(n);
    (r.read(isr) >> shift) & dma1::ALL_FLAGS
}

/// SxCR of the transmit stream, without EN.
const TX_CR: u32 =
    dma1::cr_chsel(0) | dma1::cr_pl(2) | dma1::CR_MSIZE_16 | dma1::CR_PSIZE_16 | dma1::CR_DIR_M2P;
/// SxCR of the receive stream, without EN.
const RX_CR: u32 = dma1::cr_chsel(0)
    | dma1::CR_DBM
    | dma1::cr_pl(3)
    | dma1::CR_MSIZE_16
    | dma1::CR_PSIZE_16
    | dma1::CR_MINC
    | dma1::CR_TCIE
    | dma1::CR_TEIE
    | dma1::CR_DMEIE;

/// How `stop` and `start` treat the hardware.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RestartPath {
    /// Masks BUSY, stops CONVST, waits for the conversion and the read to
    /// end, disables the SPI DMA requests, drains the SPI, clears every
    /// pending bit (the box).
    Clean,
    /// The restart before issue 18 (BUSY left unmasked, one DR/SR flush),
    /// kept only so that a test shows what it corrupts.
    Legacy,
}

/// The acquisition hardware of the reference board, driven from the idle
/// task: TIM3, TIM5, SPI2, DMA1 streams 3 and 4, EXTI0's mask, CS.
pub struct AdcDma<R: 'static, const N: usize> {
    regs: R,
    shared: &'static AdcShared,
    plan: ReadPlan,
    /// Address of the two halves (2 × vectors × 8 × 16 bit, 4-aligned).
    memory: u32,
    /// Address of the 16-bit word the transmit DMA sends.
    dummy: u32,
    vectors_per_half: usize,
    captures: Consumer<'static, u32, N>,
    path: RestartPath,
    revert: Revert,
}

impl<R: Registers + Clone, const N: usize> AdcDma<R, N> {
    /// Configures the timers and SPI2 for `plan` (clocks on, pins in their
    /// alternate functions, EXTI0 routed to PB0); nothing runs until
    /// [`AcquisitionHardware::start`]. `memory` is the address of the two
    /// halves of `vectors_per_half` vectors each, `dummy` the address of
    /// the transmitted word.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        mut regs: R,
        shared: &'static AdcShared,
        plan: ReadPlan,
        memory: u32,
        dummy: u32,
        vectors_per_half: usize,
        captures: Consumer<'static, u32, N>,
        path: RestartPath,
    ) -> Self {
        let t = plan.timing;
        let r = &mut regs;
        // CONVST: TIM3 channel 1, PWM mode 2 (high from CCR1 to the end of
        // the period), TRGO on enable to start TIM5.
        r.write(tim::TIM3 + tim::CR1, tim::CR1_ARPE);
        r.write(tim::TIM3 + tim::PSC, u32::from(t.prescaler));
        r.write(tim::TIM3 + tim::ARR, t.auto_reload);
        r.write(tim::TIM3 + tim::CCR1, t.compare);
        r.write(tim::TIM3 + tim::CCMR1, tim::CCMR1_OC1_PWM2);
        r.write(tim::TIM3 + tim::CCER, tim::CCER_CC1E);
        r.write(tim::TIM3 + tim::CR2, tim::CR2_MMS_ENABLE);
        r.write(tim::TIM3 + tim::EGR, tim::EGR_UG);
        // Keyphasor: TIM5 channel 2 captures TI2's rising edges through
        // the debouncing filter; 32-bit free run from TIM3's enable.
        r.write(tim::TIM5 + tim::PSC, 0);
        r.write(tim::TIM5 + tim::ARR, u32::MAX);
        r.write(
            tim::TIM5 + tim::CCMR1,
            tim::CCMR1_CC2S_TI2 | tim::ccmr1_ic2f(KEYPHASOR_FILTER),
        );
        r.write(tim::TIM5 + tim::CCER, tim::CCER_CC2E);
        r.write(
            tim::TIM5 + tim::SMCR,
            tim::SMCR_TS_ITR1 | tim::SMCR_SMS_TRIGGER,
        );
        r.write(tim::TIM5 + tim::EGR, tim::EGR_UG);
        r.write(tim::TIM5 + tim::SR, 0);
        r.write(tim::TIM5 + tim::DIER, tim::DIER_CC2IE);
        // SPI2: master, mode 2 (SCK idles high, data taken on the falling
        // edge, as the AD7606 shifts on the rising one), the plan's
        // divider, 16-bit frames MSB first, CS by GPIO.
        r.write(
            spi2::CR1,
            spi2::CR1_MSTR
                | spi2::CR1_CPOL
                | spi2::cr1_br(plan.spi_br)
                | spi2::CR1_DFF
                | spi2::CR1_SSM
                | spi2::CR1_SSI,
        );
        r.write(spi2::CR2, 0);
        r.modify(spi2::CR1, spi2::CR1_SPE, spi2::CR1_SPE);
        // BUSY's falling edge, masked until `start`.
        r.modify(exti::FTSR, exti::LINE_BUSY, exti::LINE_BUSY);
        let unmask = if path == RestartPath::Legacy {
            exti::LINE_BUSY
        } else {
            0
        };
        r.modify(exti::IMR, exti::LINE_BUSY, unmask);
        r.write(gpiob::BSRR, gpiob::CS);
        Self {
            regs,
            shared,
            plan,
            memory,
            dummy,
            vectors_per_half: vectors_per_half.max(1),
            captures,
            path,
            revert: Revert::None,
        }
    }

    /// Switches one fix off (tests only: the board model shows what the
    /// fault matrix finds without it; the box never calls this).
    pub fn revert(&mut self, revert: Revert) {
        self.revert = revert;
        self.shared
            .slip_check
            .store(revert != Revert::SlipDetector, Ordering::Relaxed);
    }

    /// The plan in use.
    pub fn plan(&self) -> ReadPlan {
        self.plan
    }

    /// The fault counters.
    pub fn faults(&self) -> AdcFaults {
        self.shared.faults()
    }

    /// Polls `addr` until `bits` read as `value` (at most [`STOP_POLLS`]).
    fn wait(&mut self, addr: usize, bits: u32, value: u32) {
        for _ in 0..STOP_POLLS {
            if self.regs.read(addr) & bits == value {
                return;
            }
        }
    }

    /// Disables DMA1 stream `n` and waits until it has stopped.
    fn disable_stream(&mut self, n: usize) {
        self.regs.modify(dma1::cr(n), dma1::CR_EN, 0);
        self.wait(dma1::cr(n), dma1::CR_EN, 0);
    }

    /// Capture count of sample 0 as the timebase takes it.
    fn origin(&self) -> u32 {
        self.plan
            .timing
            .first_rise_ticks
            .wrapping_sub(TIM5_START_LAG_TICKS)
            .wrapping_add(CAPTURE_DELAY_TICKS)
    }

    /// The stop before issue 18: timers and streams off, nothing waited for.
    fn legacy_stop(&mut self) {
        let r = &mut self.regs;
        r.modify(tim::TIM3 + tim::CR1, tim::CR1_CEN, 0);
        r.modify(tim::TIM5 + tim::CR1, tim::CR1_CEN, 0);
        self.disable_stream(TX_STREAM);
        self.disable_stream(RX_STREAM);
    }
}

impl<R: Registers + Clone, const N: usize> DoubleBuffer for AdcDma<R, N> {
    fn completed(&self) -> u32 {
        self.shared.completions.count()
    }

    fn read(&self, half: usize, vector: usize) -> [i16; CHANNELS] {
        let index = half.min(1) * self.vectors_per_half + vector.min(self.vectors_per_half - 1);
        let base = self.memory as usize + index * 2 * CHANNELS;
        let mut regs = self.regs.clone();
        let mut out = [0i16; CHANNELS];
        for (k, pair) in out.chunks_exact_mut(2).enumerate() {
            let word = regs.read(base + 4 * k);
            pair[0] = word as u16 as i16;
            pair[1] = (word >> 16) as u16 as i16;
        }
        out
    }
}

impl<R: Registers + Clone, const N: usize> AcquisitionHardware for AdcDma<R, N> {
    fn start(&mut self) -> u32 {
        self.stop();
        self.shared.completions.reset();
        while self.captures.dequeue().is_some() {}
        let half_words = (self.vectors_per_half * CHANNELS) as u32;
        let memory = self.memory;
        let dummy = self.dummy;
        let p = self.plan.timing.timer_ticks_per_sample;
        let legacy = self.path == RestartPath::Legacy;
        let r = &mut self.regs;
        // Receive: SPI2 DR → the two halves, double-buffer mode, 16-bit.
        r.write(dma1::par(RX_STREAM), spi2::DR as u32);
        r.write(dma1::m0ar(RX_STREAM), memory);
        r.write(dma1::m1ar(RX_STREAM), memory + 2 * half_words);
        r.write(dma1::ndtr(RX_STREAM), half_words);
        r.write(dma1::fcr(RX_STREAM), 0);
        r.write(dma1::cr(RX_STREAM), RX_CR);
        // Transmit: the dummy word, 8 times per conversion (armed by
        // `busy_fell`).
        r.write(dma1::par(TX_STREAM), spi2::DR as u32);
        r.write(dma1::m0ar(TX_STREAM), dummy);
        r.write(dma1::fcr(TX_STREAM), 0);
        r.write(dma1::cr(TX_STREAM), TX_CR);
        clear_stream_flags(r, RX_STREAM);
        clear_stream_flags(r, TX_STREAM);
        if legacy {
            // Stale received words out of the SPI (one flush).
            let _ = r.read(spi2::DR);
            let _ = r.read(spi2::SR);
        }
        r.modify(dma1::cr(RX_STREAM), dma1::CR_EN, dma1::CR_EN);
        let cr2 = spi2::CR2_RXDMAEN | spi2::CR2_TXDMAEN;
        let errie = !legacy && self.revert != Revert::SpiErrorInterrupt;
        r.write(spi2::CR2, if errie { cr2 | spi2::CR2_ERRIE } else { cr2 });
        r.write(tim::TIM5 + tim::CNT, 0);
        r.write(tim::TIM5 + tim::SR, 0);
        r.write(tim::TIM3 + tim::CNT, 0);
        let first_fall = self
            .plan
            .timing
            .first_rise_ticks
            .wrapping_sub(TIM5_START_LAG_TICKS)
            .wrapping_add(self.plan.conversion_min_ticks);
        self.shared.ticks_per_sample.store(p, Ordering::Relaxed);
        self.shared.next_fall.store(first_fall, Ordering::Relaxed);
        let r = &mut self.regs;
        if !legacy {
            r.write(exti::PR, exti::LINE_BUSY);
            r.write(nvic::ICPR0, 1 << nvic::IRQ_EXTI0);
            r.modify(exti::IMR, exti::LINE_BUSY, exti::LINE_BUSY);
        }
        // Go: TIM3 counts, its TRGO starts TIM5 on the same clock.
        r.modify(tim::TIM3 + tim::CR1, tim::CR1_CEN, tim::CR1_CEN);
        self.origin()
    }

    fn stop(&mut self) {
        if self.path == RestartPath::Legacy {
            self.legacy_stop();
            return;
        }
        // No new read may start, no new conversion either.
        self.regs.modify(exti::IMR, exti::LINE_BUSY, 0);
        self.regs.modify(tim::TIM3 + tim::CR1, tim::CR1_CEN, 0);
        // A conversion in flight ends (BUSY low), the read in flight ends
        // (transmit stream done, SPI idle with nothing to send).
        if self.revert != Revert::StopWaitBusy {
            self.wait(gpiob::IDR, gpiob::BUSY, 0);
        }
        if self.revert != Revert::StopWaitSpiIdle {
            self.wait(dma1::cr(TX_STREAM), dma1::CR_EN, 0);
            self.wait(spi2::SR, spi2::SR_TXE | spi2::SR_BSY, spi2::SR_TXE);
        }
        self.regs.write(spi2::CR2, 0);
        self.disable_stream(TX_STREAM);
        self.disable_stream(RX_STREAM);
        self.regs.modify(tim::TIM5 + tim::CR1, tim::CR1_CEN, 0);
        // Words the DMA did not take, and OVR (read DR, then SR).
        if self.revert != Revert::StopDrain {
            for _ in 0..4 {
                if self.regs.read(spi2::SR) & spi2::SR_RXNE == 0 {
                    break;
                }
                let _ = self.regs.read(spi2::DR);
            }
            let _ = self.regs.read(spi2::SR);
        }
        let r = &mut self.regs;
        r.write(exti::PR, exti::LINE_BUSY);
        clear_stream_flags(r, RX_STREAM);
        clear_stream_flags(r, TX_STREAM);
        r.write(
            nvic::ICPR0,
            1 << nvic::IRQ_EXTI0 | 1 << nvic::IRQ_DMA1_STREAM3,
        );
        r.write(gpiob::BSRR, gpiob::CS);
    }

    fn take_capture(&mut self) -> Option<u32> {
        self.captures.dequeue()
    }

    fn health(&self, health: &mut BoxHealth) {
        let f = self.shared.faults();
        health.slips = f.slips;
        health.late_reads = f.late_reads;
        health.stalls = f.stalls;
        health.spi_errors = f.spi_errors;
        health.dma_errors = f.dma_errors;
        health.lost_captures = f.lost_captures;
    }

    fn sequence_faults(&self) -> u32 {
        if self.path == RestartPath::Legacy {
            let f = self.shared.faults();
            return f.late_reads.wrapping_add(f.dma_errors);
        }
        // A stall: the half after the completed ones should have been done
        // two halves ago (TIM5 against the completion count).
        let mut regs = self.regs.clone();
        if regs.read(tim::TIM3 + tim::CR1) & tim::CR1_CEN != 0 {
            let p = self.plan.timing.timer_ticks_per_sample;
            let half = p.wrapping_mul(self.vectors_per_half as u32);
            let done = self.shared.completions.count();
            let due = self
                .origin()
                .wrapping_add(self.plan.read_end_ticks)
                .wrapping_add(done.wrapping_add(3).wrapping_mul(half));
            let now = regs.read(tim::TIM5 + tim::CNT);
            if now.wrapping_sub(due) as i32 > 0 {
                bump(&self.shared.stalls);
            }
        }
        self.shared.faults().sequence()
    }
}
