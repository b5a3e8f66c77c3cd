//! A run made ready for fitting, once, before any fit: the noise of every
//! measured bearing ([`RunNoise`], its digits counted once), each bearing's
//! observations (phasors, the bearing's complex stiffness interpolated at
//! each speed and the variances of that noise), and, when the run has a
//! `base.csv`, the measured base motion with its noise. The rigid-ground
//! fits, the convention check and the refits on a base all read these;
//! nothing is rebuilt from the run after identification.

use super::{observations, IdentifyError, MIN_SPEEDS};
use crate::base_csv::BaseRow;
use crate::estimate::base::BaseObservation;
use crate::estimate::noise::{BearingNoise, ColumnDigits, Quantisation, RunNoise};
use crate::estimate::pedestal::number_variance;
use crate::estimate::Observation;
use crate::rundir::{Measurement, OutOfRange, RunDir};

/// Why a measured bearing's observations could not be made (an
/// [`IdentifyError`] raised when that bearing is fitted, in its turn).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ObservationError {
    /// The bearing has no rows in `bearings.csv`.
    UnknownBearing,
    /// The noise has no rows of the bearing.
    NoMeasurements,
    /// Fewer than [`MIN_SPEEDS`] speeds (the number measured).
    TooFewSpeeds(usize),
    /// A speed outside the bearing's table.
    BearingRange(OutOfRange),
}

impl ObservationError {
    /// The identification error of bearing `bearing`.
    pub fn of(self, bearing: &str) -> IdentifyError {
        let bearing = bearing.to_string();
        match self {
            ObservationError::UnknownBearing => IdentifyError::UnknownBearing { bearing },
            ObservationError::NoMeasurements => IdentifyError::NoMeasurements,
            ObservationError::TooFewSpeeds(speeds) => {
                IdentifyError::TooFewSpeeds { bearing, speeds }
            }
            ObservationError::BearingRange(source) => {
                IdentifyError::BearingRange { bearing, source }
            }
        }
    }
}

/// One measured bearing's observations, row for row with its noise in the
/// run's [`RunNoise`] (variances as estimated, before any fit).
#[derive(Clone, Debug, PartialEq)]
pub struct BearingObservations {
    /// The bearing.
    pub bearing: String,
    /// Its observations, or why they could not be made.
    pub observations: Result<Vec<Observation>, ObservationError>,
}

/// Every measured bearing's observations of `run` (in the order of
/// [`RunDir::measured_bearings`]) with the variances of `noise`.
pub fn observe(run: &RunDir, noise: &RunNoise) -> Vec<BearingObservations> {
    let schedules = run.bearing_schedules();
    run.measured_bearings()
        .into_iter()
        .map(|bearing| {
            let observations = (|| {
                let schedule = schedules
                    .get(bearing)
                    .ok_or(ObservationError::UnknownBearing)?;
                let (index, noise) = noise
                    .bearing(bearing)
                    .ok_or(ObservationError::NoMeasurements)?;
                let rows: Vec<&Measurement> = index.iter().map(|&i| &run.measurements[i]).collect();
                if rows.len() < MIN_SPEEDS {
                    return Err(ObservationError::TooFewSpeeds(rows.len()));
                }
                observations(&rows, schedule, noise).map_err(ObservationError::BearingRange)
            })();
            BearingObservations {
                bearing: bearing.to_string(),
                observations,
            }
        })
        .collect()
}

/// The measured motion of one base of `base.csv`, with its noise.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasuredBase {
    /// The base's name.
    pub name: String,
    /// Its rows, in file order, with the variance of every number: the
    /// `y_sd,z_sd` columns when given, else the digits of its column
    /// (counted over every row of `base.csv`).
    pub observations: Vec<BaseObservation>,
}

