//! The noise of the data a cross-coupling correction on a base makes,
//! checked against a Monte-Carlo of the measurement noise itself.

use super::*;
use crate::diagnose::foundation::{self, Kind};
use crate::diagnose::state::base_model;
use crate::effects::EffectKind;
use crate::sim::{unbalance_response, EffectSet, Machine};
use plinth_shared::regression::Parameter;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};

const SKID: &str = include_str!("../../../../examples/two-pedestals-on-skid.toml");

/// The skid machine (two pedestals on a shared base) with the left
/// pedestal cross-coupled, simulated at 5-119 Hz without noise, its noise
/// columns 0.5 % of each channel's RMS: exact data and the noise they are
/// said to carry. Returns the data and the true k_yz [N/m].
fn exact_run() -> (Prepared, f64) {
    let machine = Machine::from_toml_str(SKID, "two-pedestals-on-skid.toml").expect("machine");
    let speeds: Vec<f64> = (0..58).map(|i| 5.0 + 2.0 * i as f64).collect();
    let effects = EffectSet::none().with(EffectKind::PedestalCrossCoupling, Some("left"), None);
    let mut run = unbalance_response(&machine, &speeds, &effects)
        .expect("simulation")
        .to_run_dir(None)
        .expect("run dir");
    for name in machine.bearing_names() {
        let rows: Vec<usize> = (0..run.measurements.len())
            .filter(|&i| run.measurements[i].bearing == name)
            .collect();
        let sd: [f64; 4] = std::array::from_fn(|ch| {
            let ms: f64 = rows
                .iter()
                .map(|&i| {
                    let m = &run.measurements[i];
                    if ch < 2 { m.rel[ch] } else { m.ped[ch - 2] }.norm_sqr()
                })
                .sum::<f64>()
                / rows.len() as f64;
            0.005 * ms.sqrt()
        });
        for &i in &rows {
            run.measurements[i].noise_sd = Some(sd);
        }
    }
    let k_yz = run
        .truth
        .as_ref()
        .and_then(|t| {
            t.effect_details
                .iter()
                .find(|e| e.name == "pedestal_cross_coupling")
        })
        .and_then(|e| e.parameters.get("k_yz").copied())
        .expect("k_yz in the truth");
    (Prepared::from_run(&run).expect("prepared"), k_yz)
}

/// `prep` with complex Gaussian noise of its own variances added.
fn noisy(prep: &Prepared, rng: &mut rand::rngs::StdRng) -> Prepared {
    let mut out = prep.clone();
    for o in out.points.iter_mut().flatten().flatten() {
        let mut draw = |c: usize| {
            let re: f64 = StandardNormal.sample(&mut *rng);
            let im: f64 = StandardNormal.sample(&mut *rng);
            Complex::new(re * o.var[2 * c].sqrt(), im * o.var[2 * c + 1].sqrt())
        };
        let n: [Complex<f64>; 4] = std::array::from_fn(&mut draw);
        for d in 0..2 {
            o.rel[d] += n[d];
            o.ped[d] += n[2 + d];
        }
    }
    out
}

#[test]
fn the_residual_noise_through_a_cross_coupling_correction_matches_monte_carlo() {
    let (prep, k_yz) = exact_run();
    // The shared base fitted to the data as measured (as diagnose chooses
    // it, before any correction), and the rigid model with identify's fits
    // plus the left cross-coupling at its true value.
    let mut state = State::base(&prep, Parameter::ALL.as_slice()).expect("base state");
    let rigid_model = base_model(Parameter::ALL.as_slice(), prep.bearings.len());
    let rigid_params = crate::diagnose::model::Params {
        beta: state.params.beta.clone(),
        nl: Vec::new(),
    };
    let rigid = |c: &Prepared| Prediction::new(c, &rigid_model, &rigid_params);
    let pred = rigid(&prep);
    let gap = pred.gap(&prep, None);
    let fit = foundation::fit(&prep, &pred, gap, Kind::Shared, None)
        .expect("base fit")
        .expect("a base")
        .untested("unit test");
    state.model.terms.push(Term::CrossStiffness { bearing: 0 });
    state.params.beta.push(k_yz);
    let predict = |c: &Prepared| fit.predict_on(c, &rigid(c));
    let propagated = residual_noise(&prep, &state, Some(&fit), &predict).expect("propagated");
    let residual = |data: &Prepared| {
        let c = corrected_on(data, &state, Some(&fit));
        let p = predict(&c).expect("prediction");
        (c, p)
    };
    let (c0, p0) = residual(&prep);
    // Monte-Carlo: the residual's spread under the noise the data carry.
    const DRAWS: usize = 400;
    let mut rng = rand::rngs::StdRng::seed_from_u64(17);
    let (nb, ns) = (prep.points.len(), prep.speeds_hz.len());
    let mut empirical = vec![vec![[0.0; 2]; ns]; nb];
    for _ in 0..DRAWS {
        let (c, p) = residual(&noisy(&prep, &mut rng));
        for (b, row) in empirical.iter_mut().enumerate() {
            for (j, e) in row.iter_mut().enumerate() {
                let (Some(o), Some(x), Some(o0), Some(x0)) = (
                    c.points[b][j].as_ref(),
                    p.ped[b][j],
                    c0.points[b][j].as_ref(),
                    p0.ped[b][j],
                ) else {
                    continue;
                };
                for d in 0..2 {
                    let moved = (x[d] - o.ped[d]) - (x0[d] - o0.ped[d]);
                    e[d] += moved.norm_sqr() / DRAWS as f64;
                }
            }
        }
    }
    // Each empirical variance has a relative sd of 1/sqrt(DRAWS) = 5 %.
    let (mut worst, mut worst_unpropagated) = (1.0f64, 1.0f64);
    let (mut sum_e, mut sum_p) = (0.0, 0.0);
    for b in 0..nb {
        for j in 0..ns {
            let (Some(v), Some(v_old)) = (propagated[b][j], p0.noise_var[b][j]) else {
                continue;
            };
            for d in 0..2 {
                let e = empirical[b][j][d];
                let ratio = e / v[d];
                if (ratio.ln()).abs() > worst.ln().abs() {
                    worst = ratio;
                }
                worst_unpropagated = worst_unpropagated.max(e / v_old[d]);
                sum_e += e;
                sum_p += v[d];
            }
        }
    }
    println!(
        "Monte-Carlo / propagated variance: pooled {:.3}, worst point {worst:.3}; \
         Monte-Carlo / the corrected numbers' own variance: up to {worst_unpropagated:.2}",
        sum_e / sum_p
    );
    assert!(
        (sum_e / sum_p - 1.0).abs() < 0.03,
        "pooled {}",
        sum_e / sum_p
    );
    assert!(worst > 0.75 && worst < 1.33, "worst point {worst}");
    // Without the propagation the noise is understated somewhere by far
    // more than the Monte-Carlo's own error (what this test guards).
    assert!(worst_unpropagated > 1.5, "{worst_unpropagated}");
}
