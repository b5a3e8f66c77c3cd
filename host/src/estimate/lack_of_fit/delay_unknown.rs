//! A sensor delay the data do not exclude, counted in the pedestal ± as
//! unknown: one definition for `plinth identify` (the one-mass fit of each
//! bearing, [`delay_nuisance`]) and `plinth diagnose` (the final refit of a
//! group, `diagnose::ml_final::delay_unknown`).
//!
//! A delay τ on a bearing's rotor-relative probes multiplies the measured
//! bearing force by e^{−iΩτ}: the apparent pedestal impedance is
//! Z·(1 − iΩτ), i.e. the damping c − τ·(k − Ω²m) in place of c. Where the
//! pedestal's resonance lies above the band, k − Ω²m is nearly k over it and
//! τ and c trade almost one for one; only the Ω³τm curvature and the link
//! between the two directions tell them apart. A fit without τ reports c
//! with a ± conditional on τ = 0 exactly, a value the data did not give
//! (unseen-five `delay`, 150 µs on B1's probes, truth c_y 2000 N·s/m:
//! identify printed B1 `ok` with c_y 5.2-6.4 ± off where its score test did
//! not fire, docs/trust.md, Session 45 (idelay17); diagnose trusted
//! c_y −1729 ± 800, docs/unseen.md, Session 44 (sweep17b)).
//!
//! **The linearisation** ([`linearise`]): the fit's whitened equations
//! extended by a column for τ at τ = 0, at the fitted values. With the
//! covariance of the fit with τ held at zero (C_held, the Jacobian without
//! τ's column) and with τ free (C_free), each parameter's
//! ρ = σ_free/σ_held ≥ 1 (Baarda's external reliability); the held value of
//! a damping c moves by b·τ for a true delay τ, with
//! |b|·σ_τ = σ_held·√(ρ² − 1). τ̂ is one Gauss–Newton step from τ = 0.
//!
//! **Both signs are causal.** A delay on the `rel` probes is τ > 0; a
//! delay on the bearing's `ped` pick-ups delays the pedestal motion, and
//! for the relative phase of force and motion the equations see it is a
//! delay of −τ on the probes: τ < 0 (unseen-seven `ped-delay`, 200 µs on
//! B3's pick-ups: identify's score test reads τ̂ −107 … −292 ± 38 µs,
//! docs/unseen-seven.md, finding 2). The rule is two-sided: "a delay on its
//! rel probes or (τ̂ < 0) its ped pick-ups". Until session 46 (pdelay17) it
//! took τ ≥ 0 only, so a pick-up delay never opened the gate and its
//! interval was clipped away (diagnose trusted B3's c_y 3.5-10.8 ± off in
//! 20 of 23 runs).
//!
//! **Excluded** ([`counted_unknown`]): the data's interval of τ
//! (τ̂ ± [`Z_INTERVAL`]·σ_τ, widened to hold τ = 0, the sensors on time:
//! [min(0, τ̂ − 1.96σ_τ), max(0, τ̂ + 1.96σ_τ)]) moves every damping of the
//! bearing by at most its held ±: |b|·|τ|_max ≤ σ_held, i.e.
//! √(ρ² − 1)·|τ|_max/σ_τ ≤ 1, |τ|_max the interval's end farthest from
//! zero. Then nothing changes.
//!
//! **The gate** ([`evidence`]): only where the data favour a delay, with
//! the pedestal passive. A passive pedestal's damping is ≥ 0, and a delay
//! on the `rel` probes (τ > 0) lowers the apparent damping below the
//! resonance: a damping below zero can be the data's sign of a phase
//! error. But it is one only as far as a delay of the data's sign explains
//! it: a truly undamped pedestal's damping comes out below zero half the
//! time by chance, and until session 47 (undamp17) the gate opened on that
//! sign alone (the paper machine's pedestals on a 5-60 Hz run widened in
//! 40 of 40 runs, unseen-four's undamped B4 in 24 of 30 clean runs,
//! docs/trust-lack-of-fit.md, Session 47 (undamp17)). The statistic is the
//! likelihood ratio of τ with every damping of the bearing held to c ≥ 0
//! in both fits, in the linearisation: (τ̂/σ_τ)² + Σ min(0, ĉ)²/σ² with τ
//! held at zero, less min over τ of ((τ − τ̂)/σ_τ)² + Σ min(0, ĉ + b·τ)²/σ²
//! (b the damping's shift per unit τ, [`Linearised::path`]); the gate opens
//! beyond [`Z_FAVOURED`]² = 4. Where the dampings are well above zero it is
//! (τ̂/σ_τ)²: |τ̂| > 2σ_τ two-sided, 4.6 % per bearing under the null (a
//! delay a test at a family-wise level did not name but these data do not
//! call chance; unseen-six `delay`, B2's resonances inside the run, seeds
//! 3615 and 3617: τ̂ at 2.5 and 2.1 of its ±, the dampings positive and
//! 3.5-4.2 ± off in diagnose, docs/unseen-six.md; unseen-seven
//! `ped-delay`, τ̂ below zero, B3's c_y high). A damping below zero adds
//! what the τ-free fit cannot take back within the data's τ: on an
//! undamped pedestal about the nominal rate (2-8 % per bearing in a
//! Monte-Carlo of the linearised statistic, ρ 1.1-3), on a delay the
//! score test misses more than τ̂ alone (unseen-five `delay`, τ̂ 1.7-1.8
//! σ_τ with B1 c_y 1.5-2.6 of its held ± below zero: 5-10). Elsewhere the
//! delay is rarely excluded either (a stiff block's c cannot be told from
//! τ·k by any run-down: on unseen-train's B1, 900 MN/m, ρ ≈ 20), and
//! counting it there made every such damping unknown on clean runs
//! (docs/unseen.md, Session 45 (delay17): widening everywhere, measured,
//! B1 c_y ± ×20 on clean `clean-p2`); only bearings whose delay the data
//! do not exclude are widened.
//!
//! **Estimable** ([`estimable`]): where τ's interval spans more than
//! 1 rad of phase at the top speed the linearisation is not the delay's
//! effect and τ̂ ± σ_τ is no number for it; the gate and the widening are
//! the linearisation's as anywhere, and τ is printed as not estimable.
//!
//! **The widening** ([`widening`]): where counted, every reported pedestal
//! ± of the fit is multiplied by √(1 + (ρ² − 1)·(1 + (τ̂/σ_τ)²)): the
//! root-mean-square error of the held value when the true delay is as the
//! data give it (mean τ̂, of either sign, spread σ_τ): its offset b·τ has
//! mean square b²(τ̂² + σ_τ²) = σ_held²(ρ² − 1)(1 + (τ̂/σ_τ)²). At τ̂ = 0 it
//! is ρ (the ± of the fit with τ free, session 45's widening); the values
//! stay the fit's, so where the data put τ̂ away from zero the held value
//! sits b·τ̂ from the τ-free one and ρ alone does not cover it (unseen-five
//! `delay`, identify: B1 c_y 6.5 ± off with τ̂ 120 ± 39 µs, ρ 1.60, still
//! 4.1 ρ-widened ± off; docs/trust.md, Session 46 (idcoll17)). (Session 46
//! (idcoll17) took τ̂₊ = max(0, τ̂) here; a τ̂ below zero is a pick-up
//! delay, as far from the held value on its side.)

