//! The properties the fuzz targets check, callable from libFuzzer
//! (`fuzz_targets/`) and from the stable bounded runner (`src/bin/bounded.rs`).

use plinth_shared::protocol::{DeviceMessage, HostMessage, Receiver};
use std::path::PathBuf;
use std::sync::OnceLock;

/// The frame decoder on arbitrary bytes, as the host and the box receive
/// them: no panic, and the same events whether the bytes arrive at once or
/// split at an arbitrary point (the decoder keeps no hidden state that
/// depends on read boundaries).
pub fn frame_decoder(data: &[u8]) {
    let whole = events::<DeviceMessage>(&[data]);
    let cut = data.first().map_or(0, |&b| b as usize % (data.len() + 1));
    let split = events::<DeviceMessage>(&[&data[..cut], &data[cut..]]);
    assert_eq!(whole, split, "events depend on where the input was split");
    let bytes: Vec<u8> = data.to_vec();
    let mut rx = Receiver::<DeviceMessage>::new();
    for b in bytes {
        let _ = rx.push_byte(b);
    }
    let _ = events::<HostMessage>(&[data]);
}

fn events<M>(chunks: &[&[u8]]) -> Vec<String>
where
    M: serde::de::DeserializeOwned + plinth_shared::protocol::SessionOpener + std::fmt::Debug,
{
    let mut rx = Receiver::<M>::new();
    let mut out = Vec::new();
    for chunk in chunks {
        for e in rx.feed(chunk) {
            out.push(format!("{e:?}"));
        }
    }
    out.push(format!("{:?}", rx.stats()));
    out
}

/// The run-directory reader on arbitrary bytes: the first byte picks the
/// file they replace (`measurements.csv` or `bearings.csv`) in an otherwise
/// valid run directory; reading must not panic and must give a valid run or
/// an error that names the file.
pub fn csv_reader(data: &[u8]) {
    static DIR: OnceLock<(tempfile::TempDir, Vec<u8>, Vec<u8>)> = OnceLock::new();
    let (dir, good_m, good_b) = DIR.get_or_init(|| {
        let dir = tempfile::tempdir().expect("temporary directory");
        let run = plinth::identify::synthetic::SyntheticRun::paper_like(true, 8)
            .build()
            .expect("synthetic run");
        run.write(dir.path()).expect("writing the run");
        let m = std::fs::read(dir.path().join("measurements.csv")).expect("measurements");
        let b = std::fs::read(dir.path().join("bearings.csv")).expect("bearings");
        (dir, m, b)
    });
    let path = |name: &str| -> PathBuf { dir.path().join(name) };
    let (target, body) = match data.split_first() {
        Some((&sel, rest)) if sel & 1 == 1 => ("bearings.csv", rest),
        Some((_, rest)) => ("measurements.csv", rest),
        None => ("measurements.csv", data),
    };
    std::fs::write(path("measurements.csv"), good_m).expect("write");
    std::fs::write(path("bearings.csv"), good_b).expect("write");
    std::fs::write(path(target), body).expect("write");
    match plinth::rundir::RunDir::read(dir.path()) {
        Ok(run) => assert!(run.measurements.iter().all(|m| m.speed_hz.is_finite())),
        Err(e) => assert!(e.to_string().contains(".csv"), "{e}"),
    }
}
