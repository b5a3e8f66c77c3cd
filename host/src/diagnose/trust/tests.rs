//! Unit tests of the verdict rules (`super`).

use super::*;
use crate::diagnose::criterion::Evidence;
use crate::diagnose::gap::Gap;

fn step(before: f64, after: f64) -> Step {
    Step {
        effect: "structural_damping".into(),
        bearing: "left".into(),
        gap_before: before,
        gap_after: after,
        gap_floor_after: 0.01,
        machine_gap_before: None,
        machine_gap_after: None,
        machine_gap_change_sd: None,
        channels: None,
        parameters: Vec::new(),
        test: "Wald".into(),
        foundation: None,
        evidence: Evidence {
            wald_floor: 100.0,
            wald_robust: 100.0,
            wald: 100.0,
            extra_parameters: 1,
            delta_bic: 90.0,
            p_value: 1e-9,
            p_adjusted: 1e-8,
        },
        runner_up: None,
        passed_over: Vec::new(),
        candidates_tried: 20,
        candidates_failed: 0,
        dropped: None,
        held: None,
    }
}

/// An agreement whose χ² moves with the gap (every reading the same
/// share of it): (gap/floor)² per real number over 200 numbers.
fn gap(gap: f64, floor: f64) -> Agreement {
    with_chi2(gap, floor, 200.0 * (gap / floor).powi(2))
}

fn with_chi2(gap: f64, floor: f64, chi2: f64) -> Agreement {
    Agreement {
        gap: Gap { gap, floor },
        chi2,
        n: 200,
    }
}

/// The worn table of the unseen machine, seed 4: the amplitude-weighted
/// gap rose a little (0.411 → 0.415) while the noise-whitened χ² the
/// fit minimises fell by far: not worse, trusted, and the gap's rise is
/// still said.
#[test]
fn a_gap_that_rose_while_the_chi2_fell_is_not_said_to_be_worse() {
    let before = with_chi2(0.411, 0.2, 2400.0);
    let after = with_chi2(0.415, 0.2, 210.0);
    assert!(!got_worse(&before, &after));
    let c = conclude(before, after, &[step(0.411, 0.415)], &[], &[]);
    assert!(c.trusted, "{:?}", c.reasons);
    assert!(
        c.verdict.contains("gap ROSE from 0.4110 to 0.4150"),
        "{}",
        c.verdict
    );
    assert!(!c.verdict.contains("gap fell"), "{}", c.verdict);
    assert!(
        c.verdict
            .contains("χ² per real number dropped from 12.000 to 1.050"),
        "{}",
        c.verdict
    );
    assert!(!c.verdict.contains(UNEXPLAINED), "{}", c.verdict);
    // The same gaps with a χ² that rose: worse, untrusted, said so.
    let after = with_chi2(0.415, 0.2, 2500.0);
    assert!(got_worse(&before, &after));
    let c = conclude(before, after, &[step(0.411, 0.415)], &[], &[]);
    assert!(!c.trusted);
    assert!(c.verdict.contains("gap ROSE"), "{}", c.verdict);
    assert!(
        c.verdict.contains("GREW from 12.000 to 12.500"),
        "{}",
        c.verdict
    );
    assert!(
        c.reasons.iter().any(|r| r.contains("got worse")),
        "{:?}",
        c.reasons
    );
    // A gap that fell while the χ² rose: the gap is said to fall, the
    // model is still worse on the fit's yardstick.
    let c = conclude(
        with_chi2(0.30, 0.2, 300.0),
        with_chi2(0.25, 0.2, 320.0),
        &[step(0.30, 0.25)],
        &[],
        &[],
    );
    assert!(
        c.verdict.contains("gap fell from 0.3000 to 0.2500"),
        "{}",
        c.verdict
    );
    assert!(!c.trusted);
    // Nothing added: nothing got worse, whatever the numbers.
    assert!(
        conclude(before, with_chi2(0.411, 0.2, 2500.0), &[], &[], &[])
            .reasons
            .iter()
            .all(|r| !r.contains("got worse"))
    );
}

#[test]
fn a_gap_that_rose_is_said_to_rise_and_is_not_trusted() {
    let c = conclude(
        gap(0.10, 0.01),
        gap(0.12, 0.01),
        &[step(0.10, 0.12)],
        &[],
        &[],
    );
    assert!(c.verdict.contains("ROSE"), "{}", c.verdict);
    assert!(!c.verdict.contains("fell"), "{}", c.verdict);
    assert!(
        c.verdict.contains("ROSE from 0.1000 to 0.1200"),
        "{}",
        c.verdict
    );
    assert!(c.verdict.contains(UNEXPLAINED), "{}", c.verdict);
    assert!(!c.trusted);
    assert!(c.reasons.iter().any(|r| r.contains("rose")));
}

