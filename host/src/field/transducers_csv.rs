//! `transducers.csv`: where the transducers of an imported or extracted run
//! sat, an extension of the run directory (README, "Field data") so that
//! `plinth plot DIR` can draw every transducer's own reading later, not only
//! the resolved y and z phasors.
//!
//! One row per transducer: `bearing,quantity,angle_deg` — bearing name,
//! `rel` or `ped`, and the transducer's axis [deg from +y (vertical, up)
//! towards +z], as formats.md defines `angle_deg`. A transducer's reading is
//! the resolved phasors projected on its axis, cos α·Y + sin α·Z, in metres
//! of displacement whatever the sensor measured (velocity and acceleration
//! pick-ups were converted on the way in).

use super::transducer::{Placement, Quantity};
use anyhow::{anyhow, bail, Context, Result};
use std::path::Path;

/// The file's name inside a run directory.
pub const TRANSDUCERS_FILE: &str = "transducers.csv";

const COLUMNS: [&str; 3] = ["bearing", "quantity", "angle_deg"];

/// Writes `placements` as `dir/transducers.csv` (nothing when empty).
pub fn write(dir: &Path, placements: &[Placement]) -> Result<()> {
    if placements.is_empty() {
        return Ok(());
    }
    let file = dir.join(TRANSDUCERS_FILE);
    let mut w = csv::Writer::from_path(&file)
        .with_context(|| format!("{}: cannot create", file.display()))?;
    w.write_record(COLUMNS)?;
    for p in placements {
        w.write_record([
            p.bearing.as_str(),
            p.quantity.name(),
            &p.angle_deg.to_string(),
        ])?;
    }
    w.flush()
        .with_context(|| format!("{}: cannot write", file.display()))
}

/// Reads `dir/transducers.csv` as (bearing, quantity, angle [deg]);
/// `Ok(None)` when the run has none. Errors name file, line and column.
pub fn read(dir: &Path) -> Result<Option<Vec<(String, Quantity, f64)>>> {
    let file = dir.join(TRANSDUCERS_FILE);
    if !file.exists() {
        return Ok(None);
    }
    let name = file.display().to_string();
    if !file.is_file() {
        bail!(
            "{name}: not a regular file (expected {TRANSDUCERS_FILE}: bearing,quantity,angle_deg)"
        );
    }
    let handle = crate::csv_layout::open(&file, &COLUMNS.join(",")).map_err(|e| match e {
        crate::csv_layout::LayoutError::NotAFile(m) => anyhow!("{name}: {m}"),
        crate::csv_layout::LayoutError::At(line, m) => anyhow!("{name}:{line}: {m}"),
    })?;
    let mut r = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .from_reader(handle);
    let header = r.headers().map_err(|e| anyhow!("{name}:1: {e}"))?.clone();
    let mut index = [0usize; 3];
    for (k, want) in COLUMNS.iter().enumerate() {
        index[k] = header.iter().position(|h| h == *want).ok_or_else(|| {
            anyhow!(
                "{name}:1: header has no column `{want}` (found {:?}; expected {})",
                header.iter().collect::<Vec<_>>(),
                COLUMNS.join(",")
            )
        })?;
    }
    let mut out = Vec::new();
    let mut rows_read = crate::sim::budget::ROWS
        .reading()
        .map_err(|m| anyhow!("{name}: {m}"))?;
    for record in r.records() {
        let record = record.map_err(|e| anyhow!("{name}: {e}"))?;
        let line = record.position().map_or(0, |p| p.line());
        rows_read
            .count(&file, 1)
            .map_err(|m| anyhow!("{name}:{line}: {m}"))?;
        let cell = |k: usize| record.get(index[k]).unwrap_or("");
        let bearing = cell(0);
        if bearing.is_empty() {
            bail!("{name}:{line}:{}: empty bearing name", index[0] + 1);
        }
        if let Err(e) = crate::names::check("bearing", bearing) {
            bail!("{name}:{line}:{}: {e}", index[0] + 1);
        }
        let quantity = match cell(1) {
            "rel" => Quantity::Rel,
            "ped" => Quantity::Ped,
            other => bail!(
                "{name}:{line}:{}: quantity `{other}` (expected `rel` or `ped`)",
                index[1] + 1
            ),
        };
        let angle: f64 = cell(2)
            .parse()
            .ok()
            .filter(|a: &f64| a.is_finite())
            .ok_or_else(|| {
                anyhow!(
                    "{name}:{line}:{}: angle_deg `{}` is not a finite number of degrees",
                    index[2] + 1,
                    cell(2)
                )
            })?;
        out.push((bearing.to_string(), quantity, angle));
    }
    Ok(Some(out))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_located_errors() {
        let dir = tempfile::tempdir().unwrap();
        let placements = vec![
            Placement {
                bearing: "B1".into(),
                quantity: Quantity::Rel,
                angle_deg: 45.0,
                key: "transducer[0]".into(),
            },
            Placement {
                bearing: "B1".into(),
                quantity: Quantity::Ped,
                angle_deg: -30.5,
                key: "transducer[1]".into(),
            },
        ];
        write(dir.path(), &placements).unwrap();
        let back = read(dir.path()).unwrap().unwrap();
        assert_eq!(
            back,
            vec![
                ("B1".to_string(), Quantity::Rel, 45.0),
                ("B1".to_string(), Quantity::Ped, -30.5)
            ]
        );
        std::fs::write(
            dir.path().join(TRANSDUCERS_FILE),
            "bearing,quantity,angle_deg\nB1,rel,45\nB1,seismic,10\n",
        )
        .unwrap();
        let e = read(dir.path()).unwrap_err().to_string();
        assert!(
            e.contains("transducers.csv:3:2") && e.contains("seismic"),
            "{e}"
        );
        std::fs::write(
            dir.path().join(TRANSDUCERS_FILE),
            "bearing,quantity,angle_deg\nB1,rel,4x5\n",
        )
        .unwrap();
        let e = read(dir.path()).unwrap_err().to_string();
        assert!(e.contains("transducers.csv:2:3"), "{e}");
        let empty = tempfile::tempdir().unwrap();
        assert!(read(empty.path()).unwrap().is_none());
    }
}
