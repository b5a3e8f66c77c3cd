//! One channel in the wrong unit: one bearing's `rel_y`, `rel_z`, `ped_y`
//! or `ped_z` (the data contract's column names, docs/formats.md) s times
//! its true value, the others right (session 43, docs/session43-unitfa17.md:
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

use super::{refine, Kind, Reading, COMMON};
use crate::diagnose::data::Prepared;
use crate::diagnose::state::State;

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

#[cfg(test)]
mod tests {
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
}
