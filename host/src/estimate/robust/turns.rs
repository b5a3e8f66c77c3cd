//! A lightly damped mode passing between two logged speeds told from a
//! keyphasor flip ([`resonance_turns`]).
//!
//! Where a mode's half-power band is narrower than the speed step, one
//! logged speed catches the mode near its peak and its neighbours do not:
//! at a bearing near the mode's node, where the mode shows only there, the
//! reading turns by most of 180° against its neighbouring speeds, and the
//! test in speed ([`super::flip_search`]) cannot tell it from a flip. The
//! other bearings can. A mode moves every bearing together: the other
//! bearings' readings at that speed miss their own neighbouring speeds too
//! (by the share of the mode they show, not by a negation), and the
//! readings of all bearings stay in the subspace the machine's modes span
//! over the neighbouring speeds ([`super::cross_bearing_flips`]) as read. A
//! keyphasor fault of one bearing's channels leaves the other bearings on
//! their neighbours (or, the machine's keyphasor, negates each of them)
//! and takes the bearing out of that subspace, which only its negation
//! puts back. Measured on the seventh unseen machine
//! (docs/trust-flips.md, Session 46 (flipcrit17)): its first critical at 17.2 Hz (log dec
//! 0.06, half-power band 0.33 Hz against a 0.75 Hz step), named in speed at
//! B1, near that mode's node.

use super::cross::{
    screened_scales, signed, window, Limits, Stack, Subspace, CROSS_SIDE, SCREEN_GAP,
};
use super::flips::{
    channel_weights, chi2_8, errors, predict, readings, scales, Reading, CONSISTENT_QUANTILE,
    SCREEN_QUANTILE,
};
use super::Observation;
use statrs::distribution::ContinuousCDF;

/// Per bearing (in the order of `bearings`, each bearing's observations in
/// any order, phasors [m]), the speeds [Hz] of its `named` flips (per
/// bearing, found in speed: [`super::flip_search`]) that are a resonance
/// between two logged speeds, not a flip, ascending (module docs). Both
/// must hold:
/// - another bearing turns there too: its reading, predicted from its own
///   neighbouring speeds as [`super::flip_search`] predicts (its named
///   flips negated back), misses beyond the χ²(8) quantile
///   [`SCREEN_QUANTILE`] of its local scale as read and beyond
///   [`CONSISTENT_QUANTILE`] negated;
/// - against the other bearings at that speed (every named flip negated
///   back but this one, the subspace of the window around it as in
///   [`super::cross_bearing_flips`]) the reading as read is consistent and
///   more likely than negated ([`Limits::agrees_unnegated`]).
///
/// Two bearings or more; a speed named at two bearings or more is not
/// judged, nor one at which the other bearings are confirmed flipped with
/// this one ([`super::followed_flips`]: the machine's keyphasor, measured
/// on tests/tests/identify_flips.rs's three-bearing run flipped at 45 Hz)
/// (the machine's keyphasor negates them together, and the test
/// across bearings sees only their relative sign: measured on the sixth
/// unseen machine, B1 and B3 flipped together at 41.9 Hz, seed 6105, which
/// judged one at a time were withheld and B2 named instead).
pub fn resonance_turns(bearings: &[&[Observation]], named: &[&[f64]]) -> Vec<Vec<f64>> {
    let nb = bearings.len();
    let mut refuted = vec![Vec::new(); nb];
    if nb < 2 || named.len() != nb || named.iter().all(|f| f.is_empty()) {
        return refuted;
    }
    let off: Vec<Vec<f64>> = bearings
        .iter()
        .zip(named)
        .map(|(obs, flips)| off_unflipped(obs, flips))
        .collect();
    let none = vec![&[][..]; nb];
    // The machine's keyphasor: with this bearing's flip negated back, the
    // other bearings are negated against it ([`super::followed_flips`]).
    let followed = super::followed_flips(bearings, &none, named, named);
    let stack = Stack::of(bearings, &none, named);
    let dims = 2 * nb;
    let side = CROSS_SIDE.max(dims);
    let n = stack.ys.len();
    if n < 2 * side + 2 * SCREEN_GAP + 1 {
        return refuted;
    }
    let Some(limits) = Limits::new(nb, n) else {
        return refuted;
    };
    let index = |f: f64| stack.speeds.binary_search_by(|x| x.total_cmp(&f)).ok();
    let at: Vec<usize> = named
        .iter()
        .flat_map(|f| f.iter())
        .filter_map(|&f| index(f))
        .collect();
    let (_, _, scale_s) = screened_scales(&stack.ys, &at, side, dims, limits.null_median);
    for (b, speeds) in named.iter().enumerate() {
        for &f in speeds.iter() {
            let Some(i) = index(f) else {
                continue;
            };
            let others_turn = off
                .iter()
                .enumerate()
                .any(|(o, speeds)| o != b && speeds.contains(&f));
            let named_elsewhere = named
                .iter()
                .enumerate()
                .any(|(o, other)| o != b && (other.contains(&f) || followed[o].contains(&f)));
            if !others_turn || named_elsewhere {
                continue;
            }
            let Some(u) = Subspace::of(&stack.ys, &window(n, i..i + 1, side), dims) else {
                continue;
            };
            // In the stack bearing b is negated back at f: the reading as
            // read is that negated once more.
            if limits.agrees_unnegated(&u, &signed(&stack.ys[i], &[b]), &[b], scale_s[i]) {
                refuted[b].push(f);
            }
        }
    }
    refuted
}

/// The speeds [Hz] at which one bearing's reading (`obs`, the speeds
/// `negated_hz` [Hz] negated back) misses its neighbours' prediction
/// beyond [`SCREEN_QUANTILE`] as read and beyond [`CONSISTENT_QUANTILE`]
/// negated ([`resonance_turns`]).
fn off_unflipped(obs: &[Observation], negated_hz: &[f64]) -> Vec<f64> {
    let s: Vec<Reading> = readings(obs);
    let n = s.len();
    let negated: Vec<bool> = s.iter().map(|r| negated_hz.contains(&r.speed_hz)).collect();
    let weights = channel_weights(&s);
    let predicted: Vec<_> = (0..n)
        .map(|i| Some(predict(&s, &negated, &weights, i..i + 1, &[i])?[0]))
        .collect();
    let loo: Vec<Option<[f64; 4]>> = (0..n)
        .map(|i| predicted[i].map(|p| errors(&s, &negated, i, &p, false)))
        .collect();
    let scale = scales(&loo);
    let screen = chi2_8().inverse_cdf(SCREEN_QUANTILE);
    let consistent = chi2_8().inverse_cdf(CONSISTENT_QUANTILE);
    let a = |e: [f64; 4], i: usize| -> f64 { (0..4).map(|c| 2.0 * e[c] / scale[i][c]).sum() };
    (0..n)
        .filter(|&i| {
            predicted[i].is_some_and(|p| {
                a(errors(&s, &negated, i, &p, false), i) > screen
                    && a(errors(&s, &negated, i, &p, true), i) > consistent
            })
        })
        .map(|i| s[i].speed_hz)
        .collect()
}
