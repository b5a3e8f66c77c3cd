//! Weighted least squares of an augmented pedestal model (eq. 4 extended),
//! the noise weights that whiten it, and the 1-D profile search of a
//! nonlinear scalar (loss factor, delay).
//!
//! Errors in variables: noise enters the equations through the pedestal
//! motion (a regressor) and through `rel` (the force). For fixed parameters
//! the equation residual r = M·X + g − K*·rel is linear in both, so each real
//! equation's noise variance is the sum over every measured real number of
//! (∂r/∂number)²·σ². Each real equation is divided by that standard deviation;
//! the weights come from a reference fit (the current model) and are held
//! fixed while candidates are compared, so their residual sums are comparable.

use super::data::Prepared;
use super::model::{Model, Params};
use anyhow::{anyhow, bail, Result};
use nalgebra::{DMatrix, DVector};
use num_complex::Complex;

/// Noise standard deviation of each real equation: `sigma[b][j]` holds
/// (y re, y im, z re, z im) of bearing `b` at speed index `j` [N].
#[derive(Clone, Debug)]
pub struct Weights {
    /// Per bearing and speed; `None` where the bearing was not measured.
    pub sigma: Vec<Vec<Option<[f64; 4]>>>,
}

impl Weights {
    /// Propagates the measurement noise of `prep` through the equations of
    /// `model` at parameter values `params` (the reference fit).
    pub fn propagate(prep: &Prepared, model: &Model, params: &Params) -> Self {
        let mut out = Self {
            sigma: vec![vec![None; prep.speeds_hz.len()]; prep.bearings.len()],
        };
        for group in model.groups(prep.bearings.len()) {
            out.propagate_group(prep, model, params, &group);
        }
        out
    }

    /// [`Self::propagate`] for the bearings of `group` alone (their entries
    /// replaced).
    pub fn propagate_group(
        &mut self,
        prep: &Prepared,
        model: &Model,
        params: &Params,
        group: &[usize],
    ) {
        let sigma = &mut self.sigma;
        {
            let group = group.to_vec();
            for j in Model::group_speeds(prep, &group) {
                let Some(a) = model.assemble(prep, &group, j, &params.nl, Some(&params.beta))
                else {
                    continue;
                };
                let Some(m) = a.matrix.as_ref() else { continue };
                for (pb, &b) in group.iter().enumerate() {
                    let Some(point) = prep.points[b][j].as_ref() else {
                        continue;
                    };
                    let mut out = [0.0; 4];
                    for d in 0..2 {
                        let e = 2 * pb + d;
                        let (mut var_re, mut var_im) = (0.0, 0.0);
                        let mut add = |a: Complex<f64>, s_re: f64, s_im: f64| {
                            var_re += a.re * a.re * s_re * s_re + a.im * a.im * s_im * s_im;
                            var_im += a.im * a.im * s_re * s_re + a.re * a.re * s_im * s_im;
                        };
                        for (qc, &q) in group.iter().enumerate() {
                            let Some(pq) = prep.points[q][j].as_ref() else {
                                continue;
                            };
                            for dc in 0..2 {
                                let c = 2 * qc + dc;
                                let coef = m[(e, c)] * a.ped_phase[c];
                                add(coef, pq.sd(4 + 2 * dc), pq.sd(5 + 2 * dc));
                            }
                        }
                        for dc in 0..2 {
                            let coef = -a.kstar[pb][d][dc] * a.rel_phase[2 * pb + dc];
                            add(coef, point.sd(2 * dc), point.sd(2 * dc + 1));
                        }
                        out[2 * d] = var_re.sqrt().max(f64::MIN_POSITIVE);
                        out[2 * d + 1] = var_im.sqrt().max(f64::MIN_POSITIVE);
                    }
                    sigma[b][j] = Some(out);
                }
            }
        }
    }
}

