//! Bases as elements (host/src/sim/base.rs): the simulator against ROSS 2.3.0
//! on a machine whose pedestals stand on two bases
//! (tests/reference/ross/machine-c.toml, made by make_reference.py), a
//! near-rigid base against rigid ground, a rigid rotor on two pedestals on
//! one base against its 3-DOF chain solved independently, and the machine
//! file's errors.

use nalgebra::{Matrix3, Vector3};
use num_complex::Complex;
use plinth::sim::{unbalance_response, EffectSet, Machine, UnbalanceSolver};
use plinth_tests::ross::{channel_error, reference_dir, RossCase};
use std::f64::consts::TAU;
use std::path::PathBuf;

type C = Complex<f64>;

/// Base DOF phasors (y, z) of every base at every speed, from the solver.
fn base_motion(machine: &Machine, speeds: &[f64]) -> Vec<Vec<[C; 2]>> {
    let solver = UnbalanceSolver::new(machine, &EffectSet::none()).unwrap();
    let asm = solver.assembly();
    let mut work = asm.new_matrix();
    let mut x = vec![C::new(0.0, 0.0); asm.n_dof];
    speeds
        .iter()
        .map(|&s| {
            solver.solve_speed(s, &mut work, &mut x).unwrap();
            (0..machine.bases.len())
                .map(|j| {
                    let d = asm.bases.first_dof + 2 * j;
                    [x[d], x[d + 1]]
                })
                .collect()
        })
        .collect()
}

#[test]
fn machine_c_two_bases_matches_ross() {
    let case = RossCase::load("machine-c");
    let (machine, speeds) = (&case.machine, &case.speeds_hz);
    assert_eq!(machine.bases.len(), 2);
    let resp = unbalance_response(machine, speeds, &EffectSet::none()).unwrap();
    let mut worst = case.bearing_error(&resp, 1e-6);
    let motion = base_motion(machine, speeds);
    for (j, base) in machine.bases.iter().enumerate() {
        let got: Vec<[C; 2]> = motion.iter().map(|m| m[j]).collect();
        worst = worst.max(case.base_error("bases", &base.name, &got, 1e-6));
    }
    eprintln!("machine-c: largest error {worst:.2e} of the channel maximum");
    // truth.json records both bases and who stands on them.
    let bases = &resp.truth.bases;
    assert_eq!(bases.len(), 2);
    assert_eq!(bases[0].name, "skid");
    assert_eq!(bases[0].bearings, vec!["B1".to_string(), "B3".to_string()]);
    assert_eq!(bases[1].bearings, vec!["B2".to_string()]);
    assert_eq!((bases[1].m_y, bases[1].m_z), (150.0, 120.0));
}

/// A base 10⁸ times stiffer than the pedestals behaves as the rigid ground.
#[test]
fn stiff_base_reproduces_rigid_ground() {
    let machine = Machine::from_toml_path(reference_dir().join("machine-c.toml")).unwrap();
    let mut stiff = machine.clone();
    for b in &mut stiff.bases {
        b.k = [1e16, 1e16];
    }
    let mut rigid = machine.clone();
    rigid.bases.clear();
    for b in &mut rigid.bearings {
        b.base = None;
    }
    let speeds: Vec<f64> = (5..=200).step_by(5).map(f64::from).collect();
    let a = unbalance_response(&stiff, &speeds, &EffectSet::none()).unwrap();
    let b = unbalance_response(&rigid, &speeds, &EffectSet::none()).unwrap();
    let flexible = unbalance_response(&machine, &speeds, &EffectSet::none()).unwrap();
    let mut worst: f64 = 0.0;
    let mut base_effect: f64 = 0.0;
    for bi in 0..machine.bearings.len() {
        for d in 0..2 {
            let pick = |r: &plinth::sim::Response| -> Vec<C> {
                r.bearings.iter().map(|row| row[bi].ped[d]).collect()
            };
            worst = worst.max(channel_error(&pick(&a), &pick(&b)));
            base_effect = base_effect.max(channel_error(&pick(&flexible), &pick(&b)));
        }
    }
    assert!(worst < 1e-6, "stiff base vs rigid ground: {worst:.2e}");
    // ... and the flexible base does matter (the test can fail).
    assert!(
        base_effect > 0.1,
        "the base changed the response by only {base_effect:.2e}"
    );
}

