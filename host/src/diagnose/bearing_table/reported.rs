//! What a table correction reports: its scalar or the oil's viscosity law
//! in the `bearing_coefficients` steps, and the pedestals after the
//! maximum-likelihood refit (see the parent module).

use super::viscosity;
use super::{MlCorrection, WrittenTable};
use crate::diagnose::data::Prepared;
use crate::diagnose::model::{Model, Nonlinear};
use crate::diagnose::report::{Pedestal, Step};
use plinth_shared::regression::Parameter;

/// Writes a table correction's δ [-] and its ± [-] (`p`: the nonlinear
/// scalar of `model`) into the kept `bearing_coefficients` steps at its
/// bearing, as reported (`k_scale` or `clearance_ratio` = 1 + δ, with the
/// clearances when the table is an oil film).
pub(in crate::diagnose) fn report_delta(
    prep: &Prepared,
    model: &Model,
    p: Nonlinear,
    delta: f64,
    std_err: f64,
    steps: &mut [Step],
) {
    let b = p.bearing();
    let Some(kind) =
        crate::effects::EffectKind::from_name(super::super::candidates::BEARING_COEFFICIENTS)
    else {
        return;
    };
    for s in steps.iter_mut().filter(|s| {
        s.effect == super::super::candidates::BEARING_COEFFICIENTS
            && prep.bearings.get(b) == Some(&s.bearing)
            && s.dropped.is_none()
    }) {
        s.parameters = super::super::summaries::as_reported(
            model,
            b,
            kind,
            vec![super::super::report::Estimate {
                name: p.name().into(),
                value: delta,
                std_err,
            }],
        );
    }
}

/// Writes an oil's viscosity law (`law`, the table `table` of bearing `b`)
/// into the kept `bearing_coefficients` steps at that bearing, in place of
/// the clearance ratio: μ/μ_w at the top and the bottom measured speed
/// (`viscosity_ratio_top`, `viscosity_ratio_bottom` [-], ±), the law's
/// slope b (`viscosity_law_b` [-], ±: what the test is of), those speeds
/// (`speed_top_hz`, `speed_bottom_hz` [Hz]) and the clearance the law
/// assumes (`clearance_written` [m], as drawn).
pub(super) fn report_law(
    prep: &Prepared,
    b: usize,
    table: &WrittenTable,
    law: &viscosity::ViscosityFit,
    steps: &mut [Step],
) {
    let (top, top_se) = law.ratio_at(law.law.top_hz);
    let (bottom, bottom_se) = law.ratio_at(law.bottom_hz);
    let e = |name: &str, value: f64, std_err: f64| super::super::report::Estimate {
        name: name.into(),
        value,
        std_err,
    };
    let parameters = vec![
        e("viscosity_ratio_top", top, top_se),
        e("viscosity_ratio_bottom", bottom, bottom_se),
        e("viscosity_law_b", law.law.b, law.b_std_err()),
        e("speed_top_hz", law.law.top_hz, 0.0),
        e("speed_bottom_hz", law.bottom_hz, 0.0),
        e("clearance_written", table.film.clearance, 0.0),
    ];
    for s in steps.iter_mut().filter(|s| {
        s.effect == super::super::candidates::BEARING_COEFFICIENTS
            && prep.bearings.get(b) == Some(&s.bearing)
            && s.dropped.is_none()
    }) {
        s.parameters = parameters.clone();
    }
}

/// The pedestals reported after [`refine`]: each refitted bearing's values
/// and ± (δ's uncertainty included) from its maximum-likelihood refit
/// (the viscosity law's where it was significant).
pub fn report_refits(
    prep: &Prepared,
    refits: &[(usize, MlCorrection)],
    pedestals: &mut [Pedestal],
) {
    for (b, fit) in refits {
        let Some(name) = prep.bearings.get(*b) else {
            continue;
        };
        let (theta, std_err) = fit
            .law
            .as_ref()
            .map_or((&fit.theta, &fit.std_err), |l| (&l.theta, &l.std_err));
        if let Some(p) = pedestals.iter_mut().find(|p| &p.bearing == name) {
            for (i, q) in Parameter::ALL.iter().enumerate() {
                p.values.insert(q.name().to_string(), theta[i]);
                p.std_err.insert(q.name().to_string(), std_err[i]);
            }
        }
    }
}
