//! `plinth extract`: recordings written by other programs (Python's `wave`
//! and a hand-made float header, `tests/fixtures/field/make_fixtures.py`; a
//! WAV header written here by hand, not by the reader's crate) come back as
//! the phasors they were made from; a simulated run-down with noise, 2X,
//! gap voltage, velocity pick-ups and a notch keyphasor gives the simulator's
//! response within 1e-3 and identifies within 0.25 %; the box's pipeline
//! gives the same phasors on the same samples; bad recordings are named.

use num_complex::Complex;
use plinth::extract::channels::Channels;
use plinth::extract::keyphasor::EdgeDetector;
use plinth::extract::phasors::extract as extract_phasors;
use plinth::extract::recording::Recording;
use plinth::extract::{run, Args};
use plinth::identify::{identify_run, Options};
use plinth::rundir::RunDir;
use plinth::sim::signals::{
    synthesise, ChannelQuantity, PhasorSpline, RunDown, SensorKind, SignalOptions,
};
use plinth::sim::{EffectSet, Machine};
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/field/wav")
}

fn args(recording: &Path, channels: &Path, bearings: &Path, out: &Path) -> Args {
    Args {
        recording: recording.to_path_buf(),
        channels: channels.to_path_buf(),
        bearings: bearings.to_path_buf(),
        out: out.to_path_buf(),
        slow_roll: None,
        plots: false,
        quiet: true,
        force: false,
    }
}

fn expected() -> [Complex<f64>; 4] {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixtures().join("expected.json")).unwrap())
            .unwrap();
    ["rel_y", "rel_z", "ped_y", "ped_z"]
        .map(|k| Complex::new(v[k][0].as_f64().unwrap(), v[k][1].as_f64().unwrap()))
}

#[test]
fn python_written_recordings_in_every_format() {
    let want = expected();
    for (file, tolerance) in [
        // 16 bit: the velocity channels carry about 100 codes of signal.
        ("rec_int16.wav", 2e-3),
        ("rec_int24.wav", 2e-5),
        ("rec_int32.wav", 2e-5),
        ("rec_float32.wav", 2e-5),
        ("rec.csv", 2e-5),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("run");
        run(&args(
            &fixtures().join(file),
            &fixtures().join("channels.toml"),
            &fixtures().join("bearings.csv"),
            &out,
        ))
        .unwrap_or_else(|e| panic!("{file}: {e:#}"));
        let got = RunDir::read(&out).unwrap();
        // 0.5 s at 40 Hz: three 4-revolution phasors at one speed, a dwell
        // averaged into one row.
        assert_eq!(got.measurements.len(), 1, "{file}");
        let m = &got.measurements[0];
        assert!((m.speed_hz - 40.0).abs() < 1e-4, "{file}: {}", m.speed_hz);
        let g = [m.rel[0], m.rel[1], m.ped[0], m.ped[1]];
        for (k, (a, b)) in g.iter().zip(&want).enumerate() {
            let scale = if k < 2 {
                want[0].norm().max(want[1].norm())
            } else {
                want[2].norm().max(want[3].norm())
            };
            assert!(
                (a - b).norm() < tolerance * scale,
                "{file} phasor {k}: {a} vs {b}"
            );
        }
        // These recordings are exactly periodic (a whole number of samples
        // per revolution, no noise): every revolution is the same, the
        // scatter is 0, and 0 would claim exact phasors (refused when read).
        // So no noise columns are written and Plinth estimates the noise.
        assert!(
            m.noise_sd.is_none(),
            "{file}: no noise columns for a recording without scatter: {:?}",
            m.noise_sd
        );
    }
}

/// A WAV header for `channels` channels of 32-bit float at `rate` Hz,
/// written by hand (RIFF, `fmt ` with format 3, `data`).
fn float_wav(path: &Path, rate: u32, channels: u16, frames: &[Vec<f32>]) {
    let body: Vec<u8> = frames
        .iter()
        .flat_map(|f| f.iter().flat_map(|v| v.to_le_bytes()))
        .collect();
    let mut b = Vec::new();
    b.extend_from_slice(b"RIFF");
    b.extend_from_slice(&(4 + 8 + 16 + 8 + body.len() as u32).to_le_bytes());
    b.extend_from_slice(b"WAVEfmt ");
    b.extend_from_slice(&16u32.to_le_bytes());
    b.extend_from_slice(&3u16.to_le_bytes());
    b.extend_from_slice(&channels.to_le_bytes());
    b.extend_from_slice(&rate.to_le_bytes());
    b.extend_from_slice(&(rate * 4 * u32::from(channels)).to_le_bytes());
    b.extend_from_slice(&(4 * channels).to_le_bytes());
    b.extend_from_slice(&32u16.to_le_bytes());
    b.extend_from_slice(b"data");
    b.extend_from_slice(&(body.len() as u32).to_le_bytes());
    b.extend_from_slice(&body);
    std::fs::write(path, b).unwrap();
}

