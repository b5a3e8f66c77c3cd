//! What can go wrong with `--out`: every error names the path and what to
//! do about it.

use std::path::{Path, PathBuf};

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

/// The map from an operating-system error on `path` to [`OutputError::Io`]
/// saying `what` was being done.
pub(super) fn io<'a>(
    what: &'static str,
    path: &'a Path,
) -> impl FnOnce(std::io::Error) -> OutputError + 'a {
    move |source| OutputError::Io {
        what,
        path: path.to_path_buf(),
        source,
    }
}
