//! Issue 17 on a fourth machine nobody tuned to, different in kind from the
//! first three: a long flexible roll (3.45 m, three shell masses and an
//! overhung hub; tests/data/ross-unseen-4/unseen-flex.toml) on two
//! tilting-pad bearings whose table is ROSS's own thermo-hydrodynamic
//! `TiltingPad` element (symmetric cross terms, damping of 2-5e5 N·s/m,
//! stiffness rising with speed), run DOWN through its bending modes with
//! uneven speed steps and a recorder drop-out (55-61 Hz lost); B1's pedestal
//! a block 30-50 times stiffer than its bearing (its pick-ups read near
//! their floor), B2's a soft bracket with k_y = 3 k_z; every sensor with its
//! own noise law (probes 0.5 % + 0.05 µm, pick-ups 1 % + a velocity floor of
//! 1 µm/s). One case is a field instrument's 1X vector table (probes at
//! ±45° in µm pp, pick-ups in mm/s 0-pk, phase lag, speed in rpm, 3 digits)
//! read by `plinth import`. Every phasor and the truth are ROSS 2.3.0's and
//! scripts/ross_unseen.py's (`--machine unseen-flex`), seed 1 of each case
//! kept in tests/data/ross-unseen-4/<case>/; only the reading is Plinth's.
//! The rates over several seeds are measured by `scripts/bench_unseen.py
//! --machine unseen-flex` (docs/unseen-flex.md). What does not work yet is
//! written with the right assertion and ignored with the measured rate.

use plinth::diagnose::report::Diagnosis;
use plinth::field::import::{run as import, Args};
use plinth::rundir::RunDir;
use plinth_tests::rundown::identify;
use plinth_tests::unseen::{self, assert_ok_means_right, named, untrusted};
use std::path::Path;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-4");

/// The stored run directory of `case` (seed 1).
fn stored(case: &str) -> RunDir {
    unseen::stored(DATA, case)
}

/// `plinth diagnose RUN --machine unseen-flex.toml` as the command line
/// runs it: the search, then the machine-level check applied to the
/// verdict.
fn diagnosis(run: &RunDir) -> Diagnosis {
    unseen::diagnosis_with_machine_check(DATA, "unseen-flex.toml", run)
}

/// The stored field case (`clean-vel/field/`: the vector table, its layout,
/// the bearing table) through `plinth import` into `dir`, with the case's
/// truth.json beside it.
fn imported(dir: &Path) -> RunDir {
    let field = Path::new(DATA).join("clean-vel").join("field");
    let out = dir.join("run");
    import(&Args {
        table: field.join("vectors.csv"),
        layout: field.join("layout.toml"),
        bearings: field.join("bearings.csv"),
        out: out.clone(),
        slow_roll: None,
        plots: false,
        force: false,
    })
    .expect("plinth import");
    std::fs::copy(
        Path::new(DATA).join("clean-vel").join("truth.json"),
        out.join("truth.json"),
    )
    .expect("truth.json");
    RunDir::read(&out).expect("imported run directory")
}

/// Clean data: each sensor's own noise law without the noise columns, and
/// 2 significant digits without noise: nothing untrusted, no speed listed,
/// every `ok` within 3 of its ± (identify); nothing named and trusted
/// (diagnose). Measured over seeds 1-10 of these, of the same noise with
/// the columns and of 3 and 12 digits (`BENCH_JOBS=1 python3
/// scripts/bench_unseen.py --machine unseen-flex PLINTH DIR 10 clean-n1
/// clean-n1c clean-d2 clean-d3 clean-d12`): 0/50 flagged in identify, 0/50
/// named or untrusted in diagnose. (Without the columns a clean speed by
/// B1's 82 Hz peak is listed as an outlier in 4/30 runs, seeds 11, 12, 16,
/// 18; not seed 1.)
#[test]
fn clean_runs_are_flagged_by_nothing_and_ok_means_right() {
    for case in ["clean-n1", "clean-d2"] {
        let run = stored(case);
        let id = identify(&run);
        unseen::assert_flagged_by_nothing(&run, &id, &diagnosis(&run), case);
    }
}

