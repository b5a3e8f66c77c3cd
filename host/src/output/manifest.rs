//! Which files Plinth wrote: the manifest of an output directory (hash and
//! size per file) and the comparisons a commit makes against it.

use super::*;
use std::io::Read;

#[derive(Debug, Clone, Copy)]
pub(super) enum Entry {
    File,
    Dir,
    Symlink,
    Other,
}

/// Every entry under `dir` (relative paths, '/'-separated, parents first),
/// without following symbolic links.
pub(super) fn list_entries(dir: &Path) -> Result<Vec<(String, Entry)>, Problem> {
    let mut out = Vec::new();
    let mut stack = vec![(dir.to_path_buf(), String::new())];
    while let Some((path, rel)) = stack.pop() {
        let mut children: Vec<_> = std::fs::read_dir(&path)
            .map_err(io("cannot read", &path))?
            .filter_map(|e| e.ok())
            .collect();
        children.sort_by_key(|e| e.file_name());
        for e in children {
            let name = e.file_name().to_string_lossy().into_owned();
            let r = if rel.is_empty() {
                name
            } else {
                format!("{rel}/{name}")
            };
            let ft = e.file_type().map_err(io("cannot inspect", &e.path()))?;
            let kind = if ft.is_symlink() {
                Entry::Symlink
            } else if ft.is_dir() {
                Entry::Dir
            } else if ft.is_file() {
                Entry::File
            } else {
                Entry::Other
            };
            out.push((r.clone(), kind));
            if ft.is_dir() {
                stack.push((e.path(), r));
            }
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    Ok(out)
}

/// The regular files under `dir` (relative paths), without the manifest.
pub(super) fn list_files(dir: &Path) -> Result<BTreeSet<String>, Problem> {
    Ok(list_entries(dir)?
        .into_iter()
        .filter(|(r, k)| matches!(k, Entry::File) && r != MANIFEST_FILE)
        .map(|(r, _)| r)
        .collect())
}

/// FNV-1a 64-bit hash and size of a file's bytes.
pub(super) fn file_hash(path: &Path) -> std::io::Result<(u64, u64)> {
    let mut f = std::fs::File::open(path)?;
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut n = 0u64;
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let k = f.read(&mut buf)?;
        if k == 0 {
            break;
        }
        for &b in &buf[..k] {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        n += k as u64;
    }
    Ok((h, n))
}

pub(super) fn write_manifest(dir: &Path, files: &BTreeSet<String>) -> Result<(), Problem> {
    let mut text = String::from("# files plinth wrote here: FNV-1a-64 size path\n");
    for rel in files {
        let p = dir.join(rel);
        let (h, n) = file_hash(&p).map_err(io("cannot read", &p))?;
        text.push_str(&format!("{h:016x} {n} {rel}\n"));
    }
    let path = dir.join(MANIFEST_FILE);
    std::fs::write(&path, text).map_err(io("cannot write", &path))
}

/// The manifest of `dir` (empty when absent or unreadable).
pub(super) fn read_manifest(dir: &Path) -> BTreeMap<String, (u64, u64)> {
    let Ok(text) = std::fs::read_to_string(dir.join(MANIFEST_FILE)) else {
        return BTreeMap::new();
    };
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .filter_map(|l| {
            let mut it = l.splitn(3, ' ');
            let h = u64::from_str_radix(it.next()?, 16).ok()?;
            let n = it.next()?.parse().ok()?;
            Some((it.next()?.to_string(), (h, n)))
        })
        .collect()
}

pub(super) fn same_content(a: &Path, b: &Path) -> Result<bool, Problem> {
    let ha = file_hash(a).map_err(io("cannot read", a))?;
    let hb = file_hash(b).map_err(io("cannot read", b))?;
    Ok(ha == hb)
}

/// Whether `new` starts with every byte of `old`.
pub(super) fn is_prefix(old: &Path, new: &Path) -> Result<bool, Problem> {
    let a = std::fs::read(old).map_err(io("cannot read", old))?;
    let mut f = std::fs::File::open(new).map_err(io("cannot read", new))?;
    let mut b = vec![0u8; a.len()];
    match f.read_exact(&mut b) {
        Ok(()) => Ok(a == b),
        Err(_) => Ok(false),
    }
}
