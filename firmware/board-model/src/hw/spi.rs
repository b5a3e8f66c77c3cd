//! SPI2 as a master: TX buffer, shift register, RXNE, OVR (which locks
//! the receiver until DR then SR are read, RM0090 28.4.8), BSY; bits
//! sampled from DOUTA at each SCLK.

use super::Hw;
use plinth_firmware::acquisition::rm0090::spi2;

/// SPI2 as a master.
#[derive(Clone, Debug, Default)]
pub struct Spi {
    pub cr1: u32,
    pub cr2: u32,
    pub(super) rxne: bool,
    pub(super) ovr: bool,
    pub(super) ovr_dr_read: bool,
    pub(super) rx: u16,
    pub(super) tx: Option<u16>,
    /// The frame being shifted: start tick, end tick.
    pub(super) shift: Option<(u64, u64)>,
}

impl Hw {
    /// Ticks per SCLK bit.
    pub(super) fn bit_ticks(&self) -> u64 {
        (2u64 << ((self.spi.cr1 & spi2::CR1_BR_MASK) >> 3)) * self.pclk1_ticks
    }

    /// A frame finished shifting: its bits, sampled at each SCLK's falling
    /// edge (mode 2: CPOL = 1, CPHA = 0), go to the RX buffer.
    pub(super) fn frame_done(&mut self, t: u64) {
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

    pub(super) fn spi_dr_read(&mut self) {
        self.spi.rxne = false;
        if self.spi.ovr {
            self.spi.ovr_dr_read = true;
        }
    }
}
