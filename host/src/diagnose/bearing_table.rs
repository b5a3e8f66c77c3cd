//! The `bearing_coefficients` effect for oil-film bearings: the table in
//! `bearings.csv` was computed for another radial clearance than the
//! machine's bearing has.
//!
//! **What is fitted.** With the bearing's geometry, lubricant and load from
//! the machine file (`crate::sim::oil_film`, short-bearing theory), the
//! clearance the written table corresponds to, c_w, is found first by
//! matching the oil-film coefficients to the table over the measured speeds
//! (no measurement enters; [`WrittenTable::matched`]). The corrected bearing
//! is then
//!
//! ```text
//! K*(Ω; ρ) = K*_table(Ω) + K*_film(Ω; ρ·c_w) − K*_film(Ω; c_w)
//! ```
//!
//! with ρ = c_true/c_written the clearance ratio: at ρ = 1 it is the table
//! (the null hypothesis is nested), and when the table is the oil film at
//! c_w it is exactly the oil film at ρ·c_w. The model profiles δ = ρ − 1 as a
//! nonlinear scalar (`super::model::Nonlinear::Clearance`).
//!
//! **Why a clearance and not free scale factors.** At the pedestal level
//! only K*/Z_pedestal is observed: multiplying the whole bearing table and
//! every pedestal parameter by one factor changes nothing. A change of
//! clearance moves the modified Sommerfeld number S_s = DΩμL³/(8Wc²) and
//! with it the *shape* of the coefficients over speed, which the data do
//! see; the scale W/c then follows from the physics. A viscosity error moves
//! only S_s, so at this level it is the clearance correction less its scale
//! and is not offered separately. Without the geometry a table error is not
//! separable from the pedestal scale (only the damping-to-stiffness ratio of
//! the table would be): it is then left to the verdict (unexplained gap).

use super::data::{Complex2x2, Prepared};
use super::model::{Nonlinear, Term};
use super::report::{Pedestal, Step};
use super::state::State;
use crate::estimate::{ml, Observation};
use crate::sim::oil_film::OilFilmBearing;
use num_complex::Complex;
use plinth_shared::regression::{Parameter, PARAMETERS};

/// Widest clearance ratios searched: ρ ∈ [1 + LOWEST, 1 + HIGHEST].
pub const LOWEST: f64 = -0.5;
/// See [`LOWEST`].
pub const HIGHEST: f64 = 1.0;

/// Relative RMS misfit of the oil film to the written table above which the
/// table is not taken for an oil-film table of this geometry [-].
pub const MATCH_TOLERANCE: f64 = 0.05;

/// A bearing table that is an oil film of known geometry at clearance
/// `film.clearance` (the written clearance c_w).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WrittenTable {
    /// The machine file's bearing with the clearance the table was written for.
    pub film: OilFilmBearing,
    /// The clearance the machine file gives [m].
    pub file_clearance: f64,
    /// Relative RMS misfit of the film at `film.clearance` to the table [-].
    pub misfit: f64,
}

/// The complex stiffness K + iΩC [N/m] of `film` at `speed_hz` [Hz].
pub fn film_kstar(film: &OilFilmBearing, speed_hz: f64) -> Option<Complex2x2> {
    let bc = film.coefficients(speed_hz).ok()?;
    let omega = std::f64::consts::TAU * speed_hz;
    Some(std::array::from_fn(|r| {
        std::array::from_fn(|c| Complex::new(bc.k[r][c], omega * bc.c[r][c]))
    }))
}

/// Σ‖K*_film − K*_table‖²/Σ‖K*_table‖² over `table` (speed [Hz], K*).
fn misfit(film: &OilFilmBearing, table: &[(f64, Complex2x2)]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (f, k) in table {
        let Some(m) = film_kstar(film, *f) else {
            return f64::INFINITY;
        };
        for r in 0..2 {
            for c in 0..2 {
                num += (m[r][c] - k[r][c]).norm_sqr();
                den += k[r][c].norm_sqr();
            }
        }
    }
    if den > 0.0 {
        (num / den).sqrt()
    } else {
        f64::INFINITY
    }
}

