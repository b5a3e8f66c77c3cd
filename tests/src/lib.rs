//! Shared helpers for integration tests.

pub mod ross;
pub mod rundown;
pub mod simulated;
pub mod unseen;

use plinth::identify::synthetic::SyntheticRun;
use plinth::rundir::{DigitsMode, RunDir, WriteOptions};

/// Writes `run` to a fresh temporary run directory, the measured phasors
/// rounded to `digits` significant digits (`None`: full precision).
pub fn write_run(run: &RunDir, digits: Option<u32>) -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temporary directory");
    run.write_with(
        dir.path(),
        &WriteOptions {
            digits,
            digits_mode: DigitsMode::Round,
        },
    )
    .expect("writing the run directory");
    dir
}

/// The paper-like synthetic run (see [`SyntheticRun::paper_like`]) with the
/// pedestal damping multiplied by `damping_factor` (0 = undamped), written
/// with `digits` significant digits and read back as `plinth identify` would.
pub fn paper_like_run(speeds: usize, damping_factor: f64, digits: Option<u32>) -> RunDir {
    let mut recipe = SyntheticRun::paper_like(true, speeds);
    for p in &mut recipe.pedestals {
        p.pedestal.c_y *= damping_factor;
        p.pedestal.c_z *= damping_factor;
    }
    let run = recipe.build().expect("synthetic run");
    let dir = write_run(&run, digits);
    RunDir::read(dir.path()).expect("reading back the run directory")
}

/// |a − b| / |b|.
pub fn rel_err(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The MCU target the firmware image is built for.
pub const FIRMWARE_TARGET: &str = "thumbv7em-none-eabihf";

/// The workspace's target directory (integration tests run from
/// `target/<profile>/deps`).
pub fn target_dir() -> std::path::PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    exe.ancestors()
        .nth(3)
        .expect("target directory above target/<profile>/deps")
        .to_path_buf()
}

/// The firmware image for the QEMU tests: `PLINTH_FIRMWARE_ELF` if set,
/// otherwise the current sources built now (incrementally: a no-op when
/// scripts/test.sh already built them) in `<target>/qemu-image`, a
/// directory of its own so as not to wait on the lock of the build running
/// the tests. Never an image left over from older sources.
pub fn firmware_image() -> std::path::PathBuf {
    if let Some(p) = std::env::var_os("PLINTH_FIRMWARE_ELF") {
        return p.into();
    }
    static BUILT: std::sync::OnceLock<std::path::PathBuf> = std::sync::OnceLock::new();
    BUILT
        .get_or_init(|| {
            let own = target_dir().join("qemu-image");
            let status = std::process::Command::new(env!("CARGO"))
                .args([
                    "build",
                    "-p",
                    "plinth-firmware",
                    "--bin",
                    "plinth-firmware",
                    "--target",
                    FIRMWARE_TARGET,
                    "--release",
                ])
                .arg("--target-dir")
                .arg(&own)
                .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
                .status()
                .expect("running cargo to build the firmware image");
            assert!(status.success(), "building the firmware image failed");
            own.join(FIRMWARE_TARGET)
                .join("release")
                .join("plinth-firmware")
        })
        .clone()
}
