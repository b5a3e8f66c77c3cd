//! What the data exclude of a sub-base whose own modes lie above the run:
//! how far the pedestal's own k and m could lie from the printed ones.
//!
//! A pedestal (k, m) on a sub-base (K_S, M_S) to ground moves, per
//! direction, with the dynamic stiffness (damping left out, it does not
//! change the orders below)
//!
//! D(Ω) = k − Ω²m − k²/(k + K_S − Ω²M_S),
//!
//! whose expansion below the sub-base's own mode ω_s² = (k + K_S)/M_S (the
//! sub-base moving with the pedestal held at the bearing) is
//! K − Ω²M − Ω⁴Q − … with K = k·K_S/(k + K_S) the series stiffness,
//! M = m + M_S·r² (r = k/(k + K_S)) and Q = M_S²r²/(k + K_S)
//! (docs/diagnose-sub-base.md, session 27). One mass on one spring follows
//! the first two terms: the printed k and m are K and M, the support as a
//! whole. With s = K_S/k the sub-base's stiffness ratio,
//!
//! - the pedestal's own stiffness is k = K·(1 + 1/s): the printed one is
//!   short by the sub-base's share of the compliance, 1/(1 + s);
//! - the Ω⁴ share of the stiffness at the top speed Ω_t is
//!   δ = Ω_t⁴Q/K = (Ω_t/ω_s)⁴/s, the one number of the sub-base the run
//!   sees (the support-mode test's `drop_at_top`);
//! - the pedestal's own mass is m = M − M_S·r² = M − K/(s·ω_s²).
//!
//! So a sub-base the data leave possible (δ at most δ̄, the one-sided 95 %
//! upper bound of the Ω⁴ share, max(δ̂, 0) + 1.645σ_δ) whose own mode lies
//! at f_s has 1/s ≤ δ̄·(f_s/f_t)⁴, and to first order in the expansion
//!
//! k_own/k − 1 ≤ δ̄·(f_s/f_t)⁴,  (m − m_own)/m ≤ δ̄·(f_a·f_s)²/f_t⁴
//!
//! (f_a = √(K/M)/2π the printed pedestal's own frequency). Nothing bounds
//! a sub-base whose mode lies far enough above the run (f_s → ∞: a spring
//! without mass in series is invisible at any noise): the data can only
//! say up to which mode a sub-base holding a given share of the compliance
//! would have been seen. That frequency, for a 10 % excess of k
//! ([`HIDDEN_EXCESS`]), is f_t·(0.1/δ̄)^¼.

use crate::estimate::lack_of_fit::SupportMode;
use serde::Serialize;

/// One-sided 95 % point of the standard normal: the upper bound of the Ω⁴
/// share is max(δ̂, 0) plus this many of its standard errors [-].
pub const UPPER_Z: f64 = 1.645;

/// The excess k_own/k − 1 whose hiding frequency is reported
/// ([`SubBaseBound::mode_hiding_hz`]) [-].
pub const HIDDEN_EXCESS: f64 = 0.10;

/// The sub-base mode, as a multiple of the top speed, at which the largest
/// excesses are reported ([`SubBaseBound::stiffness_excess`]) [-].
pub const MODE_OVER_TOP: f64 = 2.0;

/// What one bearing's data exclude of a sub-base above the run (module
/// docs); per direction y, z.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SubBaseBound {
    /// Bearing name.
    pub bearing: String,
    /// Highest speed fitted f_t [Hz].
    pub top_speed_hz: f64,
    /// δ̄: the one-sided 95 % upper bound of the Ω⁴ share of the stiffness
    /// at f_t, max(δ̂, 0) + 1.645σ_δ (the support-mode test's) [-].
    pub omega4_share_upper: [f64; 2],
    /// The lowest own mode f_s of a sub-base that could leave the
    /// pedestal's own k more than 10 % above the printed k unseen,
    /// f_t·(0.1/δ̄)^¼ [Hz]: below it such a sub-base is excluded (95 %).
    pub mode_hiding_hz: [f64; 2],
    /// The largest k_own/k − 1 of a sub-base whose mode lies at twice the
    /// top speed, δ̄·2⁴ [-].
    pub stiffness_excess: [f64; 2],
    /// The largest (m − m_own)/m of that sub-base, δ̄·(f_a·f_s)²/f_t⁴
    /// (at most 1) [-].
    pub mass_excess: [f64; 2],
}

/// The largest k_own/k − 1 [-] a sub-base of own mode `mode_hz` [Hz] can
/// hide under a run to `top_hz` [Hz] whose Ω⁴ share of the stiffness is
/// at most `delta` [-] (module docs).
pub fn stiffness_excess(delta: f64, mode_hz: f64, top_hz: f64) -> f64 {
    delta * (mode_hz / top_hz).powi(4)
}

/// The largest (m − m_own)/m [-] that sub-base can hide, the printed
/// pedestal's own frequency being `f_a_hz` [Hz] (at most 1: m_own ≥ 0).
pub fn mass_excess(delta: f64, f_a_hz: f64, mode_hz: f64, top_hz: f64) -> f64 {
    (delta * (f_a_hz * mode_hz).powi(2) / top_hz.powi(4)).min(1.0)
}

