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

use plinth::demo::qemu::Qemu;
use plinth::stream::derive::derive;
use plinth::stream::port::SerialConnector;
use plinth::stream::progress::Progress;
use plinth::stream::session::SessionOptions;
use plinth_tests::firmware_image;
use std::sync::mpsc;
use std::time::Duration;
use stream_common::{measurements, reference_bytes, Scenario};

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
    let qemu = Qemu::start(&image).expect("starting qemu-system-arm (scripts/test.sh installs it)");
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
    assert!(report.ml_error.is_none(), "{:?}", report.ml_error);
    assert!(report
        .pedestals
        .iter()
        .all(|p| p.parameters.iter().all(|c| c.ml_value.is_some())));
}