impl WrittenTable {
    /// Finds the clearance the written `table` (speed [Hz], K*) corresponds
    /// to for the geometry of `film` (grid over a factor 3 either side of the
    /// machine file's clearance, then golden-section refinement); `None`
    /// when no clearance reproduces the table within [`MATCH_TOLERANCE`].
    pub fn matched(film: &OilFilmBearing, table: &[(f64, Complex2x2)]) -> Option<Self> {
        if table.is_empty() || film.clearance.is_nan() || film.clearance <= 0.0 {
            return None;
        }
        let at = |ln_c: f64| {
            let mut f = *film;
            f.clearance = ln_c.exp();
            misfit(&f, table)
        };
        let c0 = film.clearance.ln();
        let (lo, hi) = (c0 - 3f64.ln(), c0 + 3f64.ln());
        const GRID: usize = 61;
        let step = (hi - lo) / (GRID - 1) as f64;
        let (ib, _) = (0..GRID)
            .map(|i| (i, at(lo + step * i as f64)))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        let (mut a, mut b) = (
            lo + step * ib.saturating_sub(1) as f64,
            lo + step * (ib + 1).min(GRID - 1) as f64,
        );
        let phi = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..60 {
            let c = b - phi * (b - a);
            let d = a + phi * (b - a);
            if at(c) < at(d) {
                b = d;
            } else {
                a = c;
            }
        }
        let ln_c = 0.5 * (a + b);
        let mut f = *film;
        f.clearance = ln_c.exp();
        let m = misfit(&f, table);
        (m <= MATCH_TOLERANCE).then_some(Self {
            film: f,
            file_clearance: film.clearance,
            misfit: m,
        })
    }

    /// The correction K*_film(ρ·c_w) − K*_film(c_w) [N/m] at `speed_hz`
    /// [Hz] for δ = ρ − 1; `None` where the film cannot be computed.
    pub fn correction(&self, speed_hz: f64, delta: f64) -> Option<Complex2x2> {
        if delta == 0.0 {
            return Some([[Complex::new(0.0, 0.0); 2]; 2]);
        }
        let written = film_kstar(&self.film, speed_hz)?;
        let mut f = self.film;
        f.clearance *= 1.0 + delta;
        let true_ = film_kstar(&f, speed_hz)?;
        Some(std::array::from_fn(|r| {
            std::array::from_fn(|c| true_[r][c] - written[r][c])
        }))
    }
}

/// The joint maximum-likelihood estimate of one pedestal and its table's
/// clearance correction ([`ml_clearance`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MlClearance {
    /// Clearance correction δ = c_true/c_written − 1 [-].
    pub delta: f64,
    /// Standard error of δ [-].
    pub delta_std_err: f64,
    /// θ = (k_y [N/m], k_z [N/m], m [kg], c_y [N·s/m], c_z [N·s/m]).
    pub theta: [f64; PARAMETERS],
    /// Standard errors of θ, δ's uncertainty included [θ units].
    pub std_err: [f64; PARAMETERS],
    /// The ML cost J (χ² of the equations) at the estimate [-].
    pub chi2: f64,
    /// Its degrees of freedom, 4n − 6 [-].
    pub dof: usize,
}

/// Step of the central differences in δ for the curvature of the profile
/// and the slope of θ̂ [-] (about a third of δ's standard error at 1 %
/// noise on the unseen machine; J is smooth in δ).
const DELTA_STEP: f64 = 1e-3;

