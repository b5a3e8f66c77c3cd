//! Monte-Carlo checks of the ML refit on unseen-flex's stiff block B1, whose
//! pick-ups read 0.2-20 nm against 13 nm of noise: exact phasors (the
//! stored run's rel as the true rel, the pedestal motion from a true
//! pedestal and effect), then the noise of its columns on every real number.

use super::*;
use crate::diagnose::state::{base_model, pedestals};
use crate::diagnose::test_runs::stored;
use num_complex::Complex;
use plinth_shared::regression::Parameter;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// B1's true pedestal (k_y, k_z [N/m], m [kg], c_y, c_z [N·s/m]).
const THETA: [f64; 5] = [3.0e9, 2.0e9, 450.0, 3.0e4, 2.5e4];

/// One Monte-Carlo lab: a stored run (its noise columns weight the fits and
/// set the noise drawn), the bearing that carries the effect and its true
/// pedestal (k_y, k_z [N/m], m [kg], c_y, c_z [N·s/m]); `exact`: a stored
/// noise-free run of the same machine and grid whose phasors are the true
/// ones (ROSS's, effect included), else the stored run's rel is taken as
/// true and the bearing's pedestal motion made from `theta` and the effect.
struct Lab {
    case: &'static str,
    bearing: &'static str,
    theta: [f64; 5],
    exact: Option<&'static str>,
}

/// unseen-flex's stiff block B1 (the stored runout run).
const FLEX_B1: Lab = Lab {
    case: "ross-unseen-4/runout",
    bearing: "B1",
    theta: THETA,
    exact: None,
};

/// An effect at B1 and its true values.
#[derive(Clone, Copy)]
enum Effect {
    /// A probe runout (r_y, r_z) [m].
    Runout([Complex<f64>; 2]),
    /// A symmetric cross stiffness k_yz [N/m].
    Cross(f64),
}

/// Mean z = (value − truth)/± of B1's (k_y, k_z, m) over `n` noise draws
/// with `effect` at B1, and the RMS z of the three. Returns (the search's
/// held-weights least squares, the ML refit), each ([mean z; 3], [RMS z; 3]).
fn z_stats(effect: Effect, n: usize) -> [([f64; 3], [f64; 3]); 2] {
    z_stats_at(&FLEX_B1, effect, n, 37)
}

/// [`z_stats`] at `lab`'s bearing, the noise drawn from `seed`.
fn z_stats_at(lab: &Lab, effect: Effect, n: usize, seed: u64) -> [([f64; 3], [f64; 3]); 2] {
    let theta = lab.theta;
    let prep0 = stored(lab.case);
    let b = prep0
        .bearings
        .iter()
        .position(|x| x == lab.bearing)
        .expect("the lab's bearing");
    let exact = lab.exact.map(stored);
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let unit = Normal::new(0.0, 1.0).expect("normal");
    let mut model = base_model(&Parameter::ALL, prep0.bearings.len());
    match effect {
        Effect::Runout(_) => model.terms.extend((0..4).map(|i| Term::Runout {
            bearing: b,
            dir: i / 2,
            imag: i % 2 == 1,
        })),
        Effect::Cross(_) => model.terms.push(Term::CrossStiffness { bearing: b }),
    }
    let mut out = [([0.0; 3], [0.0; 3]); 2];
    for _ in 0..n {
        let mut prep = prep0.clone();
        if let Some(ex) = &exact {
            for (p, q) in prep.points[b].iter_mut().zip(&ex.points[b]) {
                if let (Some(p), Some(q)) = (p.as_mut(), q.as_ref()) {
                    p.rel = q.rel;
                    p.ped = q.ped;
                }
            }
        }
        for p in prep.points[b].iter_mut().flatten() {
            let w = p.omega();
            let h: [Complex<f64>; 2] = std::array::from_fn(|d| {
                Complex::new(theta[d] - w * w * theta[2], w * theta[3 + d])
            });
            let (r, kyz) = match effect {
                Effect::Runout(r) => (r, 0.0),
                Effect::Cross(k) => ([Complex::new(0.0, 0.0); 2], k),
            };
            let f: [Complex<f64>; 2] = std::array::from_fn(|d| {
                p.kstar[d][0] * (p.rel[0] - r[0]) + p.kstar[d][1] * (p.rel[1] - r[1])
            });
            // [h_y kyz; kyz h_z]·ped = f
            let det = h[0] * h[1] - kyz * kyz;
            if exact.is_none() {
                p.ped = [
                    (h[1] * f[0] - kyz * f[1]) / det,
                    (h[0] * f[1] - kyz * f[0]) / det,
                ];
            }
            let mut noisy = |v: &mut Complex<f64>, c: usize| {
                v.re += p.var[c].sqrt() * unit.sample(&mut rng);
                v.im += p.var[c + 1].sqrt() * unit.sample(&mut rng);
            };
            let (mut rel, mut ped) = (p.rel, p.ped);
            for d in 0..2 {
                noisy(&mut rel[d], 2 * d);
                noisy(&mut ped[d], 4 + 2 * d);
            }
            p.rel = rel;
            p.ped = ped;
        }
        let mut state = State::fit(&prep, model.clone(), Vec::new()).expect("fit");
        let before = pedestals(&prep, &state).expect("pedestals");
        let base = state.model.clone();
        let refits = refit(&prep, &base, &mut state, 1e-3);
        assert!(
            refits.iter().any(|r| r.group == [b]),
            "the bearing refitted"
        );
        let mut after = before.clone();
        report(&prep, &state.model, &refits, &mut after, &mut []);
        for (k, peds) in [&before, &after].into_iter().enumerate() {
            for (i, q) in ["k_y", "k_z", "m"].iter().enumerate() {
                let z = (peds[b].values[*q] - theta[i]) / peds[b].std_err[*q];
                out[k].0[i] += z / n as f64;
                out[k].1[i] += z * z / n as f64;
            }
        }
    }
    for o in &mut out {
        o.1 = o.1.map(f64::sqrt);
    }
    out
}

