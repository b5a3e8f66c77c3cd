//! One channel's sensitivity off: what a bearing's one-mass fit sees of a
//! gain error on one of its four channels, and what it cannot see.
//!
//! A channel read with a relative sensitivity error ε (a probe calibrated
//! on another steel than the journal's reads 5-10 % off; a pick-up's
//! sensitivity moves a few % with temperature) scales that channel's
//! phasors by 1 + ε, its phase right. In eq. 3, Z(θ)·ped = K*·rel, per
//! speed and per direction:
//!
//! - a gain common to both `rel` probes of a bearing (or both `ped`
//!   pick-ups) scales the bearing force (or the motion) of both directions
//!   alike: θ/(1 + ε) (or θ·(1 + ε)) fits the data exactly as θ fits the
//!   machine. No run can see it (the "transducers' scale" condition of
//!   [`super::conditional`]);
//! - a gain **ratio** between y and z of the same kind is seen only
//!   through what ties the two directions together in the model: the one
//!   mass m of both directions, and the bearing table's cross terms
//!   (K*_yz·rel_z in the y force; a floating-ring table has k_yz = −k_zy
//!   ≈ 0.35 k_yy). Where the pedestal's resonance lies above the run m is
//!   weakly determined and the cross terms carry it alone.
//!
//! **The linearisation** ([`linearise`]): the fit's whitened equations at
//! the fitted θ (the one definition of them, [`Rigid`], under the fit's
//! noise level, `variance_scale`, and equation error) extended by one
//! column per channel: ∂e/∂ε of e = A(θ)·D_ped(ε)⁻¹·ped − K*·D_rel(ε)⁻¹·rel
//! at ε = 0, which is minus the equations' residual with only that
//! channel's phasor kept (`rel`: +K*·rel_c; `ped`: −Z(θ)·ped_c). The shift
//! of the fitted θ per unit ε of one channel alone is b = −X⁺t (X the θ
//! columns, t the channel's; [`GainEvidence::path`]): what the "Conditional
//! on" block states per channel and what `--sensor-uncertainty` carries
//! into the ± ([`super::conditional::sensor`]).
//!
//! **The test** ([`GainEvidence::statistic`]): the two ratios, rel_y against
//! rel_z and ped_y against ped_z (the y channel's column with θ free: its
//! common part with the z channel lies in θ's span), fitted in one
//! Gauss–Newton step from ε = 0; the statistic is ε̂ᵀC⁻¹ε̂, C their
//! covariance (the Schur complement of θ, times √(χ²/dof) squared where the
//! fit leaves more than its noise, and times the long-run factor of a
//! serial correlation the noise report found, as the delay's score test is
//! deflated). Under the null it is χ²₂. **Untrusted** where it passes the
//! run's Bonferroni point ([`significant`]: χ²₂ beyond −2·ln(1 % / bearings),
//! ≤ 1 % of clean runs across bearings); the message names the ratio that
//! shows, with its value and ±. **Widened** where the data favour a ratio
//! (beyond χ²₂'s 5 % point, [`FAVOURED`], as the delay's gate opens at
//! 2σ) but it is not significant, and the ratios the data allow (their 95 %
//! ellipse) move some value by more than its ± (not excluded): every ± is
//! multiplied by the delay's widening
//! ([`crate::estimate::lack_of_fit::delay_unknown::widening`]) with ρ =
//! σ(ratios free)/σ(ratios held) and the ratios' estimate projected on the
//! value's path, √(1 + (ρ² − 1)(1 + t²)), t² = (bᵀε̂)²/(bᵀCb): the
//! root-mean-square error of the held value when the ratios are as the data
//! give them.

use super::{Identification, PedestalFit, Warning, WarningKind};
use crate::estimate::gauss_helmert::{self as gh, Equations};
use crate::estimate::lack_of_fit::delay_unknown::{information_std_errs, ratio, widening};
use crate::estimate::ml::{Rigid, Weighting};
use crate::estimate::Observation;
use nalgebra::{DMatrix, DVector};
use num_complex::Complex;
use plinth_shared::regression::{Parameter, PARAMETERS};
use serde::{Deserialize, Serialize};

/// The four channels of a bearing, in the order of [`GainEvidence::path`].
pub const CHANNELS: [&str; 4] = ["rel_y", "rel_z", "ped_y", "ped_z"];

