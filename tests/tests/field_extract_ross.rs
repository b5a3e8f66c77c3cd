//! `plinth extract` → `identify` → `diagnose --machine` on a recording
//! Plinth's simulator did not make: a run-down of unseen-five (two plain
//! bearings, pedestal resonances inside the run) made by
//! `scripts/ross_recording.py` from ROSS 2.3.0's steady unbalance response
//! (tests/data/ross-recording/README.md): 52 → 9.6 Hz at 2 Hz/s, 4 kHz,
//! 16-bit, proximity probes on a −9 V gap and velocity pick-ups with a 2X
//! and white noise in volts, a notch keyphasor, 4 revolutions per phasor.
//! Only the reading is Plinth's. docs/field-data.md ("Session 39") has the
//! figures over seeds and machines.

use num_complex::Complex;
use plinth::extract::{run, Args};
use plinth::rundir::RunDir;
use plinth_tests::rundown::identify;
use plinth_tests::unseen::{assert_flagged_by_nothing, diagnosis_with_machine_check};
use std::path::{Path, PathBuf};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-recording");
const MACHINE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-5");

fn data(file: &str) -> PathBuf {
    Path::new(DATA).join(file)
}

/// The stored recording extracted into a temporary run directory (with the
/// recording's truth.json); the directory is returned to keep it alive.
fn extracted() -> (tempfile::TempDir, RunDir) {
    let dir = tempfile::tempdir().expect("temporary directory");
    let out = extract_into(data("recording.wav"), dir.path());
    std::fs::copy(data("truth.json"), out.join("truth.json")).expect("truth.json");
    let run = RunDir::read(&out).expect("run directory");
    (dir, run)
}

/// ROSS's phasors at the rows' speeds (expected.csv: speed_hz, bearing,
/// rel_y, rel_z, ped_y, ped_z as re, im [m]).
fn expected() -> Vec<(f64, String, [Complex<f64>; 4])> {
    let text = std::fs::read_to_string(data("expected.csv")).expect("expected.csv");
    text.lines()
        .skip(1)
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            let x = |i: usize| f[i].parse::<f64>().expect("number");
            let q = [0, 1, 2, 3].map(|k| Complex::new(x(2 + 2 * k), x(3 + 2 * k)));
            (x(0), f[1].to_string(), q)
        })
        .collect()
}

/// The noise columns mean what they say: per bearing and channel, the mean
/// over the rows of |extracted − ROSS|²/sd² lies within 0.6-1.5 (1 when the
/// sd is sqrt(E|error|²)). On main (c0eccc6) 5 of the 8 channels fail:
/// B1 rel_y 2.20, rel_z 4.08, ped_z 3.40, B2 ped_y 2.34, ped_z 8.53 (the
/// 4-revolution average's curvature bias at the resonances, which the sd
/// did not carry); here 0.83-1.19. Every row has its ROSS phasor (the
/// speeds are the extractor's, to 1e-9 Hz).
#[test]
fn noise_columns_are_calibrated_against_ross() {
    let (_dir, got) = extracted();
    let want = expected();
    assert_eq!(got.measurements.len(), want.len(), "rows");
    let mut sums = std::collections::BTreeMap::new();
    for m in &got.measurements {
        let (_, _, q) = want
            .iter()
            .find(|(s, b, _)| *b == m.bearing && (s - m.speed_hz).abs() < 1e-9)
            .unwrap_or_else(|| panic!("{} at {} Hz: no ROSS phasor", m.bearing, m.speed_hz));
        let sd = m.noise_sd.expect("noise columns");
        let g = [m.rel[0], m.rel[1], m.ped[0], m.ped[1]];
        for k in 0..4 {
            let e: &mut (f64, usize) = sums.entry((m.bearing.clone(), k)).or_default();
            e.0 += (g[k] - q[k]).norm_sqr() / (sd[k] * sd[k]);
            e.1 += 1;
        }
    }
    let bad = channels_off(&sums, "");
    assert!(bad.is_empty(), "noise columns off: {bad:?}");
}

/// The clean recording's promise: identify trusts both pedestals and every
/// `ok` k_y, k_z, m lies within 3 of its ± of the machine file's pedestals;
/// diagnose with the machine file names nothing and is trusted. Measured
/// here: B1 0.21 % off (worst of k_y, k_z, m; 0.8 of its ±), B2 2.2 % (2.0
/// of its ±).
#[test]
fn identify_and_diagnose_read_the_ross_recording_right() {
    let (_dir, got) = extracted();
    assert_eq!(got.measured_bearings().len(), 2);
    let id = identify(&got);
    let d = diagnosis_with_machine_check(MACHINE, "unseen-five.toml", &got);
    assert_flagged_by_nothing(&got, &id, &d, "ross recording");
}

