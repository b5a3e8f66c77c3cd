//! `plinth demo --qemu`: the same chain with the real firmware image under
//! QEMU (netduinoplus2) on a pseudo-terminal, on a very short run-down
//! (62 → 56 Hz at 35 Hz/s: 0.17 s of signals, 10 revolutions, one phasor
//! each; QEMU runs the firmware ~100× slower than real time, so this takes
//! about 20-30 s). It checks the demo's QEMU plumbing (image, QEMU start,
//! pty, stream, run directory, fit, figures) and that the MCU's recursive
//! (noise-weighted) estimates agree with the batch fit within their standard
//! errors; the bit-level comparison with the host-only pipeline is
//! tests/tests/qemu_stream.rs.
//!
//! Needs `qemu-system-arm` and the image, as qemu_stream.rs (scripts/test.sh
//! provides both; the image is built here when missing).

use plinth::demo::{demo, BoxTarget, DemoOptions};
use plinth::sim::signals::RunDown;
use plinth_tests::firmware_image;

#[test]
fn qemu_demo_runs_the_real_image() {
    let image = firmware_image();
    let dir = tempfile::tempdir().unwrap();
    let mut opts = DemoOptions::bundled(dir.path().join("demo")).unwrap();
    opts.target = BoxTarget::Qemu(image);
    opts.rundown = RunDown {
        start_hz: 62.0,
        end_hz: 56.0,
        rate_hz_per_s: 35.0,
    };
    opts.averaging = 1;
    let o = demo(&opts).expect("the QEMU demo runs");
    print!("{}", plinth::demo::summary(&o));
    let l = &o.stream.link_raw_log;
    assert_eq!(
        (l.sequence_gaps, l.crc_failures, l.cobs_failures),
        (0, 0, 0)
    );
    let (done, total) = o.stream.replay_blocks.expect("replay counters");
    assert_eq!(done, total);
    assert!(
        o.report.phasor_frames >= 6,
        "{} phasors",
        o.report.phasor_frames
    );
    // The MCU's f32 RLS weighs each equation by the noise it measured, the
    // host's batch fit does not: two estimates from the same rows, which
    // must agree within their standard errors (and the box must have them).
    for row in &o.report.table {
        let (b, h) = (
            row.box_value.expect("box value"),
            row.batch_value.expect("batch value"),
        );
        let (sb, sh) = (
            row.box_std_err.expect("box σ"),
            row.batch_std_err.expect("batch σ"),
        );
        assert!(
            sb.is_finite() && sb > 0.0,
            "{} {}: box σ {sb}",
            row.bearing,
            row.parameter
        );
        assert!(
            (b - h).abs() <= 3.0 * sb.hypot(sh),
            "{} {}: box {b} ± {sb} vs batch {h} ± {sh}",
            row.bearing,
            row.parameter
        );
    }
    for stem in ["amplitudes", "phases", "phase_difference"] {
        assert!(o.figures_dir.join(format!("{stem}.png")).is_file());
        assert!(o.figures_dir.join(format!("{stem}.svg")).is_file());
    }
    assert!(o.run_dir.join("measurements.csv").is_file());
}