use super::super::gauss_helmert::{self as gh, Equations};
use super::delay::delay_column;
use nalgebra::{DMatrix, DVector};
use plinth_shared::regression::{Parameter, PARAMETERS};
use serde::{Deserialize, Serialize};

/// Standard normal quantile of the delay's two-sided 95 % interval [-].
pub const Z_INTERVAL: f64 = 1.96;

/// A delay the data favour: |τ̂| beyond this many of its ± [-] (two-sided:
/// τ̂ > 0 a delay on the `rel` probes, τ̂ < 0 on the `ped` pick-ups; 4.6 %
/// per bearing under the null; τ̂/σ_τ on 180 clean bearings of five ROSS
/// machines: RMS 0.98, 4 beyond 2, docs/unseen.md).
pub const Z_FAVOURED: f64 = 2.0;

/// A fit linearised with a delay at τ = 0 ([`linearise`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Linearised {
    /// One Gauss–Newton step's τ from τ = 0 [units of τ's column].
    pub tau: f64,
    /// Its ± [units of τ's column].
    pub tau_std_err: f64,
    /// Per parameter other than τ (the Jacobian's columns in order, τ's
    /// left out): its ± with τ held at zero [its unit].
    pub held: Vec<f64>,
    /// The same with τ free [its unit].
    pub free: Vec<f64>,
    /// Per parameter other than τ: b, the shift of its τ-held estimate
    /// per unit τ along the fit's equations (the τ-free fit at a given τ
    /// has it at held + b·τ; b = −X⁺t, X the Jacobian without τ's column
    /// t) [its unit per unit of τ].
    pub path: Vec<f64>,
}

