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
//! **The gate**: only where a damping of the bearing comes out below zero,
//! or where the data favour a delay (|τ̂| > [`Z_FAVOURED`]·σ_τ, two-sided:
//! a delay a test at a family-wise level did not name but these data do not
//! call chance; unseen-six `delay`, B2's resonances inside the run, seeds
//! 3615 and 3617: τ̂ at 2.5 and 2.1 of its ±, the dampings positive and
//! 3.5-4.2 ± off in diagnose, docs/unseen-six.md; unseen-seven
//! `ped-delay`, τ̂ below zero, B3's c_y high). A passive pedestal's
//! damping is ≥ 0, and a delay on the `rel` probes (τ > 0) lowers the
//! apparent damping below the resonance: a negative estimate is the data's
//! sign of a phase error. Elsewhere the delay is rarely excluded either (a
//! stiff block's c cannot be told from τ·k by any run-down: on
//! unseen-train's B1, 900 MN/m, ρ ≈ 20), and counting it there made every
//! such damping unknown on clean runs (docs/unseen.md, Session 45
//! (delay17): widening everywhere, measured, B1 c_y ± ×20 on clean
//! `clean-p2`). Two-sided, the gate's false-alarm rate per bearing under
//! the null is twice the one-sided 2.3 %: 4.6 %, and only bearings whose
//! delay the data do not exclude are widened (measured in
//! docs/trust.md, Session 46 (pdelay17)).
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
    let mut free = std_errs(jac, &after)?;
    let held = std_errs(&jac.clone().remove_column(j), &after)?;
    if free.len() != p || held.len() + 1 != p {
        return None;
    }
    let tau_std_err = free.remove(j);
    let finite = tau.is_finite()
        && tau_std_err.is_finite()
        && tau_std_err > 0.0
        && held.iter().chain(&free).all(|v| v.is_finite());
    finite.then_some(Linearised {
        tau,
        tau_std_err,
        held,
        free,
    })
}

/// Whether a delay of estimate `tau` ± `tau_std_err` (one unit) is counted
/// as unknown (module docs): the gate (`negative`: a damping of the bearing
/// below zero, or |τ̂| > [`Z_FAVOURED`]·σ_τ: τ̂ > 0 on the `rel` probes,
/// τ̂ < 0 on the `ped` pick-ups) and not excluded (some damping of the
/// bearing, its ρ in `damping_ratios`, moved by more than its held ± by a
/// τ in the data's interval, which holds τ = 0).
pub fn counted_unknown(
    tau: f64,
    tau_std_err: f64,
    damping_ratios: impl IntoIterator<Item = f64>,
    negative: bool,
) -> bool {
    if !(tau.is_finite() && tau_std_err.is_finite() && tau_std_err > 0.0) {
        return false;
    }
    if !negative && tau.abs() <= Z_FAVOURED * tau_std_err {
        return false;
    }
    // The interval [min(0, τ̂ − 1.96σ_τ), max(0, τ̂ + 1.96σ_τ)]: its end
    // farthest from zero.
    let tau_max = (tau + Z_INTERVAL * tau_std_err)
        .max(0.0)
        .max(-(tau - Z_INTERVAL * tau_std_err).min(0.0));
    // |b|·|τ|_max > σ_held with |b|·σ_τ = σ_held·√(ρ² − 1).
    damping_ratios
        .into_iter()
        .any(|r| r.is_finite() && (r * r - 1.0).max(0.0).sqrt() * tau_max > tau_std_err)
}

