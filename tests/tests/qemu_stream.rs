//! End to end with the real firmware image under QEMU (netduinoplus2, an
//! STM32F405): `plinth stream --replay` over the pseudo-terminal QEMU's
//! `-serial pty` creates. The run directory and the box's estimates must
//! match the host-only pipeline's (the firmware library compiled for the
//! host, fed the same sample blocks).
//!
//! Needs `qemu-system-arm` (scripts/test.sh installs it) and the image
//! (`cargo build -p plinth-firmware --target thumbv7em-none-eabihf
//! --release`, which scripts/test.sh runs first; built here into a separate
//! target directory when missing). QEMU is killed in every case.

mod stream_common;

use plinth::stream::derive::derive;
use plinth::stream::port::SerialConnector;
use plinth::stream::progress::Progress;
use plinth::stream::session::SessionOptions;
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;
use stream_common::{measurements, reference_bytes, Scenario};

const TARGET: &str = "thumbv7em-none-eabihf";

/// QEMU, killed when dropped.
struct Qemu {
    child: Child,
    /// The pseudo-terminal QEMU connected the box's USART to.
    pty: String,
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The workspace's target directory (this test runs from target/<profile>/deps).
fn target_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    exe.ancestors()
        .nth(3)
        .expect("target directory above target/<profile>/deps")
        .to_path_buf()
}

/// The firmware image: the one scripts/test.sh built, or one built now in a
/// separate target directory (so as not to wait on this build's lock).
fn firmware_image() -> PathBuf {
    let standard = target_dir().join(TARGET).join("release/plinth-firmware");
    if standard.is_file() {
        return standard;
    }
    let own = target_dir().join("qemu-image");
    let status = Command::new(env!("CARGO"))
        .args([
            "build",
            "-p",
            "plinth-firmware",
            "--target",
            TARGET,
            "--release",
        ])
        .arg("--target-dir")
        .arg(&own)
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .status()
        .expect("running cargo to build the firmware image");
    assert!(status.success(), "building the firmware image failed");
    own.join(TARGET).join("release/plinth-firmware")
}

fn start_qemu(image: &PathBuf) -> Qemu {
    let mut child = Command::new("qemu-system-arm")
        .args([
            "-M",
            "netduinoplus2",
            "-display",
            "none",
            "-monitor",
            "none",
            "-serial",
            "pty",
            "-semihosting-config",
            "enable=on,target=native",
            "-kernel",
        ])
        .arg(image)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("starting qemu-system-arm (scripts/test.sh installs it)");
    let (tx, rx) = mpsc::channel::<String>();
    for pipe in [
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn std::io::Read + Send>),
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn std::io::Read + Send>),
    ]
    .into_iter()
    .flatten()
    {
        let tx = tx.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(pipe).lines().map_while(Result::ok) {
                let _ = tx.send(line);
            }
        });
    }
    let mut qemu = Qemu {
        child,
        pty: String::new(),
    };
    loop {
        match rx.recv_timeout(Duration::from_secs(20)) {
            Ok(line) => {
                if let Some(rest) = line.split("char device redirected to ").nth(1) {
                    qemu.pty = rest.split_whitespace().next().unwrap_or("").to_string();
                    break;
                }
            }
            Err(e) => panic!("QEMU did not print its pseudo-terminal: {e}"),
        }
    }
    // Keep draining QEMU's output (semihosting log) so it never blocks.
    std::thread::spawn(move || for _ in rx {});
    qemu
}

#[test]
fn qemu_firmware_matches_the_host_only_pipeline() {
    let image = firmware_image();
    // 0.3 s of run-down (15 360 sample vectors, ~43 revolutions): QEMU
    // processes it in well under a minute.
    let scenario = Scenario::paper_rundown(150.0, 138.0, 40.0);
    let reference = derive(
        &reference_bytes(&scenario),
        &scenario.config,
        &scenario.tables,
    );
    let qemu = start_qemu(&image);
    let out = scenario.out_dir("qemu");
    std::fs::create_dir_all(&out).unwrap();

    // The stream runs in a thread so that a hang fails the test (QEMU is then
    // killed by the guard) instead of blocking CI.
    let (done_tx, done_rx) = mpsc::channel();
    let port = qemu.pty.clone();
    let (config, tables, signals, out2) = (
        scenario.config.clone(),
        scenario.tables.clone(),
        scenario.signals.clone(),
        out.clone(),
    );
    std::thread::spawn(move || {
        let replay = plinth::stream::replay::SignalSetReplay::load(&signals, &config)
            .expect("replay signals");
        let mut connector = SerialConnector::new(&port, 115_200);
        let options = SessionOptions {
            backoff: plinth::stream::port::Backoff {
                give_up: Duration::from_secs(10),
                ..Default::default()
            },
            ..SessionOptions::default()
        };
        let r = plinth::stream::stream(
            &mut connector,
            &out2,
            &config,
            &tables,
            Some((&signals, &replay)),
            options,
            Progress::hidden(),
        )
        .map_err(|e| format!("{e:#}"));
        let _ = done_tx.send(r);
    });
    let outcome = match done_rx.recv_timeout(Duration::from_secs(300)) {
        Ok(r) => r.expect("streaming from QEMU"),
        Err(_) => panic!("the stream from QEMU did not finish within 300 s"),
    };
    drop(qemu);
    assert!(outcome.completed, "{outcome:?}");
    let report =
        plinth::stream::finish(&out, &scenario.config, &scenario.tables, Some(&outcome)).unwrap();
    println!("{}", plinth::stream::summary(&report));
    assert_eq!(report.link_raw_log.crc_failures, 0);
    assert_eq!(report.link_raw_log.sequence_gaps, 0);

    let got = measurements(&out);
    let want = &reference.run.measurements;
    let speeds = |rows: &[plinth::rundir::Measurement]| -> Vec<f64> {
        rows.iter().map(|r| r.speed_hz).collect()
    };
    assert_eq!(
        speeds(&got),
        speeds(want),
        "measured speeds (QEMU vs host-only)"
    );
    for (g, w) in got.iter().zip(want) {
        assert_eq!((g.speed_hz, &g.bearing), (w.speed_hz, &w.bearing));
        for (a, b) in g.rel.iter().chain(&g.ped).zip(w.rel.iter().chain(&w.ped)) {
            assert!(
                (a - b).norm() <= 1e-5 * b.norm().max(1e-12),
                "{} Hz {}: {a} vs {b}",
                g.speed_hz,
                g.bearing
            );
        }
    }
    let box_est = outcome.last_estimates.expect("final estimates from QEMU");
    let ref_est = reference.last_estimates.expect("reference estimates");
    assert_eq!(box_est.pedestals.len(), ref_est.pedestals.len());
    for (a, b) in box_est.pedestals.iter().zip(&ref_est.pedestals) {
        for (x, y) in a.theta.iter().zip(&b.theta) {
            assert!((x - y).abs() <= 1e-4 * y.abs(), "estimate {x} vs {y}");
        }
    }
    assert!(report.batch_error.is_none(), "{:?}", report.batch_error);
}
