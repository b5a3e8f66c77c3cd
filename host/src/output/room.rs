//! Free space on the file system an output goes to, checked before a
//! command whose output size is known in advance writes anything.

use super::error::{OutputError, Problem};
use std::path::Path;

/// Bytes an unprivileged process may still write on the file system that
/// holds `path` (or its nearest existing ancestor: `--out` is often new);
/// `None` where it cannot be told.
pub fn free_bytes(path: &Path) -> Option<u64> {
    let mut at = if path.as_os_str().is_empty() {
        Path::new(".")
    } else {
        path
    };
    while at.symlink_metadata().is_err() {
        at = match at.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        if at == Path::new(".") {
            break;
        }
    }
    let c_path = std::ffi::CString::new(at.as_os_str().as_encoded_bytes()).ok()?;
    let mut stat = std::mem::MaybeUninit::<libc::statvfs>::uninit();
    // SAFETY: `c_path` is a NUL-terminated string that outlives the call and
    // `stat` points to writable memory of the size statvfs fills.
    let rc = unsafe { libc::statvfs(c_path.as_ptr(), stat.as_mut_ptr()) };
    if rc != 0 {
        return None;
    }
    // SAFETY: statvfs returned 0, so it filled `stat`.
    let stat = unsafe { stat.assume_init() };
    // The field types differ between targets (u32 on some 32-bit ones).
    #[allow(clippy::unnecessary_cast)]
    let (blocks, block_bytes) = (stat.f_bavail as u64, stat.f_frsize as u64);
    Some(blocks.saturating_mul(block_bytes))
}

/// Refuses, before anything is written, an output `out` (given by
/// `option`) of at least `needed` bytes [bytes] when its file system has
/// less free: the error names the option, the path and both figures.
pub fn check_room(option: &'static str, out: &Path, needed: u64) -> Result<(), OutputError> {
    match free_bytes(out) {
        Some(free) if needed > free => Err(Problem::NoRoom { needed, free }.of(option, out)),
        _ => Ok(()),
    }
}

/// Makes a write past the file-size limit (`ulimit -f`) fail as an error
/// (`EFBIG`, "File too large") instead of killing the process with SIGXFSZ:
/// the command then names the file, removes what it staged and keeps what
/// was there before, as for a full disk.
pub fn refuse_writes_past_the_size_limit() {
    // SAFETY: setting a signal's disposition to SIG_IGN installs no handler
    // code; it is done once at start, before any thread is spawned.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_request_beyond_the_free_space_is_named_with_both_figures() {
        let t = tempfile::tempdir().unwrap();
        let free = super::free_bytes(&t.path().join("new/run")).unwrap();
        assert!(free > 0);
        assert!(super::check_room("--out", &t.path().join("run"), 1).is_ok());
        let e = super::check_room("--out", &t.path().join("run"), u64::MAX)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(&format!("--out {}: ", t.path().join("run").display()))
                && e.contains(&format!("{} bytes", u64::MAX))
                && e.contains("free"),
            "{e}"
        );
    }
}
