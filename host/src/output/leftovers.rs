//! Recovery from interrupted commands and the lock of an output directory:
//! the leftovers a killed command left beside `--out` are rolled back or
//! completed, and one command at a time writes a directory.

use super::*;

/// Whether process `pid` is still running (`/proc/PID`); where that cannot
/// be known it is assumed to run, so its files are left alone.
pub(super) fn process_is_running(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    let proc_fs = Path::new("/proc/self");
    if !proc_fs.exists() {
        return true;
    }
    Path::new("/proc").join(pid.to_string()).exists()
}

/// Clears what an interrupted (killed) Plinth command left beside `out`,
/// and returns one line per thing done, for the user:
///
/// - a staging directory `.NAME.plinth-partial-PID` of a process that has
///   ended and that Plinth made (it holds the manifest mark
///   [`MANIFEST_FILE`]) is removed: it only ever holds new, incomplete
///   output;
/// - a backup `.NAME.plinth-old-PID` of an ended process while `NAME` itself
///   is missing (killed between the two renames of a commit) is the
///   previous directory: it is moved back to `NAME` (the commit is rolled
///   back);
/// - such a backup while `NAME` exists (killed after the second rename) is
///   removed when everything in it is also in `NAME` or is a file Plinth
///   wrote, unchanged (the commit is completed); otherwise it is left and
///   what it alone holds is named;
/// - a `.NAME.plinth-trash-PID` of an ended process (a backup of a complete
///   commit, renamed so before its removal, killed while being removed) is
///   removed.
///
/// Anything else (another name, a running process, no mark) is left alone.
/// Failures are reported as notes, never as errors: the command goes on.
pub fn clean_leftovers(out: &Path) -> Vec<String> {
    let mut notes = Vec::new();
    let Some(name) = out.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return notes;
    };
    let parent = parent_dir(out);
    let Ok(entries) = std::fs::read_dir(&parent) else {
        return notes;
    };
    for e in entries.filter_map(Result::ok) {
        let file = e.file_name().to_string_lossy().into_owned();
        let Some(rest) = file.strip_prefix(&format!(".{name}.")) else {
            continue;
        };
        let Some((tag, pid)) = rest.rsplit_once('-') else {
            continue;
        };
        let Ok(pid) = pid.parse::<u32>() else {
            continue;
        };
        let path = e.path();
        let is_dir = e.file_type().map(|t| t.is_dir()).unwrap_or(false);
        if !is_dir || process_is_running(pid) {
            continue;
        }
        match tag {
            "plinth-partial" if path.join(MANIFEST_FILE).is_file() => {
                match std::fs::remove_dir_all(&path) {
                    Ok(()) => notes.push(format!(
                        "note: removed {}, the unfinished output of an interrupted Plinth command (process {pid}, no longer running)",
                        path.display()
                    )),
                    Err(err) => notes.push(format!(
                        "warning: cannot remove {}, the unfinished output of an interrupted Plinth command: {err}",
                        path.display()
                    )),
                }
            }
            "plinth-trash" => match remove_tree(&path) {
                Ok(()) => notes.push(format!(
                    "note: removed {}, the previous {} that an interrupted Plinth command (process {pid}) had replaced and was removing",
                    path.display(),
                    out.display()
                )),
                Err(err) => notes.push(format!(
                    "warning: cannot remove {}, the previous {} (replaced): {err}",
                    path.display(),
                    out.display()
                )),
            },
            "plinth-old" if out.is_dir() => match backup_is_merged(&path, out) {
                Ok(()) => match remove_tree(&path) {
                    Ok(()) => notes.push(format!(
                        "note: removed {}, the previous {} that an interrupted Plinth command (process {pid}) had already merged into it",
                        path.display(),
                        out.display()
                    )),
                    Err(err) => notes.push(format!(
                        "warning: cannot remove {}, the previous {} (already merged into it): {err}",
                        path.display(),
                        out.display()
                    )),
                },
                Err(rel) => notes.push(format!(
                    "warning: {} holds the previous {} (an interrupted Plinth command moved it), and its {rel} is not in {}: left as it is, move what you need back",
                    path.display(),
                    out.display(),
                    out.display()
                )),
            },
            "plinth-old" if out.symlink_metadata().is_err() => {
                match std::fs::rename(&path, out) {
                    Ok(()) => notes.push(format!(
                        "note: restored {} from {}, where an interrupted Plinth command (process {pid}) had moved it",
                        out.display(),
                        path.display()
                    )),
                    Err(err) => notes.push(format!(
                        "warning: {} holds the previous {} (an interrupted Plinth command moved it): cannot move it back: {err}",
                        path.display(),
                        out.display()
                    )),
                }
            }
            _ => {}
        }
    }
    notes
}

