use super::*;

#[test]
fn groupings_cover_all_on_one_and_subsets() {
    assert!(groupings(1).is_empty());
    assert_eq!(groupings(2), vec![vec![vec![0, 1]]]);
    // 3: all, three pairs.
    assert_eq!(groupings(3).len(), 4);
    // 4: all, 4 triples, 6 pairs, 3 pair-pairs.
    let four = groupings(4);
    assert_eq!(four.len(), 14);
    assert!(four.contains(&vec![vec![0, 3], vec![1, 2]]));
    assert_eq!(groupings(5).len(), 1);
}

#[test]
fn sub_bases_are_single_pedestals() {
    assert_eq!(
        Kind::SubBase.groupings(3),
        vec![vec![vec![0]], vec![vec![1]], vec![vec![2]]]
    );
    assert_eq!(Kind::SubBase.effect(), "pedestal_sub_base");
    assert_eq!(Kind::Shared.groupings(3), groupings(3));
}

/// A sub-base fit with the given per-direction identifiability, base
/// k, m and their standard errors (pedestal: 8 MN/m, 80 kg).
fn fit_with(ident: [BaseIdentifiability; 2], k: [f64; 2], m: [f64; 2], se: f64) -> BaseFitResult {
    BaseFitResult {
        pedestals: vec![[8e6, 8e6, 80.0, 300.0, 250.0]],
        pedestal_std_err: vec![[1e3, 1e3, 0.1, 1.0, 1.0]],
        split_unresolved: vec![[false; 3]],
        base_unresolved: [[false; 3]; 2],
        pedestal_covariance: vec![],
        base: crate::estimate::base::BaseParams { k, c: [1e3; 2], m },
        base_std_err: crate::estimate::base::BaseParams {
            k: [se * k[0].abs(), se * k[1].abs()],
            c: [10.0; 2],
            m: [se * m[0].abs(), se * m[1].abs()],
        },
        base_frequency_hz: [40.0; 2],
        identifiability: ident,
        chi2: 100.0,
        dof: 90,
        chi2_rigid: 1e4,
        pedestal_residual_rms: vec![1.0],
        condition_number: 10.0,
        converged: true,
        iterations: 5,
        speeds_hz: vec![],
    }
}

#[test]
fn non_physical_and_undetermined_bases_are_rejected() {
    use BaseIdentifiability::*;
    let full = [Full, NotDetected];
    let good = fit_with(full, [8e6, 8e6], [120.0, 120.0], 0.01);
    assert!(physical(&good, Kind::SubBase));
    assert!(physical(&good, Kind::Shared));
    // Negative base stiffness or mass: rejected for either kind.
    let neg = fit_with(full, [-8e6, 8e6], [120.0, 120.0], 0.01);
    assert!(!physical(&neg, Kind::Shared) && !physical(&neg, Kind::SubBase));
    let neg = fit_with(full, [8e6, 8e6], [-120.0, 120.0], 0.01);
    assert!(!physical(&neg, Kind::Shared) && !physical(&neg, Kind::SubBase));
    // A negative pedestal mass: rejected.
    let mut neg = good.clone();
    neg.pedestals[0][2] = -1.0;
    assert!(!physical(&neg, Kind::Shared));
    // A sub-base seen only as a compliance or a mass line is not
    // determined (it mimics a pedestal stiffness or mass change).
    let qs = QuasiStatic {
        compliance_m_per_n: 1e-7,
        std_err: 1e-10,
    };
    let quasi = fit_with([qs, NotDetected], [1e7, 8e6], [1.0, 1.0], 0.01);
    assert!(physical(&quasi, Kind::Shared));
    assert!(!physical(&quasi, Kind::SubBase));
    // A mode in range whose k, m the data leave open (±60 %): rejected.
    let loose = fit_with(full, [8e6, 8e6], [120.0, 120.0], 0.6);
    assert!(physical(&loose, Kind::Shared));
    assert!(!physical(&loose, Kind::SubBase));
    // Nothing detected: no sub-base to offer.
    let none = fit_with([NotDetected; 2], [8e6, 8e6], [120.0, 120.0], 0.01);
    assert!(!physical(&none, Kind::SubBase));
}

#[test]
fn bootstrap_p_values() {
    let null: Vec<f64> = (0..40).map(|i| i as f64 / 4.0).collect();
    let t = FoundationTest::from_replicates(100.0, 120.0, &null, 4);
    assert_eq!(t.exceedances, 0);
    assert!(t.p_calibrated < 1e-6, "{t:?}");
    assert!(t.significant(1e-3));
    assert_eq!(t.test, "likelihood-ratio, parametric bootstrap (40)");
    let t = FoundationTest::from_replicates(5.0, 20.0, &null, 1);
    assert_eq!(t.exceedances, 20);
    assert!((t.p_empirical - 21.0 / 41.0).abs() < 1e-12);
    assert!(!t.significant(1e-3));
}

