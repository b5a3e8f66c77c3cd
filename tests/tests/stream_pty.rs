//! `plinth stream` against the firmware's device compiled for the host,
//! behind a pseudo-terminal opened by path with the serialport crate: the
//! run directory and the box's estimates must equal the host-only pipeline's
//! (the same device fed the same sample blocks in memory), bit for bit.

mod stream_common;

use plinth::stream::derive::derive;
use plinth::stream::port::SerialConnector;
use plinth::stream::progress::Progress;
use plinth::stream::session::SessionOptions;
use stream_common::{measurements, reference_bytes, DeviceThread, Faults, Scenario};

#[test]
fn a_clean_link_gives_the_host_only_pipeline_result() {
    let scenario = Scenario::paper_rundown(150.0, 110.0, 40.0);
    let replay = scenario.replay();
    let device = DeviceThread::start(Faults::default(), Faults::default(), 1);
    let out = scenario.out_dir("run");
    std::fs::create_dir_all(&out).unwrap();
    let mut connector = SerialConnector::new(&device.port, 115_200);
    let outcome = plinth::stream::stream(
        &mut connector,
        &out,
        &scenario.config,
        &scenario.tables,
        Some((&scenario.signals, &replay)),
        SessionOptions::default(),
        Progress::hidden(),
    )
    .expect("streaming");
    device.stop();
    assert!(outcome.completed, "{outcome:?}");
    let report =
        plinth::stream::finish(&out, &scenario.config, &scenario.tables, Some(&outcome)).unwrap();
    println!("{}", plinth::stream::summary(&report));

    // A clean link: nothing lost, nothing rejected.
    let l = &report.link_raw_log;
    assert_eq!(
        (
            l.sequence_gaps,
            l.crc_failures,
            l.cobs_failures,
            l.decode_failures
        ),
        (0, 0, 0, 0)
    );
    let (done, total) = outcome.replay.unwrap();
    assert_eq!(done, total);

    // The same rows as the host-only pipeline, exactly.
    let reference = derive(
        &reference_bytes(&scenario),
        &scenario.config,
        &scenario.tables,
    );
    let got = measurements(&out);
    assert!(got.len() >= 10, "only {} measurement rows", got.len());
    assert_eq!(got, reference.run.measurements);
    // The box's final estimates equal the reference's.
    assert_eq!(
        outcome.last_estimates.as_ref().map(|e| &e.pedestals),
        reference.last_estimates.as_ref().map(|e| &e.pedestals)
    );
    // And both host fits (OLS and ML) ran on them, with their ±.
    assert!(report.batch_error.is_none(), "{:?}", report.batch_error);
    assert!(report.ml_error.is_none(), "{:?}", report.ml_error);
    for p in &report.pedestals {
        assert!(p.parameters.iter().all(|c| c.batch_value.is_some()
            && c.box_value.is_some()
            && c.ml_value.is_some()
            && c.ml_std_err.is_some_and(|s| s > 0.0)));
    }
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join(plinth::stream::report::REPORT_FILE)).unwrap(),
    )
    .unwrap();
    assert!(json["pedestals"][0]["parameters"][0]["ml_std_err"].is_number());
}
