//! The acquisition's interrupt handlers: BUSY fell (arm the read, or count
//! a sequence fault), a receive half completed, an SPI error, a keyphasor
//! capture. Each writes only the resources the module docs of
//! [`super`] give it.

use super::super::rm0090::{dma1, exti, gpiob, spi2, tim};
use super::state::bump;
use super::{clear_stream_flags, stream_flags, AdcShared, RX_STREAM, TX_CR, TX_STREAM, WORDS};
use crate::clock::Registers;
use core::sync::atomic::Ordering;
use heapless::spsc::Producer;

/// BUSY fell (EXTI0, highest priority): the conversion is done; clock its
/// 8 words out, unless the sequence broke (then count and skip: the source
/// restarts).
pub fn busy_fell(r: &mut impl Registers, s: &AdcShared) {
    if r.read(exti::PR) & exti::LINE_BUSY == 0 {
        return; // pended before `stop` cleared the line: not a conversion
    }
    r.write(exti::PR, exti::LINE_BUSY);
    // Slip: TIM5 counts from sample 0; this conversion's BUSY falls no
    // earlier than `next_fall`, the next one a period later.
    let now = r.read(tim::TIM5 + tim::CNT);
    let late_by = now.wrapping_sub(s.next_fall.load(Ordering::Relaxed)) as i32;
    let p = s.ticks_per_sample.load(Ordering::Relaxed);
    if (late_by < 0 || late_by >= p as i32) && s.slip_check.load(Ordering::Relaxed) {
        bump(&s.slips);
        return;
    }
    // The previous read must be over: the receive stream has taken a whole
    // number of conversions and the transmit stream has stopped.
    let remaining = r.read(dma1::ndtr(RX_STREAM));
    let tx_running = r.read(dma1::cr(TX_STREAM)) & dma1::CR_EN != 0;
    if !remaining.is_multiple_of(WORDS) || tx_running {
        bump(&s.late_reads);
        return;
    }
    if stream_flags(r, TX_STREAM) & (dma1::TEIF | dma1::DMEIF) != 0 {
        bump(&s.dma_errors);
        return;
    }
    clear_stream_flags(r, TX_STREAM);
    // A CS falling edge starts the AD7606's serial output; CS high ≥ 50 ns
    // before it (two bus reads: ≥ 8 cycles at 168 MHz).
    r.write(gpiob::BSRR, gpiob::CS);
    let _ = r.read(gpiob::IDR);
    let _ = r.read(gpiob::IDR);
    r.write(gpiob::BSRR, gpiob::CS << 16);
    r.write(dma1::ndtr(TX_STREAM), WORDS);
    r.write(dma1::cr(TX_STREAM), TX_CR | dma1::CR_EN);
    s.next_fall.store(
        s.next_fall.load(Ordering::Relaxed).wrapping_add(p),
        Ordering::Relaxed,
    );
}

/// The receive DMA's interrupt (priority below [`busy_fell`]): a half
/// completed, or a transfer error.
pub fn adc_half(r: &mut impl Registers, s: &AdcShared) {
    let flags = stream_flags(r, RX_STREAM);
    let (isr, ifcr, shift) = dma1::flags(RX_STREAM);
    r.write(ifcr, flags << shift);
    if flags & (dma1::TEIF | dma1::DMEIF) != 0 {
        bump(&s.dma_errors);
    }
    if flags & dma1::TCIF != 0 {
        s.completions.complete();
    }
    // The clear must land before the return, or the interrupt re-enters.
    let _ = r.read(isr);
}

/// SPI2's error interrupt: an overrun (a word came before the DMA took the
/// one before) or a mode fault. Counted (a sequence fault); OVR is cleared
/// by reading DR then SR.
pub fn spi_error(r: &mut impl Registers, s: &AdcShared) {
    let sr = r.read(spi2::SR);
    if sr & (spi2::SR_OVR | spi2::SR_MODF) != 0 {
        bump(&s.spi_errors);
        let _ = r.read(spi2::DR);
        let _ = r.read(spi2::SR);
    }
}

/// A keyphasor edge was captured (TIM5 channel 2): its count goes to the
/// queue; an overcapture or a full queue is counted.
pub fn keyphasor<const N: usize>(
    r: &mut impl Registers,
    s: &AdcShared,
    captures: &mut Producer<'_, u32, N>,
) {
    let sr = r.read(tim::TIM5 + tim::SR);
    if sr & tim::SR_CC2OF != 0 {
        bump(&s.lost_captures);
        // SR's flags clear by writing 0 and ignore a 1: clear CC2OF alone.
        r.write(tim::TIM5 + tim::SR, !tim::SR_CC2OF);
    }
    if sr & tim::SR_CC2IF != 0 {
        // Reading CCR2 clears CC2IF.
        let count = r.read(tim::TIM5 + tim::CCR2);
        if captures.enqueue(count).is_err() {
            bump(&s.lost_captures);
        }
    }
}