/// A weighted linear least-squares fit of one group of pedestals with the
/// nonlinear scalars held fixed.
#[derive(Clone, Debug)]
pub struct LinearFit {
    /// Bearing indices of the group.
    pub group: Vec<usize>,
    /// Global indices of the fitted terms (design columns).
    pub terms: Vec<usize>,
    /// Fitted values of those terms (SI units).
    pub beta: Vec<f64>,
    /// Weighted residual sum of squares (noise-normalised, dimensionless).
    pub rss: f64,
    /// Whitened design matrix (rows = real equations).
    pub design: DMatrix<f64>,
    /// Whitened residual model − measurement of every row.
    pub residual: DVector<f64>,
    /// Speed index of every row.
    pub row_speed: Vec<usize>,
    /// Condition number of the column-normalised design.
    pub condition: f64,
}

/// The whitened regression of a group: term indices (columns), design,
/// right-hand side and the speed index of every row.
type Design = (Vec<usize>, DMatrix<f64>, DVector<f64>, Vec<usize>);

/// Builds the whitened design and right-hand side of `group`.
fn design(
    prep: &Prepared,
    model: &Model,
    nl: &[f64],
    weights: &Weights,
    group: &[usize],
) -> Result<Design> {
    let terms = model.group_terms(group);
    let speeds = Model::group_speeds(prep, group);
    let n_rows = speeds.len() * 4 * group.len();
    let mut x = DMatrix::zeros(n_rows, terms.len());
    let mut y = DVector::zeros(n_rows);
    let mut row_speed = Vec::with_capacity(n_rows);
    let mut r = 0;
    for &j in &speeds {
        let a = model.assemble(prep, group, j, nl, None).ok_or_else(|| {
            anyhow!(
                "speed {} Hz: a bearing of the group is missing",
                prep.speeds_hz[j]
            )
        })?;
        for (pb, &b) in group.iter().enumerate() {
            let s = weights.sigma[b][j].ok_or_else(|| {
                anyhow!(
                    "no noise weights for bearing {} at {} Hz",
                    prep.bearings[b],
                    prep.speeds_hz[j]
                )
            })?;
            for d in 0..2 {
                let e = 2 * pb + d;
                for (part, sd) in [(0, s[2 * d]), (1, s[2 * d + 1])] {
                    let pick = |z: Complex<f64>| if part == 0 { z.re } else { z.im };
                    for (c, (_, col)) in a.columns.iter().enumerate() {
                        x[(r, c)] = pick(col[e]) / sd;
                    }
                    y[r] = pick(a.force[e]) / sd;
                    row_speed.push(j);
                    r += 1;
                }
            }
        }
    }
    Ok((terms, x, y, row_speed))
}

/// Solves a least-squares problem with column normalisation; returns the
/// solution, residual Xβ − y and the condition number.
pub fn solve_normalised(
    x: &DMatrix<f64>,
    y: &DVector<f64>,
) -> Result<(DVector<f64>, DVector<f64>, f64)> {
    let p = x.ncols();
    if x.nrows() < p {
        bail!("{} equations for {} unknowns", x.nrows(), p);
    }
    let norms: Vec<f64> = (0..p).map(|c| x.column(c).norm()).collect();
    if let Some(c) = norms.iter().position(|&n| n == 0.0 || !n.is_finite()) {
        bail!("regression column {c} is zero or not finite: the parameter is not identifiable from these data");
    }
    let mut xn = x.clone();
    for (c, n) in norms.iter().enumerate() {
        xn.column_mut(c).scale_mut(1.0 / n);
    }
    let svd = xn.svd(true, true);
    let smax = svd.singular_values.max();
    let smin = svd.singular_values.min();
    let condition = smax / smin;
    if !(condition.is_finite() && condition < 1e13) {
        bail!("the regression is singular (condition number {condition:.3e})");
    }
    let bn = svd
        .solve(y, 0.0)
        .map_err(|e| anyhow!("least-squares solve failed: {e}"))?;
    let beta = DVector::from_iterator(p, bn.iter().zip(&norms).map(|(b, n)| b / n));
    let residual = x * &beta - y;
    Ok((beta, residual, condition))
}

/// Fits the linear parameters of `group` for fixed nonlinear values `nl`.
pub fn fit_group(
    prep: &Prepared,
    model: &Model,
    nl: &[f64],
    weights: &Weights,
    group: &[usize],
) -> Result<LinearFit> {
    let (terms, x, y, row_speed) = design(prep, model, nl, weights, group)?;
    let (beta, residual, condition) = solve_normalised(&x, &y)?;
    Ok(LinearFit {
        group: group.to_vec(),
        terms,
        beta: beta.iter().copied().collect(),
        rss: residual.norm_squared(),
        design: x,
        residual,
        row_speed,
        condition,
    })
}