/// The lock of an output directory: `.NAME.plinth-lock` beside it, locked
/// (`flock`, released by the kernel when the process ends, even when it is
/// killed) for as long as a command writes `NAME`; a second command on the
/// same `--out` is refused at once. The file is removed when the lock is
/// released.
#[derive(Debug)]
pub(super) struct Lock {
    path: PathBuf,
    file: std::fs::File,
}

impl Lock {
    pub(super) fn take(out: &Path) -> Result<Lock, Problem> {
        use std::os::unix::fs::MetadataExt;
        let path = lock_path(out);
        for _ in 0..8 {
            let file = std::fs::OpenOptions::new()
                .create(true)
                .truncate(false)
                .read(true)
                .write(true)
                .open(&path)
                .map_err(io("cannot create the lock", &path))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(std::fs::TryLockError::WouldBlock) => {
                    let holder = std::fs::read_to_string(&path).unwrap_or_default();
                    let holder = match holder.trim().parse::<u32>() {
                        Ok(pid) => format!("process {pid}, lock {}", path.display()),
                        Err(_) => format!("lock {}", path.display()),
                    };
                    return Err(Problem::Busy(holder));
                }
                Err(std::fs::TryLockError::Error(e)) => {
                    return Err(io("cannot lock", &path)(e));
                }
            }
            // The holder before us may have removed the file between our
            // open and our lock: then the lock is on a deleted file, retry.
            let same = match (file.metadata(), std::fs::metadata(&path)) {
                (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
                _ => false,
            };
            if same {
                let _ = file.set_len(0);
                let _ = std::io::Write::write_all(
                    &mut &file,
                    format!("{}\n", std::process::id()).as_bytes(),
                );
                return Ok(Lock { path, file });
            }
        }
        Err(Problem::Busy(format!(
            "lock {} keeps changing",
            path.display()
        )))
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        // Removed while still locked; waiters on the old file see it gone.
        let _ = std::fs::remove_file(&self.path);
        let _ = self.file.unlock();
    }
}

/// Whether every entry of `backup` (a previous directory moved aside by a
/// commit) is also in `out`, or is a file Plinth wrote and nobody changed:
/// then the commit had finished and `backup` can go. `Err` names what is
/// only in `backup`.
fn backup_is_merged(backup: &Path, out: &Path) -> Result<(), String> {
    let manifest = read_manifest(backup);
    let entries = list_entries(backup).map_err(|e| e.to_string())?;
    for (rel, kind) in entries {
        if rel == MANIFEST_FILE {
            continue;
        }
        let (old, new) = (backup.join(&rel), out.join(&rel));
        let ok = match kind {
            Entry::File => {
                let h = file_hash(&old).ok();
                h.is_some()
                    && (file_hash(&new).ok() == h || manifest.get(rel.as_str()).copied() == h)
            }
            _ => new.symlink_metadata().is_ok(),
        };
        if !ok {
            return Err(rel);
        }
    }
    Ok(())
}

/// `.NAME.plinth-lock` beside `out`.
pub(super) fn lock_path(out: &Path) -> PathBuf {
    hidden_beside(out, "plinth-lock")
}
