//! The oil's viscosity following the speed: an oil-film table written at
//! the design viscosity μ_w for a film whose temperature, and so whose
//! viscosity, changes over the run (see the parent module for the constant
//! clearance correction this one extends).
//!
//! **The law.** The film's effective temperature rises over the controlled
//! inlet temperature with the shear heating: the friction power of a
//! journal is ∝ μΩ², and where the heat leaves through the bush and housing
//! (a conductance that does not depend on the speed) the rise is ∝ Ω². Over
//! the few degrees such a rise spans, Vogel's (or Walther's) law
//! ln μ = A + B/(T + C) is linear in T (Reynolds' exponential; its curvature
//! over 10 °C at 50 °C changes ln μ by under 0.01), so
//!
//! ```text
//! ln(μ(f)/μ_w) = a + b·(f/f_top)²
//! ```
//!
//! with f_top the top measured speed: a the offset at rest, a + b at the
//! top speed (the table's "design" temperature need not be the top speed's,
//! so a is free). The other limit, the heat carried away by the side flow
//! (∝ Ω), makes the rise ∝ Ω; the squared form is the one chosen here.
//!
//! **What the pedestal data see of it.** A short-bearing film's
//! coefficients are (W/c)·k̄(S) and (W/(cΩ))·c̄(S), their shape set by the
//! Sommerfeld number S ∝ μΩ/(Wc²) alone. A constant viscosity factor e^a
//! moves S as the clearance ratio ρ = e^{−a/2} does, and differs from it
//! only in the scale W/c; the pedestal equation F = K*·rel = Z_ped·ped is
//! homogeneous (a common factor on K* and on every pedestal parameter
//! changes nothing, the errors-in-variables cost included), so the
//! likelihood of the law with b = 0 is the constant clearance's exactly,
//! and the law nests the clearance correction with one parameter more, b.
//! The likelihood ratio of b is the test ([`confirmed`]); where it is not
//! significant the constant correction stays a clearance (the form of
//! session 24), where it is, the clearance is taken as drawn and the whole
//! correction as the oil's (a clearance error and a viscosity offset are
//! not separable at the pedestal level: only their Sommerfeld number is).

use super::super::data::Complex2x2;
use super::film::{film_kstar, WrittenTable};
use crate::estimate::{ml, Observation};
use plinth_shared::regression::{Parameter, PARAMETERS};

/// Widest ln-viscosity offsets and slopes searched: a, b ∈ [−LIMIT, LIMIT]
/// [-] (a viscosity between e^−1.5 = 0.22 and 4.5 times the table's, and
/// a change over the run up to that factor).
pub const LIMIT: f64 = 1.5;

/// Step of the central differences in a and b [-] (J is smooth in both).
const STEP: f64 = 2e-3;

/// ln(μ(f)/μ_w) = a + b·(f/f_top)² (see the module).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViscosityLaw {
    /// ln-viscosity offset at rest [-].
    pub a: f64,
    /// Its change from rest to the top speed [-].
    pub b: f64,
    /// The top measured speed f_top [Hz].
    pub top_hz: f64,
}

impl ViscosityLaw {
    /// (f/f_top)² [-] at `speed_hz` [Hz].
    fn x(&self, speed_hz: f64) -> f64 {
        (speed_hz / self.top_hz).powi(2)
    }

    /// μ(f)/μ_w at `speed_hz` [Hz] [-].
    pub fn factor(&self, speed_hz: f64) -> f64 {
        (self.a + self.b * self.x(speed_hz)).exp()
    }

    /// The correction K*_film(Ω; c_w, μ_w·μ(f)/μ_w) − K*_film(Ω; c_w, μ_w)
    /// [N/m] to the written table at `speed_hz` [Hz]; `None` where a film
    /// cannot be computed.
    pub fn correction(&self, table: &WrittenTable, speed_hz: f64) -> Option<Complex2x2> {
        let written = film_kstar(&table.film, speed_hz)?;
        let mut f = table.film;
        f.viscosity *= self.factor(speed_hz);
        let true_ = film_kstar(&f, speed_hz)?;
        Some(std::array::from_fn(|r| {
            std::array::from_fn(|c| true_[r][c] - written[r][c])
        }))
    }
}