/// The two gain ratios tested: (channel, the channel it is read against).
pub const RATIOS: [(usize, usize); 2] = [(0, 1), (2, 3)];

/// The level at which the data favour a gain ratio [-] (the gate of the
/// widening, as the delay's 2σ): χ²_k's upper 5 % point.
pub const FAVOURED_LEVEL: f64 = 0.05;

/// The family-wise false-alarm rate per run of the untrusting rule [-].
pub const RUN_LEVEL: f64 = 0.01;

/// Largest ± of a direction of the two ratios that is tested [-]: beyond
/// it the data do not estimate it (the linearisation 1/(1 + ε) ≈ 1 − ε is
/// off by a tenth of ε at ε = 10 %, within 2σ of a ± of 5 %).
pub const MAX_RATIO_STD_ERR: f64 = 0.05;

/// χ²_`dof`'s upper `level` point [-].
fn chi2_upper(level: f64, dof: usize) -> f64 {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    ChiSquared::new(dof.max(1) as f64).map_or(f64::INFINITY, |d| d.inverse_cdf(1.0 - level))
}

/// The statistic beyond which the ratios are significant in a run of
/// `bearings` bearings tested, on `dof` estimable directions [-]:
/// χ²_dof's upper RUN_LEVEL/bearings point (Bonferroni; 10.6 for two
/// bearings and two directions).
pub fn significant(bearings: usize, dof: usize) -> f64 {
    chi2_upper(RUN_LEVEL / bearings.max(1) as f64, dof)
}

/// What the data say of one bearing's channel gains (module docs;
/// `sensor_gain` in `plinth identify --json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GainEvidence {
    /// Bearing name.
    pub bearing: String,
    /// Per channel ([`CHANNELS`]), per θ = (k_y, k_z, m, c_y, c_z): the
    /// shift of the fitted value per unit relative sensitivity error of
    /// that channel alone, b = −X⁺t [SI per unit ε] (0 for a fixed value).
    pub path: [[f64; PARAMETERS]; 4],
    /// ε̂ of rel_y read against rel_z and of ped_y against ped_z: the
    /// relative sensitivity of the y channel over the z one, minus 1 [-].
    pub ratio: [f64; 2],
    /// Their ± [-].
    pub ratio_std_err: [f64; 2],
    /// Their correlation [-].
    pub ratio_correlation: f64,
    /// ε̂ᵀC⁻¹ε̂, χ²₂ under the null [-].
    pub statistic: f64,
    /// The estimable directions of the two ratios tested (0-2) [-].
    pub dof: usize,
    /// The run's significance point [`significant`] [-].
    pub threshold: f64,
    /// The point beyond which the data favour a ratio, χ²_dof at 5 % [-].
    pub favoured: f64,
    /// ρ = σ(ratios free)/σ(ratios held) per θ [-] (1 for a fixed value).
    pub rho: [f64; PARAMETERS],
    /// t² = (bᵀε̂)²/(bᵀCb) per θ, the ratios' estimate along the value's
    /// path in units of its spread [-].
    pub t_squared: [f64; PARAMETERS],
    /// `untrusted` (significant), `widened` (favoured, not excluded),
    /// `none`, or `not_judged` (the noise not measured: no noise columns).
    pub verdict: std::borrow::Cow<'static, str>,
}

impl GainEvidence {
    /// The widening factor of each ± where counted ([`widening`]) [-].
    pub fn widening(&self) -> [f64; PARAMETERS] {
        std::array::from_fn(|i| widening(self.rho[i], self.t_squared[i].sqrt(), 1.0))
    }

    /// Whether the ratios the data allow (their 95 % ellipse) move some
    /// value by more than its held ±: |bᵀε̂| + √q·√(bᵀCb) > σ_held, with
    /// bᵀCb = σ_held²(ρ² − 1) (module docs).
    pub fn excluded(&self) -> bool {
        (0..PARAMETERS).all(|i| {
            let spread = (self.rho[i] * self.rho[i] - 1.0).max(0.0).sqrt();
            spread * (self.t_squared[i].sqrt() + self.favoured.sqrt()) <= 1.0
        })
    }

