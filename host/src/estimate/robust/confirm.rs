//! Flips the test in speed could not confirm, judged against the other
//! bearings at the same speeds ([`confirmed_across`]).
//!
//! At a resonance's peak or on its flank the local model in speed
//! ([`super::keyphasor_flips`]) misses a reading by more than the noise
//! there, negated or not: a flip and a true swing of the phase look alike
//! in speed. The other bearings tell them apart. A machine mode moves every
//! bearing: through a sharp peak (an undamped pedestal's true 180° turn
//! included) all bearings' phasors turn together and stay in the subspace
//! their neighbouring speeds span ([`super::cross`]); a keyphasor fault of
//! one bearing's channels negates that bearing alone, out of the subspace.
//! Across bearings only the relative sign is seen (negating one bearing of
//! two is negating the other up to a common sign), so the test in speed
//! says which bearing it is, and the test across bearings whether it is a
//! flip. Measured on the fourth unseen machine (two bearings, B1 flipped at
//! the top of the 82 Hz peak, seed 4 of `scripts/ross_unseen.py
//! --machine unseen-flex ... flips`): Σ r/s 38 800 as read, 15 negated
//! (limit 35); at 14.65 Hz on the 15.5 Hz mode's flank (seed 3): 52 and 4.
//! The undamped paper machine's true turn between 44.1 and 46.7 Hz (all
//! channels of both bearings, exact data): 19 as read, 2 200 negated.

use super::cross::{screened_scales, window, Limits, Stack, Subspace, CROSS_SIDE, SCREEN_GAP};
use super::Observation;

/// Per bearing (in the order of `bearings`, each bearing's observations in
/// any order, phasors [m]), the speeds [Hz] of its `unconfirmed` blocks
/// (per bearing, [`super::FlipSearch::unconfirmed_hz`]) that the other
/// bearings confirm as flipped, ascending. Two bearings or more. The
/// readings are stacked as [`super::cross_bearing_flips`] stacks them:
/// speeds in `listed` (per bearing [Hz], outliers) left out for every
/// bearing, speeds in `flipped` (per bearing [Hz], flips already named)
/// negated back for that bearing.
///
/// A block held by the bearings S (every bearing whose unconfirmed blocks
/// hold exactly those speeds) is named for each of them when, against the
/// subspace of the window around the block, negating S's channels passes
/// [`super::cross_bearing_flips`]'s three conditions (as read beyond the
/// noise, Bonferroni over the speeds; negated, each speed consistent and
/// the more likely; Σ r/s lowered below [`super::FLIP_RATIO`]). When S is
/// every bearing the test is blind (a common sign) and nothing is named.
/// Each block is judged on the readings as stacked, alone.
pub fn confirmed_across(
    bearings: &[&[Observation]],
    listed: &[&[f64]],
    flipped: &[&[f64]],
    unconfirmed: &[&[Vec<f64>]],
) -> Vec<Vec<f64>> {
    let nb = bearings.len();
    let mut found = vec![Vec::new(); nb];
    if nb < 2
        || listed.len() != nb
        || flipped.len() != nb
        || unconfirmed.len() != nb
        || unconfirmed.iter().all(|u| u.is_empty())
    {
        return found;
    }
    let stack = Stack::of(bearings, listed, flipped);
    let dims = 2 * nb;
    let side = CROSS_SIDE.max(dims);
    let n = stack.ys.len();
    if n < 2 * side + 2 * SCREEN_GAP + 1 {
        return found;
    }
    let Some(limits) = Limits::new(nb, n) else {
        return found;
    };
    // Each block (indices of the stack) with the bearings that hold it.
    let mut hypotheses: Vec<(std::ops::Range<usize>, Vec<usize>)> = Vec::new();
    for (b, blocks) in unconfirmed.iter().enumerate() {
        for block in blocks.iter() {
            let Some(range) = indices(&stack.speeds, block) else {
                continue;
            };
            match hypotheses.iter_mut().find(|(r, _)| *r == range) {
                Some((_, which)) if !which.contains(&b) => which.push(b),
                Some(_) => {}
                None => hypotheses.push((range, vec![b])),
            }
        }
    }
    let at: Vec<usize> = {
        let mut at: Vec<usize> = hypotheses.iter().flat_map(|(r, _)| r.clone()).collect();
        at.sort_unstable();
        at.dedup();
        at
    };
    let (_, scale, scale_s) = screened_scales(&stack.ys, &at, side, dims, limits.null_median);
    for (block, which) in hypotheses {
        if which.len() == nb {
            continue;
        }
        let Some(u) = Subspace::of(&stack.ys, &window(n, block.clone(), side), dims) else {
            continue;
        };
        if limits
            .judge(&u, &stack.ys, block.clone(), &which, &scale, &scale_s)
            .is_some()
        {
            for &b in &which {
                found[b].extend(block.clone().map(|i| stack.speeds[i]));
            }
        }
    }
    for f in &mut found {
        f.sort_by(f64::total_cmp);
        f.dedup();
    }
    found
}

