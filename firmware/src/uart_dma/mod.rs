//! The host link on USART2 with DMA both ways (`plinth-box`), written
//! against [`Registers`] so that the board model runs it: the receiver's
//! DMA (DMA1 stream 5, channel 4) runs circularly over a ring that the idle
//! loop reads ([`RxRing`]); the transmitter's DMA (stream 6, channel 4)
//! sends what the device queued, in chunks, from a buffer the CPU does not
//! touch while it runs; [`host_rx_half`] is the receive stream's interrupt.
//!
//! Ownership: stream 5's flags and the half count belong to
//! [`host_rx_half`]; everything else to the idle task ([`DmaSerial`]).

mod ring;

pub use ring::RxRing;

use crate::acquisition::rm0090::{dma1, usart2};
use crate::clock::Registers;
use crate::link::ByteLink;
use core::sync::atomic::{AtomicU32, Ordering};

/// Receive stream.
pub const RX_STREAM: usize = 5;
/// Transmit stream.
pub const TX_STREAM: usize = 6;
/// Bytes per transmit DMA transfer.
pub const TX_CHUNK_BYTES: usize = 256;

/// The receive stream's interrupt: counts half rings passed (half
/// transfer or transfer complete); a spurious entry (no flag: the stream
/// was stopped) counts nothing.
pub fn host_rx_half(r: &mut impl Registers, halves: &AtomicU32) {
    let (isr, ifcr, shift) = dma1::flags(RX_STREAM);
    let flags = (r.read(isr) >> shift) & dma1::ALL_FLAGS;
    r.write(ifcr, flags << shift);
    let passed = u32::from(flags & dma1::HTIF != 0) + u32::from(flags & dma1::TCIF != 0);
    if passed != 0 {
        halves.store(
            halves.load(Ordering::Relaxed).wrapping_add(passed),
            Ordering::Release,
        );
    }
    // The clear must land before the return, or the interrupt re-enters.
    let _ = r.read(isr);
}

/// USART2 with both DMA streams.
pub struct DmaSerial<R: 'static> {
    regs: R,
    halves: &'static AtomicU32,
    ring: RxRing,
    ring_addr: u32,
    ring_bytes: usize,
    tx_addr: u32,
    next: usize,
    waiting: usize,
    staged: heapless::Vec<u8, TX_CHUNK_BYTES>,
    line_errors: u32,
    /// The error flags seen at the last look (each error counted once).
    flags_seen: u32,
}

impl<R: Registers> DmaSerial<R> {
    /// Starts USART2 (8N1) at `baud` [bit/s] from the APB1 clock `pclk1_hz`
    /// [Hz], and its receive DMA over the `ring_bytes` (even) at
    /// `ring_addr`; `tx_addr` is a [`TX_CHUNK_BYTES`] buffer (4-aligned);
    /// `halves` is [`host_rx_half`]'s count.
    pub fn new(
        mut regs: R,
        halves: &'static AtomicU32,
        pclk1_hz: u32,
        baud: u32,
        ring_addr: u32,
        ring_bytes: usize,
        tx_addr: u32,
    ) -> Self {
        let r = &mut regs;
        r.write(usart2::BRR, crate::clock::usart_brr(pclk1_hz, baud));
        r.write(usart2::CR3, usart2::CR3_DMAR_DMAT);
        r.write(usart2::CR1, usart2::CR1_UE_TE_RE);
        let (_, ifcr, shift) = dma1::flags(RX_STREAM);
        r.write(ifcr, dma1::ALL_FLAGS << shift);
        r.write(dma1::par(RX_STREAM), usart2::DR as u32);
        r.write(dma1::m0ar(RX_STREAM), ring_addr);
        r.write(dma1::ndtr(RX_STREAM), ring_bytes as u32);
        let rx_cr = dma1::cr_chsel(4)
            | dma1::cr_pl(1)
            | dma1::CR_MINC
            | dma1::CR_CIRC
            | dma1::CR_HTIE
            | dma1::CR_TCIE;
        r.write(dma1::cr(RX_STREAM), rx_cr);
        r.write(dma1::cr(RX_STREAM), rx_cr | dma1::CR_EN);
        let (_, ifcr, shift) = dma1::flags(TX_STREAM);
        r.write(ifcr, dma1::ALL_FLAGS << shift);
        r.write(dma1::par(TX_STREAM), usart2::DR as u32);
        r.write(dma1::m0ar(TX_STREAM), tx_addr);
        r.write(
            dma1::cr(TX_STREAM),
            dma1::cr_chsel(4) | dma1::CR_MINC | dma1::CR_DIR_M2P,
        );
        Self {
            regs,
            halves,
            ring: RxRing::new(ring_bytes),
            ring_addr,
            ring_bytes,
            tx_addr,
            next: 0,
            waiting: 0,
            staged: heapless::Vec::new(),
            line_errors: 0,
            flags_seen: 0,
        }
    }

    /// Starts a transmit DMA transfer of the staged bytes if the previous
    /// one has finished. Call after every `Device::poll`.
    pub fn kick(&mut self) {
        if self.staged.is_empty() || self.regs.read(dma1::cr(TX_STREAM)) & dma1::CR_EN != 0 {
            return;
        }
        let n = self.staged.len();
        // The stream is off: the buffer is the CPU's.
        for (k, chunk) in self.staged.chunks(4).enumerate() {
            let mut word = [0u8; 4];
            word[..chunk.len()].copy_from_slice(chunk);
            self.regs
                .write(self.tx_addr as usize + 4 * k, u32::from_le_bytes(word));
        }
        self.staged.clear();
        let (_, ifcr, shift) = dma1::flags(TX_STREAM);
        self.regs.write(ifcr, dma1::ALL_FLAGS << shift);
        self.regs.write(dma1::ndtr(TX_STREAM), n as u32);
        // The copy must land before the DMA reads it.
        core::sync::atomic::fence(Ordering::SeqCst);
        let cr = self.regs.read(dma1::cr(TX_STREAM));
        self.regs.write(dma1::cr(TX_STREAM), cr | dma1::CR_EN);
    }

    /// Samples the line-error flags (framing, noise, overrun); an error
    /// counts once however long its flag stays set (the DMA's next read of
    /// DR clears it after this read of SR).
    fn check_line(&mut self) {
        let flags = self.regs.read(usart2::SR) & usart2::SR_ERRORS;
        if flags & !self.flags_seen != 0 {
            self.line_errors = self.line_errors.wrapping_add(1);
        }
        self.flags_seen = flags;
    }

    /// The receive ring's bytes waiting (for the idle loop's "anything
    /// new?" look): the stream's remaining count.
    pub fn rx_remaining(&mut self) -> u32 {
        self.regs.read(dma1::ndtr(RX_STREAM))
    }
}

impl<R: Registers> ByteLink for DmaSerial<R> {
    fn read_byte(&mut self) -> Option<u8> {
        if self.waiting == 0 {
            self.check_line();
            let halves = self.halves.load(Ordering::Acquire);
            let remaining = self.regs.read(dma1::ndtr(RX_STREAM)) as usize;
            (self.next, self.waiting) = self.ring.update(halves, remaining);
            if self.waiting == 0 {
                return None;
            }
        }
        // `next` < ring size (RxRing works modulo the ring); the DMA has
        // written this byte and will not overwrite it before the reader
        // falls a whole ring behind, which RxRing detects.
        let at = self.ring_addr as usize + self.next % self.ring_bytes;
        let word = self.regs.read(at & !3);
        let byte = (word >> (8 * (at & 3))) as u8;
        self.ring.consume(1);
        self.next = (self.next + 1) % self.ring_bytes;
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
