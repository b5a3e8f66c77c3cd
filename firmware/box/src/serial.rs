//! The host link on USART2 with DMA both ways: the receiver's DMA (DMA1
//! stream 5, channel 4) runs circularly over a ring that the idle loop
//! reads ([`RxRing`]); the transmitter's DMA (stream 6, channel 4) sends
//! what [`plinth_firmware::device::Device`] queued, in chunks, from a
//! buffer the CPU does not touch while it runs.

use crate::adc_dma::{dma1, AdcDma};
use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicU32, Ordering};
use plinth_firmware::link::ByteLink;
use plinth_firmware::uart_dma::RxRing;
use stm32f4xx_hal::pac;

/// Receive ring [bytes]: 44 ms at 115 200 bit/s; the idle loop reads it at
/// least every millisecond.
pub const RX_RING_BYTES: usize = 512;
/// Bytes per transmit DMA transfer.
pub const TX_CHUNK_BYTES: usize = 256;
/// Receive stream.
pub const RX_STREAM: usize = 5;
/// Transmit stream.
pub const TX_STREAM: usize = 6;

/// Memory a DMA stream owns while it runs.
#[repr(C, align(4))]
pub struct DmaBytes<const N: usize>(UnsafeCell<[u8; N]>);

// SAFETY: the receive ring is written by the DMA and read (volatile) by the
// idle task behind `RxRing`; the transmit buffer is written by the idle
// task only while its stream is disabled.
unsafe impl<const N: usize> Sync for DmaBytes<N> {}

static RX_RING: DmaBytes<RX_RING_BYTES> = DmaBytes(UnsafeCell::new([0; RX_RING_BYTES]));
static TX_BUFFER: DmaBytes<TX_CHUNK_BYTES> = DmaBytes(UnsafeCell::new([0; TX_CHUNK_BYTES]));

/// Half rings the receive DMA passed (its half-transfer and
/// transfer-complete interrupts).
pub static RX_HALVES: AtomicU32 = AtomicU32::new(0);

/// USART2 at `baud` with both DMA streams; the receiver runs from here on.
pub struct DmaSerial {
    usart: pac::USART2,
    ring: RxRing,
    next: usize,
    waiting: usize,
    staged: heapless::Vec<u8, TX_CHUNK_BYTES>,
    line_errors: u32,
}

impl DmaSerial {
    /// Starts USART2 (8N1) at `baud` [bit/s] from the APB1 clock
    /// `pclk1_hz` [Hz], and its receive DMA.
    pub fn new(usart: pac::USART2, pclk1_hz: u32, baud: u32) -> Self {
        let dr = usart.dr().as_ptr() as u32;
        usart
            .brr()
            .write(|w| unsafe { w.bits(plinth_firmware::clock::usart_brr(pclk1_hz, baud) as u16) });
        usart.cr3().write(|w| w.dmar().enabled().dmat().enabled());
        usart
            .cr1()
            .write(|w| w.ue().enabled().te().enabled().re().enabled());
        let rx = dma1().st(RX_STREAM);
        AdcDma::clear_stream_flags(RX_STREAM);
        rx.par().write(|w| unsafe { w.bits(dr) });
        rx.m0ar()
            .write(|w| unsafe { w.bits(RX_RING.0.get() as u32) });
        rx.ndtr().write(|w| w.ndt().set(RX_RING_BYTES as u16));
        rx.cr().write(|w| {
            w.chsel()
                .set(4)
                .pl()
                .medium()
                .msize()
                .bits8()
                .psize()
                .bits8()
                .minc()
                .incremented()
                .pinc()
                .fixed()
                .circ()
                .enabled()
                .dir()
                .peripheral_to_memory()
                .htie()
                .enabled()
                .tcie()
                .enabled()
        });
        rx.cr().modify(|_, w| w.en().enabled());
        let tx = dma1().st(TX_STREAM);
        AdcDma::clear_stream_flags(TX_STREAM);
        tx.par().write(|w| unsafe { w.bits(dr) });
        tx.m0ar()
            .write(|w| unsafe { w.bits(TX_BUFFER.0.get() as u32) });
        tx.cr().write(|w| {
            w.chsel()
                .set(4)
                .pl()
                .low()
                .msize()
                .bits8()
                .psize()
                .bits8()
                .minc()
                .incremented()
                .pinc()
                .fixed()
                .dir()
                .memory_to_peripheral()
        });
        Self {
            usart,
            ring: RxRing::new(RX_RING_BYTES),
            next: 0,
            waiting: 0,
            staged: heapless::Vec::new(),
            line_errors: 0,
        }
    }

