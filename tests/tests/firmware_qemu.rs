//! End to end under QEMU: the real firmware image on the emulated STM32F405
//! (netduinoplus2), talking the wire protocol over its USART1, fed a
//! synthetic run-down by replay; it must identify the pedestal like the
//! host's batch fit and exit cleanly through semihosting after `Stop`.
//!
//! Needs `qemu-system-arm` and the image built first (scripts/test.sh does
//! both): `cargo build -p plinth-firmware --target thumbv7em-none-eabihf
//! --release`. `PLINTH_FIRMWARE_ELF` overrides the image path.

mod firmware_support;

use firmware_support::{Client, Scenario};
use plinth::estimate::Observation;
use plinth::identify::{fit_pedestal, Options};
use plinth_shared::protocol::{DeviceMessage, HostMessage};
use std::io::{Read, Write};
use std::os::unix::net::UnixStream;
use std::path::PathBuf;
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

/// The firmware image of the current sources.
fn image() -> PathBuf {
    plinth_tests::firmware_image()
}

/// QEMU, killed if the test ends early.
struct Qemu(Child);

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Reads from the box until `done` says so; fails after `timeout`.
fn read_until(
    stream: &mut UnixStream,
    client: &mut Client,
    timeout: Duration,
    done: impl FnMut(&[DeviceMessage]) -> bool,
) {
    assert!(
        try_read_until(stream, client, timeout, done),
        "timed out waiting for the box"
    );
}

