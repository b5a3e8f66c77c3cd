//! What a person sees: the modal view in `identify`'s table and JSON, the
//! speed band, a closed stdout, `--quiet`, `import`'s rounding noise, and
//! documentation that stays inside the repository.
//!
//! This file holds what every part uses (the binary, the repository, a
//! simulated run); `modal`, `terminal`, `outputs` and `docs` the tests.

use plinth::identify::synthetic::SyntheticRun;
use plinth::rundir::{DigitsMode, RunDir, WriteOptions};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod docs;
mod modal;
mod outputs;
mod terminal;

/// The `plinth` binary under test.
fn plinth() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plinth"))
}

/// The repository's root directory.
fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("host/ has a parent")
        .to_path_buf()
}

/// A damped paper-like run with 4 significant digits and its truth.
fn run_dir() -> (tempfile::TempDir, RunDir) {
    let dir = tempfile::tempdir().unwrap();
    let run = SyntheticRun::paper_like(true, 80).build().unwrap();
    run.write_with(
        dir.path(),
        &WriteOptions {
            digits: Some(4),
            digits_mode: DigitsMode::Round,
        },
    )
    .unwrap();
    (dir, run)
}

/// `plinth ARGS`'s stdout as JSON, the command having succeeded.
fn json(args: &[&str]) -> serde_json::Value {
    let out = succeeded(plinth().args(args).output().unwrap());
    serde_json::from_slice(&out.stdout).unwrap()
}

/// `out`, once its command is seen to have succeeded (else its stderr is
/// the failure's message).
fn succeeded(out: Output) -> Output {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}