#[test]
fn a_fall_still_far_above_the_floor_is_unexplained() {
    let c = conclude(gap(1.5, 0.1), gap(1.29, 0.09), &[step(1.5, 1.29)], &[], &[]);
    assert!(
        c.verdict.contains("fell from 1.5000 to 1.2900"),
        "{}",
        c.verdict
    );
    assert!(c.verdict.contains(UNEXPLAINED), "{}", c.verdict);
    assert!(!c.trusted);
    // Nothing added, gap far above the floor: unexplained too.
    let c = conclude(gap(1.48, 0.097), gap(1.48, 0.097), &[], &[], &[]);
    assert!(c.verdict.contains(UNEXPLAINED), "{}", c.verdict);
    assert!(!c.trusted);
}

#[test]
fn a_fall_to_the_floor_is_trusted() {
    let c = conclude(gap(1.5, 0.1), gap(0.11, 0.1), &[step(1.5, 0.11)], &[], &[]);
    assert!(c.verdict.contains("fell"), "{}", c.verdict);
    assert!(!c.verdict.contains(UNEXPLAINED), "{}", c.verdict);
    assert!(c.trusted, "{:?}", c.reasons);
    let c = conclude(gap(0.02, 0.01), gap(0.02, 0.01), &[], &[], &[]);
    assert!(c.verdict.starts_with("No significant missing effect"));
    assert!(c.trusted);
}

fn channel(bearing: &str, direction: &str, gap: f64, floor: f64) -> Location {
    Location {
        bearing: bearing.into(),
        direction: direction.into(),
        share: 0.5,
        gap,
        floor,
        peak_hz: 40.0,
        resonance_hz: None,
        trend: 0.0,
        bands: Vec::new(),
        summary: String::new(),
    }
}

#[test]
fn one_channel_far_above_its_own_floor_is_unexplained_though_the_pool_is_not() {
    // The unseen four-bearing machine's sub-base case: pooled 0.29
    // against 0.24, the sub-base bearing's y channel 0.615 against 0.087.
    let chans = [
        channel("B4", "y", 0.31, 0.30),
        channel("B3", "y", 0.615, 0.087),
        channel("B3", "z", 0.09, 0.085),
    ];
    let c = conclude(gap(0.29, 0.24), gap(0.29, 0.24), &[], &[], &chans);
    assert!(!c.trusted);
    assert!(c.verdict.contains("bearing B3 y"), "{}", c.verdict);
    assert!(c.verdict.contains(UNEXPLAINED), "{}", c.verdict);
    assert_eq!(c.reasons.len(), 1, "{:?}", c.reasons);
    // Every channel within 3× its own floor: trusted as before.
    let chans = [channel("B3", "y", 0.2, 0.087), channel("B4", "y", 0.3, 0.3)];
    let c = conclude(gap(0.29, 0.24), gap(0.29, 0.24), &[], &[], &chans);
    assert!(c.trusted, "{:?}", c.reasons);
}

#[test]
fn negative_mass_is_flagged_through_identify_physical() {
    let fit = PedestalFit {
        bearing: "left".into(),
        pedestal: crate::estimate::Pedestal {
            k_y: 1e7,
            k_z: 8e6,
            m: -20.0,
            c_y: 300.0,
            c_z: 250.0,
        },
        std_err: crate::estimate::Pedestal {
            k_y: 1e4,
            k_z: 1e4,
            m: 1.0,
            c_y: 10.0,
            c_z: 10.0,
        },
        residual_rms: 0.0,
        condition_number: 1.0,
        fixed: Vec::new(),
        trusted: true,
        speeds: 50,
        equations: 200,
        speed_range_hz: [5.0, 100.0],
        warnings: Vec::new(),
        ols: None,
        suspected_convention_error: None,
        base: None,
        base_measured: None,
        covariance: None,
        modal: None,
    };
    let c = conclude(gap(0.02, 0.01), gap(0.02, 0.01), &[], &[fit], &[]);
    assert!(!c.trusted);
    assert!(c.reasons[0].contains("negative mass"), "{:?}", c.reasons);
}

/// The skid with cross-coupling at one pedestal, re-simulated with a
/// base whose ± is of the order of its values: floor 1.10, gap 0.92
/// (`plinth simulate examples/two-pedestals-on-skid.toml --speeds 5:120:2
/// --noise 0.005 --seed 57 --effect pedestal_cross_coupling:left`, then
/// `diagnose --machine`): the check cannot judge, and says so.
#[test]
fn a_machine_floor_near_the_response_cannot_judge() {
    assert_eq!(
        MachineCheck::of(0.92, 1.10),
        MachineCheck::CannotJudge {
            limit: 3.3000000000000003
        }
    );
    assert_eq!(MachineCheck::of(0.05, 0.03), MachineCheck::Agrees);
    assert!(matches!(
        MachineCheck::of(0.2, 0.03),
        MachineCheck::Disagrees { .. }
    ));
    // A gap beyond even a wide limit still disagrees.
    assert!(matches!(
        MachineCheck::of(4.0, 1.1),
        MachineCheck::Disagrees { .. }
    ));
    assert!(matches!(
        MachineCheck::of(f64::NAN, 0.01),
        MachineCheck::Disagrees { .. }
    ));
    // The edge: a limit of exactly half the response still judges.
    assert_eq!(
        MachineCheck::of(0.1, MACHINE_INFORMATIVE_LIMIT / AT_THE_FLOOR),
        MachineCheck::Agrees
    );
}
