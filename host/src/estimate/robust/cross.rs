//! Keyphasor flips against the other bearings at the same speed
//! ([`cross_bearing_flips`]). Every bearing responds through the same
//! machine modes: at a speed the phasors of all bearings (4 per bearing)
//! form one vector y = Σ_m φ_m·r_m(Ω), the mode shapes φ_m fixed, so over a
//! few neighbouring speeds these vectors lie in a subspace of few
//! dimensions (measured on the three-bearing test machine, 12 channels,
//! 11-speed windows: 3-5 dimensions above 1 % noise, also across its
//! pedestal resonances at 35-50 Hz, where the speed steps resolve nothing).
//! Negating one bearing's four channels moves the vector out of that
//! subspace; negating it back moves it in. This needs no smoothness in
//! speed, so it finds the flips next to a resonance that the local model
//! in speed ([`super::keyphasor_flips`]) cannot judge; it is blind to a
//! flip of every bearing at once (a subspace holds −y with y) and, with
//! two bearings, cannot tell which one flipped (negating either is the
//! same up to a common sign): both are left to the test in speed.

mod limits;

use super::flips::{channel_weights, readings, FLIP_BLOCK, FLIP_WINDOW};
use super::{window_medians, Observation};
pub(super) use limits::Limits;
use nalgebra::DMatrix;
use num_complex::Complex;

/// Fewest bearings the test judges [-] (with two, which one flipped is
/// undecidable: module docs).
pub const CROSS_MIN_BEARINGS: usize = 3;

/// Degrees of freedom of r/s's tail at the run's first and last
/// [`SCREEN_GAP`] + 1 speeds, whose subspace is an extrapolation
/// ([`surrounded`]) [-]: measured on clean runs, docs/trust-bad-speeds.md
/// "Session 37" and "Session 38".
pub const EDGE_DOF: f64 = 2.0;

/// Fewest window speeds on each side of a tested speed [-].
pub const CROSS_SIDE: usize = 6;

/// Speeds on each side of a screened speed left out of its window [-]:
/// every other member of a block of up to [`FLIP_BLOCK`] flipped speeds
/// that holds it (adjacent flips must not explain each other).
pub(super) const SCREEN_GAP: usize = FLIP_BLOCK - 1;