/// A field instrument's table with the speed in rpm: each speed converted
/// to Hz lands on a row of the bearing table written in Hz. rpm/60 in
/// binary (794.70/60 = 13.245000000000001) matched no row, and 28 of the
/// 102 speeds were interpolated with a warning; `plinth import` now snaps
/// the converted speed to `SPEED_DIGITS` significant digits. And the
/// pick-ups' velocity (mm/s 0-pk) and the probes at ±45° (µm pp, lag) come
/// out as the pedestal's displacement: every k and m within 3 of its ± (and
/// 10 %) of ROSS's value, whether or not trusted (the trust is the next
/// test's).
#[test]
fn a_field_table_in_rpm_and_velocity_imports_onto_the_table_speeds_and_identifies_right() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let run = imported(dir.path());
    for m in &run.measurements {
        assert!(
            run.bearings
                .iter()
                .any(|r| r.bearing == m.bearing && r.speed_hz == m.speed_hz),
            "{} at {} Hz: no row of the bearing table",
            m.bearing,
            m.speed_hz
        );
    }
    let id = identify(&run);
    for p in &id.pedestals {
        let t = unseen::truth_of(&run, &p.bearing);
        for (name, got, se, want) in [
            ("k_y", p.pedestal.k_y, p.std_err.k_y, t.k_y),
            ("k_z", p.pedestal.k_z, p.std_err.k_z, t.k_z),
            ("m", p.pedestal.m, p.std_err.m, t.m),
        ] {
            assert!(
                (got - want).abs() < 3.0 * se && (got / want - 1.0).abs() < 0.1,
                "{} {name} = {got:.6e} ± {se:.2e}, truth {want:.6e}",
                p.bearing
            );
        }
    }
}

/// The same clean field table must not be untrusted. Until session 26
/// `plinth import` wrote the table's own rounding (3 digits, 0.1°) as the
/// noise columns, and identify takes noise columns as the whole noise; a
/// field instrument's vectors carry the sensors' noise as well (here
/// 0.5-1 % of each phasor, 5-10 times the rounding), so the lack-of-fit
/// test failed at every bearing (stored run: χ²/dof 34 912 at B1, 4 106 at
/// B2; 10/10 runs untrusted, `BENCH_JOBS=1 python3 scripts/bench_unseen.py
/// --machine unseen-flex PLINTH DIR 10 clean-vel`). import now writes no
/// noise columns and identify estimates the noise from the data.
#[test]
fn a_clean_field_table_is_not_untrusted() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let run = imported(dir.path());
    let id = identify(&run);
    assert!(untrusted(&id).is_empty(), "{:?}", untrusted(&id));
    assert_ok_means_right(&run, &id, "clean-vel");
}

/// Clean data with the noise columns must not be untrusted. B1 is the
/// stiff block whose pick-ups read near their velocity floor at low speed,
/// and the support-mode test's score, with the fit's weights frozen, had a
/// nonzero mean there (the measured displacement's noise is both in the
/// extension's column and in the residual): over seeds 1-1000 of `python3
/// scripts/ross_unseen.py --machine unseen-flex DIR clean-n1c SEED` 2.0 %
/// of B1's p-values were below 0.001, 11.7 % below 0.01, and 12/1000 runs
/// were untrusted (1.2 %, above the 1 % per run); the noise-free run
/// fits the truth (T̄ 1e-10) and with the velocity floor set to zero the
/// p-values were uniform. The score is now the Gauss-Helmert criterion's
/// gradient with its weights moving (`estimate::lack_of_fit::support`):
/// seeds 1-300, B1 0/300 below 0.001, 1.0 % below 0.01; runs untrusted 0/300
/// (3/300 before). Stored: seed 275 (`clean-n1c-275`, B1 p 5.4e-5 against
/// 5e-4 before, 4.2e-3 now). docs/trust-support-mode.md, session 35.
#[test]
fn a_clean_run_with_noise_columns_is_not_untrusted() {
    let run = stored("clean-n1c-275");
    let id = identify(&run);
    assert!(untrusted(&id).is_empty(), "{:?}", untrusted(&id));
    assert_ok_means_right(&run, &id, "clean-n1c-275");
}