/// The notch keyphasor of formats.md's example: −1 V, falling linearly
/// through −5 V at shaft angle 0 (mod 2π) to −9 V over 0.3 rad.
fn notch(theta: f64) -> f64 {
    let u = (theta + 0.15).rem_euclid(TAU);
    if u < 0.3 {
        -1.0 - 8.0 * u / 0.3
    } else if u < 0.9 {
        -9.0
    } else if u < 1.2 {
        -9.0 + 8.0 * (u - 0.9) / 0.3
    } else {
        -1.0
    }
}

fn channels_toml(bearings: &[&str], revolutions: u32) -> String {
    let mut t = format!(
        "full_scale_v = 10.0\nrevolutions = {revolutions}\n\n[keyphasor]\nchannel = {}\nthreshold_v = -5.0\nedge = \"falling\"\n",
        4 * bearings.len()
    );
    for (bi, b) in bearings.iter().enumerate() {
        for (qi, (quantity, angle)) in [("rel", 0), ("rel", 90), ("ped", 0), ("ped", 90)]
            .iter()
            .enumerate()
        {
            let (sensor, s, unit) = if *quantity == "rel" {
                ("proximity", 7.87, "V/mm")
            } else {
                ("velocity", 20.0, "mV/(mm/s)")
            };
            t += &format!(
                "\n[[channel]]\nindex = {}\nbearing = \"{b}\"\nquantity = \"{quantity}\"\nangle_deg = {angle}\nsensor = \"{sensor}\"\nsensitivity = {s}\nsensitivity_unit = \"{unit}\"\n",
                4 * bi + qi
            );
        }
    }
    t
}

/// A simulated run-down of the damped paper machine through the simulated
/// 16-bit ADC (gap voltage −9 V, 1 mV noise, velocity pick-ups), plus a 2X
/// on every probe and a notch keyphasor channel, written as a float WAV.
struct Simulated {
    _dir: tempfile::TempDir,
    wav: PathBuf,
    channels: PathBuf,
    bearings: PathBuf,
    truth: RunDir,
    frames: Vec<Vec<f32>>,
    fs: f64,
}