/// The joint maximum-likelihood fit of a pedestal and its oil's viscosity
/// law ([`fit`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViscosityFit {
    /// The law at the estimate.
    pub law: ViscosityLaw,
    /// The lowest measured speed [Hz].
    pub bottom_hz: f64,
    /// Covariance of (a, b) used for every ± [-]: each variance the larger
    /// of the information's (2H⁻¹, scaled by J/dof when above 1) and the
    /// robust sandwich's (H⁻¹SH⁻¹), with the information's correlation.
    pub cov: [[f64; 2]; 2],
    /// θ = (k_y [N/m], k_z [N/m], m [kg], c_y [N·s/m], c_z [N·s/m]).
    pub theta: [f64; PARAMETERS],
    /// Standard errors of θ, the law's uncertainty included [θ units].
    pub std_err: [f64; PARAMETERS],
    /// The ML cost J at the estimate [-].
    pub chi2: f64,
    /// Its degrees of freedom, 4n − 7 [-].
    pub dof: usize,
    /// The ML cost with b = 0 (a constant viscosity factor: the constant
    /// clearance correction's likelihood), a and θ refitted [-].
    pub chi2_null: f64,
    /// var b from the information over var b from the sandwich [-] (as
    /// [`super::MlCorrection::robust_ratio`]).
    pub robust_ratio: f64,
}

impl ViscosityFit {
    /// μ(f)/μ_w at `speed_hz` [Hz] and its standard error [-] (delta
    /// method on ln μ).
    pub fn ratio_at(&self, speed_hz: f64) -> (f64, f64) {
        let x = self.law.x(speed_hz);
        let c = &self.cov;
        let var = c[0][0] + 2.0 * x * c[0][1] + x * x * c[1][1];
        let v = self.law.factor(speed_hz);
        (v, v * var.max(0.0).sqrt())
    }

    /// The standard error of b [-].
    pub fn b_std_err(&self) -> f64 {
        self.cov[1][1].max(0.0).sqrt()
    }
}

/// Minimises `cost` over `(lo, hi)` by golden section to a bracket of 1e-6.
fn golden(cost: impl FnMut(f64) -> f64, lo: f64, hi: f64) -> f64 {
    super::super::fit::golden_section(cost, (lo, hi), 200, 1e-6)
}

