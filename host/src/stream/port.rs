//! The serial link to the field box: opening it, telling a quiet line from a
//! lost one, and reopening a lost one with backoff.
//!
//! The session runs over any [`Link`] (a byte stream with a read timeout) that
//! a [`Connector`] hands out, so tests can put a fault-injecting proxy or a
//! socket pair where the serial port would be. [`SerialConnector`] is the real
//! thing: a `serialport` TTY, which also works on a pseudo-terminal such as
//! the `/dev/pts/N` that QEMU's `-serial pty` prints.

use anyhow::{bail, Result};
use std::io::{self, Read, Write};
use std::time::{Duration, Instant};

/// A byte stream to the field box whose reads return `TimedOut`/`WouldBlock`
/// when nothing arrived within the link's read timeout.
pub trait Link: Read + Write + Send {}
impl<T: Read + Write + Send> Link for T {}

/// Opens (and, after a loss, reopens) the link to the field box.
pub trait Connector {
    /// Opens a fresh link.
    fn connect(&mut self) -> io::Result<Box<dyn Link>>;
    /// What is being connected to, for messages (e.g. the port path).
    fn describe(&self) -> String;
}

/// Default read timeout of the serial port: how long one read waits for a byte.
pub const DEFAULT_READ_TIMEOUT: Duration = Duration::from_millis(50);

/// A serial port (or pseudo-terminal) opened with the `serialport` crate.
#[derive(Clone, Debug)]
pub struct SerialConnector {
    /// Device path, e.g. `/dev/ttyUSB0` or `/dev/pts/5`.
    pub path: String,
    /// Line speed [bit/s] (ignored by pseudo-terminals).
    pub baud: u32,
    /// How long one read waits for a byte.
    pub read_timeout: Duration,
}

impl SerialConnector {
    /// A connector for `path` at `baud` [bit/s] with the default read timeout.
    pub fn new(path: &str, baud: u32) -> Self {
        Self {
            path: path.to_string(),
            baud,
            read_timeout: DEFAULT_READ_TIMEOUT,
        }
    }
}

impl Connector for SerialConnector {
    fn connect(&mut self) -> io::Result<Box<dyn Link>> {
        // open_native: a TTYPort, which is Read + Write + Send. The input
        // buffer is deliberately not cleared: every byte counts.
        let port = serialport::new(&self.path, self.baud)
            .timeout(self.read_timeout)
            .open_native()
            .map_err(io::Error::from)?;
        Ok(Box::new(port))
    }

    fn describe(&self) -> String {
        format!("serial port {} at {} bit/s", self.path, self.baud)
    }
}

pub use serialport::{SerialPort, TTYPort};

/// A pseudo-terminal pair for simulated hardware: the master end (the
/// "device" side, e.g. the firmware compiled for the host) and the path of
/// the slave end, which `plinth stream --port PATH` opens like a serial port.
/// The slave is closed here so that the host can open it exclusively.
pub fn pseudo_terminal() -> io::Result<(TTYPort, String)> {
    use serialport::SerialPort;
    let (master, slave) = TTYPort::pair().map_err(io::Error::from)?;
    let path = slave
        .name()
        .ok_or_else(|| io::Error::other("the pseudo-terminal has no path"))?;
    drop(slave);
    Ok((master, path))
}

/// True for the errors that only mean "nothing happened within the timeout".
pub fn is_quiet(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::TimedOut | io::ErrorKind::WouldBlock | io::ErrorKind::Interrupted
    )
}

/// Writes all of `bytes`, waiting out write timeouts (a full line buffer)
/// until `patience` has passed; any other error, or running out of patience,
/// means the link is lost.
pub fn write_all_patiently(
    link: &mut dyn Link,
    bytes: &[u8],
    patience: Duration,
) -> io::Result<()> {
    let deadline = Instant::now() + patience;
    let mut rest = bytes;
    while !rest.is_empty() {
        match link.write(rest) {
            Ok(0) => {
                return Err(io::Error::new(
                    io::ErrorKind::WriteZero,
                    "the link accepted no bytes",
                ))
            }
            Ok(n) => rest = &rest[n..],
            Err(e) if is_quiet(&e) => {
                if Instant::now() >= deadline {
                    return Err(io::Error::new(
                        io::ErrorKind::TimedOut,
                        format!(
                            "the link took no bytes for {:.1} s ({} of {} bytes unsent)",
                            patience.as_secs_f64(),
                            rest.len(),
                            bytes.len()
                        ),
                    ));
                }
                std::thread::sleep(Duration::from_millis(1));
            }
            Err(e) => return Err(e),
        }
    }
    match link.flush() {
        Ok(()) => Ok(()),
        Err(e) if is_quiet(&e) => Ok(()),
        Err(e) => Err(e),
    }
}

