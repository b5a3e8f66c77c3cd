//! What the noise model says an estimate's scatter is: the Fisher
//! information and its inverse, the Cramér–Rao bound, at an estimate or at the
//! truth, and the true covariance of the paper's OLS under the same noise.

use super::rigid::{Rigid, Speed};
use super::{MlError, Weighting};
use crate::estimate::gauss_helmert as gh;
use crate::estimate::Observation;
use nalgebra::DMatrix;
use plinth_shared::regression::{Parameter, PARAMETERS};

/// Fisher information Σ Aᵀ Σ(θ)⁻¹ A over `columns` (θ units) at `theta`:
/// its inverse is the Cramér–Rao bound when the observations hold the true
/// phasors and the true noise.
pub fn fisher_information(
    obs: &[Observation],
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
) -> Result<DMatrix<f64>, MlError> {
    fisher_of(&Rigid::new(obs, &Weighting::default()), columns, theta)
}

pub(super) fn fisher_of(
    eq: &Rigid,
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
) -> Result<DMatrix<f64>, MlError> {
    let full = match gh::fisher(eq, theta, &[1.0; PARAMETERS]) {
        Some(f) => f,
        None => return Err(first_failure(eq, theta)),
    };
    Ok(DMatrix::from_fn(columns.len(), columns.len(), |r, c| {
        full[(columns[r] as usize, columns[c] as usize)]
    }))
}

/// The error of the first speed whose Σ cannot be factored at θ.
pub(super) fn first_failure(eq: &Rigid, theta: &[f64]) -> MlError {
    (0..eq.speeds.len())
        .find_map(|s| eq.factor(s, theta).err())
        .unwrap_or(MlError::NonFinite)
}

/// F⁻¹ over all five parameters from the Fisher information `f` over
/// `columns` (zero rows and columns for the others), with the condition
/// number of the whitened column-normalised regression.
pub(super) fn spread(
    f: &DMatrix<f64>,
    columns: &[Parameter],
) -> ([[f64; PARAMETERS]; PARAMETERS], f64) {
    let inv = gh::inverse_psd(f);
    let mut cov = [[0.0; PARAMETERS]; PARAMETERS];
    for (r, &pr) in columns.iter().enumerate() {
        for (c, &pc) in columns.iter().enumerate() {
            cov[pr as usize][pc as usize] = inv[(r, c)];
        }
    }
    (cov, gh::condition_number(f))
}

/// The covariance F⁻¹ (θ units) over all five parameters at `theta`, and the
/// condition number of the whitened column-normalised regression.
pub fn bound(
    obs: &[Observation],
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
) -> Result<([[f64; PARAMETERS]; PARAMETERS], f64), MlError> {
    Ok(spread(&fisher_information(obs, columns, theta)?, columns))
}

/// The true covariance of the paper's OLS estimate under the noise model
/// (θ units, all five parameters), the sandwich
/// (AᵀA)⁻¹·(Σ Aᵀ Σ(θ) A)·(AᵀA)⁻¹ with Σ at `theta`: what OLS's scatter
/// really is, to compare with [`bound`].
pub fn ols_covariance(
    obs: &[Observation],
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
) -> [[f64; PARAMETERS]; PARAMETERS] {
    ols_covariance_with(obs, columns, theta, 0.0)
}

/// [`ols_covariance`] with an equation error of variance `equation_var`
/// [N²] per real equation ([`fit_with_equation_error`]).
pub fn ols_covariance_with(
    obs: &[Observation],
    columns: &[Parameter],
    theta: &[f64; PARAMETERS],
    equation_var: f64,
) -> [[f64; PARAMETERS]; PARAMETERS] {
    let p = columns.len();
    let mut ata = DMatrix::zeros(p, p);
    let mut meat = DMatrix::zeros(p, p);
    for o in obs {
        let sp = Speed::new(o, 1.0);
        let sel = DMatrix::from_fn(4, p, |r, c| sp.a[(r, columns[c] as usize)]);
        let s = sp.sigma(theta, equation_var);
        let s_dyn = DMatrix::from_fn(4, 4, |r, c| s[(r, c)]);
        ata += sel.transpose() * &sel;
        meat += sel.transpose() * s_dyn * &sel;
    }
    let inv = gh::inverse_psd(&ata);
    let cov = &inv * meat * &inv;
    let mut out = [[0.0; PARAMETERS]; PARAMETERS];
    for (r, &pr) in columns.iter().enumerate() {
        for (c, &pc) in columns.iter().enumerate() {
            out[pr as usize][pc as usize] = if inv[(r, r)].is_finite() {
                cov[(r, c)]
            } else {
                f64::INFINITY
            };
        }
    }
    out
}