    /// The ratio that shows most, in words: "rel_y reads about −5.0 ± 0.4 %
    /// relative to rel_z".
    pub fn strongest(&self) -> String {
        let z = |j: usize| {
            let v = (self.ratio[j] / self.ratio_std_err[j]).abs();
            if v.is_finite() {
                v
            } else {
                0.0
            }
        };
        let j = if z(0) >= z(1) { 0 } else { 1 };
        let (a, b) = RATIOS[j];
        format!(
            "{} reads about {:+.1} ± {:.1} % relative to {}",
            CHANNELS[a],
            100.0 * self.ratio[j],
            100.0 * self.ratio_std_err[j],
            CHANNELS[b]
        )
    }
}

/// The observations of `fit` as the fit weighed them: sorted by speed, the
/// outlier speeds left out, the variances times the fit's
/// `variance_scale`.
fn as_fitted(obs: &[Observation], outliers: &[f64], variance_scale: f64) -> Vec<Observation> {
    let scale = if variance_scale.is_finite() && variance_scale > 0.0 {
        variance_scale
    } else {
        1.0
    };
    let mut out: Vec<Observation> = obs
        .iter()
        .filter(|o| o.is_finite() && !outliers.contains(&o.speed_hz))
        .map(|o| Observation {
            var: o.var.map(|v| v * scale),
            ..*o
        })
        .collect();
    out.sort_by(|a, b| a.speed_hz.total_cmp(&b.speed_hz));
    out
}

/// `o` with only channel `c` ([`CHANNELS`]) kept, the others zero.
fn only(o: &Observation, c: usize) -> Observation {
    let zero = Complex::new(0.0, 0.0);
    let mut k = Observation {
        rel: [zero; 2],
        ped: [zero; 2],
        ..*o
    };
    match c {
        0 | 1 => k.rel[c] = o.rel[c],
        _ => k.ped[c - 2] = o.ped[c - 2],
    }
    k
}

/// The whitened system at `theta`: residual r, θ's columns X (over
/// `columns`) and the four channels' columns T (module docs); `None` where
/// a covariance cannot be factored or a number is not finite.
fn linearise(
    obs: &[Observation],
    theta: &[f64; PARAMETERS],
    columns: &[Parameter],
    weighting: &Weighting<'_>,
) -> Option<(DVector<f64>, DMatrix<f64>, DMatrix<f64>)> {
    let eq = Rigid::new(obs, weighting);
    let n = eq.speeds();
    let p = columns.len();
    let mut r = DVector::zeros(4 * n);
    let mut x = DMatrix::zeros(4 * n, p);
    let mut t = DMatrix::zeros(4 * n, 4);
    for (s, o) in obs.iter().enumerate() {
        let l = gh::whitening(&eq, s, theta)?;
        let e0 = eq.error(s, theta);
        r.rows_mut(4 * s, 4)
            .copy_from(&l.solve_lower_triangular(&e0)?);
        for (k, &c) in columns.iter().enumerate() {
            let mut at = *theta;
            at[c as usize] += 1.0;
            let col = l.solve_lower_triangular(&(eq.error(s, &at) - &e0))?;
            x.view_mut((4 * s, k), (4, 1)).copy_from(&col);
        }
        for c in 0..4 {
            let one = Rigid::new(&[only(o, c)], weighting);
            let col = l.solve_lower_triangular(&(-one.error(0, theta)))?;
            t.view_mut((4 * s, c), (4, 1)).copy_from(&col);
        }
    }
    let finite = r
        .iter()
        .chain(x.iter())
        .chain(t.iter())
        .all(|v| v.is_finite());
    finite.then_some((r, x, t))
}

/// Least-squares solution of X·b = y with X's columns scaled to unit norm
/// first (their units differ by many orders); `None` where it fails.
fn solve(x: &DMatrix<f64>, y: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let norms: Vec<f64> = x.column_iter().map(|c| c.norm()).collect();
    if !norms.iter().all(|v| v.is_finite() && *v > 0.0) {
        return None;
    }
    let mut scaled = x.clone();
    for (mut c, s) in scaled.column_iter_mut().zip(&norms) {
        c /= *s;
    }
    let mut b = scaled.svd(true, true).solve(y, 1e-13).ok()?;
    for (mut row, s) in b.row_iter_mut().zip(&norms) {
        row /= *s;
    }
    Some(b)
}