/// How to retry opening a lost link: exponential backoff from `initial` to
/// `max` between attempts, giving up after `give_up` in total.
#[derive(Clone, Copy, Debug)]
pub struct Backoff {
    /// First wait between attempts.
    pub initial: Duration,
    /// Longest wait between attempts.
    pub max: Duration,
    /// Total time after which reopening is abandoned.
    pub give_up: Duration,
}

impl Default for Backoff {
    fn default() -> Self {
        Self {
            initial: Duration::from_millis(50),
            max: Duration::from_secs(2),
            give_up: Duration::from_secs(60),
        }
    }
}

/// Opens a link, retrying with `backoff`; `on_failure(attempt, error, wait)`
/// is told about every failed attempt (for the progress line).
pub fn connect_with_backoff(
    connector: &mut dyn Connector,
    backoff: Backoff,
    mut on_failure: impl FnMut(u32, &io::Error, Duration),
) -> Result<Box<dyn Link>> {
    let start = Instant::now();
    let mut wait = backoff.initial;
    let mut attempt = 0u32;
    loop {
        attempt += 1;
        match connector.connect() {
            Ok(link) => return Ok(link),
            Err(e) => {
                if start.elapsed() + wait > backoff.give_up {
                    bail!(
                        "cannot open the {} after {} attempts over {:.1} s: {e}",
                        connector.describe(),
                        attempt,
                        start.elapsed().as_secs_f64()
                    );
                }
                on_failure(attempt, &e, wait);
                std::thread::sleep(wait);
                wait = (wait * 2).min(backoff.max);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serialport::SerialPort;

    struct Flaky {
        failures_left: u32,
    }
    impl Connector for Flaky {
        fn connect(&mut self) -> io::Result<Box<dyn Link>> {
            if self.failures_left > 0 {
                self.failures_left -= 1;
                Err(io::Error::new(io::ErrorKind::NotFound, "no such device"))
            } else {
                Ok(Box::new(io::Cursor::new(Vec::<u8>::new())))
            }
        }
        fn describe(&self) -> String {
            "flaky test link".into()
        }
    }

    #[test]
    fn backoff_retries_until_the_port_comes_back() {
        let backoff = Backoff {
            initial: Duration::from_millis(1),
            max: Duration::from_millis(4),
            give_up: Duration::from_secs(5),
        };
        let mut waits = Vec::new();
        let mut c = Flaky { failures_left: 4 };
        connect_with_backoff(&mut c, backoff, |_, _, w| waits.push(w)).unwrap();
        let ms: Vec<u128> = waits.iter().map(|w| w.as_millis()).collect();
        assert_eq!(ms, vec![1, 2, 4, 4]);
    }

    #[test]
    fn backoff_gives_up_with_a_clear_error() {
        let backoff = Backoff {
            initial: Duration::from_millis(1),
            max: Duration::from_millis(2),
            give_up: Duration::from_millis(20),
        };
        let mut c = Flaky {
            failures_left: u32::MAX,
        };
        let err = match connect_with_backoff(&mut c, backoff, |_, _, _| {}) {
            Ok(_) => panic!("a link that never opens was reported open"),
            Err(e) => e,
        };
        let msg = format!("{err:#}");
        assert!(
            msg.contains("flaky test link") && msg.contains("no such device"),
            "{msg}"
        );
    }

    #[test]
    fn a_pseudo_terminal_path_opens_as_a_serial_port() {
        let (mut master, slave) = serialport::TTYPort::pair().unwrap();
        let path = slave.name().unwrap();
        drop(slave);
        let mut c = SerialConnector::new(&path, 115_200);
        let mut link = c.connect().unwrap();
        master.write_all(b"\x00\x01\xff").unwrap();
        let mut got = Vec::new();
        let deadline = Instant::now() + Duration::from_secs(5);
        let mut buf = [0u8; 16];
        while got.len() < 3 && Instant::now() < deadline {
            match link.read(&mut buf) {
                Ok(n) => got.extend_from_slice(&buf[..n]),
                Err(e) if is_quiet(&e) => {}
                Err(e) => panic!("{e}"),
            }
        }
        assert_eq!(got, b"\x00\x01\xff");
        write_all_patiently(link.as_mut(), b"\x11\x00", Duration::from_secs(1)).unwrap();
    }
}