/// Speeds [Hz] per bearing (in the order of `bearings`, each bearing's
/// observations in any order, phasors [m]) at which every channel of that
/// bearing alone looks negated against the other bearings at the same
/// speed. Speeds in `listed` (per bearing, [Hz]: outliers already named)
/// are left out of everything, for every bearing; so are speeds some
/// bearing lacks. Speeds in `flipped` (per bearing, [Hz]: flips already
/// named, by the test in speed) have that bearing's channels negated back,
/// the reading as it truly is, and are not judged again: left out, they
/// would shorten the windows and move the scales of the speeds around them
/// (measured on the three-bearing test machine, `mid` flipped at 55 and
/// 72.5 Hz at 1 % noise, seed 20: with 72.5 Hz, found in speed, left out,
/// the 55 Hz flip stood at Σ r/s ≈ 38 against its limit of 42 and was
/// missed; negated back, at 63, as with 55 Hz flipped alone).
///
/// Each channel is weighted by one over its noise-and-interpolation scale
/// (`channel_weights` of [`super::flips`]). At each speed the weighted
/// vector y (C = 4·B channels) is compared with the subspace spanned by
/// the D = 2·B leading eigenvectors of Σ y_j y_jᴴ over the window of up to
/// max([`CROSS_SIDE`], D) speeds on each side (the speeds within
/// [`FLIP_BLOCK`] − 1 left out): r = |y − UUᴴy|², and its leverage
/// ℓ = Σ_k |u_kᴴy|²/λ_k (how much of y lies along directions the window
/// barely shows; the subspace's estimation error adds about ℓ times the
/// noise to r). The scale of r is the median over [`FLIP_WINDOW`] speeds on
/// each side, so that r/s is about χ²(2(C − D)) for a good reading; the
/// speeds beyond its [`SCREEN_QUANTILE`] are candidates. The hypothesis
/// "bearing b's channels at the candidate speeds a..b (up to
/// [`FLIP_BLOCK`]) are negated" is tested against the subspace of the
/// window around the block (the block left out). It is named when
/// - Σ r/s as read is beyond the χ²(2(C − D)·L) quantile at
///   [`OUTLIER_FAMILY_RATE`]/n (Bonferroni over the n speeds),
/// - negated, each speed's studentised r/((1 + ℓ)·s′) (s′ the median scale
///   of the studentised values) is within the χ²(2(C − D)) quantile
///   [`CONSISTENT_QUANTILE`], the negation lowers Σ r/s below
///   [`FLIP_RATIO`] of what it was, and
/// - at every speed of the block the negated reading is the more likely
///   one: r/((1 + ℓ)·s′) + 2(C − D)·ln(1 + ℓ) (−2 ln of its Gaussian
///   likelihood with the variance inflated by the leverage) is lower
///   negated than as read;
///
/// the block and bearing with the largest gain of that likelihood is
/// negated first, the subspaces and scales are measured again, and so on.
/// A speed negated for one bearing is not tested again. When the
/// negations of two bearings or more pass every condition, the best is
/// named only when its gain beats every other's by the margin
/// 2 ln(n/[`OUTLIER_FAMILY_RATE`]) ([`Limits::named`]); else the data do
/// not say which one flipped (as with two bearings). At the run's first
/// and last [`SCREEN_GAP`] + 1 speeds, whose window lies on one side of
/// them ([`surrounded`]), the subspace is an extrapolation and r/s is not
/// χ²(2(C − D)) (measured on clean runs: at the first speeds the tail of
/// χ²(2) at a smaller median; at the last a tail lighter than that at a
/// median 3-18 times larger; docs/trust-bad-speeds.md "Session 38"); the first
/// condition takes each such speed's r/s over [`Limits::edge_scale`] as
/// χ²([`EDGE_DOF`]) in the block's sum, a limit above every clean end
/// reading of the three-bearing machines measured, not of unseen-four's
/// last speeds, where the other conditions hold.
pub fn cross_bearing_flips(
    bearings: &[&[Observation]],
    listed: &[&[f64]],
    flipped: &[&[f64]],
) -> Vec<Vec<f64>> {
    let nb = bearings.len();
    let mut found = vec![Vec::new(); nb];
    if nb < CROSS_MIN_BEARINGS || listed.len() != nb || flipped.len() != nb {
        return found;
    }
    let Stack { speeds, ys, known } = Stack::of(bearings, listed, flipped);
    let dims = 2 * nb;
    let side = CROSS_SIDE.max(dims);
    let n = ys.len();
    if n < 2 * side + 2 * SCREEN_GAP + 1 {
        return found;
    }
    let Some(limits) = Limits::new(nb, n) else {
        return found;
    };
    // Which bearing is negated at each speed (at most one).
    let mut negated: Vec<Option<usize>> = vec![None; n];
    for _ in 0..n / 4 {
        let y: Vec<Vec<Complex<f64>>> = (0..n)
            .map(|i| signed(&ys[i], negated[i].as_slice()))
            .collect();
        let all: Vec<usize> = (0..n).collect();
        let (plain, scale, scale_s) = screened_scales(&y, &all, side, dims, limits.null_median);
        let candidate: Vec<bool> = (0..n)
            .map(|i| !known[i] && negated[i].is_none() && plain[i] / scale[i] > limits.screen)
            .collect();
        let mut best: Option<(usize, std::ops::Range<usize>, f64)> = None;
        for start in 0..n {
            for end in start + 1..=(start + FLIP_BLOCK).min(n) {
                if !candidate[end - 1] {
                    break;
                }
                let block = start..end;
                let Some(u) = Subspace::of(&y, &window(n, block.clone(), side), dims) else {
                    continue;
                };
                // One bearing named among those whose negation passes:
                // the one, or the best by the likelihood margin; else the
                // data do not say which bearing flipped ([`Limits::named`]).
                let passing: Vec<(usize, f64)> = (0..nb)
                    .filter_map(|b| {
                        limits
                            .judge(&u, &y, block.clone(), &[b], &scale, &scale_s)
                            .map(|gain| (b, gain))
                    })
                    .collect();
                if let Some((b, gain)) = limits.named(&passing) {
                    if best.as_ref().is_none_or(|(_, _, g)| gain > *g) {
                        best = Some((b, block.clone(), gain));
                    }
                }
            }
        }
        match best {
            Some((b, block, _)) => negated[block].fill(Some(b)),
            None => break,
        }
    }
    for (i, b) in negated.iter().enumerate() {
        if let Some(b) = b {
            found[*b].push(speeds[i]);
        }
    }
    found
}