/// The bound of a pedestal printed with stiffnesses `k` [N/m] (y, z) and
/// masses `m` [kg] (y, z: the same mass twice unless it is split), fitted
/// up to `top_hz` [Hz], from its support-mode test `t`; `None` where a
/// number needed is not finite or not positive.
pub fn bound(
    bearing: &str,
    k: [f64; 2],
    m: [f64; 2],
    top_hz: f64,
    t: &SupportMode,
) -> Option<SubBaseBound> {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    if !(ok(top_hz) && k.iter().chain(&m).all(|&v| ok(v))) {
        return None;
    }
    let mut upper = [0.0; 2];
    for (d, u) in upper.iter_mut().enumerate() {
        let (drop, se) = (t.drop_at_top[d], t.drop_at_top_std_err[d]);
        if !(drop.is_finite() && ok(se)) {
            return None;
        }
        *u = drop.max(0.0) + UPPER_Z * se;
    }
    let mode = MODE_OVER_TOP * top_hz;
    let f_a = |d: usize| (k[d] / m[d]).sqrt() / std::f64::consts::TAU;
    Some(SubBaseBound {
        bearing: bearing.to_string(),
        top_speed_hz: top_hz,
        omega4_share_upper: upper,
        mode_hiding_hz: upper.map(|u| top_hz * (HIDDEN_EXCESS / u).powf(0.25)),
        stiffness_excess: upper.map(|u| stiffness_excess(u, mode, top_hz)),
        mass_excess: std::array::from_fn(|d| mass_excess(upper[d], f_a(d), mode, top_hz)),
    })
}

impl SubBaseBound {
    /// One line for people.
    pub fn message(&self) -> String {
        let pct = |v: [f64; 2]| format!("{:.1} % (y), {:.1} % (z)", 100.0 * v[0], 100.0 * v[1]);
        format!(
            "{}: the Ω⁴ share of its stiffness at the top speed {:.1} Hz is at most {} (95 %); a sub-base whose own mode lies at {:.0} Hz ({MODE_OVER_TOP:.0}× the top speed) could leave the pedestal's own k up to {} above the printed k and its m up to {} below the printed m; one hiding more than {:.0} % of k is excluded only with its mode below {:.0} Hz (y), {:.0} Hz (z)",
            self.bearing,
            self.top_speed_hz,
            pct(self.omega4_share_upper),
            MODE_OVER_TOP * self.top_speed_hz,
            pct(self.stiffness_excess),
            pct(self.mass_excess),
            100.0 * HIDDEN_EXCESS,
            self.mode_hiding_hz[0],
            self.mode_hiding_hz[1]
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    /// The bound against the exact two-mass chain: a pedestal (2e8 N/m,
    /// 800 kg) on a sub-base (3e8 N/m, 400 kg), run to 50 Hz (unseen-seven's
    /// B1 in y). With δ the chain's own Ω⁴ share and f_s its own sub-base
    /// mode, the bound holds the pedestal's own k and m (to the expansion's
    /// order), and the apparent values are the series stiffness and
    /// m + M_S·r².
    #[test]
    fn the_chain_is_within_its_bound_at_its_own_mode() {
        let (k, m, ks, ms) = (2e8, 800.0, 3e8, 400.0);
        let top = 50.0;
        let s = ks / k;
        let series = k * ks / (k + ks);
        let r = k / (k + ks);
        let apparent_m = m + ms * r * r;
        let q = ms * ms * r * r / (k + ks);
        let delta = (TAU * top).powi(4) * q / series;
        let f_s = ((k + ks) / ms).sqrt() / TAU;
        // δ = (f_t/f_s)⁴/s exactly.
        assert!((delta - (top / f_s).powi(4) / s).abs() < 1e-12);
        let own_excess = k / series - 1.0;
        assert!((stiffness_excess(delta, f_s, top) / own_excess - 1.0).abs() < 1e-9);
        let f_a = (series / apparent_m).sqrt() / TAU;
        let own_mass = (apparent_m - m) / apparent_m;
        assert!((mass_excess(delta, f_a, f_s, top) / own_mass - 1.0).abs() < 1e-9);
        // A larger δ̄ bounds it; a sub-base of the same δ with a lower mode
        // hides less.
        assert!(stiffness_excess(1.5 * delta, f_s, top) > own_excess);
        assert!(stiffness_excess(delta, 0.8 * f_s, top) < own_excess);
    }

    #[test]
    fn the_bound_reads_the_tests_figures() {
        let t = SupportMode {
            statistic: 1.0,
            p_value: 0.3,
            drop_at_top: [-0.002, 0.004],
            drop_at_top_std_err: [0.003, 0.005],
        };
        let b = bound("B1", [1.2e8, 4.8e7], [870.0, 870.0], 50.0, &t).expect("bound");
        // y: max(−0.2 %, 0) + 1.645·0.3 %; z: 0.4 % + 1.645·0.5 %.
        assert!((b.omega4_share_upper[0] - 0.004935).abs() < 1e-12);
        assert!((b.omega4_share_upper[1] - 0.012225).abs() < 1e-12);
        assert!((b.stiffness_excess[0] - 16.0 * 0.004935).abs() < 1e-12);
        let hide = 50.0 * (0.1f64 / 0.004935).powf(0.25);
        assert!((b.mode_hiding_hz[0] - hide).abs() < 1e-9);
        assert!(b.mass_excess.iter().all(|&v| v > 0.0 && v <= 1.0));
        assert!(b.message().contains("B1"));
        let mut bad = t;
        bad.drop_at_top_std_err[1] = f64::NAN;
        assert!(bound("B1", [1.2e8, 4.8e7], [870.0, 870.0], 50.0, &bad).is_none());
        assert!(bound("B1", [-1.0, 4.8e7], [870.0, 870.0], 50.0, &t).is_none());
    }
}