/// A clean run on which diagnose named a `sensor_delay` at the stiff block
/// B1 (ped_y, τ 485 ± 73 µs, Wald 44, untrusted): a delay there trades
/// against B1's damping (−τ·k), and the Wald form's curvature at τ̂
/// overstated the criterion's drop from τ = 0 (12.6). The profiled scalar
/// is now tested by that drop (`plinth::diagnose::criterion`, "Profiled
/// scalars"). Over seeds 93-292 of `python3 scripts/ross_unseen.py
/// --machine unseen-flex DIR clean-n1c SEED`: 13/200 runs named a delay at
/// B1 and were untrusted before, 0/200 now (docs/diagnose.md, "Session 36").
/// Stored: seed 382 (`clean-n1c-382`). Its B1 support-mode p-value is
/// 5.9e-4: below the session-36 rate's share (0.005 per run, 2.5e-3 per
/// bearing), so identify untrusts B1 on it, one of that rule's measured
/// clean false alarms (docs/trust-support-mode.md "Session 36"); what is
/// tested here is that no delay (and nothing else) is named and that the
/// only reason given is that test's.
#[test]
fn a_clean_run_at_the_stiff_block_names_no_delay() {
    let run = stored("clean-n1c-382");
    let id = identify(&run);
    assert!(
        untrusted(&id).iter().all(|b| b == "B1"),
        "{:?}",
        untrusted(&id)
    );
    assert_ok_means_right(&run, &id, "clean-n1c-382");
    let d = diagnosis(&run);
    assert!(named(&d).is_empty(), "{}", d.to_text());
    assert!(
        d.trust_reasons
            .iter()
            .all(|r| r.starts_with("bearing B1: its dynamic stiffness falls with speed")),
        "{:?}",
        d.trust_reasons
    );
}

/// Every effect untrusts exactly the bearing it acts on in identify, and the
/// other bearing's `ok` values are right: pick-up-side cross-coupling, a
/// delay and a table 25 % too stiff at the soft bracket B2, runout on the
/// probes of the stiff block B1. Measured over seeds 1-5 (`BENCH_JOBS=1
/// python3 scripts/bench_unseen.py --machine unseen-flex PLINTH DIR 5
/// cross delay runout table-scale`): 20/20; diagnose named each right and
/// trusted, 20/20 (not run here: 40-130 s a run).
#[test]
fn each_effect_untrusts_exactly_its_bearing_in_identify() {
    for (case, bearings) in [
        ("cross", &["B2"][..]),
        ("delay", &["B2"]),
        ("runout", &["B1"]),
    ] {
        let run = stored(case);
        let id = identify(&run);
        assert_eq!(untrusted(&id), bearings, "{case}");
        assert_ok_means_right(&run, &id, case);
    }
}

/// B1's stiff block (450 kg, 3.0/2.0 GN/m) stands on a soft sub-base
/// (600 kg, 0.4/0.3 GN/m, its own resonance 130/112 Hz, above the 110 Hz
/// top speed); together they have one resonance in range (about 92 Hz in y,
/// 79 Hz in z) and the block's own far above it, so over 12-110 Hz the
/// support moves, per direction, as K − Ω²M − Ω⁴Q − …: one mass on one
/// spring follows the first two terms only (identify printed B1 `ok` 88 %
/// low and 117 % high until session 27). The Cramér–Rao bounds of the full
/// two-mass model on this machine's speeds and noise, with the block's and
/// the sub-base's masses each one number for y and z, are m ±132 %,
/// k_y/k_z ±220/200 %, sub-base K ±30 %, M ±69 % (docs/diagnose-sub-base.md,
/// "`pedestal_sub_base` above the range"): the bodies are not separable, so
/// diagnose names `pedestal_sub_base` (variant `above_range`) at B1 with
/// the Ω⁴ coefficient per direction and its ±, and leaves B1's values
/// untrusted. Session 28, `BENCH_JOBS=1 python3 scripts/bench_unseen.py
/// --machine unseen-flex PLINTH DIR 5 sub-base`: identify B1 untrusted 5/5;
/// diagnose named right 5/5 (pedestal_sub_base at B1 only; q_y
/// 0.95-1.23e-4 ± 1.5-2.0e-5, q_z 1.12-1.42e-4 ± 1.7-2.2e-5 N·s⁴/m; ΔBIC
/// 47 on seed 1), untrusted 5/5, wrong and trusted 0/5.
#[test]
fn a_sub_base_under_the_stiff_block_is_untrusted_and_named() {
    let run = stored("sub-base");
    let id = identify(&run);
    assert_eq!(untrusted(&id), ["B1"]);
    let d = diagnosis(&run);
    assert_eq!(
        named(&d),
        [("pedestal_sub_base".to_string(), "B1".to_string())],
        "{}",
        d.to_text()
    );
}