/// Whether speed `i` of `n` is surrounded: its screening window (the
/// speeds beyond [`SCREEN_GAP`] on each side, [`screened_scales`]) holds
/// speeds on both sides of it. At the run's first and last
/// [`SCREEN_GAP`]&nbsp;+&nbsp;1 speeds it lies on one side only: the
/// subspace is then an extrapolation, and the reading's plain residual is
/// neither χ²(2(C − D)) over its scale nor owed to one bearing (measured
/// on the third unseen machine's clean run-up,
/// docs/trust-bad-speeds.md "Session 37": over 300 runs the 99.9 % quantile of
/// r/s at the first four speeds is 9.4 times its median, χ²(12)'s is 2.9,
/// χ²(2)'s 10.0; docs/trust-bad-speeds.md "Session 38" for the last four).
fn surrounded(n: usize, i: usize) -> bool {
    i > SCREEN_GAP && i + SCREEN_GAP + 1 < n
}

/// All bearings' weighted phasors at the speeds every bearing has and none
/// lists ([`cross_bearing_flips`]'s `listed`), each bearing's known flips
/// negated back.
pub(super) struct Stack {
    /// The speeds [Hz], ascending.
    pub(super) speeds: Vec<f64>,
    /// Per speed, the 4·B channels (bearing by bearing: rel y, rel z, ped
    /// y, ped z), each weighted by one over its noise-and-interpolation
    /// scale (`channel_weights` of [`super::flips`]) [-].
    pub(super) ys: Vec<Vec<Complex<f64>>>,
    /// Per speed, whether some bearing is known flipped there.
    pub(super) known: Vec<bool>,
}

impl Stack {
    /// The stack of `bearings` (each bearing's observations in any order,
    /// phasors [m]) without the speeds in `listed` (per bearing [Hz]: left
    /// out for every bearing) or that some bearing lacks, the speeds in
    /// `flipped` (per bearing [Hz]) negated for that bearing.
    pub(super) fn of(bearings: &[&[Observation]], listed: &[&[f64]], flipped: &[&[f64]]) -> Self {
        let nb = bearings.len();
        let per_bearing: Vec<_> = bearings.iter().map(|o| readings(o)).collect();
        let weights: Vec<[f64; 4]> = per_bearing.iter().map(|s| channel_weights(s)).collect();
        let is_listed = |f: f64| listed.iter().any(|l| l.contains(&f));
        let mut stack = Stack {
            speeds: Vec::new(),
            ys: Vec::new(),
            known: Vec::new(),
        };
        let Some(first) = per_bearing.first() else {
            return stack;
        };
        for r in first {
            if is_listed(r.speed_hz) {
                continue;
            }
            let mut y = Vec::with_capacity(4 * nb);
            let mut any_flipped = false;
            for ((s, w), f) in per_bearing.iter().zip(&weights).zip(flipped) {
                let Ok(k) = s.binary_search_by(|x| x.speed_hz.total_cmp(&r.speed_hz)) else {
                    break;
                };
                let sign = if f.contains(&r.speed_hz) {
                    any_flipped = true;
                    -1.0
                } else {
                    1.0
                };
                y.extend((0..4).map(|c| s[k].q[c] * (w[c] * sign)));
            }
            if y.len() == 4 * nb {
                stack.speeds.push(r.speed_hz);
                stack.ys.push(y);
                stack.known.push(any_flipped);
            }
        }
        stack
    }
}

