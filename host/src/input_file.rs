//! Input files that must be regular files: a FIFO, socket or device named
//! where a table, machine file, configuration or JSON file is expected is
//! refused at once (reading a FIFO with no writer would block forever).

use std::io::{Error, ErrorKind};
use std::path::Path;

/// Checks that `path` is a regular file (symbolic links followed); the
/// error says what it is instead and what is expected.
pub fn ensure_regular(path: &Path) -> std::io::Result<()> {
    let meta = std::fs::metadata(path)?;
    if meta.is_file() {
        return Ok(());
    }
    let kind = if meta.is_dir() {
        "a directory"
    } else {
        "not a regular file (a FIFO, socket or device)"
    };
    Err(Error::new(
        ErrorKind::InvalidInput,
        format!("is {kind}: give it as a regular file"),
    ))
}

/// [`std::fs::read_to_string`] of a regular file only ([`ensure_regular`]
/// first, so a FIFO never blocks).
pub fn read_to_string(path: &Path) -> std::io::Result<String> {
    ensure_regular(path)?;
    let bytes = std::fs::metadata(path)?.len();
    if bytes > MAX_TEXT_BYTES {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            format!(
                "is {bytes} bytes long; a configuration, machine or JSON file is at most {MAX_TEXT_BYTES} bytes: is it the right file?"
            ),
        ));
    }
    std::fs::read_to_string(path)
}

/// The largest text file [`read_to_string`] reads whole [bytes]: 64 MiB
/// (configuration, machine, layout and JSON files are kilobytes).
pub const MAX_TEXT_BYTES: u64 = 64 << 20;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directories_are_refused_and_files_read() {
        let t = tempfile::tempdir().unwrap();
        let e = read_to_string(t.path()).unwrap_err();
        assert!(e.to_string().contains("a directory"), "{e}");
        let f = t.path().join("a.toml");
        std::fs::write(&f, "x = 1\n").unwrap();
        assert_eq!(read_to_string(&f).unwrap(), "x = 1\n");
        let missing = read_to_string(&t.path().join("none")).unwrap_err();
        assert_eq!(missing.kind(), ErrorKind::NotFound);
    }
}