/// The ± of every column of the whitened Jacobian `jac` from its
/// information (JᵀJ)⁻¹ [each column's unit], the columns scaled to unit
/// norm first (their units differ by many orders); `None` when it is
/// singular or has no more rows than columns.
pub fn information_std_errs(jac: &DMatrix<f64>) -> Option<Vec<f64>> {
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
    Some(
        (0..p)
            .map(|i| {
                let var: f64 = (0..p)
                    .map(|k| (v_t[(k, i)] / svd.singular_values[k]).powi(2))
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
}

impl DelayNuisance {
    /// The factor each of θ's ± is multiplied by where the delay is
    /// counted as unknown ([`widening`]) [-].
    pub fn widening(&self) -> [f64; PARAMETERS] {
        self.ratio
            .map(|r| widening(r, self.delay_us, self.delay_std_us))
    }

    /// Whether the delay is counted as unknown ([`counted_unknown`]) where
    /// `negative` says whether a damping of the bearing's reported fit is
    /// below zero.
    pub fn counted_unknown(&self, negative: bool) -> bool {
        counted_unknown(
            self.delay_us,
            self.delay_std_us,
            [
                self.ratio[Parameter::Cy as usize],
                self.ratio[Parameter::Cz as usize],
            ],
            negative,
        )
    }
}

/// The linearisation (module docs) of the one-mass fit `eq` (one bearing,
/// 4 rows per speed, e = A·θ − K*·rel) at `theta` (SI) over the estimated
/// `columns`, `omega` the speeds [rad/s] (one per block of `eq`), with a
/// delay on both `rel` probes, τ in µs; the ± from the information under
/// the weights of `eq` (frozen at θ), times √(χ²/dof) where the fit leaves
/// more than them (as diagnose takes the larger of its floor and robust ±).
/// `None` where no damping is estimated or the figures cannot be formed.
pub fn delay_nuisance<E: Equations + ?Sized>(
    eq: &E,
    theta: &[f64; PARAMETERS],
    omega: &[f64],
    columns: &[Parameter],
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
    let dof = (4 * n).checked_sub(p + 1).filter(|&d| d > 0)? as f64;
    let excess = (resid.norm_squared() / dof).max(1.0).sqrt();
    let lin = linearise(&jac, &resid, p, |j, _| {
        information_std_errs(j).map(|v| v.into_iter().map(|s| s * excess).collect())
    })?;
    let mut ratio = [1.0; PARAMETERS];
    for (k, &c) in columns.iter().enumerate() {
        ratio[c as usize] = self::ratio(lin.held[k], lin.free[k]);
    }
    Some(DelayNuisance {
        delay_us: lin.tau,
        delay_std_us: lin.tau_std_err,
        ratio,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exclusion and the gate: a delay whose interval moves no damping
    /// by its ± is excluded; one that does counts only with a negative
    /// damping or |τ̂| beyond 2 σ_τ, either sign; τ̂ = 0 leaves the
    /// widening at ρ, |τ̂| widens it the same on both sides.
    #[test]
    fn the_gate_the_exclusion_and_the_widening() {
        // ρ 1.1: |b|σ_τ = 0.458 σ_held; τ_max = 1.96 σ_τ at τ̂ = 0 moves c
        // by 0.90 σ_held: excluded even with a negative damping.
        assert!(!counted_unknown(0.0, 1.0, [1.1], true));
        // ρ 1.6: 1.25 σ_held per σ_τ: not excluded, counted only where gated.
        assert!(counted_unknown(0.0, 1.0, [1.6], true));
        assert!(!counted_unknown(1.9, 1.0, [1.6], false));
        assert!(counted_unknown(2.1, 1.0, [1.6], false));
        // Two-sided: τ̂ below zero is a delay on the ped pick-ups, causal
        // too; the gate opens at |τ̂| > 2 σ_τ on either side.
        assert!(!counted_unknown(-1.9, 1.0, [1.6], false));
        assert!(counted_unknown(-2.1, 1.0, [1.6], false));
        assert!(counted_unknown(-3.0, 1.0, [5.0], true));
        // The interval holds zero and reaches |τ̂| + 1.96 σ_τ on τ̂'s side:
        // ρ 1.05 (|b|σ_τ = 0.32 σ_held) is excluded at τ̂ = −1 (|τ|_max
        // 2.96: 0.95 σ_held), not at τ̂ = −2.5 (4.46: 1.43 σ_held).
        assert!(!counted_unknown(-1.0, 1.0, [1.05], true));
        assert!(counted_unknown(-2.5, 1.0, [1.05], false));
        assert!(!counted_unknown(f64::NAN, 1.0, [5.0], true));
        assert_eq!(widening(1.6, 0.0, 1.0), 1.6);
        // |τ̂| = 3 σ_τ, either side: √(1 + (ρ² − 1)·10).
        for tau in [3.0, -3.0] {
            let w = widening(1.6, tau, 1.0);
            assert!((w - (1.0 + 1.56 * 10.0f64).sqrt()).abs() < 1e-12, "{w}");
        }
        assert_eq!(ratio(2.0, 1.0), 1.0);
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
        assert!(information_std_errs(&DMatrix::from_element(3, 2, 1.0)).is_none());
    }
}
