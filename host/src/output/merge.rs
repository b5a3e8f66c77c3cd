//! What a `--force` commit does with the previous directory: every
//! collision checked (a file Plinth did not write is never replaced), the
//! files that are kept linked into the staging directory, and anything that
//! appeared while the command ran refused.

use super::*;

impl OutputDir {
    /// `Err(Appeared)` when `dir` holds an entry that is not in `known`.
    pub(super) fn refuse_if_appeared(
        &self,
        dir: &Path,
        known: &BTreeSet<String>,
    ) -> Result<(), Problem> {
        let mut new: Vec<String> = list_entries(dir)?
            .into_iter()
            .map(|(r, _)| r)
            .filter(|r| !known.contains(r))
            .collect();
        if new.is_empty() {
            return Ok(());
        }
        new.sort();
        Err(Problem::Appeared(describe(&new)))
    }

    /// Checks every collision and links the old files that are kept into the
    /// staging directory; the old directory is only read.
    /// Returns every entry the old directory held.
    pub(super) fn merge_old(&self) -> Result<BTreeSet<String>, Problem> {
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
            return Err(Problem::WouldReplace {
                file,
                why: why.clone(),
            });
        }
        Ok(old_entries.into_iter().map(|(r, _)| r).collect())
    }
}
