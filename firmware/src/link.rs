//! The byte link to the host (a UART on the box, a pty under QEMU), as a
//! non-blocking trait so the main loop never waits on it.

/// A full-duplex byte link that never blocks.
pub trait ByteLink {
    /// The next received byte, if one is waiting.
    fn read_byte(&mut self) -> Option<u8>;
    /// Queues one byte for transmission; `false` when the transmitter is busy
    /// (try again on a later pass of the main loop).
    fn write_byte(&mut self, byte: u8) -> bool;
    /// Receive errors (overrun, framing, noise) seen since start.
    fn receive_errors(&self) -> u32 {
        0
    }
}

/// An in-memory link for host tests: bytes queued in `rx` are received, bytes
/// written land in `tx`; `tx_room` limits how many bytes are accepted per
/// test step, to exercise back-pressure.
#[derive(Debug)]
pub struct MemoryLink<const RX: usize, const TX: usize> {
    /// Bytes waiting to be received by the firmware.
    pub rx: heapless::Deque<u8, RX>,
    /// Bytes the firmware has sent.
    pub tx: heapless::Vec<u8, TX>,
    /// Bytes the transmitter still accepts before reporting busy.
    pub tx_room: usize,
}

impl<const RX: usize, const TX: usize> Default for MemoryLink<RX, TX> {
    fn default() -> Self {
        Self {
            rx: heapless::Deque::new(),
            tx: heapless::Vec::new(),
            tx_room: usize::MAX,
        }
    }
}

impl<const RX: usize, const TX: usize> ByteLink for MemoryLink<RX, TX> {
    fn read_byte(&mut self) -> Option<u8> {
        self.rx.pop_front()
    }

    fn write_byte(&mut self, byte: u8) -> bool {
        if self.tx_room == 0 {
            return false;
        }
        if self.tx.push(byte).is_err() {
            return false;
        }
        self.tx_room = self.tx_room.saturating_sub(1);
        true
    }
}
