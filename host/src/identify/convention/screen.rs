//! The OLS screen of a corrected run ([`super::diagnose`]): every pedestal
//! fitted by the paper's OLS from the normal equations, accumulated in one
//! pass over the run (5×5 numbers per pedestal, no design matrix, no SVD),
//! with the full OLS fit ([`exact`], as `--estimator ols` makes it) where
//! the normal equations are not well conditioned. Eight corrections of a
//! 20 000-speed run cost eight passes, not eight SVDs of 40 000×5 matrices.
//!
//! A screen fit carries what a reading of it needs (the parameters, their
//! standard errors, the fit's speed range and fixed parameters, its
//! physical violations); its other fields are those of the pedestal as
//! found. Its parameters agree with the full fit's to about
//! [`MAX_CONDITION`]²·ε relative.

use super::super::lsq::NormalEquations;
use super::super::physical::violations;
use super::super::{Options, PedestalFit};
use super::rows::BearingRows;
use crate::estimate::Observation;
use plinth_shared::regression::{equations_for_mode, Parameter, PARAMETERS};

/// Largest condition number of the column-scaled design matrix [-] at
/// which the normal equations are solved (θ then carries at most about
/// 1e8·ε ≈ 2e-8 relative error, far below any figure a reading prints);
/// beyond it the screen is the full OLS fit.
pub const MAX_CONDITION: f64 = 1e4;

/// The OLS fit of every pedestal of a run as found with a mistake undone,
/// given as its measured bearings' rows ([`super::rows`]), with the model
/// and equations of `options`, or `None` when the run cannot be fitted (a
/// speed outside its bearing's table). `found` are the pedestals as found,
/// whose fields the screen fits keep where a reading does not use them.
pub fn screen(
    rows: &[BearingRows],
    options: &Options,
    found: &[PedestalFit],
) -> Option<Vec<PedestalFit>> {
    rows.iter()
        .map(|r| {
            let points = r.in_range()?;
            let template = found.iter().find(|p| p.bearing == r.bearing);
            template
                .and_then(|t| normal(points, options, t))
                .or_else(|| exact(points, options, &r.bearing))
        })
        .collect()
}

/// The paper's OLS fit of `bearing`'s pedestal from its observations
/// `points` (in the run's order), as [`super::super::fit_run`] makes it
/// with `--estimator ols`.
pub fn exact(points: &[Observation], options: &Options, bearing: &str) -> Option<PedestalFit> {
    super::super::fit_pedestal(bearing, points, &options.ols()).ok()
}

/// The relative residual Σ|e|²/Σ|F|² [-] of the OLS screen of `bearing`'s
/// observations `points` and its degrees of freedom (equations − parameters),
/// `found` the pedestals as found ([`screen`]); `None` when the screen
/// cannot be made. With R&I equations Σ|e|² is the screen's residual sum of
/// squares and Σ|F|² that of its right-hand sides.
pub fn relative_residual(
    points: &[Observation],
    options: &Options,
    found: &[PedestalFit],
    bearing: &str,
) -> Option<(f64, usize)> {
    let template = found.iter().find(|p| p.bearing == bearing)?;
    let fit = normal(points, options, template).or_else(|| exact(points, options, bearing))?;
    let forces: f64 = points
        .iter()
        .map(|p| p.force().iter().map(|f| f.norm_sqr()).sum::<f64>())
        .sum();
    let rss = fit.residual_rms * fit.residual_rms * fit.equations as f64;
    let parameters = options.model().parameters().len();
    (forces > 0.0 && rss.is_finite())
        .then(|| (rss / forces, fit.equations.saturating_sub(parameters)))
}

