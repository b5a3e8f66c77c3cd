//! The reading side of a UART receive DMA running circularly over a ring
//! buffer: where the new bytes are, and whether the DMA lapped the reader.
//!
//! The DMA's remaining-count register gives the write position only modulo
//! the ring size; the half-transfer and transfer-complete interrupts count
//! the half rings passed, a lower bound of what was written, so a reader
//! that came more than a ring late sees it (the bytes are gone, counted as
//! an overrun), never reads old bytes as new ones.

/// Read cursor over a circular DMA ring of `size` bytes (even, ≥ 2).
#[derive(Clone, Debug)]
pub struct RxRing {
    size: u64,
    /// Bytes taken by the reader since start.
    read: u64,
    /// Bytes written by the DMA since start, as last worked out.
    written: u64,
    /// Half rings passed, as last seen (unwrapped).
    halves: u64,
    /// Times the DMA lapped the reader.
    overruns: u32,
    /// Bytes lost to those overruns.
    lost: u64,
}

impl RxRing {
    /// A cursor over a ring of `size` bytes (rounded up to an even count).
    pub fn new(size: usize) -> Self {
        Self {
            size: (size.max(2) as u64 + 1) & !1,
            read: 0,
            written: 0,
            halves: 0,
            overruns: 0,
            lost: 0,
        }
    }

    /// Times the DMA overwrote bytes not yet read.
    pub fn overruns(&self) -> u32 {
        self.overruns
    }

    /// Bytes lost to overruns.
    pub fn lost(&self) -> u64 {
        self.lost
    }

    /// Folds in the DMA's state: `halves` half rings passed (the interrupt
    /// count, wrapping; read first) and its remaining count `remaining`
    /// (NDTR, read after). Returns the ring index of the next unread byte
    /// and how many are waiting.
    pub fn update(&mut self, halves: u32, remaining: usize) -> (usize, usize) {
        let half = self.size / 2;
        self.halves += u64::from(halves.wrapping_sub(self.halves as u32));
        // NDTR reads `size` at the moment of the circular reload.
        let pos = (self.size - (remaining as u64).min(self.size)) % self.size;
        let mut written = self.written + (pos + self.size - self.written % self.size) % self.size;
        let at_least = self.halves * half;
        if written < at_least {
            // Whole rings passed unseen.
            written += (at_least - written).div_ceil(self.size) * self.size;
        }
        self.written = written;
        if written - self.read > self.size {
            self.overruns = self.overruns.saturating_add(1);
            self.lost += written - self.read;
            self.read = written;
        }
        (
            (self.read % self.size) as usize,
            (written - self.read) as usize,
        )
    }

    /// Marks `n` bytes as read.
    pub fn consume(&mut self, n: usize) {
        self.read = (self.read + n as u64).min(self.written);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn follows_the_writer_around_the_ring() {
        let mut r = RxRing::new(8);
        assert_eq!(r.update(0, 8), (0, 0));
        // 3 bytes in.
        assert_eq!(r.update(0, 5), (0, 3));
        r.consume(3);
        // 7 more: across the end (halves at 4 and 8 passed).
        assert_eq!(r.update(2, 6), (3, 7));
        r.consume(7);
        assert_eq!(r.update(2, 6), (2, 0));
        assert_eq!(r.overruns(), 0);
    }

    #[test]
    fn a_lapped_reader_drops_the_lost_bytes_and_counts_them() {
        let mut r = RxRing::new(8);
        // 19 bytes written, none read: position 3, but 4 halves passed.
        assert_eq!(r.update(4, 5).1, 0);
        assert_eq!(r.overruns(), 1);
        assert_eq!(r.lost(), 19);
        // Then it goes on normally.
        assert_eq!(r.update(4, 3), (3, 2));
    }
}
