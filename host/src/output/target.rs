//! `--out` checked before anything is computed: resolved to a real last
//! component, and refused when it is a file, a link, a device, the current
//! directory, a read-only tree, or (without `--force`) a directory that
//! already holds something, which the error names.

use super::*;

/// `out` with a real last component (`.`, `..` and `a/..` resolved), and
/// refused when it is, or contains, the current directory (it could not be
/// moved into place).
pub(super) fn resolve(out: &Path) -> Result<PathBuf, Problem> {
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
                return Err(Problem::HoldsCurrentDir(cwd));
            }
        }
        if odd {
            canon
        } else {
            out.to_path_buf()
        }
    } else if odd {
        let name = out.file_name().ok_or(Problem::NotADirectory)?;
        let parent = parent_dir(out);
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

/// Checks `out`: returns whether it exists (as a directory that may be
/// written into).
pub(super) fn check_target(out: &Path, force: bool) -> Result<bool, Problem> {
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
        return Err(Problem::IsSymlink(to));
    }
    if ft.is_file() {
        return Err(Problem::IsFile);
    }
    if !ft.is_dir() {
        return Err(Problem::NotADirectory);
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
        return Err(Problem::NotEmpty(describe(&names)));
    }
    if let Some(dir) = read_only_dir(out) {
        return Err(Problem::ReadOnly(dir));
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
