//! The host link on USART2 with DMA both ways: the library's
//! [`DmaSerial`] (`plinth_firmware::uart_dma`, run by the host's board
//! model) on the MCU's memory map, with the memory its streams own.

use core::cell::UnsafeCell;
use core::sync::atomic::AtomicU32;
use plinth_firmware::stm32::Mmio;
use plinth_firmware::uart_dma::{DmaSerial, TX_CHUNK_BYTES};

/// Receive ring [bytes]: 44 ms at 115 200 bit/s; the idle loop reads it at
/// least every millisecond.
pub const RX_RING_BYTES: usize = 512;

/// Memory a DMA stream owns while it runs.
#[repr(C, align(4))]
pub struct DmaBytes<const N: usize>(UnsafeCell<[u8; N]>);

// SAFETY: the receive ring is written by the DMA and read (volatile, by
// `Mmio`) by the idle task behind `RxRing`; the transmit buffer is written
// by the idle task only while its stream is disabled.
unsafe impl<const N: usize> Sync for DmaBytes<N> {}

static RX_RING: DmaBytes<RX_RING_BYTES> = DmaBytes(UnsafeCell::new([0; RX_RING_BYTES]));
static TX_BUFFER: DmaBytes<TX_CHUNK_BYTES> = DmaBytes(UnsafeCell::new([0; TX_CHUNK_BYTES]));

/// Half rings the receive DMA passed (`host_rx_half`).
pub static RX_HALVES: AtomicU32 = AtomicU32::new(0);

/// The board's host link.
pub type BoxSerial = DmaSerial<Mmio>;

/// USART2 at `baud` [bit/s] from the APB1 clock `pclk1_hz` [Hz] (clock
/// enabled, pins in AF7); the receiver runs from here on.
pub fn new(pclk1_hz: u32, baud: u32) -> BoxSerial {
    DmaSerial::new(
        Mmio,
        &RX_HALVES,
        pclk1_hz,
        baud,
        RX_RING.0.get() as u32,
        RX_RING_BYTES,
        TX_BUFFER.0.get() as u32,
    )
}
