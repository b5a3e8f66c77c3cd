//! The final refits written into the report: the pedestals' values and
//! ± and the kept steps' parameters at their bearings ([`report`]).

use super::GroupRefit;
use crate::diagnose::bearing_table::report_delta;
use crate::diagnose::data::Prepared;
use crate::diagnose::model::{Model, Term};
use crate::diagnose::report::{Pedestal, Step};
use std::collections::BTreeMap;

/// Writes the refits of [`super::refit`] into the reported pedestals and the kept
/// steps at their bearings: values and ± ([`Inference::std_err`]) of every
/// pedestal term and of every effect parameter the steps list by name. A
/// delay fitted beside a damping held at zero gets the ± with that damping
/// free ([`HeldDelay::std_err`]); the held fit's own ± goes under the
/// step's `held` ([`super::summaries::HeldDamping::tau_std_err_damping_zero`]).
pub fn report(
    prep: &Prepared,
    model: &Model,
    refits: &[GroupRefit],
    pedestals: &mut [Pedestal],
    steps: &mut [Step],
) {
    for r in refits {
        // Dampings the search held and the refit freed are no longer held.
        for dir in r.freed.iter().filter_map(|t| match *t {
            Term::Damping { bearing, dir } => Some((bearing, dir)),
            _ => None,
        }) {
            let Some(bname) = prep.bearings.get(dir.0) else {
                continue;
            };
            for s in steps.iter_mut().filter(|s| &s.bearing == bname) {
                s.held = None;
            }
        }
        let entries = r
            .terms
            .iter()
            .map(|&t| {
                let term = model.terms[t];
                (term.bearings()[0], term.name(), term.is_pedestal(), None)
            })
            .chain(r.nonlinear.iter().map(|&k| {
                let p = model.nonlinear[k];
                let held = r.held_delays.iter().find(|h| h.nonlinear == k);
                (Some(p.bearing()), p.name().to_string(), false, held)
            }));
        for (i, (bearing, name, is_pedestal, held)) in entries.enumerate() {
            let Some(bname) = bearing.and_then(|b| prep.bearings.get(b)) else {
                continue;
            };
            let value = r.inference.estimate[i];
            let unknown = r.held_unknown.as_ref();
            let se = held.map_or(r.inference.std_err(i), |h| h.std_err);
            let se = unknown.map_or(se, |u| se.max(u.std_err[i]));
            // A table's δ is reported as its ratio (1 + δ), by the one
            // writer of the `bearing_coefficients` step's parameters.
            let table = i
                .checked_sub(r.terms.len())
                .map(|j| model.nonlinear[r.nonlinear[j]])
                .filter(|p| model.table_correction(p).is_some());
            if let Some(p) = table {
                report_delta(prep, model, p, value, se, steps);
                continue;
            }
            if is_pedestal {
                if let Some(p) = pedestals.iter_mut().find(|p| &p.bearing == bname) {
                    p.values.insert(name.clone(), value);
                    // Reported by the one rule of every pedestal's ±
                    // (`Inference::reported_std_err`); the effects' ± below
                    // stay those the tests use.
                    let reported = held.map_or(r.inference.reported_std_err(i), |h| h.std_err);
                    let reported =
                        unknown.map_or(reported, |u| reported.max(u.reported_std_err[i]));
                    p.std_err.insert(name.clone(), reported);
                }
            }
            for s in steps
                .iter_mut()
                .filter(|s| &s.bearing == bname && s.dropped.is_none())
            {
                if let Some(e) = s.parameters.iter_mut().find(|e| e.name == name) {
                    e.value = value;
                    e.std_err = se;
                    if let (Some(h), Some(sh)) = (held, s.held.as_mut()) {
                        sh.tau_std_err_damping_zero = Some(h.std_err_held);
                    }
                }
            }
        }
        // The ± with an unexcluded delay unknown: each reported pedestal ±
        // times its ρ = σ_free/σ_held, the largest over the group's delays.
        let mut rho: BTreeMap<(usize, &str), f64> = BTreeMap::new();
        for w in r.delay_unknown.iter().flat_map(|d| &d.widened) {
            let e = rho.entry((w.bearing, w.name.as_str())).or_insert(1.0);
            *e = e.max(w.ratio());
        }
        for ((b, name), ratio) in rho {
            let Some(p) = prep
                .bearings
                .get(b)
                .and_then(|n| pedestals.iter_mut().find(|p| &p.bearing == n))
            else {
                continue;
            };
            if let Some(se) = p.std_err.get_mut(name) {
                *se *= ratio;
            }
        }
    }
}
