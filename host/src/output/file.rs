//! A single output file (`report --out REPORT.html`): checked before
//! anything is computed, written whole through a hidden sibling renamed into
//! place, and never over anything but a regular file.

use super::error::{io, OutputError, Problem};
use std::path::Path;

/// Checks the output file `path` given by `option` before anything is
/// computed: a missing path, or (with `force`) an existing regular file,
/// is fine; a directory, a symbolic link, a device, FIFO or socket, or
/// (without `force`) an existing file is refused.
pub fn check_file(option: &'static str, path: &Path, force: bool) -> Result<(), OutputError> {
    check(path, force).map_err(|p| p.of(option, path))
}

fn check(path: &Path, force: bool) -> Result<(), Problem> {
    if path.file_name().is_none() {
        return Err(Problem::NoFileName);
    }
    let meta = match path.symlink_metadata() {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(io("cannot inspect", path)(e)),
    };
    let ft = meta.file_type();
    if ft.is_symlink() {
        let to = std::fs::read_link(path).unwrap_or_default();
        return Err(Problem::FileIsSymlink(to));
    }
    if ft.is_dir() {
        return Err(Problem::IsDirectory);
    }
    if !ft.is_file() {
        return Err(Problem::NotAFile);
    }
    if !force {
        return Err(Problem::FileExists);
    }
    Ok(())
}

/// Writes `bytes` as the output file `path` given by `option` ([`check_file`]
/// first, missing parent directories created): through a hidden sibling
/// renamed into place, so `path` is its old content or the whole new one.
pub fn write_file(
    option: &'static str,
    path: &Path,
    force: bool,
    bytes: &[u8],
) -> Result<(), OutputError> {
    check_file(option, path, force)?;
    let parent = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent)
        .map_err(io("cannot create", parent))
        .map_err(|p| p.of(option, path))?;
    super::write_atomically(path, bytes).map_err(|p| p.of(option, path))
}