/// ρ = σ_free/σ_held [-], at least 1 (1 where either is not a positive
/// finite number).
pub fn ratio(held: f64, free: f64) -> f64 {
    let r = free / held;
    if r.is_finite() {
        r.max(1.0)
    } else {
        1.0
    }
}

/// The factor [-] a reported ± is multiplied by where a delay of estimate
/// `tau` ± `tau_std_err` (one unit) is counted as unknown, the value's
/// ρ = σ_free/σ_held being `rho` (module docs, "The widening"): ≥ ρ ≥ 1;
/// 1 where a figure is not finite.
pub fn widening(rho: f64, tau: f64, tau_std_err: f64) -> f64 {
    let t = tau.abs() / tau_std_err;
    let w = (1.0 + (rho * rho - 1.0).max(0.0) * (1.0 + t * t)).sqrt();
    if w.is_finite() {
        w
    } else {
        1.0
    }
}

/// The fit whose whitened Jacobian is `jac` (rows: real equations; column
/// `j` τ's, at τ = 0) and whitened residual `resid`, linearised with τ
/// free and held (module docs); `std_errs` gives the ± of every column of
/// a whitened Jacobian from the whitened residual it is given (each tool's
/// own covariance: diagnose's floor and autocorrelation-robust one,
/// identify's [`information_std_errs`]). Both fits' ± are formed from the
/// residual after the step, resid + J·Δ (the larger model's, as an F test
/// takes its variance): the residual at τ = 0 carries the delay's own
/// signature where there is one, and an autocorrelation-robust ± from it
/// is inflated by the very effect it measures (unseen-seven `ped-delay`,
/// diagnose: σ_τ 72-187 µs from it against 38 µs from the residual after
/// the step, identify's 38-44 µs on the same runs; docs/trust.md, Session 46 (pdelay17)).
/// `None` when a covariance or the step cannot be formed or a figure is
/// not finite.
pub fn linearise(
    jac: &DMatrix<f64>,
    resid: &DVector<f64>,
    j: usize,
    mut std_errs: impl FnMut(&DMatrix<f64>, &DVector<f64>) -> Option<Vec<f64>>,
) -> Option<Linearised> {
    let p = jac.ncols();
    if j >= p || jac.nrows() != resid.len() {
        return None;
    }
    // One Gauss–Newton step of the whitened equations from τ = 0.
    let step = jac.clone().svd(true, true).solve(&(-resid), 1e-14).ok()?;
    let tau = step[j];
    let after = resid + jac * &step;
    let held_jac = jac.clone().remove_column(j);
    let path: Vec<f64> = held_jac
        .clone()
        .svd(true, true)
        .solve(&jac.column(j).into_owned(), 1e-14)
        .ok()?
        .iter()
        .map(|v| -v)
        .collect();
    let mut free = std_errs(jac, &after)?;
    let held = std_errs(&held_jac, &after)?;
    if free.len() != p || held.len() + 1 != p {
        return None;
    }
    let tau_std_err = free.remove(j);
    let finite = tau.is_finite()
        && tau_std_err.is_finite()
        && tau_std_err > 0.0
        && held.iter().chain(&free).chain(&path).all(|v| v.is_finite());
    finite.then_some(Linearised {
        tau,
        tau_std_err,
        held,
        free,
        path,
    })
}