/// A rigid, symmetric rotor (central disk, end bearings, identical isotropic
/// bearings and pedestals, no cross terms) moves in y and z separately as a
/// 3-DOF chain: rotor mass – 2 bearings – 2 pedestal masses – 2 pedestal
/// springs – base mass – base spring to ground. Solved here from that chain.
#[test]
fn rigid_rotor_on_one_base_matches_its_three_dof_chain() {
    let (kb, cb) = (2.0e8, 3.0e3);
    let (mp, kp, cp) = (80.0, [1.2e7, 9.0e6], [500.0, 700.0]);
    let (mb, kg, cg) = ([500.0, 420.0], [2.0e7, 1.5e7], [4.0e3, 2.5e3]);
    let (md, me) = (60.0, 1.0e-4);
    let text = format!(
        r#"
name = "rigid-on-skid"
[shaft]
material = {{ young_modulus = 2.0e17, poisson_ratio = 0.3, density = 7800.0 }}
[[shaft.sections]]
length = 0.8
outer_diameter = 0.12
elements = 2
[[disks]]
node = 1
mass = {md}
polar_inertia = 1.0
diametral_inertia = 0.6
unbalance = {me}
unbalance_angle = 30.0
[[base]]
name = "skid"
m_y = {my}
m_z = {mz}
k_y = {kgy}
k_z = {kgz}
c_y = {cgy}
c_z = {cgz}
[[bearings]]
name = "L"
node = 0
coefficients = [ {{ speed_hz = 0.0, kyy = {kb}, kzz = {kb}, cyy = {cb}, czz = {cb} }} ]
pedestal = {{ m = {mp}, k_y = {kpy}, k_z = {kpz}, c_y = {cpy}, c_z = {cpz} }}
base = "skid"
[[bearings]]
name = "R"
node = 2
coefficients = [ {{ speed_hz = 0.0, kyy = {kb}, kzz = {kb}, cyy = {cb}, czz = {cb} }} ]
pedestal = {{ m = {mp}, k_y = {kpy}, k_z = {kpz}, c_y = {cpy}, c_z = {cpz} }}
base = "skid"
"#,
        my = mb[0],
        mz = mb[1],
        kgy = kg[0],
        kgz = kg[1],
        cgy = cg[0],
        cgz = cg[1],
        kpy = kp[0],
        kpz = kp[1],
        cpy = cp[0],
        cpz = cp[1],
    );
    let machine = Machine::from_toml_str(&text, "rigid-on-skid.toml").unwrap();
    let rotor_mass = md + 7800.0 * std::f64::consts::PI * 0.12f64.powi(2) / 4.0 * 0.8;
    // Base modes of the chain lie near 20-40 Hz: sweep across them.
    let speeds: Vec<f64> = (1..=60).map(|i| 2.0 * f64::from(i)).collect();
    let resp = unbalance_response(&machine, &speeds, &EffectSet::none()).unwrap();
    let motion = base_motion(&machine, &speeds);
    let mut worst: f64 = 0.0;
    for (s, &hz) in speeds.iter().enumerate() {
        let w = TAU * hz;
        let w2 = w * w;
        let u = C::from_polar(me, 30f64.to_radians()) * w2;
        let force = [u, u * C::new(0.0, -1.0)];
        for d in 0..2 {
            let zb = C::new(2.0 * kb, 2.0 * w * cb);
            let zp = C::new(2.0 * kp[d], 2.0 * w * cp[d]);
            let zg = C::new(kg[d] - w2 * mb[d], w * cg[d]);
            let a = Matrix3::new(
                zb - w2 * rotor_mass,
                -zb,
                C::new(0.0, 0.0),
                -zb,
                zb + zp - w2 * 2.0 * mp,
                -zp,
                C::new(0.0, 0.0),
                -zp,
                zp + zg,
            );
            let x = a
                .lu()
                .solve(&Vector3::new(force[d], C::new(0.0, 0.0), C::new(0.0, 0.0)))
                .unwrap();
            let scale = x.iter().map(|v| v.norm()).fold(0.0, f64::max);
            for bi in 0..2 {
                let row = &resp.bearings[s][bi];
                worst = worst.max((row.rel[d] - (x[0] - x[1])).norm() / scale);
                worst = worst.max((row.ped[d] - x[1]).norm() / scale);
            }
            worst = worst.max((motion[s][0][d] - x[2]).norm() / scale);
        }
    }
    assert!(worst < 1e-6, "3-DOF chain vs simulator: {worst:.2e}");
}

