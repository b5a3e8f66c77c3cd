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

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

mod leftovers;
mod manifest;

pub use leftovers::clean_leftovers;
use leftovers::*;
use manifest::*;

/// The manifest of the files Plinth wrote into an output directory: one line
/// per file, `HASH SIZE RELATIVE/PATH` (FNV-1a 64-bit in hex, bytes).
pub const MANIFEST_FILE: &str = ".plinth-written";

/// Errors of an output directory; each names the path and what to do.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// `--out` is an existing file, not a directory.
    #[error("--out {}: is a file, not a directory: give a directory name (a new one, or an existing run directory with --force)", .0.display())]
    IsFile(PathBuf),
    /// `--out` is a symbolic link.
    #[error("--out {}: is a symbolic link: give the directory it points to ({}) or a new directory, links are not followed", .0.display(), .1.display())]
    IsSymlink(PathBuf, PathBuf),
    /// `--out` is neither a file nor a directory (a FIFO, a device...).
    #[error("--out {}: is not a directory (a FIFO, socket or device): give a directory name", .0.display())]
    NotADirectory(PathBuf),
    /// `--out` already holds something and `--force` was not given.
    #[error("--out {}: already holds {what}: pass --force to write into it (files Plinth did not write are kept), or choose another directory", .path.display())]
    NotEmpty {
        /// The directory.
        path: PathBuf,
        /// What it holds, e.g. "a run directory (measurements.csv, raw.bin)".
        what: String,
    },
    /// `--force` would have replaced a file Plinth did not write.
    #[error("--out {}: {file} would be replaced, but Plinth did not write it ({why}): move it away or choose another directory; nothing was changed", .dir.display())]
    WouldReplace {
        /// The directory.
        dir: PathBuf,
        /// The file, relative to the directory.
        file: String,
        /// Why it is protected.
        why: String,
    },
    /// Another Plinth command holds the lock of `--out`.
    #[error("--out {}: another Plinth command is writing it ({}): wait for it to finish, or choose another directory; nothing was changed", .0.display(), .1)]
    Busy(PathBuf, String),
    /// Something appeared in `--out` while the command ran.
    #[error("--out {}: {what} appeared in it while this command ran (not written by it): nothing was replaced; move it away or choose another directory and run again", .path.display())]
    Appeared {
        /// The directory.
        path: PathBuf,
        /// What appeared, e.g. "2 entries (notes.txt, run.csv)".
        what: String,
    },
    /// `--out` is (or contains) the current directory.
    #[error("--out {}: is the current directory or contains it ({}); Plinth moves a finished directory into place and cannot replace the one you are in: give a new directory name, e.g. --out run1", .0.display(), .1.display())]
    HoldsCurrentDir(PathBuf, PathBuf),
    /// `--out` (or a directory in it) cannot be written.
    #[error("--out {}: {} is read-only: the previous directory could not be removed after the new one is moved into place; make it writable (chmod -R u+w) or choose another directory; nothing was changed", .0.display(), .1.display())]
    ReadOnly(PathBuf, PathBuf),
    /// An operating-system error on a path.
    #[error("{what} {}: {source}", .path.display())]
    Io {
        /// What was being done, e.g. "cannot create".
        what: &'static str,
        /// The path.
        path: PathBuf,
        /// The operating-system error.
        #[source]
        source: std::io::Error,
    },
}

fn io<'a>(what: &'static str, path: &'a Path) -> impl FnOnce(std::io::Error) -> OutputError + 'a {
    move |source| OutputError::Io {
        what,
        path: path.to_path_buf(),
        source,
    }
}

/// A directory being written: staged in a hidden sibling of `--out`, moved
/// into place by [`OutputDir::commit`].
#[derive(Debug)]
pub struct OutputDir {
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
    /// Checks `out` and creates the staging directory. `force`: write into an
    /// `out` that already holds something (files Plinth did not write are
    /// still never deleted or replaced).
    pub fn create(out: &Path, force: bool) -> Result<OutputDir, OutputError> {
        let out = &resolve(out)?;
        let lock = Lock::take(out)?;
        for note in clean_leftovers(out) {
            eprintln!("{note}");
        }
        let existing = check_target(out, force)?;
        let staging = sibling(out, "plinth-partial", std::process::id());
        if staging.symlink_metadata().is_ok() {
            std::fs::remove_dir_all(&staging).map_err(io("cannot clear", &staging))?;
        }
        std::fs::create_dir(&staging).map_err(io("cannot create", &staging))?;
        // The staging directory's mark: an empty manifest (the commit
        // writes the real one), so a leftover is known to be Plinth's.
        std::fs::write(staging.join(MANIFEST_FILE), "")
            .map_err(io("cannot write", &staging.join(MANIFEST_FILE)))?;
        Ok(OutputDir {
            target: out.to_path_buf(),
            staging,
            existing,
            appends: BTreeSet::new(),
            keep_as: None,
            done: false,
            lock: Some(lock),
        })
    }

