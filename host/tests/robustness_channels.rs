//! Issue 20, items 3, 5, 6 and 7 through the command line: inputs the size
//! of the disk fail fast with bounded memory, dead, stuck, absurd and
//! clipped channels are named before they are fitted, a lost keyphasor is
//! reported, another machine's file and a raw log without frames are
//! refused, and WAV files as recorders write them are read. The damaged
//! inputs are made here from the bundled examples, byte by byte.

use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant};

mod robustness_common;
use robustness_common::{
    edited_wav, example, field, offline_rebuild, plinth_quiet as plinth, simulated_run,
    stream_config, text,
};

fn import(table: &Path, out: &Path) -> Output {
    plinth()
        .arg("import")
        .arg(table)
        .arg("--layout")
        .arg(field("layout.toml"))
        .arg("--bearings")
        .arg(field("bearings.csv"))
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

fn extract(recording: &Path, out: &Path) -> Output {
    plinth()
        .arg("extract")
        .arg(recording)
        .arg("--channels")
        .arg(field("channels.toml"))
        .arg("--bearings")
        .arg(field("bearings.csv"))
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

/// The example table with `edit` applied to every data row's fields.
fn edited_table(dir: &Path, name: &str, edit: impl Fn(usize, &mut Vec<String>)) -> PathBuf {
    let text = std::fs::read_to_string(field("vector-table.csv")).unwrap();
    let mut out = String::new();
    for (i, line) in text.lines().enumerate() {
        let mut f: Vec<String> = line.split(',').map(str::to_string).collect();
        if i > 0 {
            edit(i + 1, &mut f);
        }
        out.push_str(&f.join(","));
        out.push('\n');
    }
    let path = dir.join(name);
    std::fs::write(&path, out).unwrap();
    path
}

#[test]
fn a_disk_sized_file_of_nul_bytes_or_one_line_fails_fast() {
    let t = tempfile::tempdir().unwrap();
    // 1 GiB of NUL bytes (sparse: no disk used) as a table and a recording.
    let zeros = t.path().join("zeros.csv");
    std::fs::File::create(&zeros)
        .unwrap()
        .set_len(1 << 30)
        .unwrap();
    let started = Instant::now();
    let o = import(&zeros, &t.path().join("a"));
    assert!(!o.status.success());
    assert!(text(&o).contains("zeros.csv:1:"), "{}", text(&o));
    let o = extract(&zeros, &t.path().join("b"));
    assert!(!o.status.success());
    assert!(text(&o).contains("zeros.csv"), "{}", text(&o));
    // 16 MiB on one line: the error gives the line and the bound, not the line.
    let long = t.path().join("long.csv");
    std::fs::write(&long, vec![b'7'; 16 << 20]).unwrap();
    let o = import(&long, &t.path().join("c"));
    let msg = text(&o);
    assert!(
        msg.contains("line 1 is longer than 1048576 bytes") && !msg.contains("7777"),
        "{}",
        &msg[..msg.len().min(500)]
    );
    assert!(started.elapsed() < Duration::from_secs(20));
    assert!(!t.path().join("a").exists() && !t.path().join("c").exists());
}

#[test]
fn accuracy_refuses_a_billion_draws_naming_the_option() {
    let o = plinth()
        .arg("accuracy")
        .arg(example())
        .args(["--draws", "1000000000", "--speeds", "5:60:5"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(
        text(&o).contains("--draws 1000000000: needs about"),
        "{}",
        text(&o)
    );
}

#[test]
fn dead_stuck_and_absurd_table_columns_are_named() {
    let t = tempfile::tempdir().unwrap();
    // Column 7: `left vel 0 1X Amp`, transducer[2] of the layout.
    let dead = edited_table(t.path(), "dead.csv", |_, f| f[6] = "0".into());
    let o = import(&dead, &t.path().join("dead"));
    assert!(!o.status.success());
    assert!(
        text(&o).contains("column 7 `left vel 0 1X Amp`")
            && text(&o).contains("transducer[2]")
            && text(&o).contains("reads 0 at every one of the 61 speeds"),
        "{}",
        text(&o)
    );
    let stuck = edited_table(t.path(), "stuck.csv", |_, f| {
        f[6] = "1.5".into();
        f[7] = "30".into();
    });
    let o = import(&stuck, &t.path().join("stuck"));
    assert!(text(&o).contains("same 1.5 at 30°"), "{}", text(&o));
    let absurd = edited_table(t.path(), "absurd.csv", |line, f| {
        if line == 5 {
            f[2] = "1e300".into();
        }
    });
    let o = import(&absurd, &t.path().join("absurd"));
    assert!(
        text(&o).contains("absurd.csv:5:3: column `left 45L 1X Amp`")
            && text(&o).contains("beyond any machine's vibration"),
        "{}",
        text(&o)
    );
    for d in ["dead", "stuck", "absurd"] {
        assert!(!t.path().join(d).exists());
    }
    // The example itself imports.
    let o = import(&field("vector-table.csv"), &t.path().join("good"));
    assert!(o.status.success(), "{}", text(&o));
}

#[test]
fn dead_and_flat_topped_channels_and_a_lost_keyphasor_are_named() {
    let t = tempfile::tempdir().unwrap();
    let dead = edited_wav(t.path(), "dead.wav", |_, c, v| if c == 1 { 0 } else { v });
    let o = extract(&dead, &t.path().join("dead"));
    assert!(!o.status.success());
    assert!(
        text(&o).contains("channel 1 (channel[1]: bearing `left`") && text(&o).contains("is dead"),
        "{}",
        text(&o)
    );
    // Channel 0 flat-topped at 80 % of its peak about its mean (a probe
    // driver saturating far below the converter's full scale).
    let bytes = std::fs::read(field("recording.wav")).unwrap();
    let data = bytes.windows(4).position(|w| w == b"data").unwrap() + 8;
    let codes: Vec<i32> = bytes[data..]
        .chunks_exact(3)
        .step_by(9)
        .map(|s| i32::from_le_bytes([0, s[0], s[1], s[2]]) >> 8)
        .collect();
    let mean = codes.iter().map(|&c| f64::from(c)).sum::<f64>() / codes.len() as f64;
    let peak = codes
        .iter()
        .map(|&c| (f64::from(c) - mean).abs())
        .fold(0.0, f64::max);
    let clipped = edited_wav(t.path(), "clipped.wav", |_, c, v| {
        if c == 0 {
            let lim = 0.8 * peak;
            (mean + (f64::from(v) - mean).clamp(-lim, lim)).round() as i32
        } else {
            v
        }
    });
    let o = extract(&clipped, &t.path().join("clipped"));
    assert!(!o.status.success());
    assert!(
        text(&o).contains("channel 0 (channel[0]") && text(&o).contains("is clipped"),
        "{}",
        text(&o)
    );
    // The keyphasor (channel 8) stuck high after 0.3 s.
    let high = bytes[data..]
        .chunks_exact(3)
        .skip(8)
        .step_by(9)
        .map(|s| i32::from_le_bytes([0, s[0], s[1], s[2]]) >> 8)
        .max()
        .unwrap();
    let lost = edited_wav(t.path(), "lost.wav", |frame, c, v| {
        if c == 8 && frame > 1536 {
            high
        } else {
            v
        }
    });
    let o = extract(&lost, &t.path().join("lost"));
    assert!(
        text(&o).contains("keyphasor: pulses only from") && text(&o).contains("94 %"),
        "{}",
        text(&o)
    );
    // The example itself passes without a word about its channels.
    let o = extract(&field("recording.wav"), &t.path().join("good"));
    assert!(o.status.success(), "{}", text(&o));
    assert!(!text(&o).contains("clipped") && !text(&o).contains("pulses only"));
}

#[test]
fn a_64_bit_float_wav_with_a_streaming_size_and_an_odd_chunk_reads_as_the_pcm_one() {
    let t = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(field("recording.wav")).unwrap();
    let data = bytes.windows(4).position(|w| w == b"data").unwrap() + 8;
    // Volts: codes × full scale (10 V) / 2^23, written as f64.
    let body: Vec<u8> = bytes[data..]
        .chunks_exact(3)
        .flat_map(|s| {
            let code = i32::from_le_bytes([0, s[0], s[1], s[2]]) >> 8;
            (f64::from(code) * 10.0 / f64::from(1 << 23)).to_le_bytes()
        })
        .collect();
    let (channels, rate) = (9u16, 5120u32);
    let mut w = b"RIFF\xff\xff\xff\xffWAVEfmt ".to_vec();
    w.extend_from_slice(&16u32.to_le_bytes());
    w.extend_from_slice(&3u16.to_le_bytes());
    w.extend_from_slice(&channels.to_le_bytes());
    w.extend_from_slice(&rate.to_le_bytes());
    w.extend_from_slice(&(rate * 8 * 9).to_le_bytes());
    w.extend_from_slice(&(8 * channels).to_le_bytes());
    w.extend_from_slice(&64u16.to_le_bytes());
    w.extend_from_slice(b"LIST\x05\0\0\0abcde\0");
    w.extend_from_slice(b"data\xff\xff\xff\xff");
    w.extend_from_slice(&body);
    let f64_wav = t.path().join("f64.wav");
    std::fs::write(&f64_wav, w).unwrap();
    let a = extract(&field("recording.wav"), &t.path().join("pcm"));
    let b = extract(&f64_wav, &t.path().join("f64"));
    assert!(a.status.success() && b.status.success(), "{}", text(&b));
    assert!(text(&b).contains("64-bit float WAV"), "{}", text(&b));
    let rows =
        |d: &str| std::fs::read_to_string(t.path().join(d).join("measurements.csv")).unwrap();
    assert_eq!(rows("pcm").lines().count(), rows("f64").lines().count());
}

#[test]
fn another_machines_file_and_a_frameless_raw_log_are_refused() {
    let t = tempfile::tempdir().unwrap();
    let run = t.path().join("run");
    simulated_run(&run, "5:60:1");
    // A machine file with one bearing renamed is another machine's.
    let text_m = std::fs::read_to_string(example()).unwrap();
    let renamed = t.path().join("renamed.toml");
    std::fs::write(
        &renamed,
        text_m.replace("name = \"right\"", "name = \"NDE\""),
    )
    .unwrap();
    let o2 = plinth()
        .arg("diagnose")
        .arg(&run)
        .arg("--machine")
        .arg(&renamed)
        .output()
        .unwrap();
    assert!(!o2.status.success());
    assert!(
        text(&o2).contains("`NDE` not in the run") && text(&o2).contains("renamed.toml"),
        "{}",
        text(&o2)
    );
    // stream --offline on a raw log of random bytes: an error, no run.
    let config = stream_config(&run);
    let before = std::fs::read(run.join("measurements.csv")).unwrap();
    let noise: Vec<u8> = (0..4096u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    std::fs::write(run.join("raw.bin"), noise).unwrap();
    let o = offline_rebuild(&config, &run);
    assert!(!o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("holds no valid phasor frame"),
        "{}",
        text(&o)
    );
    assert_eq!(std::fs::read(run.join("measurements.csv")).unwrap(), before);
    assert!(!run.join("stream-report.json").exists());
}
