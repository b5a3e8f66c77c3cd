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
/// ([`robust::flip_search`]), then, with those speeds negated back, the
/// test against the other bearings at the same speed
/// ([`robust::cross_bearing_flips`], three bearings or more), then the
/// blocks the test in speed could not confirm, judged against the other
/// bearings ([`robust::confirmed_across`], two bearings or more). What
/// `plinth identify` names, for a caller without a fit (`plinth diagnose`
/// leaves these speeds out before it fits anything); identify runs the
/// same tests, the first inside each bearing's fit
/// ([`super::trust::bad_speeds`], with the outlier speeds), the others in
/// [`mark_cross_bearing_flips`].
pub fn flipped_speeds(bearings: &[&[Observation]]) -> Vec<Vec<f64>> {
    let mut searches: Vec<robust::FlipSearch> = bearings
        .iter()
        .map(|obs| robust::flip_search(obs))
        .collect();
    withhold_resonances(bearings, &mut searches);
    let mut found: Vec<Vec<f64>> = searches.iter().map(|s| s.flipped_hz.clone()).collect();
    let flipped: Vec<&[f64]> = found.iter().map(Vec::as_slice).collect();
    let none = vec![&[][..]; bearings.len()];
    let across = robust::cross_bearing_flips(bearings, &none, &flipped);
    merge(&mut found, across);
    let confirmed = confirmed(bearings, &searches, &none, &found);
    merge(&mut found, confirmed);
    let followed = followed(bearings, &searches, &none, &found);
    merge(&mut found, followed);
    found
}

/// Takes out of each bearing's flips found in speed (`searches`, per
/// bearing) the speeds at which another bearing's reading turns with a
/// resonance ([`robust::resonance_turns`]: a mode between two logged
/// speeds, not a flip), returning them per bearing [Hz].
fn withhold_resonances(
    bearings: &[&[Observation]],
    searches: &mut [robust::FlipSearch],
) -> Vec<Vec<f64>> {
    let named: Vec<&[f64]> = searches.iter().map(|s| s.flipped_hz.as_slice()).collect();
    let withheld = robust::resonance_turns(bearings, &named);
    for (search, out) in searches.iter_mut().zip(&withheld) {
        search.flipped_hz.retain(|f| !out.contains(f));
    }
    withheld
}

/// Adds `more` (per bearing, [Hz]) to `found` (per bearing, ascending, no
/// repeats).
fn merge(found: &mut [Vec<f64>], more: Vec<Vec<f64>>) {
    for (speeds, more) in found.iter_mut().zip(more) {
        speeds.extend(more);
        speeds.sort_by(f64::total_cmp);
        speeds.dedup();
    }
}

/// Per bearing, the speeds [Hz] of the blocks the test in speed could not
/// confirm (`searches`, per bearing) that the other bearings confirm
/// ([`robust::confirmed_across`]): `outliers` (per bearing [Hz]) left
/// out, the flips named so far (`flipped`, per bearing [Hz]) negated back;
/// a block that holds a speed already named for its bearing is not judged.
fn confirmed(
    bearings: &[&[Observation]],
    searches: &[robust::FlipSearch],
    outliers: &[&[f64]],
    flipped: &[Vec<f64>],
) -> Vec<Vec<f64>> {
    let unconfirmed: Vec<Vec<Vec<f64>>> = searches
        .iter()
        .zip(flipped)
        .map(|(s, named)| {
            s.unconfirmed_hz
                .iter()
                .filter(|block| !block.iter().any(|f| named.contains(f)))
                .cloned()
                .collect()
        })
        .collect();
    let unconfirmed_refs: Vec<&[Vec<f64>]> = unconfirmed.iter().map(Vec::as_slice).collect();
    let flipped_refs: Vec<&[f64]> = flipped.iter().map(Vec::as_slice).collect();
    robust::confirmed_across(bearings, outliers, &flipped_refs, &unconfirmed_refs)
}