    /// Uses `staging` (created if needed; e.g. the one a killed `stream`
    /// left) instead of a new hidden one; `out` is checked as in
    /// [`OutputDir::create`]. Such a staging directory is kept when the
    /// output is dropped uncommitted (it may hold a raw log): remove it
    /// with [`OutputDir::discard`].
    pub fn resume(out: &Path, staging: &Path, force: bool) -> Result<OutputDir, OutputError> {
        let out = &resolve(out)?;
        let lock = Lock::take(out)?;
        for note in clean_leftovers(out) {
            eprintln!("{note}");
        }
        let existing = check_target(out, force)?;
        if !staging.is_dir() {
            std::fs::create_dir(staging).map_err(io("cannot create", staging))?;
        }
        Ok(OutputDir {
            target: out.to_path_buf(),
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
        let result = self.commit_inner();
        if result.is_ok() {
            self.done = true;
        }
        result.map(|()| self.target.clone())
    }

    fn commit_inner(&mut self) -> Result<(), OutputError> {
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

    /// `Err(Appeared)` when `dir` holds an entry that is not in `known`.
    fn refuse_if_appeared(&self, dir: &Path, known: &BTreeSet<String>) -> Result<(), OutputError> {
        let mut new: Vec<String> = list_entries(dir)?
            .into_iter()
            .map(|(r, _)| r)
            .filter(|r| !known.contains(r))
            .collect();
        if new.is_empty() {
            return Ok(());
        }
        new.sort();
        Err(OutputError::Appeared {
            path: self.target.clone(),
            what: describe(&new),
        })
    }

    /// Checks every collision and links the old files that are kept into the
    /// staging directory; the old directory is only read.
    /// Returns every entry the old directory held.
    fn merge_old(&self) -> Result<BTreeSet<String>, OutputError> {
        let old = &self.target;
        let manifest = read_manifest(old);
        let old_entries = list_entries(old)?;
        let mut refused: Vec<(String, String)> = Vec::new();
        for (rel, kind) in &old_entries {
            if rel == MANIFEST_FILE {
                continue;
            }
            let old_path = old.join(rel);
            let ours = matches!(kind, Entry::File)
                && manifest
                    .get(rel.as_str())
                    .is_some_and(|&(h, n)| file_hash(&old_path).ok() == Some((h, n)));
            let new_path = self.staging.join(rel);
            if new_path.symlink_metadata().is_ok() {
                if matches!(kind, Entry::Dir) && new_path.is_dir() {
                    continue;
                }
                if ours && !self.appends.contains(rel) {
                    continue;
                }
                let why = match kind {
                    Entry::Dir => "it is a directory".to_string(),
                    Entry::Symlink => "it is a symbolic link".to_string(),
                    Entry::Other => "it is not a regular file".to_string(),
                    Entry::File => {
                        if same_content(&old_path, &new_path)? {
                            continue;
                        }
                        if self.appends.contains(rel) && is_prefix(&old_path, &new_path)? {
                            continue;
                        }
                        if self.appends.contains(rel) {
                            "it is an append-only log and the new one does not extend it"
                                .to_string()
                        } else if manifest.contains_key(rel.as_str()) {
                            "it was changed since Plinth wrote it".to_string()
                        } else {
                            "it is not in the directory's list of files Plinth wrote".to_string()
                        }
                    }
                };
                refused.push((rel.clone(), why));
                continue;
            }
            if !refused.is_empty() {
                continue; // only collecting the refusals now
            }
            if ours {
                continue; // a stale file of an earlier Plinth run
            }
            match kind {
                Entry::Dir => {
                    std::fs::create_dir_all(&new_path).map_err(io("cannot create", &new_path))?
                }
                Entry::Symlink => {
                    let to = std::fs::read_link(&old_path).map_err(io("cannot read", &old_path))?;
                    std::os::unix::fs::symlink(&to, &new_path)
                        .map_err(io("cannot create", &new_path))?;
                }
                Entry::File | Entry::Other => {
                    if std::fs::hard_link(&old_path, &new_path).is_err() {
                        std::fs::copy(&old_path, &new_path)
                            .map_err(io("cannot copy", &old_path))?;
                    }
                }
            }
        }
        if let Some((file, why)) = refused.first() {
            let others: Vec<&str> = refused[1..].iter().map(|(f, _)| f.as_str()).collect();
            let file = if others.is_empty() {
                file.clone()
            } else {
                format!("{file} (and {})", others.join(", "))
            };
            return Err(OutputError::WouldReplace {
                dir: old.clone(),
                file,
                why: why.clone(),
            });
        }
        Ok(old_entries.into_iter().map(|(r, _)| r).collect())
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

/// `out` with a real last component (`.`, `..` and `a/..` resolved), and
/// refused when it is, or contains, the current directory (it could not be
/// moved into place).
fn resolve(out: &Path) -> Result<PathBuf, OutputError> {
    use std::path::Component;
    let odd = out.file_name().is_none()
        || out
            .components()
            .any(|c| matches!(c, Component::CurDir | Component::ParentDir));
    let is_link = out
        .symlink_metadata()
        .is_ok_and(|m| m.file_type().is_symlink());
    if is_link {
        return Ok(out.to_path_buf()); // refused by check_target
    }
    let resolved = if out.exists() {
        let canon = std::fs::canonicalize(out).map_err(io("cannot inspect", out))?;
        if let Ok(cwd) = std::env::current_dir().and_then(std::fs::canonicalize) {
            if cwd.starts_with(&canon) {
                return Err(OutputError::HoldsCurrentDir(out.to_path_buf(), cwd));
            }
        }
        if odd {
            canon
        } else {
            out.to_path_buf()
        }
    } else if odd {
        let name = out
            .file_name()
            .ok_or_else(|| OutputError::NotADirectory(out.to_path_buf()))?;
        let parent = match out.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent).map_err(io("cannot create", &parent))?;
        std::fs::canonicalize(&parent)
            .map_err(io("cannot inspect", &parent))?
            .join(name)
    } else {
        // A new --out whose parent directories are missing (a/b/c/run):
        // created as `mkdir -p` would, as for the odd paths above.
        if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
            if parent.symlink_metadata().is_err() {
                std::fs::create_dir_all(parent).map_err(io("cannot create", parent))?;
            }
        }
        out.to_path_buf()
    };
    Ok(resolved)
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

/// The first directory at or under `dir` (symbolic links not followed)
/// whose entries the user cannot remove.
fn read_only_dir(dir: &Path) -> Option<PathBuf> {
    let writable =
        |d: &Path| std::fs::symlink_metadata(d).is_ok_and(|m| !m.permissions().readonly());
    if !writable(dir) {
        return Some(dir.to_path_buf());
    }
    let entries = list_entries(dir).ok()?;
    entries
        .into_iter()
        .filter(|(_, k)| matches!(k, Entry::Dir))
        .map(|(r, _)| dir.join(r))
        .find(|d| !writable(d))
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

/// `.NAME.TAG-N` beside `path`.
fn sibling(path: &Path, tag: &str, n: u32) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    parent.join(format!(".{name}.{tag}-{n}"))
}

/// Writes a whole output directory at `out` through `write`, which fills the
/// staging directory it is given: [`OutputDir::create`], `write`, then
/// [`OutputDir::commit`]. On any error nothing at `out` has changed.
pub fn write_dir(
    out: &Path,
    force: bool,
    write: impl FnOnce(&Path) -> anyhow::Result<()>,
) -> anyhow::Result<PathBuf> {
    let staged = OutputDir::create(out, force)?;
    write(staged.path())?;
    Ok(staged.commit()?)
}

/// Checks `out`: returns whether it exists (as a directory that may be
/// written into).
fn check_target(out: &Path, force: bool) -> Result<bool, OutputError> {
    let meta = match out.symlink_metadata() {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
                std::fs::create_dir_all(parent).map_err(io("cannot create", parent))?;
            }
            return Ok(false);
        }
        Err(e) => return Err(io("cannot inspect", out)(e)),
    };
    let ft = meta.file_type();
    if ft.is_symlink() {
        let to = std::fs::read_link(out).unwrap_or_default();
        return Err(OutputError::IsSymlink(out.to_path_buf(), to));
    }
    if ft.is_file() {
        return Err(OutputError::IsFile(out.to_path_buf()));
    }
    if !ft.is_dir() {
        return Err(OutputError::NotADirectory(out.to_path_buf()));
    }
    let mut names: Vec<String> = std::fs::read_dir(out)
        .map_err(io("cannot read", out))?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    if names.is_empty() {
        return Ok(false);
    }
    if !force {
        names.sort();
        return Err(OutputError::NotEmpty {
            path: out.to_path_buf(),
            what: describe(&names),
        });
    }
    if let Some(dir) = read_only_dir(out) {
        return Err(OutputError::ReadOnly(out.to_path_buf(), dir));
    }
    Ok(true)
}

/// "a run directory (measurements.csv, raw.bin)" or "3 files (a, b, c)".
pub fn describe(names: &[String]) -> String {
    const RUN: [&str; 4] = ["measurements.csv", "bearings.csv", "raw.bin", "signals.csv"];
    let shown: Vec<&str> = names.iter().take(4).map(String::as_str).collect();
    let more = if names.len() > 4 { ", ..." } else { "" };
    let kind = if names.iter().any(|n| RUN.contains(&n.as_str())) {
        "a run directory".to_string()
    } else {
        format!(
            "{} entr{}",
            names.len(),
            if names.len() == 1 { "y" } else { "ies" }
        )
    };
    format!("{kind} ({}{more})", shown.join(", "))
}

/// Writes `bytes` to `path` through a temporary sibling and a rename, so that
/// `path` is either its old content or the whole new one.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.plinth-partial-{}", std::process::id()));
    std::fs::write(&tmp, bytes).map_err(io("cannot write", &tmp))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io("cannot write", path)(e)
    })
}

#[cfg(test)]
mod tests;