/// What holds for the sub-base under the stiff block (above): over 12-110 Hz
/// the support shows, per direction, its series stiffness, an apparent
/// mass and an Ω⁴ fall of the stiffness (6-13 % of it at the top speed),
/// three numbers for the four of a pedestal on a sub-base, so
/// `pedestal_sub_base` cannot be separated there. identify's support-mode
/// test (noise columns; χ²(2), 0.001 per run) untrusts B1 and only B1;
/// diagnose names nothing trusted and is untrusted with B1's reason, which
/// says the sub-base is not separable. Measured over seeds 1-5
/// (`BENCH_JOBS=1 python3 scripts/bench_unseen.py --machine unseen-flex
/// PLINTH DIR 5 sub-base`, session 27): identify B1 untrusted 5/5, ok but
/// wrong 0/5; diagnose untrusted 5/5 (nothing named in 3, a runout at B1
/// the machine-level check rejects in 2), wrong and trusted 0/5.
/// Session 28: diagnose names `pedestal_sub_base` (above the range) at B1
/// 5/5, and its reason (`diagnose::trust::above_range_reason`) says the same:
/// the pedestal's and the sub-base's values cannot be separated.
#[test]
fn a_sub_base_under_the_stiff_block_is_untrusted_with_its_reason() {
    let run = stored("sub-base");
    let id = identify(&run);
    assert_eq!(untrusted(&id), ["B1"]);
    let d = diagnosis(&run);
    assert!(!d.trusted, "{}", d.to_text());
    assert!(
        d.trust_reasons
            .iter()
            .any(|r| r.starts_with("bearing B1:") && r.contains("cannot be separated")),
        "{:?}",
        d.trust_reasons
    );
    for (effect, bearing) in named(&d) {
        assert_ne!(bearing, "B2", "{effect} named at B2: {}", d.to_text());
    }
}

/// A 150 µs delay on the stiff block's rel probes (B1) and probe runout at
/// the soft bracket (B2) (stored run: `python3 scripts/ross_unseen.py
/// --machine unseen-flex DIR delay-runout 1`). A delay τ on rel probes
/// reads as a pedestal damping −τ·k (module docs of
/// `plinth::diagnose::forward`): on a 3 GN/m block −4.5e5 N·s/m, against
/// which the delay's own Ω³τm term is a few %; with the damping free the
/// delay added nothing (ΔBIC −2) and was missed 4/5, the block left with an
/// impossible damping. Tried with that damping held at the physical bound
/// zero, both effects are named at their bearings and the run is trusted,
/// the block's k and m within 3 of their ±. τ is then the delay less the
/// true damping's share c/k (3e4/3e9 = 10 µs): below the truth, not above.
/// Measured over seeds 1-5 (`BENCH_JOBS=1 python3 scripts/bench_unseen.py
/// --machine unseen-flex PLINTH DIR 5 delay-runout`, session 28): named
/// right and trusted 5/5 (1/5 before, untrusted 4/5).
/// The delay-runout case's names: the runout at the bracket B2, the delay
/// at the stiff block B1, nothing else.
fn assert_runout_at_b2_and_delay_at_b1(d: &Diagnosis) {
    assert_eq!(
        named(d),
        [
            ("probe_runout".to_string(), "B2".to_string()),
            ("sensor_delay".to_string(), "B1".to_string())
        ],
        "{}",
        d.to_text()
    );
}

