//! One channel in the wrong unit: one bearing's `rel_y`, `rel_z`, `ped_y`
//! or `ped_z` (the data contract's column names, docs/formats.md) s times
//! its true value, the others right (session 43, docs/robustness-hostile.md, Session 43 (unitfa17):
//! one probe in mil while the others are in µm, one pick-up in inches).
//!
//! A scale on one direction is no scale of the pedestal: the pedestal
//! equation couples the two directions through the bearing (K*_yz) and
//! shares the pedestal's mass between them, so the pedestal identified from
//! such readings is wrong in no simple way and `plinth identify` finds the
//! bearing's fit poor (session 40: 10/10 untrusted). The hypothesis
//! therefore divides that channel by s (its noise variances by s²) and
//! refits the base model's pedestal equations to the readings so corrected
//! ([`State::fit`], the weighted fit every diagnose step refits with), then
//! the machine is re-simulated and judged by the same check as every other
//! reading ([`super::passing`]).
//!
//! s is searched over the factors a field engineer meets
//! ([`super::COMMON`] and their inverses), then refined within
//! ×/÷ [`super::evidence::TOLERANCE`] of the best of them: a refit per
//! factor is too dear for the kinds' fine grid, and a one-channel scale
//! that is no unit factor is a calibration matter
//! ([`super::evidence`]). At s = 1 the hypothesis is the refit of the
//! readings as they are, so the evidence rule compares like with like.
//!
//! A channel is named only as a unit mistake (session 44,
//! docs/robustness-hostile.md, Session 44 (unit17b), [`a_unit_mistake`]): a field engineer's unit
//! mistake is a factor from the short list, so the factor found must lie
//! near one. Where the check does not find the final model, with the
//! physical effects it names, failing, naming the channel would overturn it, and the
//! data must tell the two apart: the factor within its ± (e^(ln ŝ ± 3 sd))
//! inside one listed factor's window ×/÷ 1.1 ([`window`], [`told_apart`];
//! the window excludes 1, the smallest listed factor being √2), and the
//! final model's gap failing the channel's yardstick ([`beats`]), not the
//! channel merely passing beside it. A channel whose factor is a range
//! (unseen-overhung's real `table-film`: B2 `ped_z` ÷ 0.6428 ± 8.8 %,
//! 0.49 to 0.84 within 3 ±, factors 0.49 to 0.87 pass the check) or whose
//! best factor sits at the window's edge (the optimum lies beyond it: B1
//! `rel_y` ÷ 1.5556 ± 5.9 % on `table-scale`) is no unit mistake there.

use super::evidence::{TOLERANCE, Z_EVIDENCE};
use super::{nearest_listed, refine, Kind, Reading, COMMON};
use crate::diagnose::data::Prepared;
use crate::diagnose::state::State;
use crate::diagnose::trust::MachineCheck;

/// The contract's column name of the channel `dir` (0: y, 1: z) of `kind`:
/// `rel_y` [text].
pub fn column(kind: Kind, dir: usize) -> String {
    format!("{}_{}", kind.columns(), if dir == 0 { "y" } else { "z" })
}

/// `prep` with channel `dir` of `kind` at bearing `bearing` divided by `s`
/// (its variances by s²), and the base model `state` refitted to it
/// ([`State::fit`]); `None` where the refit fails.
pub fn hypothesis(
    prep: &Prepared,
    state: &State,
    kind: Kind,
    bearing: usize,
    dir: usize,
    s: f64,
) -> Option<(Prepared, State)> {
    let mut p = prep.clone();
    let var = match kind {
        Kind::Rel => 2 * dir..2 * dir + 2,
        Kind::Ped => 4 + 2 * dir..4 + 2 * dir + 2,
    };
    for o in p.points.get_mut(bearing)?.iter_mut().flatten() {
        let x = match kind {
            Kind::Rel => &mut o.rel,
            Kind::Ped => &mut o.ped,
        };
        *x.get_mut(dir)? /= s;
        for v in &mut o.var[var.clone()] {
            *v /= s * s;
        }
    }
    let st = State::fit(&p, state.model.clone(), state.params.nl.clone()).ok()?;
    st.params
        .beta
        .iter()
        .all(|v| v.is_finite())
        .then_some((p, st))
}

/// The factors tried on one channel, as log10 s [-]: 1 and every common
/// unit factor either way.
fn candidates() -> Vec<f64> {
    let mut out = vec![0.0];
    for (f, _) in COMMON {
        out.push(f.log10());
        out.push(-f.log10());
    }
    out
}

/// The factor of `reading` (one channel) that minimises the gap `g(log10
/// s)` among [`candidates`], refined within the tolerance window around it
/// (module docs), with that gap. `None` when no factor can be simulated.
pub fn best_factor(g: impl Fn(f64) -> Option<f64>, reading: Reading) -> Option<(f64, f64)> {
    debug_assert!(reading.dir.is_some());
    // The refit of the readings as they are may leave a pedestal the
    // simulator cannot hold (a negative mass): then only the other factors
    // compete (`super::examine` takes the base model's gap as read).
    let (mut best_l, mut best_g) = (0.0, f64::INFINITY);
    for l in candidates() {
        if let Some(v) = g(l) {
            if v < best_g {
                (best_l, best_g) = (l, v);
            }
        }
    }
    if !best_g.is_finite() {
        return None;
    }
    let half = super::evidence::TOLERANCE.log10();
    Some(refine(&g, best_l, best_g, half))
}

