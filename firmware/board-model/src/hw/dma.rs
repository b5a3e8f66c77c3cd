//! DMA1 streams: NDTR, flags, circular and double-buffer reloads, and the
//! moves of the streams the firmware uses (3/4: SPI2, 5/6: USART2).

use super::{Hw, RAM_BASE};
use plinth_firmware::acquisition::rm0090::dma1;

/// Ticks from a DMA request to its transfer (arbitration, bus).
pub const DMA_LATENCY: u64 = 3;

/// A DMA1 stream.
#[derive(Clone, Debug, Default)]
pub struct Stream {
    pub cr: u32,
    pub ndtr: u32,
    pub(super) reload: u32,
    pub par: u32,
    pub m0ar: u32,
    pub m1ar: u32,
    pub fcr: u32,
    /// Flags, unshifted (FEIF, DMEIF, TEIF, HTIF, TCIF).
    pub flags: u32,
    /// When a pending request will be served.
    pub(super) due: Option<u64>,
}

impl Stream {
    pub(super) fn enabled(&self) -> bool {
        self.cr & dma1::CR_EN != 0
    }
    pub(super) fn irq_line(&self) -> bool {
        let f = self.flags;
        let c = self.cr;
        (f & dma1::TCIF != 0 && c & dma1::CR_TCIE != 0)
            || (f & dma1::HTIF != 0 && c & dma1::CR_HTIE != 0)
            || (f & dma1::TEIF != 0 && c & dma1::CR_TEIE != 0)
            || (f & dma1::DMEIF != 0 && c & dma1::CR_DMEIE != 0)
    }
    /// One item moved: NDTR, flags, circular/double-buffer reload.
    /// Returns the item's address.
    pub(super) fn advance(&mut self, size: u32) -> u32 {
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

impl Hw {
    /// DMA stream `n` moves one item.
    pub(super) fn dma_transfer(&mut self, n: usize) {
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
}