#[test]
fn a_delay_at_the_stiff_block_and_runout_at_the_bracket_are_both_named() {
    let run = stored("delay-runout");
    let d = diagnosis(&run);
    assert_runout_at_b2_and_delay_at_b1(&d);
    assert!(d.trusted, "{}", d.to_text());
    let tau = d
        .steps
        .iter()
        .find(|s| s.effect == "sensor_delay")
        .and_then(|s| s.parameters.iter().find(|p| p.name == "tau"))
        .expect("tau")
        .value;
    assert!((130e-6..=150e-6).contains(&tau), "tau {tau}");
    assert_within_three_se(&d, &run, &["k_y", "k_z", "m"]);
}

/// The delay at the stiff block printed with a ± that covers the truth
/// (stored run: `python3 scripts/ross_unseen.py --machine unseen-flex DIR
/// delay-runout 100`). The block's dampings are held at zero beside the
/// delay (the test above), and τ takes the true damping's share c/k
/// (10-12.5 µs): 132.7 µs here for 150. Until session 38 its ± was the held
/// fit's, conditional on c = 0 exactly: 2.9 µs, the truth 6.0 ± off and
/// the run trusted (seeds 98-117: mean z −4.2, 18/20 beyond 3). Freed, the
/// damping and τ·k correlate 0.999 (`diagnose::ml_final::held_delay`): the
/// ± now counts the held damping as unknown (the fit with it free), so it
/// covers the truth while the value stays the held fit's, a lower bound.
/// The ± stays below the delay itself (the delay is still named, not a
/// shrug), the held fit's ± is reported beside it, and the pedestals are
/// unchanged (k, m within 3 of their ±).
#[test]
fn the_delay_at_the_stiff_block_is_printed_within_its_error_of_the_truth() {
    let run = stored("delay-runout-100");
    let d = diagnosis(&run);
    assert_runout_at_b2_and_delay_at_b1(&d);
    let step = d
        .steps
        .iter()
        .position(|s| s.effect == "sensor_delay")
        .expect("sensor_delay");
    unseen::assert_delay_in_its_error(&run, &d, step);
    let tau = unseen::delay_of(&d, step);
    assert!(
        tau.std_err < tau.value,
        "tau {:.3e} ± {:.1e}",
        tau.value,
        tau.std_err
    );
    let held = d.steps[step].held.as_ref().expect("dampings held");
    let at_zero = held.tau_std_err_damping_zero.expect("the held fit's ±");
    assert!(
        at_zero < tau.std_err,
        "{at_zero:.1e} vs {:.1e}",
        tau.std_err
    );
    assert_within_three_se(&d, &run, &["k_y", "k_z", "m"]);
}

/// Both pedestals on the shared bedplate (900 kg, 3.0e8 / 1.5e8 N/m; B1's
/// block ten times stiffer than it): the shared base is named and the
/// pedestals after it are the machine's. Before session 29 the base fit
/// ended in a local minimum (χ² 989 where the true parameters give 847):
/// the bedplate's mass in B1's block (2604 kg for 450, k_y 16.7 GN/m for
/// 3.0) and a negative base mass taken for a mode above the range; the
/// machine-level gap rose (0.67 → 1.35). The fit now also starts with each
/// pedestal stiffer than its base (`estimate/base/unmeasured/starts.rs`):
/// χ² 836, both base modes inside the range. Measured on this run: k within
/// 0.5 of their ±, B1's m 470.6 kg (the block/bedplate mass split is the one
/// weakly seen direction, the sum 1349 kg of 1350); m is held to 10 % here,
/// k to 3 ±; the ± themselves are the next test's. Seeds 1-5 in
/// docs/bases.md.
#[test]
fn a_shared_bedplate_under_the_stiff_block_is_named_with_the_right_pedestals() {
    let run = stored("base");
    let d = diagnosis(&run);
    assert_eq!(
        named(&d),
        [("foundation_coupling".to_string(), "B1".to_string())],
        "{}",
        d.to_text()
    );
    let (before, after) = (
        d.machine_gap_before.expect("gap before"),
        d.machine_gap_after.expect("gap after"),
    );
    assert!(after < before, "machine-level gap {before} -> {after}");
    assert_within_three_se(&d, &run, &["k_y", "k_z"]);
    for b in ["B1", "B2"] {
        let t = unseen::truth_of(&run, b);
        let m = pedestal_after(&d, b).values["m"];
        assert!((m - t.m).abs() <= 0.1 * t.m, "{b} m {m:.1}, truth {}", t.m);
    }
}