/// The scales of the test across bearings at the speeds `at` (indices of
/// `y`, ascending): each speed of `y` within [`FLIP_WINDOW`] of one of them
/// against the subspace of the window around it (`side` speeds on each
/// side, `dims` dimensions), its neighbours within SCREEN_GAP left out; per
/// speed of `y` (NaN elsewhere), r, and the median of r and of the
/// studentised r/(1 + ℓ) over [`FLIP_WINDOW`] speeds on each side over
/// `null_median` ([`scales`]). The same figures at the speeds `at` whether
/// `at` holds every speed or a few.
pub(super) fn screened_scales(
    y: &[Vec<Complex<f64>>],
    at: &[usize],
    side: usize,
    dims: usize,
    null_median: f64,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = y.len();
    let mut needed = vec![false; n];
    for &i in at {
        needed[i.saturating_sub(FLIP_WINDOW)..(i + FLIP_WINDOW + 1).min(n)].fill(true);
    }
    let screened: Vec<Option<(f64, f64)>> = (0..n)
        .map(|i| {
            if !needed[i] {
                return None;
            }
            let gap = i.saturating_sub(SCREEN_GAP)..(i + SCREEN_GAP + 1).min(n);
            Subspace::of(y, &window(n, gap, side), dims).map(|u| u.residual(&y[i]))
        })
        .collect();
    let plain: Vec<f64> = screened
        .iter()
        .map(|r| r.map_or(f64::NAN, |r| r.0))
        .collect();
    let studentised: Vec<f64> = screened
        .iter()
        .map(|r| r.map_or(f64::NAN, |(r, l)| r / (1.0 + l)))
        .collect();
    let scale = scales(&plain, null_median);
    let scale_s = scales(&studentised, null_median);
    (plain, scale, scale_s)
}

/// `y` with the four channels of each bearing in `which` negated.
pub(super) fn signed(y: &[Complex<f64>], which: &[usize]) -> Vec<Complex<f64>> {
    let mut out = y.to_vec();
    for &b in which {
        out[4 * b..4 * b + 4].iter_mut().for_each(|z| *z = -*z);
    }
    out
}

/// Per speed, the median of `v` over [`FLIP_WINDOW`] speeds on each side
/// over `null_median` [units of `v`], never below the smallest positive
/// number.
fn scales(v: &[f64], null_median: f64) -> Vec<f64> {
    window_medians(v, FLIP_WINDOW)
        .into_iter()
        .map(|m| (m / null_median).max(f64::MIN_POSITIVE))
        .collect()
}

/// The indices of `2·side` speeds of `n` around the speeds `gap` (fewer
/// when `n` is short; more on one side at the run's ends), `gap` left out.
pub(super) fn window(n: usize, gap: std::ops::Range<usize>, side: usize) -> Vec<usize> {
    let (mut lo, mut hi) = (gap.start.saturating_sub(side), (gap.end + side).min(n));
    while hi - lo - gap.len() < 2 * side && (lo > 0 || hi < n) {
        if lo > 0 && gap.start - lo <= hi - gap.end || hi == n {
            lo -= 1;
        } else {
            hi += 1;
        }
    }
    (lo..hi).filter(|j| !gap.contains(j)).collect()
}

/// The leading eigenvectors of a window's Σ y yᴴ and their eigenvalues.
pub(super) struct Subspace {
    /// Unit eigenvectors, one per column.
    vectors: DMatrix<Complex<f64>>,
    /// Their eigenvalues (positive).
    values: Vec<f64>,
}