/// Per bearing (in the order of `bearings`, phasors [m]), the speeds [Hz]
/// another bearing names flipped in speed (`named`, per bearing [Hz]) at
/// which the other bearings confirm that this bearing flipped with it: the
/// machine's keyphasor negating every bearing at once, ascending.
///
/// The test across bearings sees only relative signs: a common sign is
/// invisible to it, and at a resonance's peak or flank the test in speed of
/// some bearings cannot confirm the flip their readings carry (nor hold it
/// as an unconfirmed block). A flip one bearing names in speed fixes the
/// keyphasor's phase at that speed: with it negated back (it is in
/// `flipped`, per bearing [Hz], the flips named so far), a bearing that
/// flipped with it is negated against it and its modes. Each named speed
/// is offered alone, as a block held by every bearing that does not name
/// it, to [`confirmed_across`] (its three conditions, no other threshold);
/// `listed` (per bearing [Hz], outliers) left out.
pub fn followed_flips(
    bearings: &[&[Observation]],
    listed: &[&[f64]],
    flipped: &[&[f64]],
    named: &[&[f64]],
) -> Vec<Vec<f64>> {
    let mut offered: Vec<Vec<Vec<f64>>> = vec![Vec::new(); bearings.len()];
    for (b, speeds) in named.iter().enumerate() {
        for &f in speeds.iter() {
            for (other, blocks) in offered.iter_mut().enumerate() {
                let block = vec![f];
                if other != b
                    && !flipped.get(other).is_some_and(|n| n.contains(&f))
                    && !blocks.contains(&block)
                {
                    blocks.push(block);
                }
            }
        }
    }
    let offered: Vec<&[Vec<f64>]> = offered.iter().map(Vec::as_slice).collect();
    confirmed_across(bearings, listed, flipped, &offered)
}

/// The consecutive indices of `speeds` (ascending) that hold exactly the
/// speeds `block` [Hz] (ascending); `None` when one is missing or they are
/// not consecutive.
fn indices(speeds: &[f64], block: &[f64]) -> Option<std::ops::Range<usize>> {
    let target = *block.first()?;
    let first = speeds.binary_search_by(|x| x.total_cmp(&target)).ok()?;
    let range = first..first + block.len();
    (range.end <= speeds.len() && speeds[range.clone()] == *block).then_some(range)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two bearings, three modes (41.1 Hz between two speeds, where the
    /// 2.5 Hz steps resolve nothing), noise 1 % of each channel's RMS
    /// (`super::super::cross`'s test machine).
    fn machine(flip: (usize, &[usize]), seed: u64) -> Vec<Vec<Observation>> {
        super::super::cross::tests::modal_machine(&[41.1, 70.0, 110.0], 2, flip, 0.01, seed)
    }

    #[test]
    fn a_flip_at_a_peak_is_confirmed_at_its_bearing_and_a_true_turn_is_not() {
        // 40 and 42.5 Hz straddle the 41.1 Hz mode: every channel turns
        // by nearly 180° between them. Offered as unconfirmed blocks, the
        // clean readings are never named; bearing 1 flipped at 42.5 Hz is
        // named at bearing 1; offered at both bearings (a common sign),
        // nothing is.
        let none: [&[f64]; 2] = [&[], &[]];
        let offer = |b: usize, f: f64| -> Vec<Vec<Vec<f64>>> {
            let mut u = vec![Vec::new(), Vec::new()];
            u[b].push(vec![f]);
            u
        };
        let run = |obs: &[Vec<Observation>], u: &[Vec<Vec<f64>>]| {
            let refs: Vec<&[Observation]> = obs.iter().map(Vec::as_slice).collect();
            let u: Vec<&[Vec<f64>]> = u.iter().map(Vec::as_slice).collect();
            confirmed_across(&refs, &none, &none, &u)
        };
        for seed in 0..10 {
            let clean = machine((1, &[]), seed);
            for f in [40.0, 42.5] {
                for b in 0..2 {
                    let found = run(&clean, &offer(b, f));
                    assert!(found.iter().all(Vec::is_empty), "{seed} {f} {b}: {found:?}");
                }
            }
            let flipped = machine((1, &[15]), seed);
            assert_eq!(
                run(&flipped, &offer(1, 42.5)),
                vec![vec![], vec![42.5]],
                "{seed}"
            );
            let both = vec![vec![vec![42.5]], vec![vec![42.5]]];
            assert!(run(&flipped, &both).iter().all(Vec::is_empty), "{seed}");
        }
    }

    #[test]
    fn a_flip_named_at_one_bearing_is_followed_where_every_bearing_flipped() {
        // 42.5 Hz just past the 41.1 Hz mode. Every bearing flipped there,
        // bearing 0 naming it in speed: bearing 1 is named with it. Bearing
        // 0 flipped alone and naming it: bearing 1 is not. A speed named
        // at no bearing offers nothing.
        let none: [&[f64]; 2] = [&[], &[]];
        let run = |obs: &[Vec<Observation>], flipped: [&[f64]; 2], named: [&[f64]; 2]| {
            let refs: Vec<&[Observation]> = obs.iter().map(Vec::as_slice).collect();
            followed_flips(&refs, &none, &flipped, &named)
        };
        for seed in 0..10 {
            let mut every = machine((1, &[15]), seed);
            for o in every[0].iter_mut().filter(|o| o.speed_hz == 42.5) {
                o.rel = o.rel.map(|z| -z);
                o.ped = o.ped.map(|z| -z);
            }
            let named: [&[f64]; 2] = [&[42.5], &[]];
            assert_eq!(
                run(&every, named, named),
                vec![vec![], vec![42.5]],
                "{seed}"
            );
            assert!(run(&every, none, none).iter().all(Vec::is_empty), "{seed}");
            let alone = machine((0, &[15]), seed);
            assert!(
                run(&alone, named, named).iter().all(Vec::is_empty),
                "{seed}"
            );
        }
    }

    #[test]
    fn blocks_are_found_by_their_speeds() {
        let speeds = [1.0, 2.0, 3.0, 5.0];
        assert_eq!(indices(&speeds, &[2.0, 3.0]), Some(1..3));
        assert_eq!(indices(&speeds, &[5.0]), Some(3..4));
        assert_eq!(indices(&speeds, &[3.0, 4.0]), None);
        assert_eq!(indices(&speeds, &[5.0, 6.0]), None);
        assert_eq!(indices(&speeds, &[]), None);
    }
}