#[test]
fn machine_file_errors_name_the_base_key() {
    let base = std::fs::read_to_string(reference_dir().join("machine-c.toml")).unwrap();
    let cases = [
        (
            base.replace("base = \"frame\"", "base = \"plinth\""),
            "bearings[1].base",
        ),
        (base.replace("k_z = 1.6e7", "k_z = -1.0"), "base[0].k_z"),
        (
            base.replace("m = 400.0", "m = 400.0\nm_y = 300.0"),
            "base[0]",
        ),
        (
            base.replace("name = \"frame\"", "name = \"skid\""),
            "base[1].name",
        ),
        (
            base.replace("c_y = 1.0e3", "c_y = 1.0e3\nzeta = 0.1"),
            "zeta",
        ),
        (
            base.replacen(
                "pedestal = { m = 60.0, k_y = 2.0e7, k_z = 1.5e7, c_y = 400.0, c_z = 300.0 }\n",
                "",
                1,
            ),
            "bearings[1].base",
        ),
    ];
    for (text, key) in cases {
        assert_ne!(text, base, "case for {key} did not change the file");
        let err = Machine::from_toml_str(&text, "machine-c.toml")
            .expect_err(key)
            .to_string();
        assert!(err.contains(key), "{key}: {err}");
        assert!(err.contains("machine-c.toml"), "{err}");
    }
}

/// Example machine on a skid: `base.csv` round-trips, and identification
/// relative to the measured base motion recovers every pedestal, where the
/// rigid-ground fit (the paper's model) is far off.
#[test]
fn measured_base_makes_the_pedestal_model_linear_again() {
    use plinth::base_csv;
    use plinth::identify::base::identify_on_measured_base;
    use plinth::identify::{identify_run, Options, Parameter};
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/two-pedestals-on-skid.toml");
    let machine = Machine::from_toml_path(&path).unwrap();
    let speeds: Vec<f64> = (5..=100).map(f64::from).collect();
    let resp = unbalance_response(&machine, &speeds, &EffectSet::none()).unwrap();
    let run = resp.to_run_dir(None).unwrap();
    let bases: Vec<(String, Vec<String>)> = resp
        .truth
        .bases
        .iter()
        .map(|b| (b.name.clone(), b.bearings.clone()))
        .collect();
    let rows = base_csv::rows_of(&resp, &bases);
    assert_eq!(rows.len(), speeds.len());
    let dir = tempfile::tempdir().unwrap();
    base_csv::write(dir.path(), &rows).unwrap();
    let back = base_csv::read(dir.path()).unwrap().unwrap();
    // Read back, each row also carries the file line it came from (the
    // header is line 1); the data round-trip exactly.
    let data: Vec<base_csv::BaseRow> = back
        .iter()
        .map(|r| base_csv::BaseRow {
            line: 0,
            ..r.clone()
        })
        .collect();
    assert_eq!(data, rows, "base.csv does not round-trip");
    assert!(back.iter().zip(2u64..).all(|(r, line)| r.line == line));
    // The skid moves: a sizeable share of the pedestal motion.
    let fits = identify_on_measured_base(&run, &back).unwrap();
    assert_eq!(fits.len(), 2);
    let rigid = identify_run(&run, &Options::default()).unwrap();
    for (fit, truth) in fits.iter().zip(&resp.truth.pedestals) {
        assert_eq!(fit.bearing, truth.bearing);
        assert_eq!(fit.base, "skid");
        for (p, want, tol) in [
            (Parameter::Ky, truth.pedestal.k_y, 1e-6),
            (Parameter::Kz, truth.pedestal.k_z, 1e-6),
            (Parameter::M, truth.pedestal.m, 1e-6),
            (Parameter::Cy, truth.pedestal.c_y, 1e-4),
            (Parameter::Cz, truth.pedestal.c_z, 1e-4),
        ] {
            let got = fit.pedestal.get(p);
            assert!(
                (got - want).abs() <= tol * want,
                "{} {}: {got} vs {want}",
                fit.bearing,
                p.name()
            );
        }
        let r = rigid.pedestal(&fit.bearing).unwrap();
        let off = (r.pedestal.k_y - truth.pedestal.k_y).abs() / truth.pedestal.k_y;
        assert!(
            off > 0.05,
            "rigid-ground fit of {} only {off:.2e} off: base too stiff for this test",
            fit.bearing
        );
    }
    // Errors name file, line and column.
    let text = std::fs::read_to_string(dir.path().join("base.csv")).unwrap();
    let bad = text.replacen("skid,left;right,", "skid,left;right,abc", 1);
    std::fs::write(dir.path().join("base.csv"), bad).unwrap();
    let err = base_csv::read(dir.path()).unwrap_err().to_string();
    assert!(err.contains("base.csv:2:4"), "{err}");
}
