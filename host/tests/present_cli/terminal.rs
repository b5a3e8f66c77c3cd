//! What a terminal shows: a closed stdout ends the command quietly,
//! `--quiet` is global, and progress is drawn on a terminal only (the
//! foundation bootstrap's replicates counted).

use super::{plinth, repo, run_dir, succeeded};
use std::process::{Command, Stdio};

/// A reader that closes the pipe early (`| head -1`) ends the command
/// quietly with exit code 0, as ripgrep does; nothing on stderr.
#[test]
fn closed_stdout_ends_quietly() {
    let (dir, _) = run_dir();
    let mut child = plinth()
        .args(["identify", dir.path().to_str().unwrap(), "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Close our end of stdout before the child writes its JSON.
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(
        !err.contains("panicked") && !err.contains("Broken pipe"),
        "{err}"
    );
}

/// `--quiet` is global: accepted before and after the command.
#[test]
fn quiet_is_global() {
    let (dir, _) = run_dir();
    let d = dir.path().to_str().unwrap();
    for args in [
        vec!["--quiet", "identify", d],
        vec!["identify", d, "--quiet"],
    ] {
        let out = plinth().args(&args).output().unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// Runs `plinth ARGS` with its stderr on a fresh pseudo-terminal (openpty),
/// stdout discarded, progress shown at once, and returns what the terminal
/// showed; `None` when no pseudo-terminal can be opened. (util-linux
/// `script` loses the session when its stdin is not a terminal.)
fn on_a_terminal(args: &[&str]) -> Option<String> {
    use std::io::Read;
    use std::os::fd::{FromRawFd, OwnedFd};
    let (mut master, mut slave) = (-1, -1);
    // SAFETY: openpty writes two new descriptors, owned from here on.
    let opened = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            std::ptr::null_mut(),
            std::ptr::null(),
            std::ptr::null(),
        )
    };
    if opened != 0 {
        return None;
    }
    // SAFETY: both descriptors were just opened by openpty and are not shared.
    let (master, slave) = unsafe { (OwnedFd::from_raw_fd(master), OwnedFd::from_raw_fd(slave)) };
    let mut terminal = std::fs::File::from(master);
    // Read while the command runs, so that a full pty buffer never blocks it;
    // the read ends with EIO once the last slave descriptor is closed.
    let reader = std::thread::spawn(move || {
        let mut shown = Vec::new();
        let mut chunk = [0u8; 4096];
        while let Ok(n) = terminal.read(&mut chunk) {
            if n == 0 {
                break;
            }
            shown.extend_from_slice(&chunk[..n]);
        }
        shown
    });
    let status = Command::new(env!("CARGO_BIN_EXE_plinth"))
        .args(args)
        .env("PLINTH_PROGRESS_AFTER_MS", "0")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::from(slave))
        .status()
        .unwrap();
    let shown = String::from_utf8_lossy(&reader.join().unwrap()).to_string();
    assert!(status.success(), "{args:?}: {shown}");
    Some(shown)
}

/// Progress is drawn on a terminal, for `identify` and `diagnose` too, and
/// never with `--quiet` or when stderr is not a terminal.
#[test]
fn progress_only_on_a_terminal_and_silenced_by_quiet() {
    let (dir, _) = run_dir();
    let d = dir.path().to_str().unwrap();
    for (command, label) in [
        ("identify", "identify: read, fit, bases"),
        ("diagnose", "diagnose: fits"),
    ] {
        let Some(shown) = on_a_terminal(&[command, d]) else {
            assert!(
                std::env::var_os("CI").is_none(),
                "no pseudo-terminal (openpty failed)"
            );
            eprintln!("SKIPPED: no pseudo-terminal (openpty failed)");
            return;
        };
        assert!(shown.contains(label), "{command}: {shown:?}");
        let quiet = on_a_terminal(&["--quiet", command, d]).unwrap();
        assert!(!quiet.contains(label), "{command} --quiet: {quiet:?}");
        let piped = plinth()
            .args([command, d])
            .env("PLINTH_PROGRESS_AFTER_MS", "0")
            .output()
            .unwrap();
        assert!(!String::from_utf8_lossy(&piped.stderr).contains(label));
    }
}

/// `diagnose` on pedestals on an unmeasured skid (the simulator's base
/// element): the foundation candidate's parametric bootstrap, its slowest
/// step, shows its replicates done out of the total on a terminal.
#[test]
fn diagnose_progress_counts_the_bootstrap_replicates() {
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("skid");
    succeeded(
        plinth()
            .args([
                "simulate",
                repo()
                    .join("examples/two-pedestals-on-skid.toml")
                    .to_str()
                    .unwrap(),
            ])
            .args([
                "--speeds",
                "5:120:2",
                "--noise",
                "0.005",
                "--out",
                run.to_str().unwrap(),
            ])
            .output()
            .unwrap(),
    );
    std::fs::remove_file(run.join("base.csv")).unwrap();
    let Some(shown) = on_a_terminal(&["diagnose", run.to_str().unwrap()]) else {
        assert!(
            std::env::var_os("CI").is_none(),
            "no pseudo-terminal (openpty failed)"
        );
        eprintln!("SKIPPED: no pseudo-terminal (openpty failed)");
        return;
    };
    let label = "diagnose: foundation bootstrap replicates";
    let total = format!("/{}", plinth::diagnose::foundation::REPLICATES);
    assert!(
        shown
            .lines()
            .any(|l| l.contains(label) && l.contains(&total))
            || shown.split(label).skip(1).any(|after| after
                .split('(')
                .next()
                .unwrap_or("")
                .contains(&total)),
        "{shown:?}"
    );
}
