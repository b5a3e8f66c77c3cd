//! The effects `pedestal_sub_base` and `bearing_coefficients` in the
//! simulator (host/src/sim/inject.rs): a pedestal on its own sub-base against
//! ROSS 2.3.0 (tests/reference/ross/machine-d.toml, made by
//! make_reference.py) and against its 3-DOF chain solved by hand, the effect
//! against the same sub-base written in the machine file, the machine file's
//! errors, and a bearing table written for another bearing.

use num_complex::Complex;
use plinth::effects::EffectKind;
use plinth::sim::cli::{simulate, SimulateArgs};
use plinth::sim::oil_film::OilFilmBearing;
use plinth::sim::{unbalance_response, BearingModel, EffectSet, Machine, UnbalanceSolver};
use plinth_tests::ross::{channel_error, reference_dir, RossCase};
use std::f64::consts::TAU;
use std::path::PathBuf;

type C = Complex<f64>;

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../examples/{name}"))
}

/// The (y, z) phasors of the last base DOFs (the sub-base, when it is the
/// only base) at every speed.
fn sub_base_motion(solver: &UnbalanceSolver, speeds: &[f64]) -> Vec<[C; 2]> {
    let asm = solver.assembly();
    assert_eq!(asm.bases.n_dof(), 2, "one sub-base expected");
    let mut work = asm.new_matrix();
    let mut x = vec![C::new(0.0, 0.0); asm.n_dof];
    speeds
        .iter()
        .map(|&s| {
            solver.solve_speed(s, &mut work, &mut x).unwrap();
            let d = asm.bases.first_dof;
            [x[d], x[d + 1]]
        })
        .collect()
}

#[test]
fn machine_d_sub_base_matches_ross() {
    let case = RossCase::load("machine-d");
    let (machine, speeds) = (&case.machine, &case.speeds_hz);
    assert!(machine.bearings[0].sub_base.is_some());
    let resp = unbalance_response(machine, speeds, &EffectSet::none()).unwrap();
    let mut worst = case.bearing_error(&resp, 1e-6);
    let solver = UnbalanceSolver::new(machine, &EffectSet::none()).unwrap();
    let motion = sub_base_motion(&solver, speeds);
    worst = worst.max(case.base_error("sub_bases", "B1", &motion, 1e-6));
    eprintln!("machine-d: largest error {worst:.2e} of the channel maximum");
    // The sub-base matters (the test can fail): without it B1's pedestal
    // moves differently.
    let mut rigid = machine.clone();
    rigid.bearings[0].sub_base = None;
    let plain = unbalance_response(&rigid, speeds, &EffectSet::none()).unwrap();
    let pick = |r: &plinth::sim::Response| -> Vec<C> {
        r.bearings.iter().map(|row| row[0].ped[0]).collect()
    };
    assert!(channel_error(&pick(&plain), &pick(&resp)) > 0.1);
    // truth.json: the machine file's sub-base is the effect in the data.
    assert_eq!(resp.truth.effects, vec!["pedestal_sub_base".to_string()]);
    let d = &resp.truth.effect_details[0];
    assert_eq!(d.bearing, "B1");
    for (key, want) in [
        ("sub_m_y", 120.0),
        ("sub_m_z", 100.0),
        ("sub_k_y", 1.5e7),
        ("sub_k_z", 1.2e7),
        ("sub_c_y", 1.5e3),
        ("sub_c_z", 1.0e3),
    ] {
        assert_eq!(d.parameters[key], want, "{key}");
    }
    let names: Vec<&str> = d.parameters.keys().map(String::as_str).collect();
    let mut expected = EffectKind::PedestalSubBase.parameter_names().to_vec();
    expected.sort_unstable();
    assert_eq!(names, expected);
    assert!(
        resp.truth.bases.is_empty(),
        "a sub-base is not a measured base"
    );
}

