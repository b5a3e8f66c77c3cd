//! The refit loop of [`super::diagnose`] (estimators other than OLS):
//! every correction whose OLS screen leaves it a chance to matter is
//! refitted with the estimator in use, cheapest first.

use super::candidate::Candidate;
use super::decide::{naming_limit, relevance_limit};
use super::judge::Judge;
use super::{mistake, Convention};

/// Refits, cheapest first, every correction of `candidates` the readings so
/// far leave a chance to matter. A first pass refits only what could name
/// a mistake ([`naming_limit`]); when it leaves the data as found the best
/// passive reading of every pedestal, nothing is named, as with every refit
/// made. Otherwise the full rule runs from the start (the order of the
/// refits decides which readings are judged), with the fits made.
pub(super) fn refit<'a>(judge: &Judge<'a>, candidates: &mut [Candidate<'a>]) {
    for naming_only in [true, false] {
        if !naming_only {
            if judge.found_is_best_everywhere(candidates) {
                break;
            }
            for k in candidates.iter_mut() {
                k.shown = false;
            }
        }
        loop {
            let wanted = wanted(judge, candidates, naming_only);
            if wanted.is_empty() {
                break;
            }
            for i in wanted {
                if candidates[i].fit.is_none() {
                    fit(judge, &mut candidates[i]);
                }
                candidates[i].shown = true;
            }
        }
    }
}

/// The candidates to refit next (indices, with repeats): per pedestal,
/// every one not yet shown whose bound is within the limit of the readings
/// so far, or the one of the smallest bound while the limit is infinite.
fn wanted(judge: &Judge, candidates: &[Candidate], naming_only: bool) -> Vec<usize> {
    let mut wanted: Vec<usize> = Vec::new();
    for j in 0..judge.pedestals.len() {
        let Some(readings) = judge.readings_of(j, candidates) else {
            continue;
        };
        let limit = if naming_only {
            naming_limit(&readings)
        } else {
            relevance_limit(&readings)
        };
        let open: Vec<(usize, f64)> = candidates
            .iter()
            .enumerate()
            .filter(|(_, k)| !k.shown)
            .map(|(i, k)| (i, k.bounds.get(j).copied().flatten().unwrap_or(0.0)))
            .filter(|&(_, b)| b <= limit)
            .collect();
        if limit.is_finite() {
            wanted.extend(open.iter().map(|&(i, _)| i));
        } else if let Some(&(i, _)) = open.iter().min_by(|a, b| a.1.total_cmp(&b.1)) {
            wanted.push(i);
        }
    }
    wanted
}

/// Candidate `k` refitted with the estimator in use, and its readings.
/// Readings need the estimates and their plausibility only;
/// `rel_negated`'s are the fits as found, negated
/// ([`mistake::rel_negated_fits`]).
fn fit<'a>(judge: &Judge<'a>, k: &mut Candidate<'a>) {
    let c = k.convention;
    let fits = if c == Convention::RelNegated {
        Some(mistake::rel_negated_fits(judge.pedestals))
    } else {
        let fixed = k.fixed.get_or_insert_with(|| c.correct(judge.run));
        crate::identify::fit_run_checked(
            fixed,
            &k.noise,
            judge.options,
            crate::identify::estimator::Checks::Estimate,
        )
        .ok()
        .map(|id| id.pedestals)
    };
    let rows = judge.rows_of(c);
    let readings = fits
        .as_deref()
        .map_or_else(Vec::new, |f| judge.readings_of_fits(k, &rows, f));
    k.readings = readings;
    k.fit = Some(fits);
}