/// The stored recording with its keyphasor made a square pulse (every
/// sample below the −5 V threshold set to −9 V, every other to −1 V: the
/// transition shorter than a sample, as a square pulse from another
/// program gives): each edge is then timed only to within ±0.5 sample
/// (0.29 sample sd, 1.3° at 77 samples per revolution), the same phase
/// error on every channel. The jitter is measured (> 0.8°; the 8° edges of
/// the stored recording 0.006°) and the noise columns still mean what they
/// say against ROSS: per bearing and channel, mean |extracted − ROSS|²/sd²
/// within 0.6-1.5. ROSS's phasor is interpolated linearly in speed from the
/// two nearest rows of expected.csv, for the rows within 0.01 Hz of one
/// (at least 75 %: 272 of 324 here). On main (57297e3 built as a binary,
/// the same square recording through `plinth extract`, the same
/// comparison): no jitter reported, 206 of 300 rows off the stored speeds,
/// and on the 94 that match rel 0.24-0.43 (B2 rel_y 0.24), ped 0.75-1.06;
/// on c0eccc6 also B2 ped_z 21.9. Here 0.86-1.20.
#[test]
fn a_square_keyphasor_pulse_is_measured_and_counted_in_the_noise_columns() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let mut wav = std::fs::read(data("recording.wav")).expect("recording.wav");
    let at = wav
        .windows(4)
        .position(|w| w == b"data")
        .expect("data chunk")
        + 8;
    // 9 channels of 16-bit PCM at 10 V full scale; the keyphasor is channel 8.
    let threshold = (-5.0 / 10.0 * 32768.0) as i16;
    let (low, high) = (
        (-9.0 / 10.0 * 32768.0) as i16,
        (-1.0 / 10.0 * 32768.0) as i16,
    );
    for frame in wav[at..].chunks_exact_mut(18) {
        let v = i16::from_le_bytes([frame[16], frame[17]]);
        let square = if v < threshold { low } else { high };
        frame[16..18].copy_from_slice(&square.to_le_bytes());
    }
    let recording = dir.path().join("square.wav");
    std::fs::write(&recording, &wav).expect("write");
    let config =
        plinth::extract::channels::Channels::read(&data("channels.toml")).expect("channels");
    let jitter = |path: &Path| {
        let mut r =
            plinth::extract::recording::Recording::open(path, config.full_scale_v).expect("open");
        plinth::extract::phasors::extract(&mut r, &config, |_| {})
            .expect("extract")
            .edge_fit
            .jitter_deg()
    };
    let (square, ramp) = (jitter(&recording), jitter(&data("recording.wav")));
    assert!(
        square > 0.8 && ramp < 0.1,
        "jitter {square}° square, {ramp}° 8° edges"
    );
    let out = extract_into(recording, dir.path());
    let got = RunDir::read(&out).expect("run directory");
    let want = expected();
    let mut sums = std::collections::BTreeMap::new();
    let mut skipped = 0;
    for m in &got.measurements {
        let mut near: Vec<&(f64, String, [Complex<f64>; 4])> =
            want.iter().filter(|(_, b, _)| *b == m.bearing).collect();
        near.sort_by(|a, b| {
            (a.0 - m.speed_hz)
                .abs()
                .total_cmp(&(b.0 - m.speed_hz).abs())
        });
        let (a, b) = (near[0], near[1]);
        if (a.0 - m.speed_hz).abs() > 0.01 {
            skipped += 1;
            continue;
        }
        let w = (m.speed_hz - a.0) / (b.0 - a.0);
        let sd = m.noise_sd.expect("noise columns");
        let g = [m.rel[0], m.rel[1], m.ped[0], m.ped[1]];
        for k in 0..4 {
            let q = a.2[k] + (b.2[k] - a.2[k]) * w;
            let e: &mut (f64, usize) = sums.entry((m.bearing.clone(), k)).or_default();
            e.0 += (g[k] - q).norm_sqr() / (sd[k] * sd[k]);
            e.1 += 1;
        }
    }
    let bad = channels_off(&sums, "square keyphasor: ");
    assert!(
        skipped * 4 <= got.measurements.len(),
        "{skipped} of {} rows not within 0.01 Hz of a stored one",
        got.measurements.len()
    );
    assert!(
        bad.is_empty(),
        "noise columns off with a square keyphasor: {bad:?}"
    );
}

/// Mean |error|²/sd² per bearing and channel (rel y, rel z, ped y, ped z)
/// from `sums` (bearing, channel) → (Σ |error|²/sd², rows), printed with
/// `label`; returns the channels outside 0.6-1.5 (noise columns that
/// misdescribe the phasors' error). Two bearings, four channels each.
fn channels_off(
    sums: &std::collections::BTreeMap<(String, usize), (f64, usize)>,
    label: &str,
) -> Vec<String> {
    let names = ["rel_y", "rel_z", "ped_y", "ped_z"];
    let mut bad = Vec::new();
    for ((bearing, k), (sum, n)) in sums {
        let ratio = sum / *n as f64;
        eprintln!(
            "{label}{bearing} {}: mean |error|²/sd² {ratio:.2} ({n} rows)",
            names[*k]
        );
        if !(0.6..=1.5).contains(&ratio) {
            bad.push(format!("{bearing} {}: {ratio:.2}", names[*k]));
        }
    }
    assert_eq!(sums.len(), 8, "two bearings, four channels");
    bad
}

/// `plinth extract` of `recording` with the stored channels and bearings
/// into `dir`/run; returns that run directory's path.
fn extract_into(recording: std::path::PathBuf, dir: &std::path::Path) -> std::path::PathBuf {
    let out = dir.join("run");
    run(&Args {
        recording,
        channels: data("channels.toml"),
        bearings: data("bearings.csv"),
        out: out.clone(),
        slow_roll: None,
        plots: false,
        quiet: true,
        force: false,
    })
    .expect("extract");
    out
}