/// A rigid rotor on one bearing (a disk at the bearing node of a short,
/// stiff, nearly massless shaft: the unbalance force acts on the journal
/// only) on a pedestal on its sub-base: per direction the 3-DOF chain
/// rotor – bearing – pedestal mass – pedestal spring/damper – sub-base mass –
/// sub-base spring/damper – ground, solved here in closed form.
#[test]
fn rigid_rotor_on_one_bearing_matches_its_two_dof_pedestal_by_hand() {
    let (kb, cb) = ([3.0e8, 2.0e8], [2.0e3, 1.5e3]);
    let (mp, kp, cp) = (80.0, [1.2e7, 9.0e6], [500.0, 700.0]);
    let (ms, ks, cs) = ([150.0, 110.0], [2.0e7, 1.5e7], [3.0e3, 2.0e3]);
    let (md, me) = (60.0, 1.0e-4);
    let text = format!(
        r#"
name = "rigid-on-sub-base"
[shaft]
material = {{ young_modulus = 2.0e14, poisson_ratio = 0.3, density = 1.0e-9 }}
[[shaft.sections]]
length = 0.1
outer_diameter = 0.1
[[disks]]
node = 0
mass = {md}
polar_inertia = 1.0
diametral_inertia = 0.5
unbalance = {me}
unbalance_angle = 30.0
[[bearings]]
name = "only"
node = 0
coefficients = [ {{ speed_hz = 0.0, kyy = {kby}, kzz = {kbz}, cyy = {cby}, czz = {cbz} }} ]
pedestal = {{ m = {mp}, k_y = {kpy}, k_z = {kpz}, c_y = {cpy}, c_z = {cpz} }}
sub_base = {{ m_y = {msy}, m_z = {msz}, k_y = {ksy}, k_z = {ksz}, c_y = {csy}, c_z = {csz} }}
"#,
        kby = kb[0],
        kbz = kb[1],
        cby = cb[0],
        cbz = cb[1],
        kpy = kp[0],
        kpz = kp[1],
        cpy = cp[0],
        cpz = cp[1],
        msy = ms[0],
        msz = ms[1],
        ksy = ks[0],
        ksz = ks[1],
        csy = cs[0],
        csz = cs[1],
    );
    let machine = Machine::from_toml_str(&text, "rigid-on-sub-base.toml").unwrap();
    // The pedestal/sub-base modes lie near 30-80 Hz: sweep across them.
    let speeds: Vec<f64> = (1..=75).map(|i| 2.0 * f64::from(i)).collect();
    let resp = unbalance_response(&machine, &speeds, &EffectSet::none()).unwrap();
    let solver = UnbalanceSolver::new(&machine, &EffectSet::none()).unwrap();
    let motion = sub_base_motion(&solver, &speeds);
    let mut worst: f64 = 0.0;
    for (s, &hz) in speeds.iter().enumerate() {
        let w = TAU * hz;
        let w2 = w * w;
        let u = C::from_polar(me, 30f64.to_radians()) * w2;
        let force = [u, u * C::new(0.0, -1.0)];
        for d in 0..2 {
            let zb = C::new(kb[d], w * cb[d]);
            let zp = C::new(kp[d], w * cp[d]);
            let zs = C::new(ks[d] - w2 * ms[d], w * cs[d]);
            // Pedestal and sub-base as seen by the bearing: the pedestal
            // mass plus its spring in series with the sub-base.
            let z_ped = -w2 * mp + zp * zs / (zp + zs);
            // Rotor on the bearing on that pedestal.
            let z_rotor = C::new(-w2 * md, 0.0);
            let x_ped = force[d] * zb / (z_rotor * (zb + z_ped) + zb * z_ped);
            let x_rotor = x_ped * (zb + z_ped) / zb;
            let x_sub = x_ped * zp / (zp + zs);
            let scale = x_rotor.norm().max(x_ped.norm());
            let row = &resp.bearings[s][0];
            worst = worst.max((row.rel[d] - (x_rotor - x_ped)).norm() / scale);
            worst = worst.max((row.ped[d] - x_ped).norm() / scale);
            worst = worst.max((motion[s][d] - x_sub).norm() / scale);
        }
    }
    assert!(
        worst < 1e-6,
        "2-DOF pedestal by hand vs simulator: {worst:.2e}"
    );
}