impl Subspace {
    /// The `dims` leading eigenpairs of Σ_{j ∈ window} y_j y_jᴴ (only those
    /// with a positive eigenvalue); `None` when the window is empty or the
    /// decomposition is not finite.
    pub(super) fn of(y: &[Vec<Complex<f64>>], window: &[usize], dims: usize) -> Option<Self> {
        let c = y.first()?.len();
        if window.is_empty() {
            return None;
        }
        let mut gram = DMatrix::<Complex<f64>>::zeros(c, c);
        for &j in window {
            for r in 0..c {
                let a = y[j][r];
                for k in 0..c {
                    gram[(r, k)] += a * y[j][k].conj();
                }
            }
        }
        let eigen = gram.symmetric_eigen();
        let mut order: Vec<usize> = (0..c).collect();
        order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
        let keep: Vec<usize> = order
            .into_iter()
            .take(dims)
            .filter(|&k| eigen.eigenvalues[k] > 0.0 && eigen.eigenvalues[k].is_finite())
            .collect();
        let vectors = DMatrix::from_fn(c, keep.len(), |r, k| eigen.eigenvectors[(r, keep[k])]);
        let values: Vec<f64> = keep.iter().map(|&k| eigen.eigenvalues[k]).collect();
        vectors
            .iter()
            .all(|z| z.re.is_finite() && z.im.is_finite())
            .then_some(Subspace { vectors, values })
    }

