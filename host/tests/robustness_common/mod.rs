//! Scaffolding shared by the host's robustness tests (`mod
//! robustness_common;` in each): the binary, the bundled examples, a
//! simulated run, an offline stream rebuild, a command's whole output, a
//! bounded run, a directory snapshot, a long machine, a stream
//! configuration for a simulated run and the example recording edited
//! sample by sample.
#![allow(dead_code)] // each test file uses its own subset

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The `plinth` binary under test.
pub fn plinth() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plinth"))
}

/// `plinth --quiet` (no progress display).
pub fn plinth_quiet() -> Command {
    let mut c = plinth();
    c.arg("--quiet");
    c
}

/// The bundled paper machine file.
pub fn example() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/feng-hahn-1997.toml")
}

/// A file of the bundled field example (examples/field/).
pub fn field(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../examples/field")
        .join(name)
}

/// Simulates the bundled machine over `speeds` (`LO:HI:STEP` [Hz]) into
/// `out`, which must succeed.
pub fn simulated_run(out: &Path, speeds: &str) {
    let o = plinth()
        .arg("simulate")
        .arg(example())
        .args(["--speeds", speeds, "--out"])
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
}

/// `plinth stream --offline --config CONFIG --out RUN`: the run rebuilt
/// from its raw log.
pub fn offline_rebuild(config: &Path, run: &Path) -> Output {
    plinth()
        .args(["stream", "--offline", "--config"])
        .arg(config)
        .arg("--out")
        .arg(run)
        .output()
        .unwrap()
}

/// A command's stdout then stderr, as text.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Every file under `dir` (relative path → bytes; symbolic links as their
/// target), to compare a directory before and after.
pub fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let e = e.unwrap();
            let p = e.path();
            let rel = p.strip_prefix(root).unwrap().display().to_string();
            let ft = e.file_type().unwrap();
            if ft.is_symlink() {
                let to = std::fs::read_link(&p).unwrap();
                out.insert(rel, to.display().to_string().into_bytes());
            } else if ft.is_dir() {
                walk(root, &p, out);
            } else {
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// Runs the command with no input, killing it (and failing) if it takes
/// longer than `limit`: a blocked or hung command is a failure, not a hang.
pub fn run_bounded(cmd: &mut Command, limit: Duration) -> Output {
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let o = child.wait_with_output().unwrap();
            panic!("still running after {limit:?}: {}", text(&o));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A machine file with `elements` shaft elements (a slow simulation).
pub fn long_machine(dir: &Path, elements: usize) -> PathBuf {
    let text = std::fs::read_to_string(example()).unwrap();
    let per = elements / 12;
    let text = text
        .replace("elements = 10\n", &format!("elements = {}\n", 10 * per))
        .replace("elements = 1\n", &format!("elements = {per}\n"));
    let path = dir.join("long.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// Writes `DIR/stream.toml` for a run of the paper machine (bearings `left`
/// and `right`, four proximity channels each) and returns its path.
pub fn stream_config(dir: &Path) -> PathBuf {
    let mut s = String::from("bearings = \"bearings.csv\"\n");
    for (b, bearing) in ["left", "right"].iter().enumerate() {
        for (q, quantity) in ["rel_y", "rel_z", "ped_y", "ped_z"].iter().enumerate() {
            s.push_str(&format!(
                "\n[[channels]]\nadc = {}\nbearing = \"{bearing}\"\nquantity = \"{quantity}\"\nsensor = \"proximity\"\nsensitivity = 7870.0\n",
                4 * b + q
            ));
        }
    }
    let path = dir.join("stream.toml");
    std::fs::write(&path, s).unwrap();
    path
}

/// The example recording (24-bit PCM, 9 channels) with `edit` applied to
/// every sample code (frame, channel, code) -> code.
pub fn edited_wav(dir: &Path, name: &str, edit: impl Fn(usize, usize, i32) -> i32) -> PathBuf {
    let bytes = std::fs::read(field("recording.wav")).unwrap();
    let data = bytes.windows(4).position(|w| w == b"data").unwrap() + 8;
    let mut out = bytes.clone();
    for (i, s) in out[data..].chunks_exact_mut(3).enumerate() {
        let code = i32::from_le_bytes([0, s[0], s[1], s[2]]) >> 8;
        let v = edit(i / 9, i % 9, code).to_le_bytes();
        s.copy_from_slice(&v[..3]);
    }
    let path = dir.join(name);
    std::fs::write(&path, out).unwrap();
    path
}