    /// Starts a transmit DMA transfer of the staged bytes if the previous
    /// one has finished. Call after every `Device::poll`.
    pub fn kick(&mut self) {
        let tx = dma1().st(TX_STREAM);
        if self.staged.is_empty() || tx.cr().read().en().is_enabled() {
            return;
        }
        let n = self.staged.len();
        // SAFETY: the stream is disabled (checked above), so nothing reads
        // the buffer; `n` ≤ its size.
        unsafe {
            let buf = TX_BUFFER.0.get().cast::<u8>();
            core::ptr::copy_nonoverlapping(self.staged.as_ptr(), buf, n);
        }
        self.staged.clear();
        AdcDma::clear_stream_flags(TX_STREAM);
        tx.ndtr().write(|w| w.ndt().set(n as u16));
        // The copy must land before the DMA reads it.
        cortex_m::asm::dmb();
        tx.cr().modify(|_, w| w.en().enabled());
    }

    /// Samples the line-error flags (framing, noise, overrun).
    fn check_line(&mut self) {
        let sr = self.usart.sr().read();
        if sr.fe().bit_is_set() || sr.nf().bit_is_set() || sr.ore().bit_is_set() {
            self.line_errors = self.line_errors.wrapping_add(1);
        }
    }
}

impl ByteLink for DmaSerial {
    fn read_byte(&mut self) -> Option<u8> {
        if self.waiting == 0 {
            self.check_line();
            let halves = RX_HALVES.load(Ordering::Acquire);
            let remaining = dma1().st(RX_STREAM).ndtr().read().ndt().bits() as usize;
            (self.next, self.waiting) = self.ring.update(halves, remaining);
            if self.waiting == 0 {
                return None;
            }
        }
        // SAFETY: `next` < RX_RING_BYTES (RxRing works modulo the ring);
        // the DMA has written this byte and will not overwrite it before
        // the reader falls a whole ring behind, which RxRing detects.
        let byte = unsafe {
            RX_RING
                .0
                .get()
                .cast::<u8>()
                .add(self.next % RX_RING_BYTES)
                .read_volatile()
        };
        self.ring.consume(1);
        self.next = (self.next + 1) % RX_RING_BYTES;
        self.waiting -= 1;
        Some(byte)
    }

    fn write_byte(&mut self, byte: u8) -> bool {
        self.staged.push(byte).is_ok()
    }

    fn receive_errors(&self) -> u32 {
        self.line_errors.wrapping_add(self.ring.overruns())
    }
}

/// What can give the idle loop work: a completed ADC half, received bytes,
/// the passing of a millisecond (status frames, transmit retries).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Look {
    halves: u32,
    rx_remaining: u16,
    rx_halves: u32,
    now_ms: u32,
}

impl Look {
    /// The state now, at `now_ms` [ms] since boot.
    pub fn now(now_ms: u32) -> Self {
        Self {
            halves: crate::adc_dma::COMPLETIONS.count(),
            rx_remaining: dma1().st(RX_STREAM).ndtr().read().ndt().bits(),
            rx_halves: RX_HALVES.load(Ordering::Relaxed),
            now_ms,
        }
    }
}
