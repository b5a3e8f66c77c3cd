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
