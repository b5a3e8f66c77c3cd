//! What can go wrong with an output directory: every error names the
//! command-line option the directory came from (`--out`, `--plots`), the
//! path, and what to do about it.

use std::path::{Path, PathBuf};

/// An error of the output directory given by `option` (e.g. `--plots`):
/// shown as `OPTION PATH: PROBLEM`.
#[derive(Debug, thiserror::Error)]
#[error("{option} {}: {problem}", .out.display())]
pub struct OutputError {
    /// The command-line option that named the directory, e.g. `--out`.
    pub option: &'static str,
    /// The directory as the command uses it.
    pub out: PathBuf,
    /// What is wrong with it.
    pub problem: Problem,
}

/// What is wrong with an output directory; the message says what to do and
/// is shown after `OPTION PATH: ` ([`OutputError`]).
#[derive(Debug, thiserror::Error)]
pub enum Problem {
    /// The directory is an existing file.
    #[error("is a file, not a directory: give a directory name (a new one, or an existing run directory with --force)")]
    IsFile,
    /// The directory is a symbolic link (to the path held).
    #[error("is a symbolic link: give the directory it points to ({}) or a new directory, links are not followed", .0.display())]
    IsSymlink(PathBuf),
    /// The directory is neither a file nor a directory (a FIFO, a device...).
    #[error("is not a directory (a FIFO, socket or device): give a directory name")]
    NotADirectory,
    /// The directory already holds something and `--force` was not given;
    /// what it holds, e.g. "a run directory (measurements.csv, raw.bin)".
    #[error("already holds {0}: pass --force to write into it (files Plinth did not write are kept), or choose another directory")]
    NotEmpty(String),
    /// `--force` would have replaced a file Plinth did not write.
    #[error("{file} would be replaced, but Plinth did not write it ({why}): move it away or choose another directory; nothing was changed")]
    WouldReplace {
        /// The file, relative to the directory.
        file: String,
        /// Why it is protected.
        why: String,
    },
    /// Another Plinth command holds the directory's lock (which process,
    /// which lock file).
    #[error("another Plinth command is writing it ({0}): wait for it to finish, or choose another directory; nothing was changed")]
    Busy(String),
    /// Something appeared in the directory while the command ran, e.g.
    /// "2 entries (notes.txt, run.csv)".
    #[error("{0} appeared in it while this command ran (not written by it): nothing was replaced; move it away or choose another directory and run again")]
    Appeared(String),
    /// The directory is (or contains) the current directory (held).
    #[error("is the current directory or contains it ({}); Plinth moves a finished directory into place and cannot replace the one you are in: give a new directory name, e.g. --out run1", .0.display())]
    HoldsCurrentDir(PathBuf),
    /// The directory (or the directory held, inside it) cannot be written.
    #[error("{} is read-only: the previous directory could not be removed after the new one is moved into place; make it writable (chmod -R u+w) or choose another directory; nothing was changed", .0.display())]
    ReadOnly(PathBuf),
    /// An output file's path has no file name (`..`, `/`).
    #[error("has no file name: give the file's name")]
    NoFileName,
    /// An output file is an existing directory.
    #[error("is a directory: give the file's name")]
    IsDirectory,
    /// An output file is a symbolic link (to the path held).
    #[error("is a symbolic link (to {}): links are not followed; give another name, or remove the link", .0.display())]
    FileIsSymlink(PathBuf),
    /// An output file is a device, FIFO or socket.
    #[error("is not a regular file (a device, FIFO or socket): give a file name")]
    NotAFile,
    /// The file system holding the output has less free space [bytes]
    /// than the output needs at least [bytes].
    #[error("would need at least {needed} bytes and its file system has {free} bytes free: free some space, or choose a directory on another file system; nothing was written")]
    NoRoom {
        /// The least the output takes [bytes].
        needed: u64,
        /// Free space an unprivileged process may use [bytes].
        free: u64,
    },
    /// An output file exists and `--force` was not given.
    #[error("already exists (add --force to replace it)")]
    FileExists,
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

impl Problem {
    /// This problem as an error of the directory `out` given by `option`.
    pub fn of(self, option: &'static str, out: &Path) -> OutputError {
        OutputError {
            option,
            out: out.to_path_buf(),
            problem: self,
        }
    }
}

/// The map from an operating-system error on `path` to [`Problem::Io`]
/// saying `what` was being done.
pub(super) fn io<'a>(
    what: &'static str,
    path: &'a Path,
) -> impl FnOnce(std::io::Error) -> Problem + 'a {
    move |source| Problem::Io {
        what,
        path: path.to_path_buf(),
        source,
    }
}
