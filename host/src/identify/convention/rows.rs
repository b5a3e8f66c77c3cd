//! The data a reading of a run is judged on ([`super::diagnose`]): each
//! measured bearing's rows as observations (phasors and the bearing's
//! complex stiffness at each speed, no noise), made once for the run as
//! found and derived from them for each correction instead of copying and
//! re-reading the whole run per correction.
//!
//! A correction that changes only phasors (`conjugated`, `swapped_yz`,
//! `rel_negated`, `ped_conjugated`, `ped_velocity`) applies
//! [`Convention::fix_phasors`] to each observation, the arithmetic
//! [`Convention::correct`] applies to each row, and keeps the stiffness (the
//! same table at the same speeds); one that changes the bearing table
//! (`bearing_transposed`, `cross_coupling_sign`) interpolates its corrected
//! schedules at the same speeds ([`corrected_schedules`]: the table's
//! coefficients mapped, which is what sorting the corrected rows gives, as
//! the speeds do not change); `speed_in_rpm` reads the run's rows at the
//! corrected speeds from the corrected table's schedules, made from the
//! table's rows as the corrected run's are. Every number is the one the
//! corrected run gives, bit for bit.

use super::{Convention, Schedules};
use crate::estimate::{complex_stiffness, Observation};
use crate::rundir::RunDir;
use plinth_shared::phasor::omega_from_hz;

/// One measured bearing's rows of a reading of a run.
#[derive(Clone, Debug)]
pub struct BearingRows {
    /// The bearing.
    pub bearing: String,
    /// Indices in `run.measurements` of its rows whose speed is inside the
    /// bearing's table, increasing.
    pub index: Vec<usize>,
    /// Their observations (variances 0), row for row.
    pub obs: Vec<Observation>,
    /// Whether every row of the bearing is inside its table.
    pub complete: bool,
}

impl BearingRows {
    /// Every observation, in the run's order, or `None` when a speed is
    /// outside the bearing's table (the OLS fit then cannot be made).
    pub fn in_range(&self) -> Option<&[Observation]> {
        self.complete.then_some(&self.obs)
    }

    /// Each observation with the noise sd row of `sigma`
    /// ([`super::super::misfit::noise_floor`]; indexed as
    /// `run.measurements`) that belongs to it.
    pub fn with_sigma<'a>(
        &'a self,
        sigma: &'a [[f64; 4]],
    ) -> impl Iterator<Item = (Observation, &'a [f64; 4])> + 'a {
        self.index
            .iter()
            .zip(&self.obs)
            .filter_map(move |(&i, o)| Some((*o, sigma.get(i)?)))
    }
}

/// Every measured bearing's rows of `run` (in the order of
/// [`RunDir::measured_bearings`]), the stiffness from `schedules`.
pub fn of_run(run: &RunDir, schedules: &Schedules) -> Vec<BearingRows> {
    of_run_at(run, schedules, |f| f)
}

/// [`of_run`] with every measurement speed `f` [Hz] read as `speed(f)`
/// (the speeds of the measurements of a corrected run).
fn of_run_at(run: &RunDir, schedules: &Schedules, speed: impl Fn(f64) -> f64) -> Vec<BearingRows> {
    let bearings = run.measured_bearings();
    // Room for each bearing's rows at once (they are counted first).
    let mut counts = vec![0usize; bearings.len()];
    let mut last = 0;
    for m in &run.measurements {
        if bearings.get(last).is_none_or(|b| *b != m.bearing) {
            match bearings.iter().position(|b| *b == m.bearing) {
                Some(k) => last = k,
                None => continue,
            }
        }
        counts[last] += 1;
    }
    let mut out: Vec<BearingRows> = bearings
        .iter()
        .zip(counts)
        .map(|(b, n)| BearingRows {
            bearing: b.to_string(),
            index: Vec::with_capacity(n),
            obs: Vec::with_capacity(n),
            complete: true,
        })
        .collect();
    let mut last = 0;
    for (i, m) in run.measurements.iter().enumerate() {
        // Rows of one bearing usually follow each other: try the last first.
        if out.get(last).is_none_or(|r| r.bearing != m.bearing) {
            match out.iter().position(|r| r.bearing == m.bearing) {
                Some(k) => last = k,
                None => continue,
            }
        }
        let Some(rows) = out.get_mut(last) else {
            continue;
        };
        let speed_hz = speed(m.speed_hz);
        let coefficients = schedules
            .get(&rows.bearing)
            .and_then(|s| s.at(speed_hz).ok());
        let Some(c) = coefficients else {
            rows.complete = false;
            continue;
        };
        rows.index.push(i);
        rows.obs.push(Observation {
            speed_hz,
            rel: m.rel,
            ped: m.ped,
            kstar: complex_stiffness(&c, omega_from_hz(speed_hz)),
            var: [0.0; 8],
        });
    }
    out
}

/// `found` (the rows of the run as found) with the phasors of mistake `c`
/// undone (a mistake of the phasors only).
pub fn with_phasors_fixed(c: Convention, found: &[BearingRows]) -> Vec<BearingRows> {
    found
        .iter()
        .map(|r| BearingRows {
            bearing: r.bearing.clone(),
            index: r.index.clone(),
            obs: r
                .obs
                .iter()
                .map(|&o| {
                    let mut o = o;
                    c.fix_phasors(o.speed_hz, &mut o.rel, &mut o.ped);
                    o
                })
                .collect(),
            complete: r.complete,
        })
        .collect()
}

/// `found` with every stiffness interpolated anew from `schedules` (a
/// corrected bearing table listing the same speeds).
pub fn with_schedules(found: &[BearingRows], schedules: &Schedules) -> Vec<BearingRows> {
    found
        .iter()
        .map(|r| {
            let schedule = schedules.get(&r.bearing);
            let mut out = BearingRows {
                bearing: r.bearing.clone(),
                index: Vec::with_capacity(r.index.len()),
                obs: Vec::with_capacity(r.obs.len()),
                complete: r.complete,
            };
            for (&i, o) in r.index.iter().zip(&r.obs) {
                match schedule.and_then(|s| s.at(o.speed_hz).ok()) {
                    Some(c) => {
                        out.index.push(i);
                        out.obs.push(Observation {
                            kstar: complex_stiffness(&c, omega_from_hz(o.speed_hz)),
                            ..*o
                        });
                    }
                    None => out.complete = false,
                }
            }
            out
        })
        .collect()
}

/// Every measured bearing's rows of `run` with mistake `c` undone, from
/// those of the run as found (`found`, with the bearing schedules
/// `schedules`), without making the corrected run: `speed_in_rpm` reads the
/// run's rows at the corrected speeds with the corrected table
/// ([`super::mistake::rpm_schedules`]).
pub fn corrected(
    c: Convention,
    run: &RunDir,
    found: &[BearingRows],
    schedules: &Schedules,
) -> Vec<BearingRows> {
    match c {
        Convention::SpeedInRpm => of_run_at(
            run,
            &super::mistake::rpm_schedules(run, schedules),
            super::mistake::rpm_to_hz,
        ),
        Convention::BearingTransposed | Convention::CrossCouplingSign => {
            with_schedules(found, &corrected_schedules(c, schedules))
        }
        _ => with_phasors_fixed(c, found),
    }
}

/// The bearing schedules of the run with mistake `c` of the bearing table
/// undone, from those of the run as found (`schedules`).
pub fn corrected_schedules(c: Convention, schedules: &Schedules) -> Schedules {
    schedules
        .iter()
        .map(|(name, s)| (name.clone(), s.map_coefficients(|k| c.fix_coefficients(k))))
        .collect()
}