fn simulated(rundown: RunDown, sample_rate_hz: f64, revolutions: u32) -> Simulated {
    // The paper machine with a field-sized unbalance (5e-3 kg·m on each
    // 123 kg disk, 40 µm eccentricity: 35 µm 0-pk at the probes at resonance; the bundled file's 1e-4 kg·m gives
    // probe signals of a fraction of a millivolt, below the 1 mV noise).
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/feng-hahn-1997-damped.toml"),
    )
    .unwrap()
    .replace("unbalance = 1.0e-4", "unbalance = 5.0e-3");
    let machine = Machine::from_toml_str(&text, "feng-hahn-1997-damped, unbalance 5e-3").unwrap();
    let opts = SignalOptions {
        rundown,
        sample_rate_hz,
        seismic_kind: SensorKind::Velocity,
        seismic_sensitivity: 20.0,
        ..SignalOptions::default()
    };
    let (set, truth) = synthesise(&machine, &EffectSet::none(), &opts).unwrap();
    let n = set.channels();
    let frames: Vec<Vec<f32>> = (0..set.len())
        .map(|k| {
            let theta = rundown.angle_rad(set.time_s(k));
            let mut f: Vec<f32> = (0..n)
                .map(|c| {
                    let probe = matches!(
                        set.header.channels[c].quantity,
                        ChannelQuantity::RelY | ChannelQuantity::RelZ
                    );
                    let two_x = if probe {
                        0.05 * (2.0 * theta + 0.4).cos()
                    } else {
                        0.0
                    };
                    (set.volts(k, c) + two_x) as f32
                })
                .collect();
            f.push(notch(theta) as f32);
            f
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let wav = dir.path().join("rundown.wav");
    float_wav(&wav, opts.sample_rate_hz as u32, (n + 1) as u16, &frames);
    let names: Vec<String> = machine.bearings.iter().map(|b| b.name.clone()).collect();
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    let channels = dir.path().join("channels.toml");
    std::fs::write(&channels, channels_toml(&names, revolutions)).unwrap();
    let bearings = dir.path().join("bearings.csv");
    truth.write(dir.path().join("truth")).unwrap();
    std::fs::copy(dir.path().join("truth/bearings.csv"), &bearings).unwrap();
    Simulated {
        _dir: dir,
        wav,
        channels,
        bearings,
        truth,
        frames,
        fs: opts.sample_rate_hz,
    }
}

#[test]
fn simulated_rundown_phasors_within_1e_3_and_identification_within_quarter_percent() {
    // One revolution per phasor: an average over R revolutions of a
    // run-down is the mean response over their speed span, not the response
    // at the mean speed (0.15 Hz at 27 Hz for R = 4 at 1 Hz/s, wider than the
    // lightly damped mode there).
    let sim = simulated(
        RunDown {
            start_hz: 65.0,
            end_hz: 15.0,
            rate_hz_per_s: 1.0,
        },
        25_600.0,
        1,
    );
    let out = sim._dir.path().join("run");
    run(&args(&sim.wav, &sim.channels, &sim.bearings, &out)).unwrap();
    let got = RunDir::read(&out).unwrap();
    let spline = PhasorSpline::from_measurements(&sim.truth.measurements).unwrap();
    let mut worst: f64 = 0.0;
    for q in ChannelQuantity::ALL {
        for b in got.measured_bearings() {
            let peak = sim
                .truth
                .measurements
                .iter()
                .filter(|m| m.bearing == b && m.speed_hz >= 15.0 && m.speed_hz <= 65.0)
                .map(|m| q.of(m).norm())
                .fold(0.0, f64::max);
            for m in got.measurements.iter().filter(|m| m.bearing == b) {
                let truth = spline.at(b, q, m.speed_hz).unwrap();
                let e = (q.of(m) - truth).norm() / peak;
                if e > 1e-3 {
                    eprintln!(
                        "{b} {} at {:.3} Hz: {e:.2e} ({} vs {truth})",
                        q.name(),
                        m.speed_hz,
                        q.of(m)
                    );
                }
                worst = worst.max(e);
            }
        }
    }
    eprintln!(
        "worst phasor error {worst:.2e} of the channel peak over {} rows",
        got.measurements.len()
    );
    assert!(
        worst < 1e-3,
        "worst phasor error {worst:e} of the channel's peak"
    );
    // The noise columns against the actual errors: sqrt(E|n|²) per phasor,
    // so mean(|error|²/sd²) ≈ 1 where the error is noise (away from the
    // resonances, where the run-down itself adds a systematic part).
    let mut ratios = Vec::new();
    for q in ChannelQuantity::ALL {
        let k = ChannelQuantity::ALL.iter().position(|x| *x == q).unwrap();
        let (mut e2, mut s2, mut n) = (0.0, 0.0, 0);
        for m in got
            .measurements
            .iter()
            .filter(|m| m.speed_hz > 32.0 && m.speed_hz < 40.0)
        {
            let truth = spline.at(&m.bearing, q, m.speed_hz).unwrap();
            let sd = m.noise_sd.unwrap()[k];
            ratios.push((q.of(m) - truth).norm_sqr() / (sd * sd));
            e2 += (q.of(m) - truth).norm_sqr();
            s2 += sd * sd;
            n += 1;
        }
        let ratio = (s2 / e2).sqrt();
        eprintln!(
            "{}: rms error {:.3e}, rms sd {:.3e} m over {n} phasors: sd/error {ratio:.3}",
            q.name(),
            (e2 / n as f64).sqrt(),
            (s2 / n as f64).sqrt()
        );
        // The calibration through an independent path (the simulator's
        // signals, extract, the spline of the truth): never low, and high
        // by at most what the resonances' trend leaves in the pool.
        assert!(
            ratio > 0.85 && ratio < 1.35,
            "{}: reported sd / rms error {ratio}",
            q.name()
        );
    }
    let mean_ratio = ratios.iter().sum::<f64>() / ratios.len() as f64;
    eprintln!(
        "mean |error|²/sd² = {mean_ratio:.3} over {} phasors (32-40 Hz)",
        ratios.len()
    );
    assert!(
        mean_ratio > 0.6 && mean_ratio < 1.3,
        "noise columns off: mean |error|²/sd² = {mean_ratio}"
    );
    let id = identify_run(&got, &Options::default()).unwrap();
    for p in &sim.truth.truth.as_ref().unwrap().pedestals {
        let f = id.pedestal(&p.bearing).unwrap();
        for (name, a, b) in [
            ("k_y", f.pedestal.k_y, p.pedestal.k_y),
            ("k_z", f.pedestal.k_z, p.pedestal.k_z),
            ("m", f.pedestal.m, p.pedestal.m),
        ] {
            eprintln!(
                "{} {name}: {a} vs {b}: {:+.3} %",
                p.bearing,
                100.0 * (a - b) / b
            );
            assert!(
                ((a - b) / b).abs() < 2.5e-3,
                "{} {name}: {a} vs {b}",
                p.bearing
            );
        }
    }
}

/// The box's pipeline (the firmware's `Pipeline`, compiled for the host)
/// fed the same volts and keyphasor edges gives the same phasors as
/// `extract`, to f32 rounding.
#[test]
fn box_and_extract_agree_on_the_same_samples() {
    use plinth_firmware::config::Configuration;
    use plinth_firmware::pipeline::Pipeline;
    use plinth_firmware::source::{SampleBuffer, BUFFER_VECTORS, CHANNELS};
    use plinth_shared::extractor::KeyphasorEdge as Edge;
    use plinth_shared::protocol::{
        Averaging, ChannelConfig, ChannelSet, DeviceMessage, Quantity, SensorKind as WireKind,
    };

    let sim = simulated(
        RunDown {
            start_hz: 60.0,
            end_hz: 45.0,
            rate_hz_per_s: 5.0,
        },
        25_600.0,
        4,
    );
    let config = Channels::read(&sim.channels).unwrap();
    let mut recording = Recording::open(&sim.wav, config.full_scale_v).unwrap();
    let host = extract_phasors(&mut recording, &config, |_| {}).unwrap();
    assert!(host.outputs.len() > 20);

    // The box: one bearing's four channels at a time (y at 0°, z at 90°).
    let kp = config.keyphasor;
    for bearing in 0..2 {
        let mut box_config = Configuration::new();
        let mut set = ChannelSet {
            channels: heapless::Vec::new(),
        };
        for (c, quantity) in [
            Quantity::RelY,
            Quantity::RelZ,
            Quantity::PedY,
            Quantity::PedZ,
        ]
        .into_iter()
        .enumerate()
        {
            let ch = &config.channels[4 * bearing + c];
            set.channels
                .push(ChannelConfig {
                    channel: c as u8,
                    kind: if c < 2 {
                        WireKind::Displacement
                    } else {
                        WireKind::Velocity
                    },
                    sensitivity: ch.sensitivity_si as f32,
                    bearing: 0,
                    quantity,
                })
                .unwrap();
        }
        box_config.set_channels(&set).unwrap();
        box_config
            .set_averaging(&Averaging {
                revolutions_per_phasor: 4,
            })
            .unwrap();
        let mut pipeline = Pipeline::new(&box_config, sim.fs as f32).unwrap();
        let tables = core::array::from_fn(|_| plinth_shared::bearing::BearingTable::new());
        let mut detector = EdgeDetector::new(&kp);
        let mut frames_out = Vec::new();
        for chunk in sim.frames.chunks(BUFFER_VECTORS) {
            let mut buf = SampleBuffer::default();
            for (k, f) in chunk.iter().enumerate() {
                let mut v = [0.0f32; CHANNELS];
                v[..4].copy_from_slice(&f[4 * bearing..4 * bearing + 4]);
                buf.samples.push(v).unwrap();
                if let Some(fraction) = detector.push(f64::from(f[kp.channel])) {
                    buf.edges.push(Edge { index: k, fraction }).unwrap();
                }
            }
            pipeline.process(&buf, &tables, &mut |m| {
                if let DeviceMessage::Phasors(p) = m {
                    frames_out.push(p);
                }
            });
        }
        assert_eq!(frames_out.len(), host.outputs.len(), "bearing {bearing}");
        let mut sds = 0;
        for (b, h) in frames_out.iter().zip(&host.outputs) {
            assert!((f64::from(b.speed_hz) - h.speed_hz).abs() < 1e-5 * h.speed_hz);
            let bp = &b.bearings[0];
            let wire = [bp.rel[0], bp.rel[1], bp.ped[0], bp.ped[1]];
            let wire_sd = [bp.rel_sd[0], bp.rel_sd[1], bp.ped_sd[0], bp.ped_sd[1]];
            for (c, w) in wire.iter().enumerate() {
                let hq = h.displacement[4 * bearing + c];
                let diff = Complex::new(w.re - hq.re, w.im - hq.im).norm();
                assert!(
                    diff <= 4.0 * f32::EPSILON * hq.norm(),
                    "bearing {bearing} channel {c}: box {w:?}, extract {hq}"
                );
                // The same noise: one definition, the shared extractor's.
                let hs = h.noise_sd[4 * bearing + c].expect("extract's noise sd");
                let bs = f64::from(wire_sd[c]);
                assert!(
                    (bs - hs).abs() <= 4.0 * f64::from(f32::EPSILON) * hs,
                    "bearing {bearing} channel {c}: box sd {bs:e}, extract sd {hs:e}"
                );
                sds += 1;
            }
        }
        assert_eq!(sds, 4 * frames_out.len(), "bearing {bearing}");
    }
}

fn error_of(recording: &Path, channels_text: Option<&str>) -> String {
    let dir = tempfile::tempdir().unwrap();
    let channels = dir.path().join("channels.toml");
    std::fs::write(
        &channels,
        channels_text.map_or_else(
            || std::fs::read_to_string(fixtures().join("channels.toml")).unwrap(),
            String::from,
        ),
    )
    .unwrap();
    let out = dir.path().join("run");
    let e = run(&args(
        recording,
        &channels,
        &fixtures().join("bearings.csv"),
        &out,
    ))
    .expect_err("must fail");
    assert!(!out.exists());
    format!("{e:#}")
}

#[test]
fn bad_recordings_are_named() {
    // A probe channel clipped from frame 1350 (0.263672 s at 5120 Hz).
    let e = error_of(&fixtures().join("rec_clipped.wav"), None);
    assert!(
        e.contains("channel 1 ") && e.contains("clipped from 0.263672 s (frame 1350)"),
        "{e}"
    );
    // No keyphasor edges: the channel never reaches −5 V.
    let e = error_of(&fixtures().join("rec_no_keyphasor.wav"), None);
    assert!(
        e.contains("no keyphasor edges on channel 4") && e.contains("does not reach the threshold"),
        "{e}"
    );
    // A channel index beyond the file's five channels.
    let text = std::fs::read_to_string(fixtures().join("channels.toml"))
        .unwrap()
        .replacen("index = 3", "index = 7", 1);
    let e = error_of(&fixtures().join("rec_int16.wav"), Some(&text));
    assert!(
        e.contains("channel[3].index")
            && e.contains("channel 7 is beyond the recording")
            && e.contains("5 channels"),
        "{e}"
    );
    // 2000 Hz sampling of a 40 Hz shaft: 50 samples per revolution.
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("slow.csv");
    let mut text = String::from("time_s,a,b,c,d,kp\n");
    for k in 0..2000 {
        let th = TAU * 40.0 * k as f64 / 2000.0;
        text += &format!(
            "{},{},{},{},{},{}\n",
            k as f64 / 2000.0,
            -8.0 + 0.1 * th.cos(),
            -8.0 + 0.1 * th.sin(),
            0.01 * th.cos(),
            0.01 * th.sin(),
            notch(th)
        );
    }
    std::fs::write(&csv, text).unwrap();
    let e = error_of(&csv, None);
    assert!(
        e.contains("sample rate 2000 Hz is too low") && e.contains("40.0 Hz"),
        "{e}"
    );
    // A CSV with a gap in time.
    let text: String = std::fs::read_to_string(&csv)
        .unwrap()
        .lines()
        .enumerate()
        .filter(|(i, _)| *i != 1500)
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    std::fs::write(&csv, text).unwrap();
    let e = error_of(&csv, None);
    assert!(e.contains("slow.csv:1501:1") && e.contains("time_s"), "{e}");
}