/// The physically admissible interval of a nonlinear scalar over `group`'s
/// speeds. A delay is causal (τ ≥ 0: a sensor cannot read before the motion;
/// this is what tells a delay on the pedestal channels from an advance on the
/// rel channels, which the pedestal equation cannot) and at most half a period
/// at the highest speed (Ω_max·τ ≤ π, beyond which a phase is ambiguous). A
/// loss factor dissipates energy (η ≥ 0) and is below 1.
///
/// Both nulls (τ = 0, η = 0) lie on the boundary, where the Wald statistic
/// is a 50:50 mixture of χ²(0) and χ²(1); testing against χ²(1) is
/// conservative.
pub fn search_interval(prep: &Prepared, model: &Model, k: usize, group: &[usize]) -> (f64, f64) {
    match model.nonlinear[k] {
        super::model::Nonlinear::LossFactor { .. } => (0.0, 1.0),
        super::model::Nonlinear::Clearance { .. } => (
            super::bearing_table::film::LOWEST,
            super::bearing_table::film::HIGHEST,
        ),
        super::model::Nonlinear::StiffnessRatio { .. } => (
            super::bearing_table::scale::LOWEST,
            super::bearing_table::scale::HIGHEST,
        ),
        super::model::Nonlinear::Delay { .. } => {
            let f_max = Model::group_speeds(prep, group)
                .iter()
                .map(|&j| prep.speeds_hz[j])
                .fold(0.0, f64::max);
            (0.0, 0.5 / f_max.max(f64::MIN_POSITIVE))
        }
    }
}

/// The errors-in-variables criterion of `group` at nonlinear values `nl`:
/// the whitened residual sum of squares with the noise propagated at the
/// values tried (the effective variance), not at the reference fit's
/// `weights` (which give the linear parameters' first fit) [-, χ² units].
///
/// With the reference's weights held, the noise the value itself carries
/// into the equations (|K*(s)|²·σ²_rel through the bearing force) counts
/// as misfit, and the minimum moves towards the value that carries less of
/// it: a clearance ratio of 1.011-1.014 (~3 ± off 1) at an oil film under
/// the third unseen machine's noise where the true ratio is 1
/// (docs/unseen-train.md, item 6). [`profile`] minimises it; its drop from
/// a scalar's null is the likelihood ratio the scalar is tested by
/// (`super::criterion::Inference::evidence_profiled`).
pub fn gauss_helmert_rss(
    prep: &Prepared,
    model: &Model,
    nl: &[f64],
    weights: &Weights,
    group: &[usize],
) -> Result<f64> {
    let first = fit_group(prep, model, nl, weights, group)?;
    let mut beta = vec![0.0; model.terms.len()];
    for (t, v) in first.terms.iter().zip(&first.beta) {
        beta[*t] = *v;
    }
    let mut own = weights.clone();
    own.propagate_group(
        prep,
        model,
        &Params {
            beta,
            nl: nl.to_vec(),
        },
        group,
    );
    Ok(fit_group(prep, model, nl, &own, group)?.rss)
}

/// The likelihood ratio of profiled scalar `k` of `model` against its null
/// (0, every scalar's null): the drop of [`gauss_helmert_rss`] over `group`
/// from `nl` with `nl[k]` = 0 to `nl`, the linear parameters refitted at
/// both and the group's other scalars held at `nl` [χ²]. The one
/// definition the forward step, the backward check and the held-damping
/// freeing test a scalar by (`super::criterion::Inference::evidence_profiled`).
pub fn scalar_drop(
    prep: &Prepared,
    model: &Model,
    nl: &[f64],
    weights: &Weights,
    group: &[usize],
    k: usize,
) -> Result<f64> {
    let mut null = nl.to_vec();
    *null
        .get_mut(k)
        .ok_or_else(|| anyhow!("no nonlinear scalar {k}"))? = 0.0;
    Ok(gauss_helmert_rss(prep, model, &null, weights, group)?
        - gauss_helmert_rss(prep, model, nl, weights, group)?)
}

