//! What every reading of a run is judged with ([`super::diagnose`]): the
//! run's rows and noise floor as found, each bearing's stiffness, the
//! reading of every pedestal as found, and the screening of every
//! correction by OLS ([`Judge::candidates`]).

use super::candidate::{corrected_noise, Candidate};
use super::decide::{found_is_best, plausible};
use super::rows::{self, BearingRows};
use super::{screen, Convention, Reading, Schedules};
use crate::estimate::noise::{Quantisation, RunNoise};
use crate::estimate::pedestal::floor_sd;
use crate::identify::misfit::misfit_of;
use crate::identify::{Estimator, Identification, Options, PedestalFit};
use crate::rundir::RunDir;
use std::borrow::Cow;
use std::collections::BTreeMap;

/// A run under examination for convention mistakes, with what every
/// reading of it is judged with.
pub(super) struct Judge<'a> {
    /// The run as found.
    pub run: &'a RunDir,
    /// Its pedestals as identified.
    pub pedestals: &'a [PedestalFit],
    /// Its noise.
    pub noise: &'a RunNoise,
    /// The options it was identified with.
    pub options: &'a Options,
    /// Whether the estimator in use is OLS (then the screens are the fits).
    pub ols: bool,
    /// Its bearing schedules.
    pub schedules: Schedules,
    /// Its rows as found.
    pub found_rows: Vec<BearingRows>,
    /// Each bearing's stiffness [N/m], the yardstick of [`plausible`] (the
    /// same under every reading: no mistake tried rescales the table's
    /// values).
    bearing_stiffness: BTreeMap<&'a str, Option<f64>>,
    /// The reading of each pedestal as found (same order as `pedestals`)
    /// and its fit.
    found: Vec<Option<(Reading, PedestalFit)>>,
}

impl<'a> Judge<'a> {
    /// The run `run`, identified as `identification` with `options`, whose
    /// noise is `noise`, ready to be judged.
    pub fn new(
        run: &'a RunDir,
        identification: &'a Identification,
        noise: &'a RunNoise,
        options: &'a Options,
    ) -> Self {
        let sigma = floor_of(
            run,
            &mut || RunNoise::estimate(run, Quantisation::Rounding),
            noise,
        );
        let schedules = run.bearing_schedules();
        let found_rows = rows::of_run(run, &schedules);
        let bearing_stiffness = identification
            .pedestals
            .iter()
            .map(|p| {
                let kb = crate::identify::plausibility::bearing_stiffness(run, &p.bearing);
                (p.bearing.as_str(), kb)
            })
            .collect();
        let mut judge = Self {
            run,
            pedestals: &identification.pedestals,
            noise,
            options,
            ols: options.effective_estimator() == Estimator::Ols,
            schedules,
            found_rows,
            bearing_stiffness,
            found: Vec::new(),
        };
        judge.found = judge
            .pedestals
            .iter()
            .map(|p| {
                Some((
                    judge.reading(&judge.found_rows, &sigma, p, None)?,
                    p.clone(),
                ))
            })
            .collect();
        judge
    }

    /// The reading `c` (`None`: as found) of pedestal fit `p` on `rows`
    /// with the noise floor `sigma`.
    pub fn reading(
        &self,
        rows: &[BearingRows],
        sigma: &[[f64; 4]],
        p: &PedestalFit,
        c: Option<Convention>,
    ) -> Option<Reading> {
        let rows = rows.iter().find(|r| r.bearing == p.bearing)?;
        let kb = self
            .bearing_stiffness
            .get(p.bearing.as_str())
            .copied()
            .flatten();
        misfit_of(rows.with_sigma(sigma), p).map(|m| Reading {
            convention: c,
            chi2: m.chi2,
            dof: m.dof,
            relative_residual: m.relative_residual,
            plausible: plausible(p, kb),
        })
    }

    /// The reading of `fits` for each pedestal (same order), each misfit
    /// computed once and kept: the refit loop asks for them again and again.
    pub fn readings_of_fits(
        &self,
        k: &Candidate,
        rows: &[BearingRows],
        fits: &[PedestalFit],
    ) -> Vec<Option<(Reading, PedestalFit)>> {
        self.pedestals
            .iter()
            .map(|p| {
                if !k.reads_at(&p.bearing) {
                    return None;
                }
                let q = fits.iter().find(|q| q.bearing == p.bearing)?;
                let r = self.reading(rows, &k.sigma, q, Some(k.convention))?;
                Some((r, q.clone()))
            })
            .collect()
    }

    /// The rows of the run with mistake `c` undone. Each correction's rows
    /// are made when they are read, not kept: eight copies of a long run's
    /// observations cost more to hold than to make.
    pub fn rows_of(&self, c: Convention) -> Vec<BearingRows> {
        rows::corrected(c, self.run, &self.found_rows, &self.schedules)
    }