/// The window of the listed unit factor nearest `s` (or 1/s): log10 of
/// f/[`TOLERANCE`] and f·[`TOLERANCE`] [-]; `None` when `s` is near no
/// listed factor ([`nearest_listed`]).
pub fn window(s: f64) -> Option<[f64; 2]> {
    let (f, _) = nearest_listed(s)?;
    let half = TOLERANCE.log10();
    Some([f.log10() - half, f.log10() + half])
}

/// Whether the factor `s` [-] with ln-standard-deviation `sd` [-]
/// ([`super::evidence::log_sd`]) is told apart as a unit mistake: s
/// within [`Z_EVIDENCE`] of its ± (e^(ln s ± 3 sd)) lies within the
/// [`window`] of one listed factor, and so excludes 1 (the smallest listed
/// factor is √2, its window starts at 1.29). A NaN or infinite sd tells
/// nothing apart.
pub fn told_apart(s: f64, sd: f64) -> bool {
    let Some([lo, hi]) = window(s) else {
        return false;
    };
    let (l, half) = (s.log10(), Z_EVIDENCE * sd / std::f64::consts::LN_10);
    half.is_finite() && lo < l - half && l + half < hi && (l - half > 0.0 || l + half < 0.0)
}

/// Whether a channel whose hypothesis passes with noise floor `floor` [-]
/// beats the final model that passes the check with gap `rival` [-] by the
/// evidence rule: that gap fails the channel's yardstick
/// ([`MachineCheck::of`] at `floor` does not agree). No rival (the check
/// finds the final model failing): true.
pub fn beats(rival: Option<f64>, floor: f64) -> bool {
    rival.is_none_or(|g| MachineCheck::of(g, floor) != MachineCheck::Agrees)
}

/// Whether a channel found at factor `s` [-] (ln-standard-deviation `sd`
/// [-], its hypothesis's noise floor `floor` [-]) is named as a unit
/// mistake. When the check does not find the final model failing (its gap
/// `rival` [-]), naming the channel would overturn a physical reading of
/// the run (and may untrust a diagnosis otherwise trusted): the factor
/// must be told apart from a range of scales ([`told_apart`]) and the
/// channel beat that reading by the evidence rule ([`beats`]). When the
/// check finds the final model failing, or the simulator cannot hold it
/// (`rival` `None`: no physical reading the machine file accepts; session
/// 43 asked every reading there), it is named when `s` is near a listed
/// factor ([`nearest_listed`]).
pub fn a_unit_mistake(s: f64, sd: f64, floor: f64, rival: Option<f64>) -> bool {
    match rival {
        Some(_) => told_apart(s, sd) && beats(rival, floor),
        None => nearest_listed(s).is_some(),
    }
}

#[cfg(test)]
mod tests {
    use super::{a_unit_mistake, beats, told_apart, window};
    use super::{candidates, column};
    use crate::diagnose::machine::unit_scale::Kind;

    #[test]
    fn the_channels_carry_the_contracts_names_and_the_factors_both_ways() {
        assert_eq!(column(Kind::Rel, 0), "rel_y");
        assert_eq!(column(Kind::Ped, 1), "ped_z");
        let c = candidates();
        for f in [25.4_f64, 1.0 / 25.4, 1000.0, 1.0e-3, 39.37, 1.0e6] {
            assert!(
                c.iter().any(|l| (l - f.log10()).abs() < 1e-3),
                "{f} is not tried"
            );
        }
    }

    #[test]
    fn a_channel_is_told_apart_only_within_one_listed_factors_window() {
        let [lo, hi] = window(25.9).expect("near 25.4");
        assert!((10f64.powf(lo) - 25.4 / 1.1).abs() < 1e-9);
        assert!((10f64.powf(hi) - 25.4 * 1.1).abs() < 1e-9);
        let [lo, hi] = window(0.70).expect("near 1/√2");
        assert!(10f64.powf(hi) < 1.0, "the window of 1/√2 excludes 1");
        assert!(lo < hi);
        assert_eq!(window(1.7), None, "near no listed factor");
        assert!(told_apart(25.76, 0.021), "25.76 ± 2.1 %: 24.2 to 27.4");
        assert!(!told_apart(0.6428, 0.088), "÷ 0.6428 ± 8.8 %: a range");
        assert!(!told_apart(1.5556, 0.059), "at the window's edge of √2");
        assert!(!told_apart(25.4, f64::NAN));
        assert!(!told_apart(1.7, 0.001), "near no listed factor");
        assert!(beats(None, 0.1));
        assert!(a_unit_mistake(26.5, 0.05, 0.1, None), "nothing passes");
        assert!(
            !a_unit_mistake(26.5, 0.05, 0.1, Some(10.0)),
            "± wider than the window"
        );
        assert!(a_unit_mistake(25.6, 0.02, 0.1, Some(10.0)));
        assert!(
            !a_unit_mistake(25.6, 0.02, 0.1, Some(0.05)),
            "beside a passing model"
        );
        assert!(
            !a_unit_mistake(1.7, 0.001, 0.1, None),
            "near no listed factor"
        );
        assert!(!beats(Some(0.05), 0.1), "the final model passes there too");
        assert!(beats(Some(10.0), 0.1));
    }
}