/// The same run: what is printed trusted is right within 3 of its ±.
/// Session 29's fit gave B1's block m 470.6 ± 6.2 kg for 450 (3.3 ± off,
/// trusted): the Fisher ± at the fit's end, where J rose by only 0.054 at
/// one such ± along the block/bedplate mass split. The ± of a pedestal on
/// an unmeasured base now come from the profile likelihood
/// (`estimate/base/unmeasured/profile.rs`): B1 m ± 26.8 kg, k_y ± 187,
/// k_z ± 197 MN/m (Fisher 59 / 65). Main names the base untrusted with the
/// pedestals 5-11 times off.
#[test]
fn the_stiff_block_on_the_bedplate_is_trusted_only_within_its_likelihood_error() {
    let run = stored("base");
    let d = diagnosis(&run);
    assert!(d.trusted, "{}", d.to_text());
    assert_within_three_se(&d, &run, &["k_y", "k_z", "m"]);
}

/// The same run: the bedplate's own K_B, M_B, C_B printed within 3 of their
/// ± of its truth (900 kg, 3.0e8 / 1.5e8 N/m, 2.0e4 / 1.2e4 N·s/m), in the
/// step that names it and in the foundation entry. Session 31 gave them
/// the Fisher ± at the fit's end: M_B 877.9 ± 6.7 kg (y) and 884.4 ± 5.6
/// (z), 3.3 and 2.8 ± off, K_B,z 2.4 ± off, trusted; M_B sits on the
/// block/bedplate mass split, the valley the Fisher curvature understates.
/// The base's ± now come from the profile likelihood too
/// (`estimate/base/unmeasured/profile.rs`): M_B ± 26.6 / 22.8 kg, K_B ±
/// 1.28 / 0.83 MN/m, z within 1.2.
#[test]
fn the_bedplate_itself_is_printed_within_its_likelihood_error() {
    let run = stored("base");
    let d = diagnosis(&run);
    let t = &run.truth.as_ref().expect("truth").bases[0];
    let step = d
        .steps
        .iter()
        .find(|s| s.effect == "foundation_coupling")
        .expect("the base named");
    let entry = &d.foundation.as_ref().expect("foundation entry").groups[0];
    for list in [&step.parameters, &entry.parameters] {
        for (name, want) in [
            ("base_k_y", t.k_y),
            ("base_k_z", t.k_z),
            ("base_m_y", t.m_y),
            ("base_m_z", t.m_z),
            ("base_c_y", t.c_y),
            ("base_c_z", t.c_z),
        ] {
            let e = list.iter().find(|e| e.name == name).expect(name);
            assert!(
                (e.value - want).abs() <= 3.0 * e.std_err,
                "{name} {:.4e} ± {:.2e}, truth {want:.4e}",
                e.value,
                e.std_err
            );
        }
    }
}

/// The pedestal `b` after diagnose's steps.
fn pedestal_after<'a>(d: &'a Diagnosis, b: &str) -> &'a plinth::diagnose::report::Pedestal {
    d.pedestals_after
        .iter()
        .find(|p| p.bearing == b)
        .expect("pedestal")
}

/// B1's and B2's `names` (k_y, k_z, m) after diagnose's steps within 3 of
/// their ± of `run`'s truth.
fn assert_within_three_se(d: &Diagnosis, run: &RunDir, names: &[&str]) {
    for b in ["B1", "B2"] {
        let t = unseen::truth_of(run, b);
        let p = pedestal_after(d, b);
        for &name in names {
            let want = match name {
                "k_y" => t.k_y,
                "k_z" => t.k_z,
                _ => t.m,
            };
            let (got, se) = (p.values[name], p.std_err[name]);
            assert!(
                (got - want).abs() <= 3.0 * se,
                "{b} {name} {got:.4e} ± {se:.2e}, truth {want:.4e}"
            );
        }
    }
}
