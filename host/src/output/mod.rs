//! Output directories that never destroy input.
//!
//! Every command that writes a directory (`simulate`, `signals`, `stream`,
//! `demo`, `diagnose --plots`, `paper --plots`, ...) writes through an
//! [`OutputDir`]:
//!
//! 1. [`OutputDir::create`] checks `--out` before anything is computed: a path
//!    that does not exist or an empty directory is fine; a file, a symbolic
//!    link, or a directory that already holds something is refused unless
//!    `--force` is given. It then creates a staging directory, a hidden
//!    sibling `.NAME.plinth-partial-PID`, and the command writes into
//!    [`OutputDir::path`] only.
//! 2. [`OutputDir::commit`] moves the finished staging directory into place.
//!    Over an existing directory (only with `--force`) the files the previous
//!    contents had are merged in: a file of the old directory that the new
//!    output also writes is replaced only if Plinth wrote it (it is listed,
//!    unchanged, in the old directory's manifest [`MANIFEST_FILE`]), if its
//!    content is identical, or if the command declared the file an
//!    append-only log ([`OutputDir::appends`]) and the new file starts with
//!    every byte of the old one. Anything else (a measured run's
//!    `measurements.csv`, a configuration the user wrote) makes the commit
//!    fail with the previous directory untouched. Files of the old directory
//!    that the new output does not write are kept (hard-linked, or copied
//!    across file systems), except files Plinth itself wrote earlier and
//!    that are unchanged (stale derived files such as an old `truth.json`).
//!    Symbolic links are moved as links, never followed.
//! 3. The swap is two renames: the old directory to a hidden backup sibling,
//!    the staging directory to `--out`; then the backup is removed. The old
//!    directory is never modified before the new one is complete, so a
//!    command that fails or is killed leaves the previous state as it was
//!    (at worst a leftover `.NAME.plinth-partial-PID` staging directory,
//!    which holds nothing of the old run and may be deleted).
//!
//! Dropping an [`OutputDir`] without committing removes the staging
//! directory, unless [`OutputDir::keep_on_failure`] gave it a name to keep it
//! under (`stream` keeps the raw log of a failed run that way).
//!
//! ```no_run
//! # fn main() -> anyhow::Result<()> {
//! use plinth::output::OutputDir;
//! let out = OutputDir::create(std::path::Path::new("run"), false)?;
//! std::fs::write(out.path().join("measurements.csv"), "speed_hz,...\n")?;
//! let final_dir = out.commit()?; // "run", complete, or the error and "run" as it was
//! # let _ = final_dir; Ok(()) }
//! ```
//!
//! The parts: `target` checks `--out` before anything is computed, `merge`
//! decides what a `--force` commit keeps of the previous directory against
//! its `manifest`, `leftovers` recovers from killed commands and holds the
//! lock, and `error` names every refusal.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

mod error;
mod file;
mod leftovers;
mod manifest;
mod merge;
mod room;
mod target;

pub use error::{OutputError, Problem};
pub use file::{check_file, write_file};
pub use leftovers::clean_leftovers;
pub use room::{check_room, free_bytes, refuse_writes_past_the_size_limit};
pub use target::describe;

use error::io;
use leftovers::*;
use manifest::*;
use target::{check_target, resolve};

/// The manifest of the files Plinth wrote into an output directory: one line
/// per file, `HASH SIZE RELATIVE/PATH` (FNV-1a 64-bit in hex, bytes).
pub const MANIFEST_FILE: &str = ".plinth-written";

/// A directory being written: staged in a hidden sibling of `--out`, moved
/// into place by [`OutputDir::commit`].
#[derive(Debug)]
pub struct OutputDir {
    /// The command-line option that named `target` (`--out`, `--plots`).
    option: &'static str,
    target: PathBuf,
    staging: PathBuf,
    existing: bool,
    appends: BTreeSet<String>,
    keep_as: Option<PathBuf>,
    done: bool,
    /// The lock of `--out`, held until the output is committed or dropped.
    lock: Option<Lock>,
}

impl OutputDir {
    /// Checks `out` (the option `--out`) and creates the staging directory.
    /// `force`: write into an `out` that already holds something (files
    /// Plinth did not write are still never deleted or replaced).
    pub fn create(out: &Path, force: bool) -> Result<OutputDir, OutputError> {
        Self::create_as("--out", out, force)
    }