/// J(θ) = Σ eᵀΣ⁻¹e of `obs` under `weighting` with each channel's
/// sensitivity error `eps` [-] undone ([`CHANNELS`]): the phasors divided
/// by 1 + ε and their noise variances by (1 + ε)², the one definition of
/// the equations ([`Rigid`]) on what the channels would have read.
fn objective(
    obs: &[Observation],
    weighting: &Weighting<'_>,
    theta: &[f64; PARAMETERS],
    eps: [f64; 4],
) -> Option<f64> {
    let undone: Vec<Observation> = obs
        .iter()
        .map(|o| {
            let mut u = *o;
            for (c, e) in eps.iter().enumerate() {
                let g = 1.0 + e;
                match c {
                    0 | 1 => u.rel[c] /= g,
                    _ => u.ped[c - 2] /= g,
                }
                u.var[2 * c] /= g * g;
                u.var[2 * c + 1] /= g * g;
            }
            u
        })
        .collect();
    Rigid::new(&undone, weighting).objective(theta)
}

/// What the data of `obs` (one bearing, as observed) say of its channel
/// gains at the fit `fit` (module docs); `outliers` the speeds the fit left
/// out [Hz], `variance_scale` and `equation_error_sd` [N] the fit's noise
/// level and equation error, `inflation` the long-run factor of a serial
/// correlation of its residuals (1 without), `bearings` the number of
/// bearings of the run tested. `None` where a figure cannot be formed or
/// no direction of the ratios is estimable.
#[allow(clippy::too_many_arguments)]
pub fn evidence(
    fit: &PedestalFit,
    obs: &[Observation],
    outliers: &[f64],
    variance_scale: f64,
    equation_error_sd: f64,
    inflation: f64,
    bearings: usize,
) -> Option<GainEvidence> {
    let columns: Vec<Parameter> = Parameter::ALL
        .into_iter()
        .filter(|c| !fit.fixed.iter().any(|f| f == c.name()))
        .collect();
    let obs = as_fitted(obs, outliers, variance_scale);
    let p = columns.len();
    let n = obs.len();
    let dof = (4 * n).checked_sub(p + 2).filter(|&d| d > 0)? as f64;
    let theta = fit.pedestal.theta();
    let tau2 = if equation_error_sd.is_finite() {
        equation_error_sd * equation_error_sd
    } else {
        0.0
    };
    let (_, x, t) = linearise(&obs, &theta, &columns, &Weighting::equation_error(tau2))?;
    // Each channel alone: b = −X⁺t.
    let paths = -solve(&x, &t)?;
    let mut path = [[0.0; PARAMETERS]; 4];
    for c in 0..4 {
        for (k, &q) in columns.iter().enumerate() {
            path[c][q as usize] = paths[(k, c)];
        }
    }
    // The two ratios, with θ free: one Newton step of J from (θ̂, ε = 0)
    // with J's exact gradient and Hessian (module docs: J's Σ(ε) term
    // removes the errors-in-variables bias and the information a
    // Gauss–Newton form would give a direction J does not see).
    let weighting = Weighting::equation_error(tau2);
    let held_se = information_std_errs(&x)?;
    // J's gradient and Hessian over (θ free, ε_rel_y, ε_ped_y) by central
    // differences of the one definition of J (module docs), each step a
    // tenth of the value's ± (ε: 1e-3).
    let m = p + 2;
    let steps: Vec<f64> = (0..m)
        .map(|k| if k < p { 0.1 * held_se[k] } else { 1e-3 })
        .collect();
    let at = |d: &[f64]| -> Option<f64> {
        let mut th = theta;
        for (k, &c) in columns.iter().enumerate() {
            th[c as usize] += d[k];
        }
        let mut eps = [0.0; 4];
        for (j, &(a, _)) in RATIOS.iter().enumerate() {
            eps[a] = d[p + j];
        }
        objective(&obs, &weighting, &th, eps)
    };
    let zero = vec![0.0; m];
    let j0 = at(&zero)?;
    let mut grad = DVector::zeros(m);
    let mut hess = DMatrix::zeros(m, m);
    let mut plus = vec![0.0; m];
    let mut minus = vec![0.0; m];
    for k in 0..m {
        let mut d = zero.clone();
        d[k] = steps[k];
        plus[k] = at(&d)?;
        d[k] = -steps[k];
        minus[k] = at(&d)?;
        grad[k] = (plus[k] - minus[k]) / (2.0 * steps[k]);
        hess[(k, k)] = (plus[k] - 2.0 * j0 + minus[k]) / (steps[k] * steps[k]);
    }
    for k in 0..m {
        for l in (k + 1)..m {
            let mut d = zero.clone();
            d[k] = steps[k];
            d[l] = steps[l];
            let pp = at(&d)?;
            d[k] = -steps[k];
            d[l] = -steps[l];
            let mm = at(&d)?;
            // f(+,+) + f(−,−) = 2f + h_k²f_kk + h_l²f_ll + 2h_kh_lf_kl.
            let v = (pp + mm
                - 2.0 * j0
                - steps[k] * steps[k] * hess[(k, k)]
                - steps[l] * steps[l] * hess[(l, l)])
                / (2.0 * steps[k] * steps[l]);
            hess[(k, l)] = v;
            hess[(l, k)] = v;
        }
    }
    // θ profiled out: H_eff = H_εε − H_εθ·H_θθ⁻¹·H_θε, g_eff likewise.
    let h_tt = hess.view((0, 0), (p, p)).into_owned();
    let h_te = hess.view((0, p), (p, 2)).into_owned();
    let h_ee = hess.view((p, p), (2, 2)).into_owned();
    let h_tt_inv = h_tt.clone().try_inverse()?;
    let h_eff = &h_ee - h_te.transpose() * &h_tt_inv * &h_te;
    let g_eff = grad.rows(p, 2).into_owned() - h_te.transpose() * &h_tt_inv * grad.rows(0, p);
    let excess = (j0 / dof).max(1.0).sqrt() * inflation.max(1.0).sqrt();
    // Per eigen-direction of H_eff: estimable where its ± (√(2/λ)·excess)
    // is below MAX_RATIO_STD_ERR; the others (e.g. all y channels alike at
    // a bearing whose table has no cross terms: J does not change) are
    // left out and the test has that many fewer degrees of freedom.
    let eig = h_eff.clone().symmetric_eigen();
    let mut g = [0.0; 2];
    let mut statistic = 0.0;
    let mut dof_test = 0usize;
    let mut c = DMatrix::<f64>::zeros(2, 2);
    for k in 0..2 {
        let lambda = eig.eigenvalues[k];
        let v = eig.eigenvectors.column(k).into_owned();
        let sd = (2.0 / lambda).sqrt() * excess;
        if !(lambda > 0.0 && sd.is_finite() && sd <= MAX_RATIO_STD_ERR) {
            continue;
        }
        // Newton step along v: −(vᵀg)/λ; its variance sd².
        let along = -(v.dot(&g_eff)) / lambda;
        g[0] += along * v[0];
        g[1] += along * v[1];
        statistic += (along / sd).powi(2);
        c += &v * v.transpose() * (sd * sd);
        dof_test += 1;
    }
    if dof_test == 0 {
        return None;
    }
    let threshold = significant(bearings, dof_test);
    let favoured = chi2_upper(FAVOURED_LEVEL, dof_test);
    let tr = DMatrix::from_fn(4 * n, 2, |i, j| t[(i, RATIOS[j].0)]);
    let (c00, c01, c11) = (c[(0, 0)], c[(0, 1)], c[(1, 1)]);
    // ρ and t² per θ from the ratios' joint path B = −X⁺T'.
    let joint = -solve(&x, &tr)?;
    let held = held_se;
    let mut free = DMatrix::zeros(4 * n, p + 2);
    free.columns_mut(0, p).copy_from(&x);
    free.columns_mut(p, 2).copy_from(&tr);
    let free_se = information_std_errs(&free)?;
    let mut rho = [1.0; PARAMETERS];
    let mut t_squared = [0.0; PARAMETERS];
    for (k, &q) in columns.iter().enumerate() {
        let i = q as usize;
        rho[i] = ratio(held[k], free_se[k]);
        let b = [joint[(k, 0)], joint[(k, 1)]];
        let spread = b[0] * b[0] * c00 + 2.0 * b[0] * b[1] * c01 + b[1] * b[1] * c11;
        let along = b[0] * g[0] + b[1] * g[1];
        let v = along * along / spread;
        t_squared[i] = if v.is_finite() { v } else { 0.0 };
    }
    let finite = statistic.is_finite()
        && g.iter().all(|v| v.is_finite())
        && path.iter().flatten().all(|v| v.is_finite());
    if !finite {
        return None;
    }
    let mut e = GainEvidence {
        bearing: fit.bearing.clone(),
        path,
        ratio: g,
        ratio_std_err: [c00.sqrt(), c11.sqrt()],
        ratio_correlation: c01 / (c00 * c11).sqrt(),
        statistic,
        dof: dof_test,
        threshold,
        favoured,
        rho,
        t_squared,
        verdict: "none".into(),
    };
    e.verdict = if statistic > threshold {
        "untrusted"
    } else if statistic > favoured && !e.excluded() {
        "widened"
    } else {
        "none"
    }
    .into();
    Some(e)
}