/// `--effect pedestal_sub_base:right=0.4` is the machine file's `sub_base`
/// with K_S = k/0.4, M_S = m, C_S = 0.1·sqrt(K_S·M_S).
#[test]
fn sub_base_effect_is_the_machine_file_element() {
    let path = example("feng-hahn-1997-damped.toml");
    let machine = Machine::from_toml_path(&path).unwrap();
    let p = machine.pedestal("right").unwrap().unwrap();
    let size = 0.4;
    let speeds: Vec<f64> = (5..=200).step_by(3).map(f64::from).collect();
    let effects = EffectSet::none().with(EffectKind::PedestalSubBase, Some("right"), Some(size));
    let injected = unbalance_response(&machine, &speeds, &effects).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let (ks, ms) = ([p.k_y / size, p.k_z / size], p.m);
    let line = format!(
        "sub_base = {{ m = {ms:?}, k_y = {:?}, k_z = {:?}, c_y = {:?}, c_z = {:?} }}\n",
        ks[0],
        ks[1],
        0.1 * (ks[0] * ms).sqrt(),
        0.1 * (ks[1] * ms).sqrt()
    );
    // The right bearing is the last table of the file: append its sub-base.
    let by_file = Machine::from_toml_str(&format!("{text}\n{line}"), "with-sub-base.toml").unwrap();
    assert!(
        by_file.bearings[1].sub_base.is_some(),
        "sub_base went to the wrong bearing"
    );
    let filed = unbalance_response(&by_file, &speeds, &EffectSet::none()).unwrap();
    let plain = unbalance_response(&machine, &speeds, &EffectSet::none()).unwrap();
    let mut same: f64 = 0.0;
    let mut moved: f64 = 0.0;
    for b in 0..2 {
        for d in 0..2 {
            let pick = |r: &plinth::sim::Response| -> Vec<C> {
                r.bearings.iter().map(|row| row[b].ped[d]).collect()
            };
            same = same.max(channel_error(&pick(&injected), &pick(&filed)));
            moved = moved.max(channel_error(&pick(&injected), &pick(&plain)));
        }
    }
    assert!(same < 1e-12, "effect vs machine file: {same:.2e}");
    assert!(
        moved > 0.1,
        "the sub-base changed the response by only {moved:.2e}"
    );
    assert_eq!(
        injected.truth.effects,
        vec!["pedestal_sub_base".to_string()]
    );
    assert_eq!(injected.truth.effect_details, filed.truth.effect_details);
    let d = &injected.truth.effect_details[0];
    assert_eq!(d.bearing, "right");
    assert_eq!(d.parameters["sub_k_z"], p.k_z / size);
    assert_eq!(d.parameters["sub_m_y"], p.m);
    // A second sub-base under the same pedestal, or a foundation under it, is refused.
    let twice = effects
        .clone()
        .with(EffectKind::PedestalSubBase, Some("right"), None);
    let err = unbalance_response(&machine, &speeds, &twice)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("pedestal_sub_base") && err.contains("right"),
        "{err}"
    );
    let both = effects.with(EffectKind::FoundationCoupling, None, None);
    let err = unbalance_response(&machine, &speeds, &both)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("foundation_coupling") && err.contains("sub-base"),
        "{err}"
    );
}

#[test]
fn machine_file_errors_name_the_sub_base_key() {
    let base = std::fs::read_to_string(reference_dir().join("machine-d.toml")).unwrap();
    let cases = [
        (base.replace("k_y = 1.5e7", "k_y = -1.5e7"), "bearings[0].sub_base.k_y"),
        (base.replace("m_y = 120.0, m_z = 100.0", "m = 1.0, m_z = 100.0"), "bearings[0].sub_base"),
        (base.replace("c_y = 1.5e3", "c_y = 1.5e3, zeta = 0.1"), "zeta"),
        (
            base.replace("sub_base = { m_y", "sub_base = { name = \"x\", m_y"),
            "bearings[0].sub_base.name",
        ),
        (
            base.replace(
                "pedestal = { m = 90.0, k_y = 1.0e7, k_z = 8.0e6, c_y = 600.0, c_z = 400.0 }\n",
                "",
            ),
            "bearings[0].sub_base",
        ),
        (
            base.replace("[[bearings]]\nname = \"B1\"", "[[base]]\nname = \"skid\"\nm = 100.0\nk_y = 1e7\nk_z = 1e7\n\n[[bearings]]\nname = \"B1\"\nbase = \"skid\""),
            "bearings[0].sub_base",
        ),
    ];
    for (text, key) in cases {
        assert_ne!(text, base, "case for {key} did not change the file");
        let err = Machine::from_toml_str(&text, "machine-d.toml")
            .expect_err(key)
            .to_string();
        assert!(err.contains(key), "{key}: {err}");
        assert!(err.contains("machine-d.toml"), "{err}");
    }
}