/// The maximum-likelihood fit of a pedestal on rigid ground and the
/// viscosity law of its oil-film `table` on `points` (errors-in-variables
/// cost of [`crate::estimate::ml`], θ from `start`): the profile
/// J(a, b) = min_θ J(θ, a, b), minimised by golden section over b with an
/// inner golden section over a (both on [−LIMIT, LIMIT]); also J with b = 0
/// for the likelihood ratio. ± from the curvature of the profile and the
/// sandwich of its per-speed scores, θ's including the law's,
/// cov θ = F⁻¹ + G·cov(a, b)·Gᵀ (G = dθ̂/d(a, b)). `None` when a fit fails,
/// an estimate ends at the edge of its range, or the profile is not convex
/// there.
pub fn fit(
    table: &WrittenTable,
    points: &[Observation],
    start: &[f64; PARAMETERS],
) -> Option<ViscosityFit> {
    let top_hz = points.iter().map(|p| p.speed_hz).fold(0.0, f64::max);
    let bottom_hz = points
        .iter()
        .map(|p| p.speed_hz)
        .fold(f64::INFINITY, f64::min);
    if !(top_hz > 0.0 && bottom_hz < top_hz) {
        return None;
    }
    let law = |a: f64, b: f64| ViscosityLaw { a, b, top_hz };
    let corrected = |a: f64, b: f64| -> Option<Vec<Observation>> {
        let l = law(a, b);
        points
            .iter()
            .map(|p| {
                let c = l.correction(table, p.speed_hz)?;
                let kstar =
                    std::array::from_fn(|r| std::array::from_fn(|k| p.kstar[r][k] + c[r][k]));
                Some(Observation { kstar, ..*p })
            })
            .collect()
    };
    let one = |a: f64, b: f64, from: &[f64; PARAMETERS]| -> Option<ml::MlFit> {
        let f = ml::fit(&corrected(a, b)?, &Parameter::ALL, from).ok()?;
        (f.chi2.is_finite() && f.theta.iter().all(|v| v.is_finite())).then_some(f)
    };
    // The profile over a at a given b: (â(b), J(â(b), b)), each fit
    // started from the last one's θ.
    let profile_a = |b: f64, theta: &mut [f64; PARAMETERS]| -> (f64, f64) {
        let mut cost = |a: f64| match one(a, b, theta) {
            Some(f) => {
                *theta = f.theta;
                f.chi2
            }
            None => f64::INFINITY,
        };
        let a = golden(&mut cost, -LIMIT, LIMIT);
        (a, cost(a))
    };
    let mut null_from = *start;
    let (a_null, _) = profile_a(0.0, &mut null_from);
    let mut theta = null_from;
    let b = golden(|b| profile_a(b, &mut theta).1, -LIMIT, LIMIT);
    let (a, _) = profile_a(b, &mut theta);
    let edge = |v: f64| LIMIT - v.abs() < 2.0 * STEP;
    if edge(a) || edge(b) || edge(a_null) {
        return None;
    }
    let at = one(a, b, &theta)?;
    let null = one(a_null, 0.0, &null_from)?;
    // The profile's curvature and per-speed scores by central differences.
    let h = STEP;
    let shifts = [(h, 0.0), (-h, 0.0), (0.0, h), (0.0, -h)];
    let fits = shifts
        .iter()
        .map(|&(da, db)| one(a + da, b + db, &at.theta))
        .collect::<Option<Vec<_>>>()?;
    let corners = [(h, h), (h, -h), (-h, h), (-h, -h)]
        .iter()
        .map(|&(da, db)| one(a + da, b + db, &at.theta).map(|f| f.chi2))
        .collect::<Option<Vec<_>>>()?;
    let haa = (fits[0].chi2 + fits[1].chi2 - 2.0 * at.chi2) / (h * h);
    let hbb = (fits[2].chi2 + fits[3].chi2 - 2.0 * at.chi2) / (h * h);
    let hab = (corners[0] - corners[1] - corners[2] + corners[3]) / (4.0 * h * h);
    let det = haa * hbb - hab * hab;
    if !(haa > 0.0 && det > 0.0 && det.is_finite()) {
        return None;
    }
    let hinv = [[hbb / det, -hab / det], [-hab / det, haa / det]];
    let obs = shifts
        .iter()
        .map(|&(da, db)| corrected(a + da, b + db))
        .collect::<Option<Vec<_>>>()?;
    let scores = (0..points.len())
        .map(|s| {
            let j = |i: usize| ml::cost(std::slice::from_ref(&obs[i][s]), &fits[i].theta).ok();
            let ga = (j(0)? - j(1)?) / (2.0 * h);
            let gb = (j(2)? - j(3)?) / (2.0 * h);
            (ga.is_finite() && gb.is_finite()).then(|| nalgebra::DVector::from_vec(vec![ga, gb]))
        })
        .collect::<Option<Vec<_>>>()?;
    let (s, _) = super::super::criterion::long_run_covariance(&scores, 2);
    let hi = nalgebra::Matrix2::new(hinv[0][0], hinv[0][1], hinv[1][0], hinv[1][1]);
    let sm = nalgebra::Matrix2::new(s[(0, 0)], s[(0, 1)], s[(1, 0)], s[(1, 1)]);
    let robust = hi * sm * hi;
    let dof = (4 * points.len()).checked_sub(PARAMETERS + 2)?;
    let scale = (at.chi2 / dof.max(1) as f64).max(1.0);
    let info = hi * 2.0;
    let var = [
        (scale * info[(0, 0)]).max(robust[(0, 0)]),
        (scale * info[(1, 1)]).max(robust[(1, 1)]),
    ];
    let corr = info[(0, 1)] / (info[(0, 0)] * info[(1, 1)]).sqrt();
    let cab = corr * (var[0] * var[1]).sqrt();
    let cov = [[var[0], cab], [cab, var[1]]];
    let robust_ratio = if robust[(1, 1)] > 0.0 {
        info[(1, 1)] / robust[(1, 1)]
    } else {
        1.0
    };
    let g: [[f64; 2]; PARAMETERS] = std::array::from_fn(|i| {
        [
            (fits[0].theta[i] - fits[1].theta[i]) / (2.0 * h),
            (fits[2].theta[i] - fits[3].theta[i]) / (2.0 * h),
        ]
    });
    let std_err = std::array::from_fn(|i| {
        let gi = g[i];
        let carried =
            gi[0] * gi[0] * cov[0][0] + 2.0 * gi[0] * gi[1] * cov[0][1] + gi[1] * gi[1] * cov[1][1];
        (scale * at.covariance[i][i] + carried.max(0.0)).sqrt()
    });
    Some(ViscosityFit {
        law: law(a, b),
        bottom_hz,
        cov,
        theta: at.theta,
        std_err,
        chi2: at.chi2,
        dof,
        chi2_null: null.chi2,
        robust_ratio,
    })
}