    /// [`OutputDir::create`] for the directory given by the command-line
    /// option `option` (e.g. `--plots`), which every error names.
    pub fn create_as(
        option: &'static str,
        out: &Path,
        force: bool,
    ) -> Result<OutputDir, OutputError> {
        let (target, lock, existing) = open_target(option, out, force)?;
        let staging = sibling(&target, "plinth-partial", std::process::id());
        let made = || -> Result<(), Problem> {
            if staging.symlink_metadata().is_ok() {
                std::fs::remove_dir_all(&staging).map_err(io("cannot clear", &staging))?;
            }
            std::fs::create_dir(&staging).map_err(io("cannot create", &staging))?;
            // The staging directory's mark: an empty manifest (the commit
            // writes the real one), so a leftover is known to be Plinth's.
            std::fs::write(staging.join(MANIFEST_FILE), "")
                .map_err(io("cannot write", &staging.join(MANIFEST_FILE)))
        };
        made().map_err(|p| p.of(option, &target))?;
        Ok(OutputDir {
            option,
            target,
            staging,
            existing,
            appends: BTreeSet::new(),
            keep_as: None,
            done: false,
            lock: Some(lock),
        })
    }

    /// Uses `staging` (created if needed; e.g. the one a killed `stream`
    /// left) instead of a new hidden one; `out` (the option `--out`) is
    /// checked as in [`OutputDir::create`]. Such a staging directory is
    /// kept when the output is dropped uncommitted (it may hold a raw log):
    /// remove it with [`OutputDir::discard`].
    pub fn resume(out: &Path, staging: &Path, force: bool) -> Result<OutputDir, OutputError> {
        let option = "--out";
        let (target, lock, existing) = open_target(option, out, force)?;
        if !staging.is_dir() {
            std::fs::create_dir(staging)
                .map_err(io("cannot create", staging))
                .map_err(|p| p.of(option, &target))?;
        }
        Ok(OutputDir {
            option,
            target,
            staging: staging.to_path_buf(),
            existing,
            appends: BTreeSet::new(),
            keep_as: Some(staging.to_path_buf()),
            done: false,
            lock: Some(lock),
        })
    }

    /// The directory to write into (the staging directory).
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// The final directory (`--out`).
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Declares `file` (relative) an append-only log: it may replace the old
    /// directory's file of that name when it starts with all of its bytes,
    /// and it is not listed in the manifest (a later command that does not
    /// write it keeps it).
    pub fn appends(&mut self, file: &str) {
        self.appends.insert(file.to_string());
    }

    /// On failure (drop without commit), keep the staging directory renamed
    /// to `name` (a sibling of `--out`) instead of removing it.
    pub fn keep_on_failure(&mut self, name: PathBuf) {
        self.keep_as = Some(name);
    }

    /// Removes the staging directory and everything in it; `--out` is as
    /// it was.
    pub fn discard(mut self) {
        self.keep_as = None;
    }

    /// Moves the staged output into place (see the module docs); returns the
    /// final directory. On error the previous `--out` is as it was.
    pub fn commit(mut self) -> Result<PathBuf, OutputError> {
        let result = self
            .commit_inner()
            .map_err(|p| p.of(self.option, &self.target));
        if result.is_ok() {
            self.done = true;
        }
        result.map(|()| self.target.clone())
    }

    fn commit_inner(&mut self) -> Result<(), Problem> {
        let new_files = list_files(&self.staging)?;
        let exists = self.target.symlink_metadata().is_ok();
        // What the old directory held when it was merged: anything else
        // found at the swap appeared while this command ran.
        let snapshot = if exists && self.existing {
            Some(self.merge_old()?)
        } else {
            None
        };
        // Append-only logs are records, not derived files: never listed.
        let derived: BTreeSet<String> = new_files.difference(&self.appends).cloned().collect();
        write_manifest(&self.staging, &derived)?;
        let Some(snapshot) = snapshot else {
            // A new or empty `--out`: it must still be absent or empty. A
            // directory is renamed over an empty one only (the kernel
            // refuses a non-empty one), so nothing that appears is replaced.
            if exists {
                self.refuse_if_appeared(&self.target, &BTreeSet::new())?;
            }
            return std::fs::rename(&self.staging, &self.target).map_err(|e| {
                if self.target.is_dir() {
                    self.refuse_if_appeared(&self.target, &BTreeSet::new())
                        .err()
                        .unwrap_or_else(|| io("cannot move the output into", &self.target)(e))
                } else {
                    io("cannot move the output into", &self.target)(e)
                }
            });
        };
        // Swap: old -> backup, staging -> target, remove backup.
        let backup = sibling(&self.target, "plinth-old", std::process::id());
        std::fs::rename(&self.target, &backup)
            .map_err(io("cannot move the previous directory aside", &self.target))?;
        if let Err(e) = self.refuse_if_appeared(&backup, &snapshot) {
            let _ = std::fs::rename(&backup, &self.target);
            return Err(e);
        }
        if let Err(e) = std::fs::rename(&self.staging, &self.target) {
            let _ = std::fs::rename(&backup, &self.target);
            return Err(io("cannot move the output into", &self.target)(e));
        }
        // The commit is complete: the backup becomes trash in one rename
        // before it is removed, so a kill (or Ctrl-C) in the middle of the
        // removal leaves a directory the next command removes without
        // asking (`leftovers::clean_leftovers`), never a half-removed backup
        // whose manifest is gone and whose files cannot be told from a
        // user's.
        let trash = sibling(&self.target, "plinth-trash", std::process::id());
        let doomed = match std::fs::rename(&backup, &trash) {
            Ok(()) => trash,
            Err(_) => backup,
        };
        remove_tree(&doomed).map_err(io("cannot remove", &doomed))
    }
}