/// `bearing_coefficients`: the simulation is the machine's, `bearings.csv`
/// is an oil-film table for a 15 % smaller clearance (computed here from the
/// geometry), the speed-table bearing's K and C × 1.15; truth.json holds the
/// correction and `plinth simulate` writes the true table beside it.
#[test]
fn bearing_table_for_another_bearing() {
    let path = example("feng-hahn-1997.toml");
    let mut machine = Machine::from_toml_path(&path).unwrap();
    // Make the right bearing a speed table (its oil film at 100 Hz).
    let at_100 = machine.bearing_coefficients(1, 100.0).unwrap();
    machine.bearings[1].model = BearingModel::Table(vec![(0.0, at_100)]);
    let speeds: Vec<f64> = (5..=200).step_by(5).map(f64::from).collect();
    let effects = EffectSet::none().with(EffectKind::BearingCoefficients, None, None);
    let wrong = unbalance_response(&machine, &speeds, &effects).unwrap();
    let right = unbalance_response(&machine, &speeds, &EffectSet::none()).unwrap();
    // The measurements are the machine's.
    assert_eq!(wrong.measurements(), right.measurements());
    assert_eq!(wrong.true_bearing_rows(), right.bearing_rows());
    assert!(wrong.table_differs() && !right.table_differs());
    let BearingModel::OilFilm(of) = machine.bearings[0].model.clone() else {
        panic!("the paper machine's left bearing is an oil film");
    };
    let smaller = OilFilmBearing {
        clearance: 0.85 * of.clearance,
        ..of
    };
    for row in wrong.bearing_rows() {
        let want = if row.bearing == "left" {
            smaller.coefficients(row.speed_hz).unwrap()
        } else {
            let mut w = at_100;
            for i in 0..2 {
                for j in 0..2 {
                    w.k[i][j] *= 1.15;
                    w.c[i][j] *= 1.15;
                }
            }
            w
        };
        for i in 0..2 {
            for j in 0..2 {
                for (g, w) in [
                    (row.coefficients.k[i][j], want.k[i][j]),
                    (row.coefficients.c[i][j], want.c[i][j]),
                ] {
                    assert!(
                        (g - w).abs() <= 1e-12 * w.abs().max(1.0),
                        "{} {} Hz: {g} vs {w}",
                        row.bearing,
                        row.speed_hz
                    );
                }
            }
        }
    }
    // The smaller clearance changes the table (the test can fail): the
    // largest change of a K or C entry relative to that matrix's largest.
    let mut change: f64 = 0.0;
    for row in &wrong.bearings {
        let (t, c) = (row[0].table, row[0].coefficients);
        for (a, b) in [(t.k, c.k), (t.c, c.c)] {
            let scale = b.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            for i in 0..2 {
                for j in 0..2 {
                    change = change.max((a[i][j] - b[i][j]).abs() / scale);
                }
            }
        }
    }
    assert!(
        change > 0.1,
        "a 15 % clearance error changed the table by only {change:.3}"
    );
    let d = &wrong.truth.effect_details;
    assert_eq!(
        wrong.truth.effects,
        vec!["bearing_coefficients".to_string()]
    );
    assert_eq!(d.len(), 2);
    assert_eq!(d[0].bearing, "left");
    assert!((d[0].parameters["clearance_ratio"] - 1.0 / 0.85).abs() < 1e-12);
    assert_eq!(d[0].parameters["clearance_true"], of.clearance);
    assert_eq!(d[0].parameters["clearance_written"], 0.85 * of.clearance);
    assert!((d[1].parameters["k_scale"] - 1.0 / 1.15).abs() < 1e-15);
    assert!((d[1].parameters["c_scale"] - 1.0 / 1.15).abs() < 1e-15);
    for p in &d[0].parameters {
        assert!(EffectKind::BearingCoefficients
            .parameter_names()
            .contains(&p.0.as_str()));
    }
    // `plinth simulate --effect bearing_coefficients:left=0.15` writes both tables.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    simulate(&SimulateArgs {
        machine: path.clone(),
        out: out.clone(),
        force: false,
        speeds: "10:200:10".into(),
        digits: None,
        truncate: false,
        noise: None,
        seed: 1,
        effects: vec![
            "bearing_coefficients:left=0.15".into(),
            "pedestal_sub_base:right".into(),
        ],
    })
    .unwrap();
    let written = plinth::rundir::read_bearings(out.join("bearings.csv")).unwrap();
    let true_rows = plinth::rundir::read_bearings(out.join("bearings_true.csv")).unwrap();
    assert_eq!(written.len(), true_rows.len());
    let first = |rows: &[plinth::rundir::BearingRow]| {
        rows.iter()
            .find(|r| r.bearing == "left")
            .unwrap()
            .coefficients
    };
    assert_eq!(first(&written), smaller.coefficients(10.0).unwrap());
    assert_eq!(first(&true_rows), of.coefficients(10.0).unwrap());
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("truth.json")).unwrap()).unwrap();
    let effects: Vec<&str> = truth["effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(effects, vec!["bearing_coefficients", "pedestal_sub_base"]);
    // A bad SIZE is refused with the effect's name.
    let err = unbalance_response(
        &machine,
        &speeds,
        &EffectSet::none().with(EffectKind::BearingCoefficients, Some("left"), Some(1.0)),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("bearing_coefficients") && err.contains("[0, 1)"),
        "{err}"
    );
}