/// The text report's line under a `bearing_coefficients` step whose
/// `parameters` are a viscosity law's (written by the parent module's
/// reporting), `None` otherwise.
pub fn note(parameters: &[super::super::report::Estimate]) -> Option<String> {
    let get = |name: &str| parameters.iter().find(|p| p.name == name);
    let (top, bottom) = (get("viscosity_ratio_top")?, get("viscosity_ratio_bottom")?);
    let (f_top, f_bottom, b) = (
        get("speed_top_hz")?,
        get("speed_bottom_hz")?,
        get("viscosity_law_b")?,
    );
    Some(format!(
        "     oil viscosity ×{:.3} ± {:.3} at the top speed ({:.1} Hz), ×{:.3} ± {:.3} at the bottom ({:.1} Hz), against the table's: ln(μ/μ_table) = a + b·(f/f_top)², b = {:.3} ± {:.3} significant against a constant correction; the clearance as drawn",
        top.value, top.std_err, f_top.value, bottom.value, bottom.std_err, f_bottom.value, b.value, b.std_err
    ))
}

/// The likelihood-ratio test of the law's slope b against a constant
/// factor (the constant clearance correction): LR = (J(b = 0) − J(b̂))
/// × min(1/s, robust ratio), s = max(1, J/dof), as χ²(1) with `tried`
/// (the laws tested in the run) as the Bonferroni count at level `alpha`,
/// and the Schwarz penalty ln `n_total` (N real equations), as
/// [`super::confirmed`] tests the clearance. `Err` with the reason when it
/// is not significant.
pub fn confirmed(
    fit: &ViscosityFit,
    tried: usize,
    n_total: usize,
    alpha: f64,
) -> Result<f64, String> {
    let scale = (fit.chi2 / fit.dof.max(1) as f64).max(1.0);
    let lr = (fit.chi2_null - fit.chi2) * (1.0 / scale).min(fit.robust_ratio);
    let p = super::super::criterion::chi2_sf(lr, 1);
    let p_adjusted = (p * tried.max(1) as f64).min(1.0);
    let delta_bic = lr - (n_total.max(2) as f64).ln();
    if delta_bic > 0.0 && p_adjusted < alpha {
        Ok(lr)
    } else {
        Err(format!(
            "the oil's viscosity following the speed not significant against a constant correction: likelihood ratio {lr:.2} (ΔBIC {delta_bic:.1}, adjusted p {p_adjusted:.2e}, level {alpha})"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::super::film::tests::film;
    use super::*;
    use num_complex::Complex;

    /// Exact data of a pedestal behind a film whose oil is 30 % more
    /// viscous at rest than at the top speed (the table at the top speed's
    /// viscosity): the fit finds the law and the pedestal, and the law is
    /// significant against a constant factor.
    #[test]
    fn recovers_a_viscosity_that_follows_the_speed() {
        let drawn = film();
        let theta = [2.0e7, 1.5e7, 100.0, 2.0e3, 1.5e3];
        let truth = ViscosityLaw {
            a: 1.3f64.ln(),
            b: -(1.3f64.ln()),
            top_hz: 100.0,
        };
        let table = WrittenTable {
            film: drawn,
            file_clearance: drawn.clearance,
            misfit: 0.0,
        };
        let points: Vec<Observation> = (0..46)
            .map(|i| {
                let f = 10.0 + 2.0 * i as f64;
                let w = std::f64::consts::TAU * f;
                let rel = [Complex::new(1.0e-5, 2.0e-6), Complex::new(-3.0e-6, 8.0e-6)];
                let k0 = film_kstar(&drawn, f).expect("film");
                let c = truth.correction(&table, f).expect("film");
                let ped: [Complex<f64>; 2] = std::array::from_fn(|d| {
                    let force = (k0[d][0] + c[d][0]) * rel[0] + (k0[d][1] + c[d][1]) * rel[1];
                    force / Complex::new(theta[d] - w * w * theta[2], w * theta[3 + d])
                });
                let sd = 1.0e-3 * 1.0e-5;
                Observation {
                    speed_hz: f,
                    rel,
                    ped,
                    kstar: k0,
                    var: [sd * sd; 8],
                }
            })
            .collect();
        let got = fit(&table, &points, &theta.map(|v| 1.05 * v)).expect("fit");
        assert!((got.law.a - truth.a).abs() < 1e-4, "{:?}", got.law);
        assert!((got.law.b - truth.b).abs() < 1e-4, "{:?}", got.law);
        for ((v, want), se) in got.theta.iter().zip(theta).zip(got.std_err) {
            assert!((v / want - 1.0).abs() < 1e-4, "{v} vs {want}");
            assert!(se > 0.0 && se.is_finite());
        }
        let (top, top_se) = got.ratio_at(100.0);
        assert!((top - 1.0).abs() < 1e-4 && top_se > 0.0);
        assert!(confirmed(&got, 1, 4 * points.len(), 0.01).is_ok());
    }
}