/// The bases of `base.csv` (`rows`) as observations, each number's
/// variance by the one rule ([`number_variance`]) with the digits counted
/// once per column, and for each bearing the base it stands on (the first
/// row that lists it).
pub fn measured_bases(
    rows: &[BaseRow],
    quantisation: Quantisation,
) -> (Vec<MeasuredBase>, Vec<(String, usize)>) {
    let part = |r: &BaseRow, c: usize| {
        let z = r.motion[c / 2];
        if c.is_multiple_of(2) {
            z.re
        } else {
            z.im
        }
    };
    // The digits of each base's columns, counted on its own rows (each
    // base written with its own resolution, as each bearing).
    let mut digits: Vec<(&str, [ColumnDigits; 4])> = Vec::new();
    for r in rows {
        if !digits.iter().any(|(name, _)| *name == r.base) {
            let of_base = rows.iter().filter(|q| q.base == r.base);
            let columns =
                std::array::from_fn(|c| ColumnDigits::of(of_base.clone().map(|q| part(q, c))));
            digits.push((&r.base, columns));
        }
    }
    let mut bases: Vec<MeasuredBase> = Vec::new();
    let mut on: Vec<(String, usize)> = Vec::new();
    for r in rows {
        let k = match bases.iter().position(|b| b.name == r.base) {
            Some(k) => k,
            None => {
                bases.push(MeasuredBase {
                    name: r.base.clone(),
                    observations: Vec::new(),
                });
                bases.len() - 1
            }
        };
        bases[k].observations.push(BaseObservation {
            speed_hz: r.speed_hz,
            motion: r.motion,
            var: std::array::from_fn(|c| {
                let sd = r.noise_sd.map(|sd| sd[c / 2]);
                let ulp = digits
                    .iter()
                    .find(|(name, _)| *name == r.base)
                    .map_or(0.0, |(_, d)| d[c].ulp(part(r, c)));
                number_variance(quantisation, ulp, sd)
            }),
        });
        for b in &r.bearings {
            if !on.iter().any(|(name, _)| name == b) {
                on.push((b.clone(), k));
            }
        }
    }
    (bases, on)
}

/// A run made ready for fitting (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Prepared {
    /// The noise of every measured bearing, as estimated (no fit has
    /// switched or rescaled it: each fit works on its own copy).
    pub noise: RunNoise,
    /// Every measured bearing's observations ([`observe`]).
    pub bearings: Vec<BearingObservations>,
    /// The bases of `base.csv` (empty: rigid ground, or not measured).
    pub bases: Vec<MeasuredBase>,
    /// Each bearing on a measured base, with the base's index in `bases`.
    pub on_base: Vec<(String, usize)>,
}

impl Prepared {
    /// `run` (as it will be fitted) and the rows of its `base.csv`, if
    /// any, made ready for fitting with the digits reduced by
    /// `quantisation`.
    pub fn new(run: &RunDir, base: Option<&[BaseRow]>, quantisation: Quantisation) -> Self {
        let noise = RunNoise::estimate(run, quantisation);
        let bearings = observe(run, &noise);
        let (bases, on_base) =
            base.map_or_else(Default::default, |rows| measured_bases(rows, quantisation));
        Self {
            noise,
            bearings,
            bases,
            on_base,
        }
    }

    /// The observations of `bearing` and their noise as estimated.
    pub fn bearing(&self, bearing: &str) -> Result<(&[Observation], &BearingNoise), IdentifyError> {
        let obs = self
            .bearings
            .iter()
            .find(|b| b.bearing == bearing)
            .ok_or_else(|| IdentifyError::UnknownBearing {
                bearing: bearing.to_string(),
            })?;
        let observations = obs.observations.as_deref().map_err(|e| e.of(bearing))?;
        let (_, noise) = self
            .noise
            .bearing(bearing)
            .ok_or(IdentifyError::NoMeasurements)?;
        Ok((observations, noise))
    }

    /// The measured base `bearing` stands on, if any.
    pub fn base_of(&self, bearing: &str) -> Option<&MeasuredBase> {
        let (_, k) = self.on_base.iter().find(|(b, _)| b == bearing)?;
        self.bases.get(*k)
    }

    /// The measured bearings, in order of first appearance.
    pub fn measured_bearings(&self) -> Vec<&str> {
        self.bearings.iter().map(|b| b.bearing.as_str()).collect()
    }
}