/// Judges the channel gains of every ML pedestal of `identification` on
/// rigid ground from its observations in `prepared` (module docs): the
/// evidence into `identification.sensor_gain`, a significant ratio
/// untrusts the bearing ([`WarningKind::SensorGain`]), a favoured one not
/// excluded widens its ± ([`WarningKind::SensorGainNotExcluded`]).
pub fn mark(prepared: &super::data::Prepared, identification: &mut Identification) {
    if identification.estimator != "ml" {
        return;
    }
    let tested: Vec<usize> = identification
        .pedestals
        .iter()
        .enumerate()
        .filter(|(_, p)| p.base.is_none())
        .map(|(i, _)| i)
        .collect();
    let bearings = tested.len();
    let mut found = Vec::new();
    for i in tested {
        let p = &identification.pedestals[i];
        let Some(obs) = prepared
            .bearings
            .iter()
            .find(|b| b.bearing == p.bearing)
            .and_then(|b| b.observations.as_ref().ok())
        else {
            continue;
        };
        let Some(report) = identification.noise.get(&p.bearing) else {
            continue;
        };
        let inflation = report
            .serial_correlation
            .as_ref()
            .map_or(1.0, |s| crate::estimate::serial::long_run_factor(s.lag_one));
        let Some(e) = evidence(
            p,
            obs,
            &report.outlier_speeds_hz,
            report.variance_scale,
            report.equation_error_sd,
            inflation,
            bearings,
        ) else {
            continue;
        };
        // Acted on only where the noise was measured (noise columns): with
        // the level from digits or from the scatter the statistic is not
        // calibrated (docs/trust.md, Session 49 (gain17): the 12-digit
        // runs' simulator spline, unseen-eight's scatter-level runs).
        let mut e = e;
        if report.source != crate::estimate::noise::NoiseSource::Columns {
            e.verdict = "not_judged".into();
        }
        let p = &mut identification.pedestals[i];
        match e.verdict.as_ref() {
            "untrusted" => {
                p.warnings.push(Warning {
                    kind: WarningKind::SensorGain,
                    message: format!(
                        "{} {} (the y/z sensitivity ratios' statistic {:.1} > {:.1}, χ² on {} at 1 % per run across the bearings): check the probe's calibration (a probe calibrated on another steel than the journal's reads 5-10 % off; a pick-up's sensitivity moves a few % with temperature); a channel's sensitivity error goes into that direction's k and c",
                        p.bearing,
                        e.strongest(),
                        e.statistic,
                        e.threshold,
                        e.dof
                    ),
                });
                p.trusted = false;
            }
            "widened" => widen(p, &e),
            _ => {}
        }
        found.push(e);
    }
    identification.sensor_gain = found;
}

