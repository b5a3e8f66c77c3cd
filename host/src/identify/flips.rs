//! Keyphasor flips found against the other bearings at the same speed
//! ([`crate::estimate::robust::cross_bearing_flips`]), after every bearing
//! was fitted: the test needs all bearings' phasors at once, while each
//! bearing's own fit already named the flips its neighbouring speeds show
//! ([`super::trust::bad_speeds`]) and the outlier speeds. What it finds is
//! added to that bearing's `outlier_speeds_hz` with a `keyphasor_flip`
//! warning that says which evidence named it. The fit is unchanged: a
//! negated (rel, ped) pair fits eq. 3 exactly as the pair negated back.
//!
//! Two hypotheses, each named with its evidence: one bearing's channels
//! flipped (its own acquisition's keyphasor: found in speed or against the
//! other bearings) or every bearing's at once (the machine's keyphasor:
//! invisible across bearings, found in speed at each bearing). A speed
//! every bearing lists gets a note saying it may be the latter.

use super::data::BearingObservations;
use super::{Identification, Warning, WarningKind};
use crate::estimate::{robust, Observation};

/// Per bearing (in the order of `bearings`, each bearing's observations in
/// any order, phasors [m]), the speeds [Hz] at which its channels look
/// negated, ascending: the test in speed of each bearing
/// ([`robust::keyphasor_flips`]), then, with those speeds left out, the
/// test against the other bearings at the same speed
/// ([`robust::cross_bearing_flips`], three bearings or more). What
/// `plinth identify` names, for a caller without a fit (`plinth diagnose`
/// leaves these speeds out before it fits anything); identify runs the
/// same two tests, the first inside each bearing's fit
/// ([`super::trust::bad_speeds`], with the outlier speeds), the second in
/// [`mark_cross_bearing_flips`].
pub fn flipped_speeds(bearings: &[&[Observation]]) -> Vec<Vec<f64>> {
    let mut found: Vec<Vec<f64>> = bearings
        .iter()
        .map(|obs| robust::keyphasor_flips(obs))
        .collect();
    let flipped: Vec<&[f64]> = found.iter().map(Vec::as_slice).collect();
    let none = vec![&[][..]; bearings.len()];
    let across = robust::cross_bearing_flips(bearings, &none, &flipped);
    for (speeds, more) in found.iter_mut().zip(across) {
        speeds.extend(more);
        speeds.sort_by(f64::total_cmp);
        speeds.dedup();
    }
    found
}

/// The speeds [Hz] every one of `listed` (per bearing, two bearings or
/// more) holds: where every bearing looks flipped, the fault is common to
/// all channels, the machine's keyphasor itself.
pub fn listed_by_every_bearing(listed: &[Vec<f64>]) -> Vec<f64> {
    match listed {
        [first, _, ..] => first
            .iter()
            .copied()
            .filter(|s| listed.iter().all(|l| l.contains(s)))
            .collect(),
        _ => Vec::new(),
    }
}

/// Adds to `identification` the keyphasor flips of its bearings found
/// against the other bearings (`bearings`: the observations it was fitted
/// to; speeds already listed for any bearing are not judged again: the
/// outliers left out, the flips found in speed negated back).
pub fn mark_cross_bearing_flips(
    bearings: &[BearingObservations],
    identification: &mut Identification,
) {
    let usable: Vec<(&str, &[Observation])> = bearings
        .iter()
        .filter_map(|b| {
            let obs = b.observations.as_deref().ok()?;
            identification
                .noise
                .contains_key(&b.bearing)
                .then_some((b.bearing.as_str(), obs))
        })
        .collect();
    if usable.len() < robust::CROSS_MIN_BEARINGS {
        return;
    }
    let listed: Vec<Vec<f64>> = usable
        .iter()
        .map(|(name, _)| {
            identification
                .noise
                .get(*name)
                .map(|n| n.outlier_speeds_hz.clone())
                .unwrap_or_default()
        })
        .collect();
    let observations: Vec<&[Observation]> = usable.iter().map(|(_, o)| *o).collect();
    // The flips each bearing's fit found in speed (the same test, run
    // again: the report merges them with the outliers) are negated back,
    // the outliers left out.
    let in_speed: Vec<Vec<f64>> = observations
        .iter()
        .map(|o| robust::keyphasor_flips(o))
        .collect();
    let outliers: Vec<Vec<f64>> = listed
        .iter()
        .zip(&in_speed)
        .map(|(l, f)| l.iter().copied().filter(|s| !f.contains(s)).collect())
        .collect();
    let outlier_refs: Vec<&[f64]> = outliers.iter().map(Vec::as_slice).collect();
    let flipped_refs: Vec<&[f64]> = in_speed.iter().map(Vec::as_slice).collect();
    let found = robust::cross_bearing_flips(&observations, &outlier_refs, &flipped_refs);
    // Speeds every bearing listed before this test.
    let everywhere = listed_by_every_bearing(&listed);
    if !everywhere.is_empty() {
        let list: Vec<String> = everywhere.iter().map(|s| format!("{s}")).collect();
        for p in identification
            .pedestals
            .iter_mut()
            .filter(|p| p.has_warning(WarningKind::KeyphasorFlip))
        {
            p.warnings.push(Warning {
                kind: WarningKind::KeyphasorFlip,
                message: format!(
                    "every bearing lists {} Hz (flipped against its neighbouring speeds, or an outlier): where every bearing flipped, the fault is common to all channels, the machine's keyphasor itself triggering half a revolution off",
                    list.join(", ")
                ),
            });
        }
    }
    for ((name, _), speeds) in usable.iter().zip(found) {
        if speeds.is_empty() {
            continue;
        }
        if let Some(report) = identification.noise.get_mut(*name) {
            report.outlier_speeds_hz.extend(&speeds);
            report.outlier_speeds_hz.sort_by(f64::total_cmp);
            report.outlier_speeds_hz.dedup();
        }
        let list: Vec<String> = speeds.iter().map(|s| format!("{s}")).collect();
        if let Some(p) = identification
            .pedestals
            .iter_mut()
            .find(|p| p.bearing == *name)
        {
            p.warnings.push(Warning {
                kind: WarningKind::KeyphasorFlip,
                message: format!(
                    "every channel (rel and ped, y and z) is flipped by 180° against the other bearings at the same speed at {} Hz (the machine's modes fix how the bearings' phasors relate; this bearing's agree only negated): a likely keyphasor fault of this bearing's channels; the pedestal equation is blind to it (rel and ped flip together), but check those speeds",
                    list.join(", ")
                ),
            });
        }
    }
}