/// A damping of the bearing as the fit with τ held at zero gives it, with
/// what the delay's linearisation says of it ([`Linearised`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeldDamping {
    /// Its τ-held value [N·s/m].
    pub value: f64,
    /// Its τ-held ± [N·s/m], from the same linearisation as σ_τ.
    pub std_err: f64,
    /// ρ = σ_free/σ_held [-] ([`ratio`]).
    pub ratio: f64,
    /// b: its shift per unit τ along the fit's equations
    /// ([`Linearised::path`]) [N·s/m per unit of τ].
    pub path: f64,
}

/// The data's evidence for a delay [-]: the likelihood-ratio statistic of
/// τ (estimate `tau` ± `tau_std_err`, one unit) with the bearing's
/// `dampings` held passive (c ≥ 0) in both fits (module docs, "The
/// gate"): (τ̂/σ_τ)² + Σ min(0, ĉ)²/σ² with τ held at zero, less
/// min over τ of ((τ − τ̂)/σ_τ)² + Σ min(0, ĉ + b·τ)²/σ² with τ free (the
/// dampings' τ-held errors taken independent given τ). (τ̂/σ_τ)² where
/// every damping is above zero by more than what the data's τ move it;
/// 0 where a figure is not finite.
pub fn evidence(tau: f64, tau_std_err: f64, dampings: &[HeldDamping]) -> f64 {
    if !(tau.is_finite() && tau_std_err.is_finite() && tau_std_err > 0.0) {
        return 0.0;
    }
    let t = tau / tau_std_err;
    // Per damping (a, β): ĉ/σ and b·σ_τ/σ; the τ-free cost in u = τ/σ_τ.
    let ab: Vec<(f64, f64)> = dampings
        .iter()
        .filter(|d| d.std_err.is_finite() && d.std_err > 0.0)
        .map(|d| (d.value / d.std_err, d.path * tau_std_err / d.std_err))
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .collect();
    let cost = |u: f64| {
        (u - t).powi(2)
            + ab.iter()
                .map(|(a, b)| (a + b * u).min(0.0).powi(2))
                .sum::<f64>()
    };
    // Its derivative is nondecreasing (a sum of convex terms) and goes
    // from −∞ to +∞: bracket its root and bisect.
    let slope = |u: f64| {
        (u - t)
            + ab.iter()
                .map(|(a, b)| b * (a + b * u).min(0.0))
                .sum::<f64>()
    };
    let (mut lo, mut hi) = (t - 1.0, t + 1.0);
    let mut width = 1.0;
    while slope(lo) > 0.0 || slope(hi) < 0.0 {
        width *= 2.0;
        if width > 1e12 {
            return 0.0;
        }
        (lo, hi) = (t - width, t + width);
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if slope(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let held = t * t + ab.iter().map(|(a, _)| a.min(0.0).powi(2)).sum::<f64>();
    let lr = held - cost(0.5 * (lo + hi));
    if lr.is_finite() {
        lr.max(0.0)
    } else {
        0.0
    }
}

/// Whether a delay of estimate `tau` ± `tau_std_err` (one unit) is counted
/// as unknown (module docs): the gate (the data favour a delay with the
/// pedestal passive: [`evidence`] beyond [`Z_FAVOURED`]²; τ̂ > 0 on the
/// `rel` probes, τ̂ < 0 on the `ped` pick-ups) and not excluded (some of
/// the bearing's `dampings` moved by more than its held ± by a τ in the
/// data's interval, which holds τ = 0).
pub fn counted_unknown(tau: f64, tau_std_err: f64, dampings: &[HeldDamping]) -> bool {
    if !(tau.is_finite() && tau_std_err.is_finite() && tau_std_err > 0.0) {
        return false;
    }
    if evidence(tau, tau_std_err, dampings) <= Z_FAVOURED * Z_FAVOURED {
        return false;
    }
    // The interval [min(0, τ̂ − 1.96σ_τ), max(0, τ̂ + 1.96σ_τ)]: its end
    // farthest from zero.
    let tau_max = (tau + Z_INTERVAL * tau_std_err)
        .max(0.0)
        .max(-(tau - Z_INTERVAL * tau_std_err).min(0.0));
    // |b|·|τ|_max > σ_held with |b|·σ_τ = σ_held·√(ρ² − 1).
    dampings.iter().any(|d| {
        d.ratio.is_finite() && (d.ratio * d.ratio - 1.0).max(0.0).sqrt() * tau_max > tau_std_err
    })
}

/// Whether the data estimate the delay at all: its 95 % interval
/// ±[`Z_INTERVAL`]·σ_τ (`tau_std_err` [s]) is at most
/// [`MAX_LINEAR_PHASE`] of phase at the run's top speed `top_speed`
/// [rad/s]. Beyond, the linearisation e^{−iΩτ} ≈ 1 − iΩτ at τ = 0 is not
/// the delay's effect over the delays the data allow, and τ̂ ± σ_τ is no
/// number for it (the paper machine's undamped pedestals on a 5-60 Hz
/// run: ± 1.8 ms, 0.68 rad at 60 Hz).
pub fn estimable(tau_std_err: f64, top_speed: f64) -> bool {
    let phase = Z_INTERVAL * tau_std_err * top_speed;
    phase.is_finite() && phase <= MAX_LINEAR_PHASE
}

/// The largest phase [rad] at the top speed the delay's interval may span
/// for τ̂ ± σ_τ to be a number ([`estimable`]): at 1 rad, e^{−iΩτ} differs
/// from its linearisation 1 − iΩτ by 0.49, half the delay's own effect.
pub const MAX_LINEAR_PHASE: f64 = 1.0;

/// The whitened Jacobian `jac`'s columns scaled to unit norm (their units
/// differ by many orders) and decomposed: (the columns' norms, the
/// singular values, Vᵀ); `None` when it has no more rows than columns, a
/// column is zero or not finite, or a singular value is below 1e-13 of
/// the largest (the information is singular). One definition for every
/// rule that reads θ̂'s information from its Jacobian.
pub fn scaled_svd(jac: &DMatrix<f64>) -> Option<(Vec<f64>, DVector<f64>, DMatrix<f64>)> {
    let (n, p) = jac.shape();
    if n <= p || p == 0 {
        return None;
    }
    let norms: Vec<f64> = jac.column_iter().map(|c| c.norm()).collect();
    if !norms.iter().all(|v| v.is_finite() && *v > 0.0) {
        return None;
    }
    let mut scaled = jac.clone();
    for (mut c, s) in scaled.column_iter_mut().zip(&norms) {
        c /= *s;
    }
    let svd = scaled.svd(false, true);
    let v_t = svd.v_t?;
    let smax = svd.singular_values.max();
    if svd.singular_values.iter().any(|&s| s <= 1e-13 * smax) {
        return None;
    }
    Some((norms, svd.singular_values, v_t))
}

/// The ± of every column of the whitened Jacobian `jac` from its
/// information (JᵀJ)⁻¹ [each column's unit] ([`scaled_svd`]); `None` when
/// it is singular or has no more rows than columns.
pub fn information_std_errs(jac: &DMatrix<f64>) -> Option<Vec<f64>> {
    let (norms, singular_values, v_t) = scaled_svd(jac)?;
    let p = norms.len();
    Some(
        (0..p)
            .map(|i| {
                let var: f64 = (0..p)
                    .map(|k| (v_t[(k, i)] / singular_values[k]).powi(2))
                    .sum();
                var.sqrt() / norms[i]
            })
            .collect(),
    )
}

/// What identify's one-mass fit of a bearing says about a delay on its
/// `rel` probes or (τ̂ < 0) its `ped` pick-ups ([`delay_nuisance`];
/// `identify --json`:
/// `noise.<bearing>.lack_of_fit.delay_unknown`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DelayNuisance {
    /// τ̂, one Gauss–Newton step from τ = 0 [µs] (below zero: a delay on
    /// the `ped` pick-ups).
    pub delay_us: f64,
    /// Its ± [µs].
    pub delay_std_us: f64,
    /// ρ = σ_free/σ_held per θ = (k_y, k_z, m, c_y, c_z) [-] (1 for a
    /// parameter the model fixes).
    pub ratio: [f64; PARAMETERS],
    /// σ_held per θ, the ± with τ held at zero from the same linearisation
    /// [SI] (0 for a parameter the model fixes).
    #[serde(default)]
    pub held_std_err: [f64; PARAMETERS],
    /// b per θ: the shift of the τ-held estimate per µs of delay
    /// ([`Linearised::path`]) [SI per µs] (0 for a fixed parameter).
    #[serde(default)]
    pub path_per_us: [f64; PARAMETERS],
    /// The run's top speed [rad/s] ([`estimable`]).
    #[serde(default)]
    pub top_speed_rad_s: f64,
}

impl DelayNuisance {
    /// The factor each of θ's ± is multiplied by where the delay is
    /// counted as unknown ([`widening`]) [-].
    pub fn widening(&self) -> [f64; PARAMETERS] {
        self.ratio
            .map(|r| widening(r, self.delay_us, self.delay_std_us))
    }

    /// The bearing's estimated dampings at the fit's `theta` (SI) as the
    /// gate and the exclusion read them ([`HeldDamping`]).
    pub fn dampings(&self, theta: &[f64; PARAMETERS]) -> Vec<HeldDamping> {
        [Parameter::Cy, Parameter::Cz]
            .iter()
            .map(|&c| c as usize)
            .filter(|&i| self.held_std_err[i] > 0.0)
            .map(|i| HeldDamping {
                value: theta[i],
                std_err: self.held_std_err[i],
                ratio: self.ratio[i],
                path: self.path_per_us[i],
            })
            .collect()
    }

    /// The data's evidence for the delay with the pedestal passive
    /// ([`evidence`]) at the fit's `theta` [-].
    pub fn evidence(&self, theta: &[f64; PARAMETERS]) -> f64 {
        evidence(self.delay_us, self.delay_std_us, &self.dampings(theta))
    }

    /// Whether the delay is counted as unknown ([`counted_unknown`]) at
    /// the fit's `theta` (SI).
    pub fn counted_unknown(&self, theta: &[f64; PARAMETERS]) -> bool {
        counted_unknown(self.delay_us, self.delay_std_us, &self.dampings(theta))
    }

    /// Whether the data estimate τ at all ([`estimable`]).
    pub fn estimable(&self) -> bool {
        estimable(self.delay_std_us * 1e-6, self.top_speed_rad_s)
    }
}

/// The linearisation (module docs) of the one-mass fit `eq` (one bearing,
/// 4 rows per speed, e = A·θ − K*·rel) at `theta` (SI) over the estimated
/// `columns`, `omega` the speeds [rad/s] (one per block of `eq`), with a
/// delay on both `rel` probes, τ in µs; the ± from the information under
/// the weights of `eq` (frozen at θ), times √(χ²/dof) where the fit leaves
/// more than them (as diagnose takes the larger of its floor and robust ±).
/// Where the noise is correlated along the run, an AR(1) of lag-one
/// correlation `serial` [-] ([`super::super::serial`]), the whitened
/// equations are first prewhitened by it
/// ([`super::super::serial::prewhitened_equations`]): τ̂, σ_τ, the ρ and the
/// paths are then the generalised fit's under that noise. Without it the
/// white-noise figures read a correlated noise's slow wander as a delay:
/// on ROSS unseen-eight `corr-noise` (ρ 0.80) τ̂/σ_τ was about three times
/// what the AR(1) allows, the gate opened and the dampings' ± were widened
/// ×8-36 (docs/estimation-scatter.md, Session 49 (corr17b)).
/// `None` where no damping is estimated or the figures cannot be formed.
pub fn delay_nuisance<E: Equations + ?Sized>(
    eq: &E,
    theta: &[f64; PARAMETERS],
    omega: &[f64],
    columns: &[Parameter],
    serial: Option<f64>,
) -> Option<DelayNuisance> {
    let n = eq.speeds();
    let p = columns.len();
    if n != omega.len()
        || !columns
            .iter()
            .any(|c| matches!(c, Parameter::Cy | Parameter::Cz))
    {
        return None;
    }
    let mut jac = DMatrix::<f64>::zeros(4 * n, p + 1);
    let mut resid = DVector::<f64>::zeros(4 * n);
    for (s, &w) in omega.iter().enumerate() {
        let l = gh::whitening(eq, s, theta)?;
        let e0 = eq.error(s, theta);
        if e0.len() != 4 {
            return None;
        }
        resid
            .rows_mut(4 * s, 4)
            .copy_from(&l.solve_lower_triangular(&e0)?);
        for (k, &c) in columns.iter().enumerate() {
            // e is linear in θ: a unit step gives the column exactly.
            let mut t = *theta;
            t[c as usize] += 1.0;
            let col = l.solve_lower_triangular(&(eq.error(s, &t) - &e0))?;
            jac.view_mut((4 * s, k), (4, 1)).copy_from(&col);
        }
        jac.view_mut((4 * s, p), (4, 1))
            .copy_from(&delay_column(eq, s, w, &l)?);
    }
    if let Some(rho) = serial {
        jac = super::super::serial::prewhitened_equations(&jac, rho);
        resid = super::super::serial::prewhitened_equations(
            &DMatrix::from_column_slice(4 * n, 1, resid.as_slice()),
            rho,
        )
        .column(0)
        .into_owned();
    }
    let dof = (4 * n).checked_sub(p + 1).filter(|&d| d > 0)? as f64;
    let excess = (resid.norm_squared() / dof).max(1.0).sqrt();
    let lin = linearise(&jac, &resid, p, |j, _| {
        information_std_errs(j).map(|v| v.into_iter().map(|s| s * excess).collect())
    })?;
    let mut ratio = [1.0; PARAMETERS];
    let mut held_std_err = [0.0; PARAMETERS];
    let mut path_per_us = [0.0; PARAMETERS];
    for (k, &c) in columns.iter().enumerate() {
        ratio[c as usize] = self::ratio(lin.held[k], lin.free[k]);
        held_std_err[c as usize] = lin.held[k];
        path_per_us[c as usize] = lin.path[k];
    }
    Some(DelayNuisance {
        delay_us: lin.tau,
        delay_std_us: lin.tau_std_err,
        ratio,
        held_std_err,
        path_per_us,
        top_speed_rad_s: omega.iter().fold(0.0, |a: f64, &w| a.max(w.abs())),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A damping of ± 1 at `value` of them, ρ `rho`, b·σ_τ/σ = √(ρ² − 1)
    /// (a delay on the rel probes lowering it below resonance, τ in units
    /// of σ_τ = 1).
    fn damping(value: f64, rho: f64) -> HeldDamping {
        HeldDamping {
            value,
            std_err: 1.0,
            ratio: rho,
            path: (rho * rho - 1.0).sqrt(),
        }
    }

    /// The gate: τ̂'s own significance where the dampings are well above
    /// zero, either sign; a damping below zero adds evidence only as far as
    /// a delay of the data's sign explains it (an undamped pedestal's
    /// chance negative damping with τ̂ near zero opens nothing); the
    /// exclusion; |τ̂| widens the same on both sides.
    #[test]
    fn the_gate_the_exclusion_and_the_widening() {
        let damped = |rho| [damping(20.0, rho)];
        // Well damped: the evidence is (τ̂/σ_τ)², the gate |τ̂| > 2 σ_τ.
        assert!((evidence(2.5, 1.0, &damped(1.6)) - 6.25).abs() < 1e-9);
        assert!(!counted_unknown(1.9, 1.0, &damped(1.6)));
        assert!(counted_unknown(2.1, 1.0, &damped(1.6)));
        // Two-sided: τ̂ below zero is a delay on the ped pick-ups.
        assert!(!counted_unknown(-1.9, 1.0, &damped(1.6)));
        assert!(counted_unknown(-2.1, 1.0, &damped(1.6)));
        // An undamped pedestal's dampings below zero by chance, τ̂ near
        // zero (the paper machine; unseen-four's B4): main's gate opened
        // on the sign alone; here the τ-free fit brings them to zero at
        // a cost of its own and the evidence stays small.
        let chance = [damping(-1.0, 1.6), damping(-0.5, 1.1)];
        assert!(evidence(0.2, 1.0, &chance) < 2.0);
        assert!(!counted_unknown(0.2, 1.0, &chance));
        // A damping below zero that the data's delay explains (unseen-five
        // `delay`: τ̂ 1.8 σ_τ, B1 c_y 2.6 of its τ-held ± below zero): the
        // evidence adds both.
        let explained = [damping(-2.6, 1.6)];
        assert!(evidence(1.8, 1.0, &explained) > 9.0);
        assert!(counted_unknown(1.8, 1.0, &explained));
        // ... but not one a delay of the data's sign would lower further.
        assert!(evidence(-1.0, 1.0, &[damping(-3.0, 1.6)]) < 4.0);
        // The interval holds zero and reaches |τ̂| + 1.96 σ_τ on τ̂'s side:
        // at τ̂ = −3, ρ 1.01 (|b|σ_τ = 0.14 σ_held) is excluded (4.96 σ_τ:
        // 0.70 σ_held), ρ 1.05 (1.59 σ_held) is not.
        assert!(!counted_unknown(-3.0, 1.0, &damped(1.01)));
        assert!(counted_unknown(-3.0, 1.0, &damped(1.05)));
        assert!(!counted_unknown(f64::NAN, 1.0, &damped(5.0)));
        assert_eq!(evidence(f64::NAN, 1.0, &damped(5.0)), 0.0);
        assert_eq!(widening(1.6, 0.0, 1.0), 1.6);
        // |τ̂| = 3 σ_τ, either side: √(1 + (ρ² − 1)·10).
        for tau in [3.0, -3.0] {
            let w = widening(1.6, tau, 1.0);
            assert!((w - (1.0 + 1.56 * 10.0f64).sqrt()).abs() < 1e-12, "{w}");
        }
        assert_eq!(ratio(2.0, 1.0), 1.0);
        // Estimable: unseen-five's 40 µs at 56 Hz is; the paper machine's
        // 1815 µs at 60 Hz (1.34 rad over the interval) is not.
        let tau = std::f64::consts::TAU;
        assert!(estimable(40e-6, tau * 56.0));
        assert!(!estimable(1815e-6, tau * 60.0));
        assert!(!estimable(f64::NAN, tau * 60.0));
    }

    /// The information ± of a straight-line fit y = a + b·x with unit
    /// noise: var(b) = 1/Σ(x − x̄)², var(a) = Σx²/(n·Σ(x − x̄)²); the delay's
    /// column at j, held and free.
    #[test]
    fn information_errors_and_the_linearisation() {
        let x = [0.0, 1.0, 2.0, 3.0, 5.0];
        let jac = DMatrix::from_fn(5, 2, |r, c| if c == 0 { 1.0 } else { x[r] });
        let se = information_std_errs(&jac).expect("se");
        let mean = x.iter().sum::<f64>() / 5.0;
        let sxx: f64 = x.iter().map(|v| (v - mean).powi(2)).sum();
        let sx2: f64 = x.iter().map(|v| v * v).sum();
        assert!((se[1] - (1.0 / sxx).sqrt()).abs() < 1e-12);
        assert!((se[0] - (sx2 / (5.0 * sxx)).sqrt()).abs() < 1e-12);
        // Residual 2 + 0.5·x: the step from zero is (−2, −0.5); b is τ.
        let resid = DVector::from_iterator(5, x.iter().map(|v| 2.0 + 0.5 * v));
        let lin = linearise(&jac, &resid, 1, |j, _| information_std_errs(j)).expect("lin");
        assert!((lin.tau + 0.5).abs() < 1e-12);
        assert!((lin.tau_std_err - se[1]).abs() < 1e-12);
        assert!((lin.free[0] - se[0]).abs() < 1e-12);
        assert!((lin.held[0] - (1.0f64 / 5.0).sqrt()).abs() < 1e-12);
        // The intercept held alone absorbs the slope column's mean: b = −x̄.
        assert!((lin.path[0] + mean).abs() < 1e-12, "{:?}", lin.path);
        assert!(information_std_errs(&DMatrix::from_element(3, 2, 1.0)).is_none());
    }
}
