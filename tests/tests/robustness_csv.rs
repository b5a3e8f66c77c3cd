//! Property test of the run-directory reader (issue 13): random bytes and
//! random mutations of a valid run directory never panic and never hang;
//! every outcome is an error that names the file, or a valid run.
//!
//! A seeded loop (reproducible; the failing case's seed and bytes are in the
//! message), bounded in count and time. The `fuzz/` directory runs the same
//! property unbounded under libFuzzer.

use plinth::identify::synthetic::SyntheticRun;
use plinth::rundir::RunDir;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::panic::AssertUnwindSafe;
use std::path::Path;
use std::time::{Duration, Instant};

/// One mutation of `bytes`: flip, insert, delete, duplicate a line, splice
/// in a token that readers find hard.
fn mutate(bytes: &mut Vec<u8>, rng: &mut StdRng) {
    const TOKENS: [&[u8]; 16] = [
        b",",
        b";",
        b"\t",
        b"\"",
        b"\n",
        b"\r\n",
        b"nan",
        b"inf",
        b"-1e309",
        b"1e-320",
        b"\xEF\xBB\xBF",
        b"\xFF\xFE",
        b"\x00",
        b"\xC3",
        b"left",
        b",,,,",
    ];
    if bytes.is_empty() {
        bytes.push(rng.random());
        return;
    }
    let at = rng.random_range(0..bytes.len());
    match rng.random_range(0..6) {
        0 => bytes[at] ^= 1 << rng.random_range(0..8),
        1 => bytes.insert(at, rng.random()),
        2 => {
            let end = (at + rng.random_range(1..40)).min(bytes.len());
            bytes.drain(at..end);
        }
        3 => {
            let t = TOKENS[rng.random_range(0..TOKENS.len())];
            bytes.splice(at..at, t.iter().copied());
        }
        4 => {
            // Duplicate the line around `at`.
            let start = bytes[..at]
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(0, |i| i + 1);
            let end = bytes[at..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(bytes.len(), |i| at + i + 1);
            let line = bytes[start..end].to_vec();
            bytes.splice(end..end, line);
        }
        _ => {
            // Replace a digit with another character class.
            if bytes[at].is_ascii_digit() {
                bytes[at] = *b"x.-+e ".get(rng.random_range(0..6)).unwrap_or(&b'x');
            } else {
                bytes.truncate(at);
            }
        }
    }
}

/// Reads `dir`, asserting no panic and a located error or a valid run.
fn check(dir: &Path, seed: u64, what: &str) {
    let result = std::panic::catch_unwind(AssertUnwindSafe(|| RunDir::read(dir)));
    match result {
        Err(_) => panic!("RunDir::read panicked on {what} (seed {seed})"),
        Ok(Ok(run)) => {
            // A valid run: every number finite where formats.md needs it.
            for m in &run.measurements {
                assert!(m.speed_hz.is_finite(), "{what} (seed {seed})");
            }
        }
        Ok(Err(e)) => {
            let msg = e.to_string();
            assert!(
                msg.contains(".csv"),
                "the error names no file on {what} (seed {seed}): {msg}"
            );
        }
    }
}

#[test]
fn random_and_mutated_run_directories_never_panic_or_hang() {
    let dir = tempfile::tempdir().unwrap();
    let run = SyntheticRun::paper_like(true, 12).build().unwrap();
    run.write(dir.path()).unwrap();
    let m_path = dir.path().join("measurements.csv");
    let b_path = dir.path().join("bearings.csv");
    let good_m = std::fs::read(&m_path).unwrap();
    let good_b = std::fs::read(&b_path).unwrap();
    check(dir.path(), 0, "the valid run");

    let started = Instant::now();
    let budget = Duration::from_secs(20);
    let mut cases = 0;
    for seed in 0..600u64 {
        if started.elapsed() > budget {
            break;
        }
        let mut rng = StdRng::seed_from_u64(seed);
        let (mut m, mut b) = (good_m.clone(), good_b.clone());
        match seed % 5 {
            0 => {
                // Random bytes in place of measurements.csv.
                let n = rng.random_range(0..400);
                m = (0..n).map(|_| rng.random()).collect();
            }
            1 => {
                // Random printable CSV-ish text.
                let alphabet = b"0123456789.,;-+eE \n\r\"leftright_hzspeedbearingrel_y";
                let n = rng.random_range(0..600);
                m = (0..n)
                    .map(|_| alphabet[rng.random_range(0..alphabet.len())])
                    .collect();
            }
            2 => {
                for _ in 0..rng.random_range(1..8) {
                    mutate(&mut b, &mut rng);
                }
            }
            _ => {
                for _ in 0..rng.random_range(1..12) {
                    mutate(&mut m, &mut rng);
                }
            }
        }
        std::fs::write(&m_path, &m).unwrap();
        std::fs::write(&b_path, &b).unwrap();
        let case = Instant::now();
        check(dir.path(), seed, "a mutated run directory");
        assert!(
            case.elapsed() < Duration::from_secs(2),
            "seed {seed} took {:?}",
            case.elapsed()
        );
        cases += 1;
    }
    assert!(cases >= 100, "only {cases} cases in {budget:?}");
}