/// Reads from the box until `done` says so; false after `timeout`.
fn try_read_until(
    stream: &mut UnixStream,
    client: &mut Client,
    timeout: Duration,
    mut done: impl FnMut(&[DeviceMessage]) -> bool,
) -> bool {
    let deadline = Instant::now() + timeout;
    let mut buf = [0u8; 4096];
    while !done(&client.received) {
        if Instant::now() >= deadline {
            return false;
        }
        match stream.read(&mut buf) {
            Ok(0) => panic!("the box closed the link"),
            Ok(n) => {
                client.feed(&buf[..n]);
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
            Err(e) => panic!("link read: {e}"),
        }
    }
    true
}

fn acked(received: &[DeviceMessage], seq: u32) -> bool {
    received
        .iter()
        .any(|m| matches!(m, DeviceMessage::Ack(a) if a.command_seq == seq))
}

#[test]
fn image_identifies_a_replayed_run_down_under_qemu_and_exits_cleanly() {
    let elf = image();
    assert!(
        elf.exists(),
        "no firmware image at {}: build it with `cargo build -p plinth-firmware --target thumbv7em-none-eabihf --release`",
        elf.display()
    );
    let dir = tempfile::tempdir().unwrap();
    let sock = dir.path().join("usart1.sock");
    let log = std::fs::File::create(dir.path().join("semihosting.bin")).unwrap();
    let link = format!("socket,id=link,path={},server=on,wait=on", sock.display());
    let child = plinth::demo::qemu::command(&elf, &["-chardev", &link, "-serial", "chardev:link"])
        .stdin(Stdio::null())
        .stdout(Stdio::from(log))
        .stderr(Stdio::piped())
        .spawn()
        .expect("qemu-system-arm must be installed (scripts/test.sh installs it)");
    let mut qemu = Qemu(child);

    // QEMU waits for us on the socket before it starts the CPU.
    let deadline = Instant::now() + Duration::from_secs(20);
    let mut stream = loop {
        match UnixStream::connect(&sock) {
            Ok(s) => break s,
            Err(_) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(20)),
            Err(e) => panic!("cannot connect to QEMU's USART1 socket: {e}"),
        }
    };
    stream
        .set_read_timeout(Some(Duration::from_millis(50)))
        .unwrap();
    let mut client = Client::new();
    let t = Duration::from_secs(30);

    // The host speaks first, and keeps saying Hello until the box answers:
    // bytes that arrive before the image has enabled USART1 are dropped.
    let hello_acked = |r: &[DeviceMessage]| {
        r.iter()
            .any(|m| matches!(m, DeviceMessage::HelloAck(a) if a.host_nonce == 0x5eed))
    };
    let deadline = Instant::now() + t;
    loop {
        let (_, hello) = client.hello(0x5eed);
        stream.write_all(&hello).unwrap();
        if try_read_until(
            &mut stream,
            &mut client,
            Duration::from_millis(500),
            hello_acked,
        ) {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "no HelloAck from the box within {t:?}"
        );
    }

    let scenario = Scenario::short();
    let mut commands = scenario.configuration();
    commands.push(HostMessage::Start);
    for m in &commands {
        let (seq, bytes) = client.encode(m);
        stream.write_all(&bytes).unwrap();
        read_until(&mut stream, &mut client, t, |r| acked(r, seq));
    }

    // Stream the blocks with up to 16 unacknowledged (the USART takes a
    // byte only when the firmware has read the previous one, so nothing is
    // lost; the window keeps the socket buffers small).
    let blocks = scenario.blocks();
    let mut seqs = std::collections::VecDeque::new();
    for block in blocks {
        let (seq, bytes) = client.encode(&HostMessage::Samples(block));
        stream.write_all(&bytes).unwrap();
        seqs.push_back(seq);
        if seqs.len() >= 16 {
            let oldest = seqs.pop_front().unwrap();
            read_until(&mut stream, &mut client, t, |r| acked(r, oldest));
        }
    }
    let (stop, bytes) = client.encode(&HostMessage::Stop);
    stream.write_all(&bytes).unwrap();
    read_until(&mut stream, &mut client, t, |r| {
        acked(r, stop)
            && r.iter()
                .rev()
                .take(3)
                .any(|m| matches!(m, DeviceMessage::Status(_)))
    });

    // The image exits by itself through semihosting, with status 0.
    let deadline = Instant::now() + Duration::from_secs(20);
    let status = loop {
        if let Some(s) = qemu.0.try_wait().unwrap() {
            break s;
        }
        assert!(
            Instant::now() < deadline,
            "the image did not exit after Stop"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    assert!(status.success(), "QEMU exit status {status}");

    let nacks: Vec<_> = client
        .received
        .iter()
        .filter(|m| matches!(m, DeviceMessage::Nack(_)))
        .collect();
    assert!(nacks.is_empty(), "refused: {nacks:?}");
    let frames: Vec<_> = client
        .received
        .iter()
        .filter_map(|m| match m {
            DeviceMessage::Phasors(p) => Some(p.clone()),
            _ => None,
        })
        .collect();
    // 45 → 28 Hz over 1.2 s is ≈ 44 revolutions.
    assert!(frames.len() >= 38, "{} phasor frames", frames.len());
    let status = client
        .received
        .iter()
        .rev()
        .find_map(|m| match m {
            DeviceMessage::Status(s) => Some(s.clone()),
            _ => None,
        })
        .unwrap();
    assert_eq!(status.counters.queue_full_drops, 0);
    assert_eq!(status.counters.keyphasor_missing, 0);
    assert_eq!(status.link.crc_failures, 0);
    let estimate = client
        .received
        .iter()
        .rev()
        .find_map(|m| match m {
            DeviceMessage::Estimates(e) => e.pedestals.first().copied(),
            _ => None,
        })
        .expect("estimates from the box");

    // The MCU's f32 recursive estimate against the host's f64 batch fit of
    // the phasors the MCU reported, and against the truth.
    let c = |w: plinth_shared::protocol::WirePhasor| {
        num_complex::Complex::new(f64::from(w.re), f64::from(w.im))
    };
    let points: Vec<Observation> = frames
        .iter()
        .map(|f| {
            let b = &f.bearings[0];
            let speed = f64::from(f.speed_hz);
            Observation::without_noise(
                speed,
                [c(b.rel[0]), c(b.rel[1])],
                [c(b.ped[0]), c(b.ped[1])],
                &scenario.bearing,
            )
        })
        .collect();
    let batch = fit_pedestal("0", &points, &Options::default())
        .unwrap()
        .pedestal
        .theta();
    for (i, &fitted) in batch.iter().enumerate() {
        let got = f64::from(estimate.theta[i]);
        assert!(
            (got - fitted).abs() < 2e-3 * fitted.abs(),
            "parameter {i}: MCU {got} vs batch {fitted}"
        );
        let truth = scenario.pedestal[i];
        let tol = if i < 3 { 1e-2 } else { 5e-2 };
        assert!(
            (got - truth).abs() < tol * truth,
            "parameter {i}: MCU {got} vs truth {truth}"
        );
    }
}