/// The maximum-likelihood fit of a pedestal on rigid ground whose bearing
/// table `table` is corrected by δ: the profile J(δ) = min_θ J(θ, δ) of
/// the errors-in-variables cost of `crate::estimate::ml` (the estimator of
/// `plinth identify`, at the Cramér–Rao bound) on `points` with K* + the
/// correction at δ, minimised over [δ0 − half_width, δ0 + half_width]
/// (golden section; `start` θ). The least-squares profile of the search
/// (`super::fit`) weighs each equation by noise propagated at the current
/// parameters but treats the noisy pedestal motion as a regressor: at 1 %
/// noise on the unseen machine it put δ 2.5 of its σ high and every
/// pedestal parameter of that bearing 2 % low with it; this fit does not.
///
/// Standard errors: of δ from the profile's curvature, var δ = 2/J″(δ̂);
/// of θ, the fit's own at δ̂ plus what δ's uncertainty carries into it,
/// cov θ = F⁻¹ + (dθ̂/dδ)(dθ̂/dδ)ᵀ·var δ (the Schur complement of the joint
/// information: exact where the model is linear in δ); both scaled by
/// J/dof when that exceeds 1. `None` when a fit fails or the profile is
/// not convex at its minimum.
pub fn ml_clearance(
    table: &WrittenTable,
    points: &[Observation],
    start: &[f64; PARAMETERS],
    delta0: f64,
    half_width: f64,
) -> Option<MlClearance> {
    let corrected = |delta: f64| -> Option<Vec<Observation>> {
        points
            .iter()
            .map(|p| {
                let c = table.correction(p.speed_hz, delta)?;
                let kstar =
                    std::array::from_fn(|r| std::array::from_fn(|k| p.kstar[r][k] + c[r][k]));
                Some(Observation { kstar, ..*p })
            })
            .collect()
    };
    let fit = |delta: f64, from: &[f64; PARAMETERS]| -> Option<ml::MlFit> {
        let f = ml::fit(&corrected(delta)?, &Parameter::ALL, from).ok()?;
        (f.chi2.is_finite() && f.theta.iter().all(|v| v.is_finite())).then_some(f)
    };
    let lo = (delta0 - half_width).max(LOWEST);
    let hi = (delta0 + half_width).min(HIGHEST);
    if lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
        return None;
    }
    let mut theta = *start;
    let mut cost = |delta: f64| -> f64 {
        match fit(delta, &theta) {
            Some(f) => {
                theta = f.theta;
                f.chi2
            }
            None => f64::INFINITY,
        }
    };
    // Down to a bracket of 1e-7 in δ (about 40 steps over the widest one).
    let delta = super::fit::golden_section(&mut cost, (lo, hi), 200, 1e-7);
    // A minimum on the bracket's edge is no interior minimum.
    if delta - lo < 2.0 * DELTA_STEP || hi - delta < 2.0 * DELTA_STEP {
        return None;
    }
    let at = fit(delta, &theta)?;
    let plus = fit(delta + DELTA_STEP, &at.theta)?;
    let minus = fit(delta - DELTA_STEP, &at.theta)?;
    let curvature = (plus.chi2 + minus.chi2 - 2.0 * at.chi2) / (DELTA_STEP * DELTA_STEP);
    if !(curvature > 0.0 && curvature.is_finite()) {
        return None;
    }
    let dof = (4 * points.len()).checked_sub(PARAMETERS + 1)?;
    let scale = (at.chi2 / dof.max(1) as f64).max(1.0);
    let var_delta = scale * 2.0 / curvature;
    let slope: [f64; PARAMETERS] =
        std::array::from_fn(|i| (plus.theta[i] - minus.theta[i]) / (2.0 * DELTA_STEP));
    let std_err = std::array::from_fn(|i| {
        (scale * at.covariance[i][i] + slope[i] * slope[i] * var_delta).sqrt()
    });
    Some(MlClearance {
        delta,
        delta_std_err: var_delta.sqrt(),
        theta: at.theta,
        std_err,
        chi2: at.chi2,
        dof,
    })
}

/// The index in θ = (k_y, k_z, m, c_y, c_z) of a base-model term.
fn theta_index(t: Term) -> Option<usize> {
    match t {
        Term::Stiffness { dir, .. } => Some(dir),
        Term::Mass { dir: None, .. } => Some(2),
        Term::Damping { dir, .. } => Some(3 + dir),
        _ => None,
    }
}