/// Multiplies `p`'s ± and covariance by `e`'s widening and says so.
fn widen(p: &mut PedestalFit, e: &GainEvidence) {
    let w = e.widening();
    p.widen_by(w);
    let widened: Vec<String> = Parameter::ALL
        .iter()
        .filter(|&&c| w[c as usize] >= 1.05)
        .map(|&c| format!("{} ±×{:.2}", c.name(), w[c as usize]))
        .collect();
    p.warnings.push(Warning {
        kind: WarningKind::SensorGainNotExcluded,
        message: format!(
            "the data do not exclude a sensitivity error between its y and z channels ({}; statistic {:.1} > {:.1}, below the {:.1} that untrusts): its ± count the ratios as unknown, multiplied by √(1 + (ρ² − 1)·(1 + t²)) ({}); the values are the fit's",
            e.strongest(),
            e.statistic,
            e.favoured,
            e.threshold,
            if widened.is_empty() {
                "every factor below 1.05".to_string()
            } else {
                widened.join(", ")
            }
        ),
    });
}

/// Under the table: one line per pedestal whose ± count a sensitivity
/// ratio as unknown; empty when none.
pub fn describe(identification: &Identification) -> String {
    identification
        .warnings_of(WarningKind::SensorGainNotExcluded)
        .map(|(bearing, w)| format!("\n{bearing}: {}\n", w.message))
        .collect()
}