impl Drop for OutputDir {
    fn drop(&mut self) {
        // The lock goes last, after the staging directory is gone.
        let _lock = self.lock.take();
        if self.done {
            return;
        }
        match &self.keep_as {
            Some(name) => {
                let _ = std::fs::rename(&self.staging, name);
            }
            None => {
                let _ = std::fs::remove_dir_all(&self.staging);
            }
        }
    }
}

/// The first steps of [`OutputDir::create`] and [`OutputDir::resume`]:
/// `out` resolved, locked, cleared of a killed command's leftovers and
/// checked; returns the resolved directory, its lock and whether it exists.
fn open_target(
    option: &'static str,
    out: &Path,
    force: bool,
) -> Result<(PathBuf, Lock, bool), OutputError> {
    let target = resolve(out).map_err(|p| p.of(option, out))?;
    let lock = Lock::take(&target).map_err(|p| p.of(option, &target))?;
    for note in clean_leftovers(&target) {
        eprintln!("{note}");
    }
    let existing = check_target(&target, force).map_err(|p| p.of(option, &target))?;
    Ok((target, lock, existing))
}

/// `remove_dir_all`, retried once with every directory made writable by its
/// owner (a read-only directory inside a backup must not leave it behind).
fn remove_tree(dir: &Path) -> std::io::Result<()> {
    use std::os::unix::fs::PermissionsExt;
    if std::fs::remove_dir_all(dir).is_ok() || !dir.exists() {
        return Ok(());
    }
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        if let Ok(m) = d.symlink_metadata() {
            if m.is_dir() {
                let mode = m.permissions().mode() | 0o700;
                let _ = std::fs::set_permissions(&d, std::fs::Permissions::from_mode(mode));
                if let Ok(rd) = std::fs::read_dir(&d) {
                    stack.extend(rd.filter_map(Result::ok).map(|e| e.path()));
                }
            }
        }
    }
    std::fs::remove_dir_all(dir)
}

/// `.NAME.TAG-N` beside `path`.
fn sibling(path: &Path, tag: &str, n: u32) -> PathBuf {
    hidden_beside(path, &format!("{tag}-{n}"))
}

/// `.NAME.SUFFIX` in the directory `path` is in (NAME `out` when `path`
/// has no last component).
fn hidden_beside(path: &Path, suffix: &str) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    parent_dir(path).join(format!(".{name}.{suffix}"))
}

/// The directory `path` is in: its parent, or `.` for a bare name.
fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Writes a whole output directory at `out` (the option `--out`) through
/// `write`, which fills the staging directory it is given:
/// [`OutputDir::create`], `write`, then [`OutputDir::commit`]. On any error
/// nothing at `out` has changed.
pub fn write_dir(
    out: &Path,
    force: bool,
    write: impl FnOnce(&Path) -> anyhow::Result<()>,
) -> anyhow::Result<PathBuf> {
    write_dir_as("--out", out, force, write)
}

/// [`write_dir`] for the directory given by the command-line option
/// `option` (e.g. `--plots`), which every error names.
pub fn write_dir_as(
    option: &'static str,
    out: &Path,
    force: bool,
    write: impl FnOnce(&Path) -> anyhow::Result<()>,
) -> anyhow::Result<PathBuf> {
    let staged = OutputDir::create_as(option, out, force)?;
    write(staged.path())?;
    Ok(staged.commit()?)
}

/// Writes `bytes` to `path` through a temporary sibling and a rename, so that
/// `path` is either its old content or the whole new one.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), Problem> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.plinth-partial-{}", std::process::id()));
    // A write cut short (a full disk, a file-size limit) leaves no
    // half-written sibling behind: the partial file is removed.
    std::fs::write(&tmp, bytes).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io("cannot write", &tmp)(e)
    })?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io("cannot write", path)(e)
    })
}

#[cfg(test)]
mod tests;