/// Per bearing, the speeds [Hz] another bearing's test in speed named
/// flipped (`searches`, per bearing) at which the other bearings confirm
/// this bearing flipped with it ([`robust::followed_flips`]): `outliers`
/// (per bearing [Hz]) left out, the flips named so far (`flipped`, per
/// bearing [Hz]) negated back.
fn followed(
    bearings: &[&[Observation]],
    searches: &[robust::FlipSearch],
    outliers: &[&[f64]],
    flipped: &[Vec<f64>],
) -> Vec<Vec<f64>> {
    let named: Vec<&[f64]> = searches.iter().map(|s| s.flipped_hz.as_slice()).collect();
    let flipped: Vec<&[f64]> = flipped.iter().map(Vec::as_slice).collect();
    robust::followed_flips(bearings, outliers, &flipped, &named)
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

/// The speeds each of `usable`'s bearings lists (outliers and flips) [Hz].
fn listed_speeds(
    identification: &Identification,
    usable: &[(&str, &[Observation])],
) -> Vec<Vec<f64>> {
    usable
        .iter()
        .map(|(name, _)| {
            identification
                .noise
                .get(*name)
                .map(|n| n.outlier_speeds_hz.clone())
                .unwrap_or_default()
        })
        .collect()
}

/// Adds to `identification` the keyphasor flips of its bearings found
/// against the other bearings (`bearings`: the observations it was fitted
/// to; speeds already listed for any bearing are not judged again: the
/// outliers left out, the flips found in speed negated back): those the
/// test across bearings names alone (three bearings or more) and those the
/// test in speed could not confirm and the other bearings do (two bearings
/// or more).
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
    // The test in speed's findings, taken from each ML fit's report (not
    // reported); without them (an OLS fit) the test in speed is run again
    // where the test across bearings alone can name (three bearings), and
    // nothing is confirmed.
    let stored: Vec<Option<robust::FlipSearch>> = usable
        .iter()
        .map(|(name, _)| {
            identification
                .noise
                .get_mut(*name)
                .and_then(|n| n.flip_search.take())
        })
        .collect();
    for report in identification.noise.values_mut() {
        report.flip_search = None;
    }
    let complete = stored.iter().all(Option::is_some);
    if usable.len() < 2 || (usable.len() < robust::CROSS_MIN_BEARINGS && !complete) {
        return;
    }
    let observations: Vec<&[Observation]> = usable.iter().map(|(_, o)| *o).collect();
    // The flips each bearing's fit found in speed (the report merges them
    // with the outliers) are negated back, the outliers left out.
    let mut searches: Vec<robust::FlipSearch> = stored
        .into_iter()
        .zip(&observations)
        .map(|(s, o)| s.unwrap_or_else(|| robust::flip_search(o)))
        .collect();
    // A flip found in speed where another bearing turns with a resonance
    // is withheld: out of the listing, its warning said again without it.
    let withheld = withhold_resonances(&observations, &mut searches);
    for (((name, _), out), search) in usable.iter().zip(&withheld).zip(&searches) {
        // Without the fits' own findings nothing was listed in speed.
        if out.is_empty() || !complete {
            continue;
        }
        if let Some(report) = identification.noise.get_mut(*name) {
            report.outlier_speeds_hz.retain(|f| !out.contains(f));
        }
        if let Some(p) = identification
            .pedestals
            .iter_mut()
            .find(|p| p.bearing == *name)
        {
            p.warnings.retain(|w| w.kind != WarningKind::KeyphasorFlip);
        }
        add_flips(
            identification,
            name,
            &search.flipped_hz,
            "against its neighbouring speeds",
            "the speeds withheld from this list turn with a resonance: against the other bearings at the same speed they agree as read and only as read, as when a mode between two logged speeds turns every bearing's phase (a flip negates one bearing alone)",
        );
    }
    let listed = listed_speeds(identification, &usable);
    let mut flipped: Vec<Vec<f64>> = searches.iter().map(|s| s.flipped_hz.clone()).collect();
    let outliers: Vec<Vec<f64>> = listed
        .iter()
        .zip(&flipped)
        .map(|(l, f)| l.iter().copied().filter(|s| !f.contains(s)).collect())
        .collect();
    let outlier_refs: Vec<&[f64]> = outliers.iter().map(Vec::as_slice).collect();
    let flipped_refs: Vec<&[f64]> = flipped.iter().map(Vec::as_slice).collect();
    let found = robust::cross_bearing_flips(&observations, &outlier_refs, &flipped_refs);
    merge(&mut flipped, found.clone());
    let confirmed = if complete {
        confirmed(&observations, &searches, &outlier_refs, &flipped)
    } else {
        vec![Vec::new(); usable.len()]
    };
    let followed = if complete {
        merge(&mut flipped, confirmed.clone());
        followed(&observations, &searches, &outlier_refs, &flipped)
    } else {
        vec![Vec::new(); usable.len()]
    };
    for ((name, _), speeds) in usable.iter().zip(found) {
        add_flips(
            identification,
            name,
            &speeds,
            "against the other bearings at the same speed",
            "the machine's modes fix how the bearings' phasors relate; this bearing's agree only negated",
        );
    }
    for ((name, _), speeds) in usable.iter().zip(confirmed) {
        add_flips(
            identification,
            name,
            &speeds,
            "at a resonance's peak or flank",
            "negated, they fit the neighbouring speeds far better, though the local model in speed misses there by more than the noise; and against the other bearings at the same speed they agree only negated: the machine's modes move every bearing together, a flip moves one bearing alone",
        );
    }
    for ((name, _), speeds) in usable.iter().zip(followed) {
        add_flips(
            identification,
            name,
            &speeds,
            "where another bearing's channels are flipped (found in speed)",
            "with that bearing's flip negated back, this bearing's readings agree with the machine's modes only negated: both flipped together, as when the machine's keyphasor triggers half a revolution off",
        );
    }
    // Speeds every bearing lists.
    let now = listed_speeds(identification, &usable);
    let everywhere = listed_by_every_bearing(&now);
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
}

/// Adds the flipped `speeds` [Hz] of bearing `name` to its
/// `outlier_speeds_hz` and a `keyphasor_flip` warning saying `where` they
/// were found and `why` (nothing when `speeds` is empty).
fn add_flips(
    identification: &mut Identification,
    name: &str,
    speeds: &[f64],
    place: &str,
    why: &str,
) {
    if speeds.is_empty() {
        return;
    }
    if let Some(report) = identification.noise.get_mut(name) {
        report.outlier_speeds_hz.extend(speeds);
        report.outlier_speeds_hz.sort_by(f64::total_cmp);
        report.outlier_speeds_hz.dedup();
    }
    let list: Vec<String> = speeds.iter().map(|s| format!("{s}")).collect();
    if let Some(p) = identification
        .pedestals
        .iter_mut()
        .find(|p| p.bearing == name)
    {
        p.warnings.push(Warning {
            kind: WarningKind::KeyphasorFlip,
            message: format!(
                "every channel (rel and ped, y and z) is flipped by 180° {place} at {} Hz ({why}): a likely keyphasor fault (of this bearing's channels, or of the machine's keyphasor where other bearings list the same speeds); the pedestal equation is blind to it (rel and ped flip together), but check those speeds",
                list.join(", ")
            ),
        });
    }
}