    /// The readings judged for pedestal `j`: as found first, then those of
    /// every shown candidate; `None` when the data as found give none.
    pub fn readings_of(
        &self,
        j: usize,
        candidates: &[Candidate],
    ) -> Option<Vec<(Reading, PedestalFit)>> {
        let found = self.found[j].clone()?;
        let mut readings = vec![found];
        readings.extend(
            candidates
                .iter()
                .filter(|k| k.shown)
                .filter_map(|k| k.readings.get(j).cloned().flatten()),
        );
        Some(readings)
    }

    /// Whether the data as found are the best passive reading of every
    /// pedestal ([`found_is_best`]): then nothing is named.
    pub fn found_is_best_everywhere(&self, candidates: &[Candidate]) -> bool {
        (0..self.pedestals.len()).all(|j| {
            self.readings_of(j, candidates)
                .is_none_or(|r| found_is_best(&r))
        })
    }

    /// Whether fit `q` is a candidate reading ([`plausible`]).
    fn plausible_fit(&self, q: &PedestalFit) -> bool {
        plausible(
            q,
            self.bearing_stiffness
                .get(q.bearing.as_str())
                .copied()
                .flatten(),
        )
    }

    /// A correction's reading from its screen: its noise and noise floor,
    /// and with OLS its readings (the screen is the fit), else the lower
    /// bounds of its refit's relative residual per pedestal (`None`: no
    /// bound, it is refitted).
    fn read(&self, k: &mut Candidate<'a>, rows: &[BearingRows]) {
        let c = k.convention;
        let run = self.run;
        k.noise = corrected_noise(c, self.noise, run);
        let fixed = &mut k.fixed;
        k.sigma = floor_of(
            run,
            &mut || {
                let f = fixed.get_or_insert_with(|| c.correct(run));
                RunNoise::estimate(f, Quantisation::Rounding)
            },
            &k.noise,
        );
        let screened = self.readings_of_fits(k, rows, &k.screen);
        if self.ols {
            k.fit = Some(Some(k.screen.clone()));
            k.readings = screened;
            k.shown = true;
        } else {
            // A bearing it is not read at never asks for its refit.
            k.bounds = screened
                .iter()
                .zip(self.pedestals)
                .map(|(r, p)| match r {
                    Some((r, _)) => Some(r.relative_residual * (1.0 - 1e-9)),
                    None if !k.reads_at(&p.bearing) => Some(f64::INFINITY),
                    None => None,
                })
                .collect();
        }
    }

    /// Every correction that changes these data, with its OLS screen. With
    /// OLS a correction whose screen leaves no pedestal passive is read only
    /// when it can matter: when the data as found are not the best passive
    /// reading of every pedestal without it (otherwise nothing is named,
    /// with or without it: [`found_is_best`]). Its reading costs a misfit
    /// per pedestal, and `ped_velocity`'s its noise estimated anew.
    pub fn candidates(&self) -> Vec<Candidate<'a>> {
        let mut candidates: Vec<Candidate<'a>> = Vec::new();
        let fixed_form = Convention::ALL.into_iter().map(|c| (c, None));
        let turned = super::rotation::candidates(self)
            .into_iter()
            .map(|(c, at)| (c, Some(at)));
        for (c, only) in fixed_form.chain(turned) {
            if !c.changes_with(self.run, &self.schedules) {
                continue; // the mistake changes nothing in these data
            }
            let rows = self.rows_of(c);
            let Some(screen) = screen::screen(&rows, self.options, self.pedestals) else {
                continue;
            };
            let deferred = self.ols && !screen.iter().any(|q| self.plausible_fit(q));
            let mut k = Candidate {
                convention: c,
                only,
                fit: None,
                readings: Vec::new(),
                shown: false,
                bounds: Vec::new(),
                screen,
                // The run with the mistake undone, made only where a reading
                // needs more than its rows.
                fixed: None,
                noise: Cow::Borrowed(self.noise),
                sigma: Vec::new(),
            };
            if !deferred {
                self.read(&mut k, &rows);
            }
            candidates.push(k);
        }
        if self.ols && !self.found_is_best_everywhere(&candidates) {
            for k in candidates.iter_mut().filter(|k| !k.shown) {
                let rows = self.rows_of(k.convention);
                self.read(k, &rows);
            }
        }
        candidates
    }
}

/// The noise floor of a reading of `run` whose noise is `noise` (of the run
/// with a mistake undone, made by `fixed` when needed: only a
/// truncated-digits run estimates it anew).
fn floor_of(run: &RunDir, fixed: &mut dyn FnMut() -> RunNoise, noise: &RunNoise) -> Vec<[f64; 4]> {
    if noise.quantisation == Quantisation::Rounding {
        floor_sd(noise, run.measurements.len())
    } else {
        floor_sd(&fixed(), run.measurements.len())
    }
}
