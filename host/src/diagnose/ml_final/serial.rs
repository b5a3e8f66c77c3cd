//! The final fit's inference under noise correlated along the run: the
//! one rule of `plinth identify` ([`crate::estimate::serial`]) on the
//! group's whitened equations.
//!
//! **Why.** A tracking filter slower than the logging step makes each
//! channel's noise an AR(1) along the run (ROSS unseen-eight `corr-noise`,
//! ρ = 0.80, docs/unseen-eight.md finding 1). The floor of [`Inference`]
//! takes the speeds as independent, and its autocorrelation-robust sandwich
//! (Bartlett kernel, Andrews' bandwidth, [`crate::estimate::serial::long_run_covariance`])
//! keeps about 7.3 of the 9 of (1 + ρ)/(1 − ρ) at ρ = 0.8 and a long run,
//! less with a short one: diagnose's final ± were about 30 % short there
//! (RMS z of k, m 1.3; docs/estimation-scatter.md, Session 49 (corr17b)),
//! while identify's, widened by the AR(1) it measures, were right.
//!
//! **Rule.** The correlation is measured on the fit's whitened residuals as
//! identify measures it ([`serial::measured_equations`]: ρ̂ of the
//! detrended residuals pooled over all of a speed's rows, above its 1 %
//! limit for white noise, the AR(1)'s ρ with the detrending's bias removed).
//! Where it is there, the inference is made on the equations prewhitened by
//! ρ ([`serial::prewhitened_equations_of`]), whose floor is the generalised
//! fit's covariance under the AR(1) and whose robust sandwich then sees
//! nearly white scores, and each parameter's ± is scaled from the
//! generalised fit's to the sandwich of the white fit's values, which are
//! the ones reported ([`serial::ar1_gls_widening`], the same long-run
//! covariance identify widens by). Where it is not there (a white run: all
//! but about 1 % of bearings) the inference is exactly the one before.
//! The delay rule ([`super::delay_unknown`]) linearises on the same
//! prewhitened equations, as identify's does
//! ([`crate::estimate::lack_of_fit::delay_unknown::delay_nuisance`]).

use crate::diagnose::criterion::Inference;
use crate::diagnose::data::Prepared;
use crate::estimate::serial;
use anyhow::Result;
use nalgebra::{DMatrix, DVector};

/// The AR(1) along the run of whitened equations whose residual `resid`
/// has the same number of real rows at each of the group's `speeds`
/// (indices into [`Prepared::speeds_hz`], ascending): (ρ with the
/// detrending's bias removed, the rows per speed); `None` where the
/// correlation is not there or cannot be measured.
pub(super) fn measured(
    prep: &Prepared,
    speeds: &[usize],
    resid: &DVector<f64>,
) -> Option<(f64, usize)> {
    let hz: Vec<f64> = speeds
        .iter()
        .map(|&j| prep.speeds_hz.get(j).copied())
        .collect::<Option<_>>()?;
    let (rho, _, _) = serial::measured_equations(&hz, resid)?;
    Some((rho, resid.len() / hz.len()))
}

/// Whitened equations `jac`, `resid` prewhitened by the AR(1) of lag-one
/// correlation `rho` [-], `rows_per_speed` real rows per speed
/// ([`serial::prewhitened_equations_of`]).
pub(super) fn prewhitened(
    jac: &DMatrix<f64>,
    resid: &DVector<f64>,
    rows_per_speed: usize,
    rho: f64,
) -> (DMatrix<f64>, DVector<f64>) {
    let r = DMatrix::from_column_slice(resid.len(), 1, resid.as_slice());
    (
        serial::prewhitened_equations_of(jac, rows_per_speed, rho),
        serial::prewhitened_equations_of(&r, rows_per_speed, rho)
            .column(0)
            .into_owned(),
    )
}

/// The inference at `estimate` (the white fit's values, SI units) of the
/// fit whose whitened equations are `jac`, `resid` (rows grouped by speed
/// as `row_speed` gives them, at the group's `speeds`) with the noise's
/// correlation along the run counted (module docs); [`Inference::new`] of
/// the equations as they are where it is not there.
pub(super) fn inference(
    prep: &Prepared,
    speeds: &[usize],
    jac: &DMatrix<f64>,
    resid: &DVector<f64>,
    row_speed: &[usize],
    estimate: DVector<f64>,
) -> Result<Inference> {
    let Some((rho, rows)) = measured(prep, speeds, resid) else {
        return Inference::new(jac, resid, row_speed, estimate);
    };
    let Some(widening) = serial::ar1_gls_widening(jac, rows, rho) else {
        return Inference::new(jac, resid, row_speed, estimate);
    };
    let (mut jt, rt) = prewhitened(jac, resid, rows, rho);
    // A column scaled by 1/w scales its parameter's ± (floor and robust
    // alike: the inference normalises the columns) by w.
    for (k, w) in widening.iter().enumerate() {
        jt.column_mut(k).scale_mut(1.0 / w);
    }
    Inference::new(&jt, &rt, row_speed, estimate)
}
