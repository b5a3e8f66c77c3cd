//! Append-only log of every byte the field box sent, written before anything
//! is decoded.
//!
//! The log is the ground truth of a streaming session: frames are decoded from
//! it again at the end of a run, so a host that crashed or was killed and then
//! restarted loses nothing that had already arrived. It is opened in append
//! mode (never truncated) and every chunk is handed to the kernel as soon as it
//! is read, so a crash of the host process loses no received byte; `sync`
//! additionally asks the kernel to put it on disk (survives a power cut).

use anyhow::{Context, Result};
use std::fs::{File, OpenOptions};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// File name of the raw byte log inside a run directory.
pub const RAW_LOG_FILE: &str = "raw.bin";

/// An append-only raw byte log.
#[derive(Debug)]
pub struct RawLog {
    file: File,
    path: PathBuf,
    len: u64,
    bytes_at_open: u64,
}

impl RawLog {
    /// Opens (creating if needed) the log at `path` for appending; bytes already
    /// there are kept.
    pub fn open(path: &Path) -> Result<Self> {
        let file = OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .with_context(|| format!("cannot open the raw log {}", path.display()))?;
        let len = file
            .metadata()
            .with_context(|| format!("cannot read the size of the raw log {}", path.display()))?
            .len();
        Ok(Self {
            file,
            path: path.to_path_buf(),
            len,
            bytes_at_open: len,
        })
    }

    /// Appends `bytes` and hands them to the kernel at once (no user-space
    /// buffering), so a crash of this process cannot lose them.
    pub fn append(&mut self, bytes: &[u8]) -> Result<()> {
        if bytes.is_empty() {
            return Ok(());
        }
        self.file
            .write_all(bytes)
            .and_then(|()| self.file.flush())
            .with_context(|| {
                // A full disk takes part of the bytes: say how many are lost.
                let now = self.file.metadata().map_or(self.len, |m| m.len());
                let written = now.saturating_sub(self.len).min(bytes.len() as u64);
                format!(
                    "cannot append {} bytes to the raw log {} at byte {} ({written} of them written, the last {} lost)",
                    bytes.len(),
                    self.path.display(),
                    self.len,
                    bytes.len() as u64 - written
                )
            })?;
        self.len += bytes.len() as u64;
        Ok(())
    }

    /// Asks the kernel to write the log to the disk (fdatasync).
    pub fn sync(&mut self) -> Result<()> {
        self.file
            .sync_data()
            .with_context(|| format!("cannot sync the raw log {}", self.path.display()))
    }

    /// Total length of the log [bytes], including what earlier sessions wrote.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// True when the log holds no byte at all.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Length the log had when this session opened it [bytes].
    pub fn bytes_at_open(&self) -> u64 {
        self.bytes_at_open
    }

    /// Where the log lives.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Reads a whole log (every session's bytes, in arrival order).
    pub fn read_all(path: &Path) -> Result<Vec<u8>> {
        let mut bytes = Vec::new();
        crate::input_file::ensure_regular(path)
            .and_then(|()| File::open(path))
            .and_then(|mut f| f.read_to_end(&mut bytes))
            .with_context(|| format!("cannot read the raw log {}", path.display()))?;
        Ok(bytes)
    }
}

/// Refuses to rebuild a run (`stream --offline`) from a raw log of `bytes`
/// bytes at `path` in which no valid phasor frame was found (`frames` = 0):
/// a truncated, foreign or empty (0-byte) file gives an error, not an empty
/// run.
pub fn require_frames(path: &Path, bytes: usize, frames: usize) -> Result<()> {
    if frames == 0 && bytes == 0 {
        anyhow::bail!(
            "--offline: the raw log {} is empty (0 bytes: the stream received nothing): there is no run to rebuild",
            path.display()
        );
    }
    if frames == 0 {
        anyhow::bail!(
            "--offline: the raw log {} ({bytes} bytes) holds no valid phasor frame (cut short, or not a Plinth box's log): there is no run to rebuild",
            path.display()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reopening_appends_and_never_truncates() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(RAW_LOG_FILE);
        {
            let mut log = RawLog::open(&path).unwrap();
            assert!(log.is_empty());
            log.append(b"\x01\x02\x00").unwrap();
            log.append(b"").unwrap();
            assert_eq!(log.len(), 3);
            // Dropped without sync: the bytes are with the kernel already.
        }
        let mut log = RawLog::open(&path).unwrap();
        assert_eq!(log.bytes_at_open(), 3);
        log.append(b"\x05\x00").unwrap();
        log.sync().unwrap();
        assert_eq!(log.len(), 5);
        assert_eq!(RawLog::read_all(&path).unwrap(), b"\x01\x02\x00\x05\x00");
    }

    #[test]
    fn a_log_without_frames_rebuilds_nothing() {
        let e = require_frames(Path::new("x/raw.bin"), 17, 0)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("x/raw.bin (17 bytes) holds no valid phasor frame"),
            "{e}"
        );
        assert!(require_frames(Path::new("x/raw.bin"), 17, 1).is_ok());
        let e = require_frames(Path::new("x/raw.bin"), 0, 0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("x/raw.bin") && e.contains("is empty"), "{e}");
    }

    #[test]
    fn a_missing_directory_is_a_clear_error() {
        let err = RawLog::open(Path::new("/nonexistent-plinth-dir/raw.bin")).unwrap_err();
        assert!(format!("{err:#}").contains("/nonexistent-plinth-dir/raw.bin"));
    }
}