    /// (|y − UUᴴy|², Σ_k |u_kᴴy|²/λ_k) of `y` [-].
    fn residual(&self, y: &[Complex<f64>]) -> (f64, f64) {
        let mut rest = y.to_vec();
        let mut leverage = 0.0;
        for (k, &value) in self.values.iter().enumerate() {
            let u = self.vectors.column(k);
            let a: Complex<f64> = u.iter().zip(y).map(|(u, y)| u.conj() * y).sum();
            for (r, u) in rest.iter_mut().zip(u.iter()) {
                *r -= a * u;
            }
            leverage += a.norm_sqr() / value;
        }
        (rest.iter().map(|z| z.norm_sqr()).sum(), leverage)
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// Bearings over 80 speeds, 5-202.5 Hz, whose phasors (four per
    /// bearing) are sharp `modes` [Hz] (0.5 % damping) with fixed complex
    /// shapes, plus complex noise of sd `noise` × each channel's RMS; every
    /// channel of bearing `flip.0` negated at the speed indices `flip.1`.
    /// Shared with `super::super::confirm`'s tests.
    pub(in crate::estimate::robust) fn modal_machine(
        modes: &[f64],
        bearings: usize,
        flip: (usize, &[usize]),
        noise: f64,
        seed: u64,
    ) -> Vec<Vec<Observation>> {
        use rand::{rngs::StdRng, Rng, SeedableRng};
        use rand_distr::StandardNormal;
        let mut rng = StdRng::seed_from_u64(seed);
        let channels = 4 * bearings;
        let shape = |m: usize, ch: usize| -> Complex<f64> {
            let k = (7 * m + 3 * ch) as f64;
            Complex::from_polar(1.0 + 0.5 * (k * 0.37).sin(), k * 1.3)
        };
        let clean: Vec<Vec<Complex<f64>>> = (0..80)
            .map(|i| {
                let f = 5.0 + 2.5 * i as f64;
                (0..channels)
                    .map(|ch| {
                        modes
                            .iter()
                            .enumerate()
                            .map(|(m, &f0)| {
                                let r = f / f0;
                                shape(m, ch) * (1e-7 * r * r) / Complex::new(1.0 - r * r, 0.01 * r)
                            })
                            .sum()
                    })
                    .collect()
            })
            .collect();
        let rms: Vec<f64> = (0..channels)
            .map(|ch| (clean.iter().map(|q| q[ch].norm_sqr()).sum::<f64>() / 80.0).sqrt())
            .collect();
        (0..bearings)
            .map(|b| {
                clean
                    .iter()
                    .enumerate()
                    .map(|(i, q)| {
                        let mut z: [Complex<f64>; 4] = std::array::from_fn(|c| {
                            let sd = noise * rms[4 * b + c] / 2f64.sqrt();
                            q[4 * b + c]
                                + Complex::new(
                                    rng.sample::<f64, _>(StandardNormal),
                                    rng.sample::<f64, _>(StandardNormal),
                                ) * sd
                        });
                        if flip.0 == b && flip.1.contains(&i) {
                            z.iter_mut().for_each(|v| *v = -*v);
                        }
                        Observation {
                            speed_hz: 5.0 + 2.5 * i as f64,
                            rel: [z[0], z[1]],
                            ped: [z[2], z[3]],
                            kstar: [[Complex::new(1e7, 0.0), Complex::new(0.0, 0.0)]; 2],
                            var: [1e-20; 8],
                        }
                    })
                    .collect()
            })
            .collect()
    }

    /// Three bearings, four modes (two between 35 and 47 Hz, where the
    /// 2.5 Hz steps resolve nothing).
    fn machine(flip: (usize, &[usize]), noise: f64, seed: u64) -> Vec<Vec<Observation>> {
        modal_machine(&[36.3, 41.1, 70.0, 110.0], 3, flip, noise, seed)
    }

    fn run(obs: &[Vec<Observation>], listed: &[Vec<f64>]) -> Vec<Vec<f64>> {
        let refs: Vec<&[Observation]> = obs.iter().map(|o| o.as_slice()).collect();
        let l: Vec<&[f64]> = listed.iter().map(|l| l.as_slice()).collect();
        cross_bearing_flips(&refs, &l, &[&[], &[], &[]])
    }

    #[test]
    fn the_run_ends_are_the_speeds_whose_window_lies_on_one_side() {
        // 80 speeds: the first and last SCREEN_GAP + 1 = 4 are screened
        // against a window on one side of them only.
        let judged: Vec<usize> = (0..80).filter(|&i| surrounded(80, i)).collect();
        assert_eq!(judged.first(), Some(&(SCREEN_GAP + 1)));
        assert_eq!(judged.last(), Some(&(80 - SCREEN_GAP - 2)));
        assert_eq!(judged.len(), 80 - 2 * (SCREEN_GAP + 1));
        // Each judged speed's screening window holds speeds on both sides.
        for &i in &judged {
            let gap = i.saturating_sub(SCREEN_GAP)..(i + SCREEN_GAP + 1).min(80);
            let w = window(80, gap, CROSS_SIDE);
            assert!(
                w.iter().any(|&j| j < i) && w.iter().any(|&j| j > i),
                "{i}: {w:?}"
            );
        }
        // And the speeds not judged have one on one side only.
        for i in (0..80).filter(|&i| !surrounded(80, i)) {
            let gap = i.saturating_sub(SCREEN_GAP)..(i + SCREEN_GAP + 1).min(80);
            let w = window(80, gap, CROSS_SIDE);
            assert!(
                w.iter().all(|&j| j > i) || w.iter().all(|&j| j < i),
                "{i}: {w:?}"
            );
        }
    }

    #[test]
    fn flips_beside_sharp_modes_are_found_and_nothing_else() {
        let none = vec![Vec::new(); 3];
        for seed in 0..10 {
            let clean = run(&machine((1, &[]), 0.01, seed), &none);
            assert!(clean.iter().all(|f| f.is_empty()), "{seed}: {clean:?}");
        }
        // Two adjacent flips between the two close modes (indices 13, 14:
        // 37.5 and 40 Hz) and one alone at 150 Hz.
        let found = run(&machine((1, &[13, 14, 58]), 0.01, 3), &none);
        assert_eq!(found, vec![vec![], vec![37.5, 40.0, 150.0], vec![]]);
        // A listed speed is left out for every bearing.
        let listed = vec![vec![], vec![150.0], vec![]];
        let found = run(&machine((1, &[13, 14, 58]), 0.01, 3), &listed);
        assert_eq!(found, vec![vec![], vec![37.5, 40.0], vec![]]);
        // Two bearings: not judged.
        let two = machine((1, &[13]), 0.01, 3);
        let refs: Vec<&[Observation]> = two[..2].iter().map(|o| o.as_slice()).collect();
        assert!(cross_bearing_flips(&refs, &[&[], &[]], &[&[], &[]])
            .iter()
            .all(|f| f.is_empty()));
    }
}