/// With a runout at the quiet block, the final k and m are not pulled low:
/// mean z of the ML refit over 40 draws within ±0.5 (its standard error
/// 0.16), where the held-weights least squares (main's final fit before
/// session 36) is near −1.
#[test]
fn the_runout_refit_does_not_pull_a_quiet_pedestal_low() {
    let r = [Complex::new(-1.2e-7, 3.3e-7), Complex::new(2.3e-7, -1.6e-7)];
    let [wls, ml] = z_stats(Effect::Runout(r), 40);
    eprintln!("runout, (mean z, RMS z) of (k_y, k_z, m): least squares {wls:?}, ML {ml:?}");
    for z in ml.0 {
        assert!(z.abs() < 0.5, "ML {ml:?} (least squares {wls:?})");
    }
}

/// The same with a cross stiffness k_yz = 0.2·k_z at the quiet block
/// (an effect main's final values took from the held-weights least squares
/// until session 37): mean z of the ML refit within ±0.5, its RMS z below
/// 1.35 (the ± cover the scatter).
#[test]
fn the_cross_stiffness_refit_does_not_pull_a_quiet_pedestal_low() {
    let [wls, ml] = z_stats(Effect::Cross(0.2 * THETA[1]), 40);
    eprintln!("cross, (mean z, RMS z) of (k_y, k_z, m): least squares {wls:?}, ML {ml:?}");
    for (z, rms) in ml.0.iter().zip(ml.1) {
        assert!(
            z.abs() < 0.5 && rms < 1.35,
            "ML {ml:?} (least squares {wls:?})"
        );
    }
}

/// unseen-four's B3 with its probe runout (ROSS, `scripts/ross_unseen.py
/// --machine unseen-four DIR runout 1`): the noise of the stored run's
/// columns on ROSS's exact phasors (`scripts/ross_unseen_exact.py`).
const FOUR_B3: Lab = Lab {
    case: "ross-unseen/runout",
    bearing: "B3",
    theta: [19.0e6, 26.0e6, 150.0, 900.0, 1100.0],
    exact: Some("ross-unseen/runout-exact"),
};

/// A pedestal whose k and m trade with a probe runout at its bearing
/// (unseen-four's B3: the runout's four parameters and the common scale of
/// k_y, k_z, m move together) has final ± that cover the scatter of its
/// ML refit over noise draws on ROSS's exact phasors: over 100 draws RMS z
/// of k_y, k_z and m within [0.65, 1.2] and mean z within ±0.4. Measured
/// (session 40, runoutpm17): RMS z 0.82/0.83/0.83, mean z −0.17/−0.19/−0.19;
/// a ± a quarter short (session 39's reading of seeds 161-181) would give
/// RMS z about 1.3. A guard: it passes on main too (the shortfall was not
/// found on fresh seeds, docs/unseen.md "Session 40 (runoutpm17)").
#[test]
fn the_final_pedestal_std_err_covers_a_runout_trade() {
    let r = [
        Complex::new(-2.166_444_355_061_7e-8, 5.952_256_946_036_95e-8),
        Complex::new(4.150_977_319_712_62e-8, -2.906_545_610_200_31e-8),
    ];
    let [wls, ml] = z_stats_at(&FOUR_B3, Effect::Runout(r), 100, 41);
    eprintln!("four B3 runout, (mean z, RMS z) of (k_y, k_z, m): least squares {wls:?}, ML {ml:?}");
    for (z, rms) in ml.0.iter().zip(ml.1) {
        assert!(
            z.abs() < 0.4 && (0.65..1.2).contains(&rms),
            "ML {ml:?} (least squares {wls:?})"
        );
    }
}