/// Refits by maximum likelihood ([`ml_clearance`]) every bearing of the
/// final `state` whose only effect is its table's clearance correction (the
/// pedestal alone in its group, its five base terms, one nonlinear scalar:
/// the clearance), in place: the state's values (what the gap, the verdict
/// and `--machine` then use) and the `bearing_coefficients` step's
/// estimates; returns the refits (bearing index, fit) for the pedestals
/// reported ([`report_refits`]). A bearing whose refit fails keeps the
/// least-squares values.
pub fn refine(prep: &Prepared, state: &mut State, steps: &mut [Step]) -> Vec<(usize, MlClearance)> {
    let mut out = Vec::new();
    for k in 0..state.model.nonlinear.len() {
        let Nonlinear::Clearance { bearing: b } = state.model.nonlinear[k] else {
            continue;
        };
        let Some(table) = state.model.tables.get(b).copied().flatten() else {
            continue;
        };
        let alone = state.model.groups(prep.bearings.len()).contains(&vec![b]);
        let terms = state.model.group_terms(&[b]);
        let mut slots = [None; PARAMETERS];
        for &t in &terms {
            if let Some(i) = theta_index(state.model.terms[t]) {
                slots[i] = Some(t);
            }
        }
        let only_base = terms.len() == PARAMETERS && slots.iter().all(Option::is_some);
        if !(alone && only_base && state.model.group_nonlinear(&[b]) == [k]) {
            continue;
        }
        let points: Vec<Observation> = prep.points[b].iter().flatten().copied().collect();
        let start: [f64; PARAMETERS] =
            std::array::from_fn(|i| slots[i].map_or(0.0, |t| state.params.beta[t]));
        let half_width = (HIGHEST - LOWEST) / 40.0;
        let Some(fit) = ml_clearance(&table, &points, &start, state.params.nl[k], half_width)
        else {
            continue;
        };
        state.params.nl[k] = fit.delta;
        for (i, slot) in slots.iter().enumerate() {
            if let Some(t) = slot {
                state.params.beta[*t] = fit.theta[i];
            }
        }
        state.weights = super::fit::Weights::propagate(prep, &state.model, &state.params);
        out.push((b, fit));
        let kind = crate::effects::EffectKind::from_name(super::candidates::BEARING_COEFFICIENTS);
        for s in steps.iter_mut().filter(|s| {
            s.effect == super::candidates::BEARING_COEFFICIENTS
                && s.bearing == prep.bearings[b]
                && s.dropped.is_none()
        }) {
            if let Some(kind) = kind {
                s.parameters = super::summaries::as_reported(
                    &state.model,
                    b,
                    kind,
                    vec![super::report::Estimate {
                        name: "clearance_ratio".into(),
                        value: fit.delta,
                        std_err: fit.delta_std_err,
                    }],
                );
            }
        }
    }
    out
}