/// Profiles nonlinear scalar `k` of `model` over its search interval (grid,
/// then golden-section refinement of the best bracket), the other scalars
/// fixed at `nl`; returns the best value and its fit.
pub fn profile(
    prep: &Prepared,
    model: &Model,
    nl: &[f64],
    weights: &Weights,
    group: &[usize],
    k: usize,
    interval: (f64, f64),
) -> Result<(f64, LinearFit)> {
    const GRID: usize = 81;
    let mut values = nl.to_vec();
    let mut eval = |s: f64| -> Result<LinearFit> {
        values[k] = s;
        fit_group(prep, model, &values, weights, group)
    };
    // The value is chosen by the errors-in-variables likelihood
    // ([`gauss_helmert_rss`]).
    let objective = |s: f64| -> Result<f64> {
        let mut at = nl.to_vec();
        at[k] = s;
        gauss_helmert_rss(prep, model, &at, weights, group)
    };
    let (lo, hi) = interval;
    let step = (hi - lo) / (GRID - 1) as f64;
    let mut best: Option<(usize, f64)> = None;
    let mut grid_rss = vec![f64::INFINITY; GRID];
    for (i, g) in grid_rss.iter_mut().enumerate() {
        if let Ok(rss) = objective(lo + step * i as f64) {
            *g = rss;
            if best.is_none_or(|(_, r)| rss < r) {
                best = Some((i, rss));
            }
        }
    }
    let (ib, _) =
        best.ok_or_else(|| anyhow!("no value of the nonlinear parameter gives a solvable fit"))?;
    let (a, b) = (
        lo + step * ib.saturating_sub(1) as f64,
        lo + step * (ib + 1).min(GRID - 1) as f64,
    );
    let s = golden_section(
        |s| objective(s).unwrap_or(f64::INFINITY),
        (a, b),
        60,
        1e-12 * (hi - lo),
    );
    let fit = eval(s)?;
    Ok((s, fit))
}

/// The minimiser of `cost` on the bracket `(a, b)` by golden section: at
/// most `max_steps` steps, stopping once the bracket is no wider than
/// `width` (in `cost`'s argument units). `cost` is called in a fixed order
/// (the two inner points, then one new point per step), so a cost that
/// warm-starts from its previous call sees the same sequence every time.
pub fn golden_section(
    mut cost: impl FnMut(f64) -> f64,
    (mut a, mut b): (f64, f64),
    max_steps: usize,
    width: f64,
) -> f64 {
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = b - phi * (b - a);
    let mut d = a + phi * (b - a);
    let mut fc = cost(c);
    let mut fd = cost(d);
    for _ in 0..max_steps {
        if (b - a).abs() <= width {
            break;
        }
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - phi * (b - a);
            fc = cost(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + phi * (b - a);
            fd = cost(d);
        }
    }
    if fc < fd {
        c
    } else {
        d
    }
}

/// The whitened Jacobian [X | ∂r/∂s] of `fit` with respect to its linear
/// parameters and the group's nonlinear scalars `nl_index` (central finite
/// differences at fixed β), for the covariance of all parameters.
pub fn jacobian(
    prep: &Prepared,
    model: &Model,
    nl: &[f64],
    weights: &Weights,
    fit: &LinearFit,
    nl_index: &[usize],
) -> Result<DMatrix<f64>> {
    let p = fit.design.ncols();
    let mut j = DMatrix::zeros(fit.design.nrows(), p + nl_index.len());
    j.columns_mut(0, p).copy_from(&fit.design);
    let beta = DVector::from_column_slice(&fit.beta);
    for (c, &k) in nl_index.iter().enumerate() {
        let (lo, hi) = search_interval(prep, model, k, &fit.group);
        let h = 1e-4 * (hi - lo);
        let resid = |s: f64| -> Result<DVector<f64>> {
            let mut v = nl.to_vec();
            v[k] = s;
            let (_, x, y, _) = design(prep, model, &v, weights, &fit.group)?;
            Ok(x * &beta - y)
        };
        let plus = resid(nl[k] + h)?;
        let minus = resid(nl[k] - h)?;
        j.column_mut(p + c).copy_from(&((plus - minus) / (2.0 * h)));
    }
    Ok(j)
}
