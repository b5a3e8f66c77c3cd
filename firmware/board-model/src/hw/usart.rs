//! USART2: receive data register, line errors (noise, framing, overrun:
//! cleared by a read of SR that sees them, then of DR), sent bytes.

use super::Hw;

/// USART2 with its receive and transmit data registers.
#[derive(Clone, Debug, Default)]
pub struct Usart {
    pub cr1: u32,
    pub cr3: u32,
    pub brr: u32,
    pub(super) rxne: bool,
    pub(super) errors: u32,
    pub(super) sr_read: bool,
    pub(super) rx: u8,
    /// Bytes the box sent.
    pub sent: Vec<u8>,
}

impl Hw {
    pub(super) fn usart_dr_read(&mut self) {
        self.usart.rxne = false;
        if self.usart.sr_read {
            self.usart.errors = 0;
            self.usart.sr_read = false;
        }
    }

    pub(super) fn usart_receive(&mut self, byte: u8, noisy: bool) {
        if self.usart.cr1 & (1 << 2) == 0 {
            return;
        }
        if self.usart.rxne {
            // ORE: this byte is lost; the flag clears by a read of SR
            // that sees it, then of DR.
            self.usart.errors |= 1 << 3;
            self.usart.sr_read = false;
            self.rx_overruns += 1;
            self.rx_lost.push(self.next_rx - 1);
            return;
        }
        self.usart.rx = byte;
        self.usart.rxne = true;
        if noisy {
            self.usart.sr_read = false;
            self.usart.errors |= 1 << 2 | 1 << 1; // NF, FE
        }
    }
}
