//! The known bearing coefficients a stream configuration names: its
//! bearings.csv read with the run-directory reader (one reader of the
//! format), kept to the configured bearings.

use super::StreamConfig;
use crate::rundir::{self, BearingRow, RunDir};
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

/// The known coefficients of every configured bearing, read from the
/// configured bearings.csv with the run-directory reader.
#[derive(Clone, Debug, PartialEq)]
pub struct BearingTables {
    /// Rows of the configured bearings, in file order.
    pub rows: Vec<BearingRow>,
}

impl BearingTables {
    /// The rows of one bearing in increasing speed.
    pub fn rows_of(&self, bearing: &str) -> Vec<&BearingRow> {
        let mut rows: Vec<&BearingRow> =
            self.rows.iter().filter(|r| r.bearing == bearing).collect();
        rows.sort_by(|a, b| a.speed_hz.total_cmp(&b.speed_hz));
        rows
    }
}

impl StreamConfig {
    /// Reads the configured bearings.csv and keeps the rows of the configured
    /// bearings; every configured bearing must have at least one row.
    pub fn load_bearing_tables(&self) -> Result<BearingTables> {
        let all = read_bearings_csv(&self.bearings_csv)?;
        let rows: Vec<BearingRow> = all
            .into_iter()
            .filter(|r| self.bearings.contains(&r.bearing))
            .collect();
        for b in &self.bearings {
            if !rows.iter().any(|r| &r.bearing == b) {
                bail!(
                    "{}: no rows for bearing {b:?}, which the stream configuration measures",
                    self.bearings_csv.display()
                );
            }
        }
        Ok(BearingTables { rows })
    }
}

/// Reads a bearings.csv (formats.md) with the run-directory reader.
///
/// The reader reads whole run directories, so the file is presented to it in
/// a scratch directory beside an empty measurements.csv; its error messages
/// are rewritten to name the real file.
pub fn read_bearings_csv(path: &Path) -> Result<Vec<BearingRow>> {
    let real = std::fs::canonicalize(path)
        .with_context(|| format!("cannot open the bearing table {}", path.display()))?;
    let scratch = ScratchDir::new()?;
    let link = scratch.0.join(rundir::BEARINGS_FILE);
    std::os::unix::fs::symlink(&real, &link).with_context(|| {
        format!(
            "cannot link {} into {}",
            real.display(),
            scratch.0.display()
        )
    })?;
    std::fs::write(
        scratch.0.join(rundir::MEASUREMENTS_FILE),
        rundir::MEASUREMENT_COLUMNS.join(",") + "\n",
    )
    .with_context(|| format!("cannot write a scratch file in {}", scratch.0.display()))?;
    match RunDir::read(&scratch.0) {
        Ok(run) => Ok(run.bearings),
        Err(e) => {
            let message = e
                .to_string()
                .replace(&link.display().to_string(), &path.display().to_string());
            bail!("{message}")
        }
    }
}

/// A directory under the system's temporary directory, removed on drop.
struct ScratchDir(PathBuf);

impl ScratchDir {
    fn new() -> Result<Self> {
        use std::sync::atomic::{AtomicU32, Ordering};
        static COUNT: AtomicU32 = AtomicU32::new(0);
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        let dir = std::env::temp_dir().join(format!(
            "plinth-bearings-{}-{}-{nanos}",
            std::process::id(),
            COUNT.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir(&dir)
            .with_context(|| format!("cannot create the scratch directory {}", dir.display()))?;
        Ok(Self(dir))
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