/// The skid machine with its left pedestal on rigid ground and its right
/// pedestal alone on the base (a sub-base of 120 kg, 8.0 and 6.0 MN/m),
/// simulated at 5-119 Hz without noise, the noise columns 0.5 % of each
/// channel's RMS (the sd the fits weight with, no noise added).
fn exact_sub_base_run() -> Prepared {
    use crate::sim::{unbalance_response, EffectSet, Machine};
    const SKID: &str = include_str!("../../../../examples/two-pedestals-on-skid.toml");
    let mut machine = Machine::from_toml_str(SKID, "two-pedestals-on-skid.toml").expect("machine");
    machine.bases[0].m = [120.0, 120.0];
    machine.bases[0].k = [8.0e6, 6.0e6];
    machine.bases[0].c = [1.5e3, 1.2e3];
    machine.bearings[0].base = None;
    machine.validate().expect("valid machine");
    let speeds: Vec<f64> = (0..58).map(|i| 5.0 + 2.0 * i as f64).collect();
    let mut run = unbalance_response(&machine, &speeds, &EffectSet::none())
        .expect("simulation")
        .to_run_dir(None)
        .expect("run dir");
    crate::diagnose::test_runs::with_noise_columns(&mut run, 0.005);
    Prepared::from_run(&run).expect("prepared")
}

#[test]
fn the_chain_is_read_off_the_receptance_of_a_pedestal_on_a_sub_base() {
    let prep = exact_sub_base_run();
    let obs = observations(&prep);
    let b = prep.bearing_index("right").expect("right");
    // The machine file's right pedestal and the sub-base above.
    let truth = [
        [6.0e6, 300.0, 60.0, 8.0e6, 1.5e3, 120.0],
        [8.0e6, 250.0, 60.0, 6.0e6, 1.2e3, 120.0],
    ];
    for (d, want) in truth.iter().enumerate() {
        let c = sub_base::chain_from_receptance(&obs[b], d).expect("a physical chain");
        let got = [c.k, c.c, c.m, c.k_s, c.c_s, c.m_s];
        for (g, w) in got.iter().zip(want) {
            assert!(
                (g - w).abs() < 1e-3 * w,
                "direction {d}: {got:?} vs {want:?}"
            );
        }
    }
    // The left pedestal stands on rigid ground: its "chain" is not
    // physical or puts the sub-base far stiffer than the pedestal.
    let left = prep.bearing_index("left").expect("left");
    for d in 0..2 {
        if let Some(c) = sub_base::chain_from_receptance(&obs[left], d) {
            assert!(c.k_s > 100.0 * c.k || c.m_s < 1e-3 * c.m, "{c:?}");
        }
    }
}

#[test]
fn the_sub_base_fit_from_the_receptance_reaches_the_physical_optimum() {
    let prep = exact_sub_base_run();
    let obs = observations(&prep);
    let b = prep.bearing_index("right").expect("right");
    let start = rigid_start(&prep).expect("rigid fits");
    let group = BaseGroup { bearings: vec![b] };
    let direct = fit_on_unmeasured_base(&obs, &group, &start).expect("base fit");
    let fit = sub_base::fit_from_receptance(&obs, b, &direct).expect("fit");
    assert!(physical(&fit, Kind::SubBase), "{fit:?}");
    // Exact data: χ² ≈ 0 against the rigid fit's, the truth recovered.
    assert!(
        fit.chi2 < 1e-6 * fit.chi2_rigid,
        "{} vs {}",
        fit.chi2,
        fit.chi2_rigid
    );
    let p = &fit.pedestals[0];
    for (g, w) in [
        p[0],
        p[1],
        p[2],
        fit.base.k[0],
        fit.base.k[1],
        fit.base.m[0],
    ]
    .iter()
    .zip([6.0e6, 8.0e6, 60.0, 8.0e6, 6.0e6, 120.0])
    {
        assert!((g - w).abs() < 1e-4 * w, "{p:?} {:?}", fit.base);
    }
    assert_eq!(fit.identifiability, [BaseIdentifiability::Full; 2]);
    // Its ± agree with those of the Fisher information of `estimate::base`
    // at the same optimum (the direct fit, when it ends there).
    if physical(&direct, Kind::SubBase) {
        for d in 0..2 {
            let (a, b) = (fit.base_std_err.k[d], direct.base_std_err.k[d]);
            assert!((a / b - 1.0).abs() < 0.05, "σ(K_S) {a} vs {b}");
        }
    }
}

/// Where the likelihood is nearly quadratic (a sub-base inside the range,
/// exact data), the profile's ± of the base's own K, M, C are the Fisher
/// ones to within the profile's interpolation, never below, and no
/// profile stays open.
#[test]
fn the_profile_gives_a_well_determined_base_its_fisher_errors() {
    let prep = exact_sub_base_run();
    let obs = observations(&prep);
    let b = prep.bearing_index("right").expect("right");
    let start = rigid_start(&prep).expect("rigid fits");
    let group = BaseGroup { bearings: vec![b] };
    let fisher = fit_on_unmeasured_base(&obs, &group, &start).expect("base fit");
    let mut fit = fisher.clone();
    crate::estimate::base::widen_by_profile(
        &obs,
        &group,
        &mut fit,
        crate::estimate::base::Misfit::Scaled,
    );
    assert_eq!(fit.base_unresolved, [[false; 3]; 2], "{fit:?}");
    assert_eq!(fit.split_unresolved, vec![[false; 3]], "{fit:?}");
    let (e, f) = (&fit.base_std_err, &fisher.base_std_err);
    for d in 0..2 {
        for (got, was) in [(e.k[d], f.k[d]), (e.m[d], f.m[d]), (e.c[d], f.c[d])] {
            assert!(
                got >= was && got <= 1.2 * was,
                "{d}: {got:e} vs Fisher {was:e}"
            );
        }
    }
}
