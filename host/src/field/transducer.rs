//! Where a transducer sits: its bearing, what it measures (`rel`/`ped`) and
//! its angle; and the check that every bearing has what y/z resolution needs.

use super::angle::{parse_bently, separation_deg, Rotation, MIN_SEPARATION_DEG};
use anyhow::{bail, Result};

/// What a transducer measures at its bearing (formats.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// Proximity probe on the pedestal: rotor relative to pedestal.
    Rel,
    /// Absolute pick-up on the pedestal.
    Ped,
}

impl Quantity {
    /// `rel` or `ped`.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Rel => "rel",
            Quantity::Ped => "ped",
        }
    }
}

/// A located transducer: bearing, quantity, angle [deg from +y towards +z],
/// and the configuration key that described it (for errors).
#[derive(Clone, Debug, PartialEq)]
pub struct Placement {
    /// Bearing name.
    pub bearing: String,
    /// `rel` or `ped`.
    pub quantity: Quantity,
    /// Angle [deg] from +y towards +z.
    pub angle_deg: f64,
    /// Configuration key, e.g. `transducer[3]`.
    pub key: String,
}

/// The angle of a transducer given as `angle_deg` (a number) or `angle`
/// (`45L`, `45R`, ...; see [`super::angle`]): exactly one of them.
pub fn angle_of(
    file: &str,
    key: &str,
    angle_deg: Option<f64>,
    angle: Option<&str>,
    rotation: Option<Rotation>,
) -> Result<f64> {
    match (angle_deg, angle) {
        (Some(a), None) if a.is_finite() => Ok(a),
        (Some(a), None) => bail!("{file}: {key}.angle_deg: {a} is not finite"),
        (None, Some(t)) => parse_bently(t, rotation).map_err(|m| anyhow::anyhow!("{file}: {key}.angle: {m}")),
        (Some(_), Some(_)) => bail!("{file}: {key}: give `angle_deg` or `angle`, not both"),
        (None, None) => bail!(
            "{file}: {key}: no angle: give `angle_deg` (degrees from +y, vertical up, towards +z) or `angle` (`45L`/`45R` with top-level `view` and `rotation`)"
        ),
    }
}

/// Groups placements by bearing in first-seen order: for each bearing the
/// indices of its `rel` and its `ped` transducers. Every bearing needs at
/// least two of each, no two of a quantity closer than
/// [`MIN_SEPARATION_DEG`] (modulo 180°).
pub fn group_by_bearing(
    file: &str,
    placements: &[Placement],
) -> Result<Vec<(String, [Vec<usize>; 2])>> {
    let mut groups: Vec<(String, [Vec<usize>; 2])> = Vec::new();
    for (i, p) in placements.iter().enumerate() {
        if let Err(e) = crate::names::check("bearing", &p.bearing) {
            bail!("{file}: {}.bearing: {e}", p.key);
        }
        let slot = match groups.iter().position(|(b, _)| *b == p.bearing) {
            Some(s) => s,
            None => {
                groups.push((p.bearing.clone(), [Vec::new(), Vec::new()]));
                groups.len() - 1
            }
        };
        groups[slot].1[p.quantity as usize].push(i);
    }
    for (bearing, sets) in &groups {
        for (q, set) in [Quantity::Rel, Quantity::Ped].iter().zip(sets) {
            if set.len() < 2 {
                let have: Vec<&str> = set.iter().map(|&i| placements[i].key.as_str()).collect();
                bail!(
                    "{file}: bearing `{bearing}` has {} `{}` transducer(s) ({}); y and z need two at distinct angles",
                    set.len(),
                    q.name(),
                    if have.is_empty() { "none".to_string() } else { have.join(", ") }
                );
            }
            for (n, &i) in set.iter().enumerate() {
                for &j in &set[n + 1..] {
                    let (a, b) = (&placements[i], &placements[j]);
                    let sep = separation_deg(a.angle_deg, b.angle_deg);
                    if sep < MIN_SEPARATION_DEG {
                        bail!(
                            "{file}: {} and {} (bearing `{bearing}`, `{}`) are at {}° and {}°, only {:.3}° apart (modulo 180°); two transducers of a quantity must be at least {MIN_SEPARATION_DEG}° apart to give y and z",
                            a.key,
                            b.key,
                            q.name(),
                            a.angle_deg,
                            b.angle_deg,
                            sep
                        );
                    }
                }
            }
        }
    }
    Ok(groups)
}