/// The pedestals reported after [`refine`]: each refitted bearing's values
/// and ± (δ's uncertainty included) from its maximum-likelihood refit.
pub fn report_refits(prep: &Prepared, refits: &[(usize, MlClearance)], pedestals: &mut [Pedestal]) {
    for (b, fit) in refits {
        let Some(name) = prep.bearings.get(*b) else {
            continue;
        };
        if let Some(p) = pedestals.iter_mut().find(|p| &p.bearing == name) {
            for (i, q) in Parameter::ALL.iter().enumerate() {
                p.values.insert(q.name().to_string(), fit.theta[i]);
                p.std_err.insert(q.name().to_string(), fit.std_err[i]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn film() -> OilFilmBearing {
        OilFilmBearing {
            diameter: 0.1,
            length: 0.04,
            clearance: 1.0e-4,
            viscosity: 0.02,
            load: 5.0e3,
        }
    }

    /// A table written for 85 % of the file's clearance is matched at that
    /// clearance, and the correction at ρ = 1/0.85 gives the file's film.
    #[test]
    fn matches_the_written_clearance_and_corrects_to_the_true_one() {
        let truth = film();
        let mut written = truth;
        written.clearance *= 0.85;
        let speeds: Vec<f64> = (0..40).map(|i| 10.0 + 2.0 * i as f64).collect();
        let table: Vec<(f64, Complex2x2)> = speeds
            .iter()
            .map(|&f| (f, film_kstar(&written, f).expect("film")))
            .collect();
        let t = WrittenTable::matched(&truth, &table).expect("matched");
        assert!((t.film.clearance / written.clearance - 1.0).abs() < 1e-6);
        assert!(t.misfit < 1e-6);
        let delta = 1.0 / 0.85 - 1.0;
        for (f, k) in &table {
            let corr = t.correction(*f, delta).expect("correction");
            let want = film_kstar(&truth, *f).expect("film");
            for r in 0..2 {
                for c in 0..2 {
                    let got = k[r][c] + corr[r][c];
                    assert!((got - want[r][c]).norm() <= 1e-6 * want[r][c].norm().max(1.0));
                }
            }
        }
    }

    /// A pedestal behind a bearing whose table was written for 85 % of its
    /// clearance, exact data (responses computed here from the film at the
    /// true clearance and the pedestal's impedance): the maximum-likelihood
    /// refit finds the clearance ratio and the pedestal, started off both,
    /// with finite positive standard errors.
    #[test]
    fn the_ml_refit_recovers_the_clearance_and_the_pedestal() {
        let drawn = film();
        let mut truth = drawn;
        truth.clearance /= 0.85;
        let theta = [2.0e7, 1.5e7, 100.0, 2.0e3, 1.5e3];
        let points: Vec<Observation> = (0..46)
            .map(|i| {
                let f = 10.0 + 2.0 * i as f64;
                let w = std::f64::consts::TAU * f;
                let rel = [Complex::new(1.0e-5, 2.0e-6), Complex::new(-3.0e-6, 8.0e-6)];
                let k = film_kstar(&truth, f).expect("film");
                let ped: [Complex<f64>; 2] = std::array::from_fn(|d| {
                    let force = k[d][0] * rel[0] + k[d][1] * rel[1];
                    force / Complex::new(theta[d] - w * w * theta[2], w * theta[3 + d])
                });
                let sd = 1.0e-3 * 1.0e-5;
                Observation {
                    speed_hz: f,
                    rel,
                    ped,
                    kstar: film_kstar(&drawn, f).expect("film"),
                    var: [sd * sd; 8],
                }
            })
            .collect();
        let table: Vec<(f64, Complex2x2)> = points.iter().map(|p| (p.speed_hz, p.kstar)).collect();
        let t = WrittenTable::matched(&drawn, &table).expect("matched");
        let delta = 1.0 / 0.85 - 1.0;
        let start = theta.map(|v| 1.05 * v);
        let fit = ml_clearance(&t, &points, &start, delta + 0.01, 0.0375).expect("refit");
        assert!((fit.delta - delta).abs() < 1e-5, "{} vs {delta}", fit.delta);
        for ((got, want), se) in fit.theta.iter().zip(theta).zip(fit.std_err) {
            assert!((got / want - 1.0).abs() < 1e-4, "{got} vs {want}");
            assert!(se > 0.0 && se.is_finite());
        }
        assert!(fit.delta_std_err > 0.0 && fit.delta_std_err.is_finite());
    }

    /// A table that is no oil film of this geometry is not matched.
    #[test]
    fn a_foreign_table_is_not_matched() {
        let k = Complex::new(1.0e8, 1.0e5);
        let z = Complex::new(0.0, 0.0);
        let table: Vec<(f64, Complex2x2)> = (0..20)
            .map(|i| (10.0 + 5.0 * i as f64, [[k, z], [z, k]]))
            .collect();
        assert!(WrittenTable::matched(&film(), &table).is_none());
    }
}
