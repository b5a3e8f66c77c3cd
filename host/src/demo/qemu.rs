//! The real firmware image under QEMU: finding the image, starting
//! `qemu-system-arm -M netduinoplus2` (an STM32F405 board model) with the
//! box's USART on a pseudo-terminal, and reading which `/dev/pts/N` QEMU
//! chose. The QEMU process is killed when the [`Qemu`] guard is dropped, in
//! every case.

use anyhow::{bail, Context, Result};
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// The MCU target the image is built for.
pub const TARGET: &str = "thumbv7em-none-eabihf";

/// The command that builds the image (from the workspace root).
pub const BUILD_COMMAND: &str =
    "cargo build -p plinth-firmware --target thumbv7em-none-eabihf --release";

/// The QEMU executable.
pub const QEMU: &str = "qemu-system-arm";

/// How long QEMU may take to say which pseudo-terminal it opened.
pub const PTY_TIMEOUT: Duration = Duration::from_secs(20);

/// Where the image is looked for when `--elf` is not given, in order: beside
/// this executable's target directory (`target/release/plinth` →
/// `target/thumbv7em-none-eabihf/release/plinth-firmware`), under
/// `$CARGO_TARGET_DIR`, and under `./target`.
pub fn image_candidates() -> Vec<PathBuf> {
    let rel = Path::new(TARGET).join("release").join("plinth-firmware");
    let mut out = Vec::new();
    if let Ok(exe) = std::env::current_exe() {
        // target/<profile>/plinth, or target/<profile>/deps/<test> in tests.
        for up in exe.ancestors().skip(2).take(2) {
            out.push(up.join(&rel));
        }
    }
    if let Some(dir) = std::env::var_os("CARGO_TARGET_DIR") {
        out.push(PathBuf::from(dir).join(&rel));
    }
    out.push(Path::new("target").join(&rel));
    let mut seen = Vec::new();
    out.retain(|p| {
        let new = !seen.contains(p);
        seen.push(p.clone());
        new
    });
    out
}

/// The firmware image to run: `elf` if given (it must exist), else the first
/// of [`image_candidates`] that exists; the error says how to build it.
pub fn find_image(elf: Option<&Path>) -> Result<PathBuf> {
    if let Some(p) = elf {
        if p.is_file() {
            return Ok(p.to_path_buf());
        }
        bail!(
            "--elf {}: no such file; build the firmware image with `{BUILD_COMMAND}` (it is written to target/{TARGET}/release/plinth-firmware)",
            p.display()
        );
    }
    let candidates = image_candidates();
    if let Some(p) = candidates.iter().find(|p| p.is_file()) {
        return Ok(p.clone());
    }
    bail!(
        "the firmware image was not found (looked for {}); build it with `{BUILD_COMMAND}` from the workspace root, or pass --elf PATH",
        candidates
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    )
}

/// A running QEMU, killed when dropped.
pub struct Qemu {
    child: Child,
    /// The pseudo-terminal QEMU connected the box's USART1 to.
    pub pty: String,
}

/// `qemu-system-arm` running `image` on the netduinoplus2 model (STM32F405)
/// with no display or monitor (not `-nographic`: its multiplexer swallows
/// 0x01 bytes), semihosting on (defmt log on stdout, exit code), and the
/// box's USART1 as `serial` says (QEMU's `-serial` and any `-chardev` it
/// names).
pub fn command<S: AsRef<std::ffi::OsStr>>(image: &Path, serial: &[S]) -> Command {
    let mut c = Command::new(QEMU);
    c.args([
        "-M",
        "netduinoplus2",
        "-display",
        "none",
        "-monitor",
        "none",
    ])
    .args(["-semihosting-config", "enable=on,target=native"])
    .args(serial)
    .arg("-kernel")
    .arg(image);
    c
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Qemu {
    /// Starts `image` on the netduinoplus2 model with the USART on a
    /// pseudo-terminal and semihosting on (logs, exit code), and waits for
    /// QEMU to print `char device redirected to /dev/pts/N`.
    pub fn start(image: &Path) -> Result<Qemu> {
        let mut child = command(image, &["-serial", "pty"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .with_context(|| {
                format!("cannot start {QEMU} (install it, e.g. `apt-get install qemu-system-arm`)")
            })?;
        let (tx, rx) = mpsc::channel::<String>();
        let pipes = [
            child
                .stdout
                .take()
                .map(|p| Box::new(p) as Box<dyn Read + Send>),
            child
                .stderr
                .take()
                .map(|p| Box::new(p) as Box<dyn Read + Send>),
        ];
        for pipe in pipes.into_iter().flatten() {
            let tx = tx.clone();
            std::thread::spawn(move || {
                // The semihosting log is binary (defmt): read bytes, split
                // lines lossily.
                let mut r = BufReader::new(pipe);
                let mut line = Vec::new();
                while let Ok(n) = r.read_until(b'\n', &mut line) {
                    if n == 0 {
                        break;
                    }
                    let _ = tx.send(String::from_utf8_lossy(&line).into_owned());
                    line.clear();
                }
            });
        }
        drop(tx);
        let mut qemu = Qemu {
            child,
            pty: String::new(),
        };
        let mut said = Vec::new();
        loop {
            match rx.recv_timeout(PTY_TIMEOUT) {
                Ok(line) => {
                    if let Some(rest) = line.split("char device redirected to ").nth(1) {
                        qemu.pty = rest.split_whitespace().next().unwrap_or("").to_string();
                        if qemu.pty.is_empty() {
                            bail!("{QEMU} printed no pseudo-terminal path: {line:?}");
                        }
                        break;
                    }
                    if said.len() < 5 {
                        said.push(line.trim_end().to_string());
                    }
                }
                Err(mpsc::RecvTimeoutError::Timeout) => bail!(
                    "{QEMU} did not say which pseudo-terminal it opened within {} s",
                    PTY_TIMEOUT.as_secs()
                ),
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    let status = qemu.child.wait().ok();
                    bail!(
                        "{QEMU} exited ({}) before opening the serial pseudo-terminal{}",
                        status.map_or("unknown status".into(), |s| s.to_string()),
                        if said.is_empty() {
                            String::new()
                        } else {
                            format!(": {}", said.join(" / "))
                        }
                    )
                }
            }
        }
        // Keep draining QEMU's output so that it never blocks on a full pipe.
        std::thread::spawn(move || for _ in rx {});
        Ok(qemu)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_image_says_how_to_build_it() {
        let e = find_image(Some(Path::new("/nonexistent/plinth-firmware"))).unwrap_err();
        let msg = format!("{e:#}");
        assert!(
            msg.contains(BUILD_COMMAND) && msg.contains("--elf"),
            "{msg}"
        );
    }

    #[test]
    fn candidates_end_with_the_workspace_default() {
        let c = image_candidates();
        assert_eq!(
            c.last().unwrap(),
            &Path::new("target/thumbv7em-none-eabihf/release/plinth-firmware")
        );
    }
}
