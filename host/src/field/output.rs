//! Writing an output directory so that a failure leaves nothing half-written.
//!
//! Everything goes into a temporary sibling (`.NAME.plinth-tmp-PID`), which
//! is renamed into place only when complete. An existing, non-empty `--out`
//! is refused unless `force` is set; then the new files replace their
//! namesakes one rename at a time and no other file there is touched.
//!
//! This is the one place import, extract and plot write directories; it is
//! to be swapped for the shared safe-output module (issue 13) once merged.

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

/// Writes a directory at `out` through `write`, which fills the temporary
/// directory it is given.
pub fn write_dir_atomically(
    out: &Path,
    force: bool,
    write: impl FnOnce(&Path) -> Result<()>,
) -> Result<()> {
    let exists_non_empty = match std::fs::symlink_metadata(out) {
        Ok(m) if m.is_dir() => std::fs::read_dir(out)
            .with_context(|| format!("{}: cannot list it", out.display()))?
            .next()
            .is_some(),
        Ok(_) => bail!(
            "{}: exists and is not a directory; choose another --out",
            out.display()
        ),
        Err(_) => false,
    };
    if exists_non_empty && !force {
        bail!(
            "{}: already exists and is not empty; choose another --out, or add --force to replace the files this command writes (others are kept)",
            out.display()
        );
    }
    let tmp = temporary_sibling(out)?;
    if tmp.exists() {
        std::fs::remove_dir_all(&tmp)
            .with_context(|| format!("{}: cannot remove a stale temporary", tmp.display()))?;
    }
    std::fs::create_dir_all(&tmp).with_context(|| format!("{}: cannot create", tmp.display()))?;
    if let Err(e) = write(&tmp) {
        let _ = std::fs::remove_dir_all(&tmp);
        return Err(e);
    }
    let result = if out.exists() {
        move_files_into(&tmp, out)
    } else {
        std::fs::rename(&tmp, out).with_context(|| {
            format!(
                "{}: cannot rename {} into place",
                out.display(),
                tmp.display()
            )
        })
    };
    let _ = std::fs::remove_dir_all(&tmp);
    result
}

/// `.NAME.plinth-tmp-PID` beside `out`.
fn temporary_sibling(out: &Path) -> Result<PathBuf> {
    let name = out
        .file_name()
        .with_context(|| format!("{}: not a directory name", out.display()))?
        .to_string_lossy();
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    Ok(parent.join(format!(".{name}.plinth-tmp-{}", std::process::id())))
}

/// Moves every entry of `from` into `to`, replacing namesakes.
fn move_files_into(from: &Path, to: &Path) -> Result<()> {
    for entry in std::fs::read_dir(from).with_context(|| format!("{}", from.display()))? {
        let entry = entry.with_context(|| format!("{}", from.display()))?;
        let target = to.join(entry.file_name());
        if entry.path().is_dir() && target.is_dir() {
            move_files_into(&entry.path(), &target)?;
        } else {
            std::fs::rename(entry.path(), &target)
                .with_context(|| format!("{}: cannot replace", target.display()))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failure_leaves_nothing_and_existing_is_refused() {
        let base = tempfile::tempdir().unwrap();
        let out = base.path().join("run");
        let err = write_dir_atomically(&out, false, |d| {
            std::fs::write(d.join("a.csv"), "x")?;
            bail!("boom")
        });
        assert!(err.is_err() && !out.exists());
        assert_eq!(std::fs::read_dir(base.path()).unwrap().count(), 0);
        write_dir_atomically(&out, false, |d| Ok(std::fs::write(d.join("a.csv"), "1")?)).unwrap();
        std::fs::write(out.join("raw.bin"), "keep").unwrap();
        assert!(write_dir_atomically(&out, false, |_| Ok(())).is_err());
        write_dir_atomically(&out, true, |d| Ok(std::fs::write(d.join("a.csv"), "2")?)).unwrap();
        assert_eq!(std::fs::read_to_string(out.join("a.csv")).unwrap(), "2");
        assert_eq!(
            std::fs::read_to_string(out.join("raw.bin")).unwrap(),
            "keep"
        );
    }
}
