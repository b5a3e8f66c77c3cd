//! The field box without hardware: the firmware's [`Device`] (protocol
//! endpoint, replay source and pipeline, exactly the code the MCU image runs)
//! compiled for the host and driven from inside the link the stream session
//! talks to.
//!
//! Each write of the session's bytes hands them to the device and polls it
//! until it is idle; each read returns what the device sent. Nothing runs
//! concurrently, so a demo run is deterministic and as fast as the pipeline
//! itself: no thread, no pseudo-terminal, no sleeping except a short wait
//! when the session polls an idle box (a serial port's read timeout).

use crate::stream::port::{Connector, Link};
use plinth_firmware::device::Device;
use plinth_firmware::link::ByteLink;
use plinth_firmware::replay::ReplaySource;
use std::collections::VecDeque;
use std::io::{self, Read, Write};
use std::time::{Duration, Instant};

/// How long a read of an idle box waits before reporting a timeout (what a
/// serial port's read timeout would do; keeps an idle session from spinning).
pub const IDLE_READ_WAIT: Duration = Duration::from_millis(1);

/// Hands out links to a freshly booted in-process box (a reconnect is a
/// reboot: the session then reconfigures it, as it would a real one).
#[derive(Clone, Debug)]
pub struct InProcessConnector {
    volts_per_code: f32,
    boots: u32,
}

impl InProcessConnector {
    /// A connector for boxes whose ADC step is `volts_per_code` [V] (what
    /// they report in `HelloAck`; the replay itself sends volts).
    pub fn new(volts_per_code: f32) -> Self {
        Self {
            volts_per_code,
            boots: 0,
        }
    }

    /// How many boxes were booted (links handed out).
    pub fn boots(&self) -> u32 {
        self.boots
    }
}

impl Connector for InProcessConnector {
    fn connect(&mut self) -> io::Result<Box<dyn Link>> {
        self.boots += 1;
        Ok(Box::new(InProcessLink::new(self.volts_per_code)))
    }

    fn describe(&self) -> String {
        "in-process field box (the firmware pipeline compiled for the host)".into()
    }
}

/// The device's two byte queues, as the firmware's non-blocking link.
#[derive(Debug, Default)]
struct Pipes {
    /// Bytes from the host, not yet read by the device.
    to_box: VecDeque<u8>,
    /// Bytes the device sent, not yet read by the host.
    from_box: VecDeque<u8>,
}

impl ByteLink for Pipes {
    fn read_byte(&mut self) -> Option<u8> {
        self.to_box.pop_front()
    }

    fn write_byte(&mut self, byte: u8) -> bool {
        self.from_box.push_back(byte);
        true
    }
}

/// One booted in-process box behind a byte-stream link.
pub struct InProcessLink {
    device: Box<Device>,
    source: ReplaySource,
    pipes: Pipes,
    booted: Instant,
}

impl InProcessLink {
    /// A box that has just booted (waiting for `Hello`).
    pub fn new(volts_per_code: f32) -> Self {
        Self {
            // ~20 KiB: on the heap.
            device: Box::new(Device::new(volts_per_code)),
            source: ReplaySource::new(volts_per_code),
            pipes: Pipes::default(),
            booted: Instant::now(),
        }
    }

    /// Runs the box's main loop until it has nothing left to do.
    fn run_until_idle(&mut self) {
        loop {
            // The box's uptime clock wraps after 49 days, as on the MCU.
            let now_ms = self.booted.elapsed().as_millis() as u32;
            let a = self.device.poll(&mut self.pipes, &mut self.source, now_ms);
            if a.received == 0 && a.sent == 0 && a.samples == 0 {
                break;
            }
        }
    }
}

impl Read for InProcessLink {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if buf.is_empty() {
            return Ok(0);
        }
        self.run_until_idle();
        if self.pipes.from_box.is_empty() {
            std::thread::sleep(IDLE_READ_WAIT);
            self.run_until_idle();
            if self.pipes.from_box.is_empty() {
                return Err(io::Error::new(
                    io::ErrorKind::TimedOut,
                    "the in-process box sent nothing",
                ));
            }
        }
        let n = buf.len().min(self.pipes.from_box.len());
        for (slot, byte) in buf.iter_mut().zip(self.pipes.from_box.drain(..n)) {
            *slot = byte;
        }
        Ok(n)
    }
}

impl Write for InProcessLink {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.pipes.to_box.extend(buf.iter().copied());
        self.run_until_idle();
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plinth_shared::protocol::{
        DeviceMessage, Hello, HostMessage, Receiver, Transmitter, MAX_FRAME_SIZE, PROTOCOL_VERSION,
    };

    #[test]
    fn the_box_answers_hello_through_the_link() {
        let mut c = InProcessConnector::new(10.0 / 32768.0);
        let mut link = c.connect().unwrap();
        assert_eq!(c.boots(), 1);
        // Idle: a read times out like a quiet serial port.
        let mut buf = [0u8; 64];
        let e = link.read(&mut buf).unwrap_err();
        assert!(crate::stream::port::is_quiet(&e));
        let mut tx = Transmitter::new();
        let mut wire = [0u8; MAX_FRAME_SIZE];
        let hello = HostMessage::Hello(Hello {
            protocol_version: PROTOCOL_VERSION,
            host_nonce: 42,
        });
        let (_, bytes) = tx.encode(&hello, &mut wire).unwrap();
        link.write_all(bytes).unwrap();
        let mut rx = Receiver::<DeviceMessage>::new();
        let mut got = Vec::new();
        while let Ok(n) = link.read(&mut buf) {
            got.extend(rx.feed(&buf[..n]).flatten().map(|f| f.message));
        }
        match got.first() {
            Some(DeviceMessage::HelloAck(a)) => assert_eq!(a.host_nonce, 42),
            other => panic!("expected HelloAck, got {other:?}"),
        }
    }
}