/// The OLS fit of the pedestal of `template.bearing` from the normal
/// equations of its observations `points` (module docs); `None` when they
/// are not well conditioned or a figure is not finite.
fn normal(
    points: &[Observation],
    options: &Options,
    template: &PedestalFit,
) -> Option<PedestalFit> {
    let options = options.ols();
    let columns = options.model().parameters();
    // The observations whose numbers are finite, with their bearing force.
    let finite = points.iter().filter_map(|p| {
        let force = p.force();
        let finite = p.speed_hz.is_finite()
            && p.ped
                .iter()
                .chain(&force)
                .all(|c| c.re.is_finite() && c.im.is_finite());
        finite.then_some((p, force))
    });
    // The columns a y and a z equation of eq. 4 can have non-zero (k_y, m,
    // c_y and k_z, m, c_z), as positions in `columns`: only their products
    // are summed ([`NormalEquations::add_sparse`]; the same sums).
    let positions = |params: [Parameter; 3]| -> Vec<usize> {
        (0..columns.len())
            .filter(|&k| params.contains(&columns[k]))
            .collect()
    };
    let y = positions([Parameter::Ky, Parameter::M, Parameter::Cy]);
    let z = positions([Parameter::Kz, Parameter::M, Parameter::Cz]);
    // The full model: the positions known at compile time, rows as made.
    let full = columns.len() == PARAMETERS && y == [0, 2, 3] && z == [1, 2, 4];
    let mut ne = NormalEquations::new(columns.len());
    // Each equation's row (the model's columns) and right-hand side, made
    // once for the sums and the residuals.
    let mut rows: Vec<([f64; PARAMETERS], f64)> = Vec::with_capacity(4 * points.len());
    let mut range = [f64::INFINITY, f64::NEG_INFINITY];
    for (p, force) in finite {
        let (eqs, n) = equations_for_mode(options.mode, p.omega(), &p.ped, &force);
        // The y equations come first, then as many z ones.
        for (i, eq) in eqs[..n].iter().enumerate() {
            let y_equation = i < n / 2;
            let row = if full {
                eq.row
            } else {
                let mut row = [0.0; PARAMETERS];
                for (r, &c) in row.iter_mut().zip(&columns) {
                    *r = eq.row[c as usize];
                }
                row
            };
            let added = full
                && if y_equation {
                    ne.add_sparse_fixed(&row, [0, 2, 3], eq.rhs)
                } else {
                    ne.add_sparse_fixed(&row, [1, 2, 4], eq.rhs)
                };
            if !added {
                let nonzero = if y_equation { &y } else { &z };
                ne.add_sparse(&row[..columns.len()], nonzero, eq.rhs);
            }
            rows.push((row, eq.rhs));
        }
        range = [range[0].min(p.speed_hz), range[1].max(p.speed_hz)];
    }
    let solution = ne.solve(MAX_CONDITION)?;
    let mut theta = [0.0; PARAMETERS];
    for (k, &c) in columns.iter().enumerate() {
        theta[c as usize] = solution.theta[k];
    }
    // The residual sum of squares from the residuals themselves (no
    // cancellation when the fit is close).
    let mut rss = 0.0;
    for (row, rhs) in &rows {
        let e: f64 = row
            .iter()
            .zip(&solution.theta)
            .map(|(r, t)| r * t)
            .sum::<f64>()
            - rhs;
        rss += e * e;
    }
    let equations = ne.rows();
    let sigma2 = rss / (equations - columns.len()) as f64;
    let p = columns.len();
    let mut se = [0.0; PARAMETERS];
    for (k, &c) in columns.iter().enumerate() {
        se[c as usize] = (sigma2 * solution.inverse[k * p + k]).sqrt();
    }
    if !theta.iter().chain(&se).all(|v| v.is_finite()) {
        return None;
    }
    let mut fit = template.clone();
    fit.pedestal = crate::estimate::Pedestal::from_theta(theta);
    fit.std_err = crate::estimate::Pedestal::from_theta(se);
    fit.residual_rms = (rss / equations as f64).sqrt();
    fit.condition_number = solution.condition_number;
    fit.equations = equations;
    fit.speed_range_hz = range;
    fit.fixed = options
        .model()
        .fixed()
        .iter()
        .map(|p| p.name().to_string())
        .collect();
    fit.warnings = violations(&fit);
    fit.trusted = fit.warnings.is_empty();
    fit.suspected_convention_error = None;
    Some(fit)
}
