//! The fuzz targets on stable Rust, for a bounded time: every file of the
//! corpus, then random mutations of corpus entries and random bytes.
//!
//!   cargo run --release --bin bounded -- SECONDS [TARGET]
//!
//! Seeded by the time (printed), so a failure is reproducible with
//! `PLINTH_FUZZ_SEED`. `--write-corpus` (re)writes the frame seeds.

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::path::Path;
use std::time::{Duration, Instant};

fn corpus(name: &str) -> Vec<Vec<u8>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("corpus")
        .join(name);
    let mut out: Vec<Vec<u8>> = std::fs::read_dir(&dir)
        .map(|it| {
            it.filter_map(|e| e.ok())
                .filter_map(|e| std::fs::read(e.path()).ok())
                .collect()
        })
        .unwrap_or_default();
    if out.is_empty() {
        out.push(Vec::new());
    }
    out
}

fn mutate(input: &mut Vec<u8>, rng: &mut StdRng) {
    for _ in 0..rng.random_range(1..8) {
        if input.is_empty() || rng.random_range(0..8) == 0 {
            input.insert(rng.random_range(0..=input.len()), rng.random::<u8>());
            continue;
        }
        let at = rng.random_range(0..input.len());
        match rng.random_range(0..5) {
            0 => input[at] ^= 1 << rng.random_range(0..8),
            1 => input[at] = rng.random(),
            2 => {
                let end = (at + rng.random_range(1..16)).min(input.len());
                input.drain(at..end);
            }
            3 => {
                let end = (at + rng.random_range(1..32)).min(input.len());
                let piece = input[at..end].to_vec();
                input.splice(at..at, piece);
            }
            _ => {
                input[at] = *[0u8, 0xFF, b',', b'\n', b';']
                    .get(rng.random_range(0..5))
                    .unwrap_or(&0)
            }
        }
    }
}

fn write_frame_corpus() {
    use plinth_shared::protocol::*;
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus/frame_decoder");
    std::fs::create_dir_all(&dir).expect("corpus directory");
    let mut tx = Transmitter::new();
    let mut buf = [0u8; MAX_FRAME_SIZE];
    let messages = [
        DeviceMessage::Ack(Ack { command_seq: 3 }),
        DeviceMessage::Ack(Ack { command_seq: 0 }),
    ];
    let mut all = Vec::new();
    for (i, m) in messages.iter().enumerate() {
        let (_, bytes) = tx.encode(m, &mut buf).expect("encode");
        std::fs::write(dir.join(format!("ack-{i}.bin")), &*bytes).expect("write");
        all.extend_from_slice(bytes);
    }
    std::fs::write(dir.join("two-frames.bin"), &all).expect("write");
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--write-corpus") {
        write_frame_corpus();
        return;
    }
    let seconds: f64 = args.first().and_then(|s| s.parse().ok()).unwrap_or(10.0);
    let only = args.get(1).cloned();
    let seed: u64 = std::env::var("PLINTH_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(1, |d| d.as_nanos() as u64)
        });
    type Target = (&'static str, fn(&[u8]));
    let targets: [Target; 2] = [
        ("frame_decoder", plinth_fuzz::frame_decoder),
        ("csv_reader", plinth_fuzz::csv_reader),
    ];
    for (name, target) in targets {
        if only.as_deref().is_some_and(|o| o != name) {
            continue;
        }
        let seeds = corpus(name);
        let mut rng = StdRng::seed_from_u64(seed);
        let until = Instant::now() + Duration::from_secs_f64(seconds);
        let mut runs = 0u64;
        for s in &seeds {
            target(s);
            runs += 1;
        }
        while Instant::now() < until {
            let mut input = if rng.random_range(0..4) == 0 {
                (0..rng.random_range(0..512))
                    .map(|_| rng.random())
                    .collect()
            } else {
                seeds[rng.random_range(0..seeds.len())].clone()
            };
            mutate(&mut input, &mut rng);
            let result = std::panic::catch_unwind(|| target(&input));
            if result.is_err() {
                let path = format!("crash-{name}-{seed}-{runs}.bin");
                let _ = std::fs::write(&path, &input);
                eprintln!("{name}: panic on input written to {path} (PLINTH_FUZZ_SEED={seed})");
                std::process::exit(1);
            }
            runs += 1;
        }
        println!(
            "{name}: {runs} inputs in {seconds} s, no panic (seed {seed}, {} corpus files)",
            seeds.len()
        );
    }
}
