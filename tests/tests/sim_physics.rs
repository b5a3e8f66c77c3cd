//! The simulator against physics: beam natural frequencies (Euler-Bernoulli
//! and Timoshenko closed forms), a rigid rotor on pedestals (closed-form
//! unbalance response), circular orbits of an isotropic machine, mirror
//! symmetry, the Woodbury solve of coupled pedestals, and the effects.

use num_complex::Complex;
use plinth::effects::EffectKind;
use plinth::sim::modal::natural_frequencies_hz;
use plinth::sim::{unbalance_response, EffectSet, Machine, Noise};
use std::f64::consts::PI;

type C = Complex<f64>;

fn beam(length: f64, d: f64, n: usize, bearing_k: f64, young: f64, extra: &str) -> Machine {
    let text = format!(
        r#"
        [shaft]
        material = {{ young_modulus = {young:e}, shear_modulus = 8.0e10, density = 7800.0 }}
        [[shaft.sections]]
        length = {length}
        outer_diameter = {d}
        elements = {n}
        [[bearings]]
        name = "L"
        node = 0
        coefficients = [ {{ speed_hz = 0.0, kyy = {bearing_k:e}, kzz = {bearing_k:e} }} ]
        [[bearings]]
        name = "R"
        node = {n}
        coefficients = [ {{ speed_hz = 0.0, kyy = {bearing_k:e}, kzz = {bearing_k:e} }} ]
        {extra}
        "#
    );
    Machine::from_toml_str(&text, "beam.toml").unwrap()
}

/// Distinct frequencies (each bending mode appears twice, in y and in z).
fn distinct(f: &[f64], floor_hz: f64) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::new();
    for &x in f.iter().filter(|&&x| x > floor_hz) {
        if out.last().is_none_or(|&l| (x - l) > 1e-6 * x) {
            out.push(x);
        }
    }
    out
}

#[test]
fn slender_pinned_pinned_beam_matches_euler_bernoulli() {
    let (l, d, e) = (2.0, 0.02, 2.0e11);
    let m = beam(l, d, 40, 1e14, e, "");
    let f = distinct(&natural_frequencies_hz(&m, 0.0).unwrap(), 1e-3);
    let (a, i) = (PI * d * d / 4.0, PI * d.powi(4) / 64.0);
    for n in 1..=3 {
        let exact = (n as f64 * PI / l).powi(2) * (e * i / (7800.0 * a)).sqrt() / (2.0 * PI);
        let rel = (f[n - 1] - exact).abs() / exact;
        // Slender (L/d = 100): shear and rotary inertia change f by < 0.1%.
        assert!(
            rel < 2e-3,
            "mode {n}: {} Hz vs {exact} Hz ({rel:.1e})",
            f[n - 1]
        );
    }
}

#[test]
fn free_free_beam_matches_euler_bernoulli() {
    let (l, d, e) = (1.5, 0.015, 2.0e11);
    let m = beam(l, d, 40, 0.0, e, "");
    let all = natural_frequencies_hz(&m, 0.0).unwrap();
    // Four rigid-body modes (translation and tilt in y and z).
    assert!(
        all[..4].iter().all(|&x| x < 1e-3 * all[4]),
        "{:?}",
        &all[..6]
    );
    let f = distinct(&all, 1e-3 * all[4]);
    let (a, i) = (PI * d * d / 4.0, PI * d.powi(4) / 64.0);
    for (n, bl) in [4.730_040_745, 7.853_204_624, 10.995_607_84]
        .iter()
        .enumerate()
    {
        let exact = (bl / l).powi(2) * (e * i / (7800.0 * a)).sqrt() / (2.0 * PI);
        let rel = (f[n] - exact).abs() / exact;
        assert!(
            rel < 2e-3,
            "mode {}: {} Hz vs {exact} Hz ({rel:.1e})",
            n + 1,
            f[n]
        );
    }
}

#[test]
fn stubby_pinned_pinned_beam_matches_timoshenko_theory() {
    // L/d = 3: shear and rotary inertia lower the first mode by tens of percent.
    let (l, d, e, g, rho) = (0.3, 0.1, 2.0e11, 8.0e10, 7800.0);
    let m = beam(l, d, 60, 1e16, e, "");
    let f = distinct(&natural_frequencies_hz(&m, 0.0).unwrap(), 1e-3);
    let el = m.elements[0];
    let kappa = el.shear_coefficient();
    let (a, i) = (PI * d * d / 4.0, PI * d.powi(4) / 64.0);
    for n in 1..=2 {
        let k = n as f64 * PI / l;
        // (κGAk² − ρAω²)(EIk² + κGA − ρIω²) − (κGAk)² = 0, lower root.
        let (p, q) = (kappa * g * a, e * i * k * k);
        let c2 = rho * a * rho * i;
        let c1 = -(rho * a * (q + p) + rho * i * p * k * k);
        let c0 = p * k * k * (q + p) - (p * k).powi(2);
        let w2 = (-c1 - (c1 * c1 - 4.0 * c2 * c0).sqrt()) / (2.0 * c2);
        let exact = w2.sqrt() / (2.0 * PI);
        let eb = k * k * (e * i / (rho * a)).sqrt() / (2.0 * PI);
        assert!(exact < 0.9 * eb, "the case must be shear-dominated");
        let rel = (f[n - 1] - exact).abs() / exact;
        assert!(
            rel < 1e-3,
            "mode {n}: {} Hz vs Timoshenko {exact} Hz (EB {eb}) ({rel:.1e})",
            f[n - 1]
        );
    }
}

/// A practically rigid rotor (E huge) on isotropic bearings and pedestals,
/// unbalance at mid-span: translation only, a 2-DOF closed form per direction.
fn rigid_rotor(pedestal: bool) -> Machine {
    let ped = if pedestal {
        "pedestal = { m = 40.0, k_y = 2.0e6, k_z = 2.0e6, c_y = 300.0, c_z = 300.0 }"
    } else {
        ""
    };
    let text = format!(
        r#"
        [shaft]
        material = {{ young_modulus = 2.0e17, poisson_ratio = 0.3, density = 7800.0 }}
        [[shaft.sections]]
        length = 0.8
        outer_diameter = 0.06
        elements = 4
        [[disks]]
        node = 2
        mass = 50.0
        polar_inertia = 1.0
        diametral_inertia = 0.6
        unbalance = 1.0e-4
        unbalance_angle = 30.0
        [[bearings]]
        name = "left"
        node = 0
        coefficients = [ {{ speed_hz = 0.0, kyy = 1.0e6, kzz = 1.0e6, cyy = 200.0, czz = 200.0 }} ]
        {ped}
        [[bearings]]
        name = "right"
        node = 4
        coefficients = [ {{ speed_hz = 0.0, kyy = 1.0e6, kzz = 1.0e6, cyy = 200.0, czz = 200.0 }} ]
        {ped}
        "#
    );
    Machine::from_toml_str(&text, "rigid.toml").unwrap()
}

#[test]
fn rigid_rotor_on_pedestals_matches_the_closed_form() {
    for with_ped in [false, true] {
        let m = rigid_rotor(with_ped);
        let mass = m.rotor_mass();
        let speeds: Vec<f64> = (1..=60).map(|s| s as f64 * 0.5).collect();
        let r = unbalance_response(&m, &speeds, &EffectSet::none()).unwrap();
        for (s, &hz) in speeds.iter().enumerate() {
            let w = 2.0 * PI * hz;
            let f = C::from_polar(1.0e-4 * w * w, 30f64.to_radians());
            let kb = C::new(1.0e6, w * 200.0);
            // Rotor: (2kb − Mω²)x − 2kb·p = F; pedestal: (kb + kp + iωcp − mpω²)p − kb·x = 0.
            let (x, p) = if with_ped {
                let kp = C::new(2.0e6 - 40.0 * w * w, w * 300.0);
                let a11 = 2.0 * kb - mass * w * w;
                let a22 = kb + kp;
                let det = a11 * a22 - 2.0 * kb * kb;
                ((f * a22) / det, (f * kb) / det)
            } else {
                (f / (2.0 * kb - mass * w * w), C::new(0.0, 0.0))
            };
            for b in 0..2 {
                let got = r.bearings[s][b];
                let tol = 2e-5 * x.norm();
                assert!(
                    (got.rel[0] - (x - p)).norm() < tol,
                    "{hz} Hz rel_y {} vs {}",
                    got.rel[0],
                    x - p
                );
                assert!((got.ped[0] - p).norm() < tol + 1e-30, "{hz} Hz ped_y");
                // Forward circular whirl: z lags y by 90°.
                assert!((got.rel[1] - got.rel[0] * C::new(0.0, -1.0)).norm() < tol);
            }
        }
    }
}

#[test]
fn isotropic_flexible_machine_whirls_in_forward_circles() {
    let mut text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/reference/ross/machine-a.toml"
    ))
    .unwrap();
    // Make bearings and pedestals isotropic and uncoupled.
    for (from, to) in [
        ("kyz = 4.0e7, kzy = -6.0e7, kzz = 2.0e8", "kzz = 3.0e8"),
        ("kyz = 3.0e7, kzy = -5.0e7, kzz = 1.8e8", "kzz = 2.5e8"),
        ("cyz = 2.0e3, czy = 2.0e3, czz = 3.0e4", "czz = 4.0e4"),
        ("czz = 2.5e4", "czz = 3.0e4"),
        (
            "k_z = 8.0e6, c_y = 600.0, c_z = 400.0",
            "k_z = 1.0e7, c_y = 600.0, c_z = 600.0",
        ),
        (
            "k_y = 6.0e6, k_z = 8.0e6, c_y = 300.0, c_z = 500.0",
            "k_y = 8.0e6, k_z = 8.0e6, c_y = 300.0, c_z = 300.0",
        ),
    ] {
        assert!(text.contains(from), "{from}");
        text = text.replace(from, to);
    }
    let m = Machine::from_toml_str(&text, "iso.toml").unwrap();
    let speeds: Vec<f64> = (1..=200).map(f64::from).collect();
    let r = unbalance_response(&m, &speeds, &EffectSet::none()).unwrap();
    for (s, row) in r.shaft.iter().enumerate() {
        for (n, x) in row.iter().enumerate() {
            let tol = 1e-9 * x[0].norm().max(1e-30);
            assert!(
                (x[1] - x[0] * C::new(0.0, -1.0)).norm() <= tol,
                "{} Hz node {n}: {x:?}",
                speeds[s]
            );
        }
    }
    // The anisotropic original does not.
    let a = Machine::from_toml_path(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/reference/ross/machine-a.toml"
    ))
    .unwrap();
    let r = unbalance_response(&a, &[60.0], &EffectSet::none()).unwrap();
    let rel = r.bearings[0][0].rel;
    assert!((rel[0].norm() - rel[1].norm()).abs() > 0.05 * rel[0].norm());
}

#[test]
fn mirror_symmetric_machine_responds_symmetrically() {
    let m = rigid_rotor(true);
    let mut m = m;
    m.elements.iter_mut().for_each(|e| e.young = 2.0e11);
    let r = unbalance_response(&m, &[3.0, 17.0, 45.0, 120.0], &EffectSet::none()).unwrap();
    for row in &r.bearings {
        for c in 0..2 {
            let (l, rr) = (row[0].rel[c], row[1].rel[c]);
            assert!((l - rr).norm() <= 1e-9 * l.norm());
            assert!((row[0].ped[c] - row[1].ped[c]).norm() <= 1e-9 * row[0].ped[c].norm());
        }
    }
}

/// `--effect foundation_coupling` stands the pedestals on a base element:
/// exactly the machine with that base written out by hand (K_B = Σk/SIZE,
/// M_B = 2Σm, 5 % damping ratio), and the truth records the base.
#[test]
fn foundation_coupling_is_a_base_element_under_the_pedestals() {
    let m = Machine::from_toml_path(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/reference/ross/machine-a.toml"
    ))
    .unwrap();
    let size = 0.5;
    let effects = EffectSet::none().with(EffectKind::FoundationCoupling, None, Some(size));
    let speeds: Vec<f64> = (1..=40).map(|i| 5.0 * i as f64).collect();
    let injected = unbalance_response(&m, &speeds, &effects).unwrap();
    let mut by_hand = m.clone();
    let on: Vec<usize> = (0..m.bearings.len())
        .filter(|&b| m.bearings[b].pedestal.is_some())
        .collect();
    assert!(on.len() >= 2);
    let (mut k, mut mass) = ([0.0; 2], 0.0);
    for &b in &on {
        let p = m.bearings[b].pedestal.unwrap();
        k[0] += p.k_y;
        k[1] += p.k_z;
        mass += p.m;
    }
    let (kb, mb) = ([k[0] / size, k[1] / size], 2.0 * mass);
    by_hand.bases.push(plinth::sim::base::Base {
        name: "by-hand".into(),
        m: [mb, mb],
        k: kb,
        c: [0.1 * (kb[0] * mb).sqrt(), 0.1 * (kb[1] * mb).sqrt()],
        eta: 0.0,
    });
    for &b in &on {
        by_hand.bearings[b].base = Some(by_hand.bases.len() - 1);
    }
    let reference = unbalance_response(&by_hand, &speeds, &EffectSet::none()).unwrap();
    let mut largest = 0.0f64;
    let mut scale = 0.0f64;
    for (a, r) in injected.bearings.iter().zip(&reference.bearings) {
        for (x, y) in a.iter().zip(r) {
            for c in 0..2 {
                largest = largest
                    .max((x.rel[c] - y.rel[c]).norm())
                    .max((x.ped[c] - y.ped[c]).norm());
                scale = scale.max(y.rel[c].norm()).max(y.ped[c].norm());
            }
        }
    }
    assert!(largest <= 1e-12 * scale, "{largest:e} of {scale:e}");
    // The base moves (4 % of the pedestals' resonant peak on this machine).
    let base_peak = injected
        .bases
        .iter()
        .flat_map(|row| row[0].iter().map(|v| v.norm()))
        .fold(0.0, f64::max);
    let ped_peak = injected
        .bearings
        .iter()
        .flat_map(|row| row.iter().flat_map(|b| b.ped.iter().map(|v| v.norm())))
        .fold(0.0, f64::max);
    assert!(
        base_peak > 0.01 * ped_peak,
        "base {base_peak:e} against the pedestals' {ped_peak:e}"
    );
    assert_eq!(
        injected.truth.effects,
        vec!["foundation_coupling".to_string()]
    );
    assert_eq!(injected.truth.bases.len(), 1, "the base is in the truth");
    let effect = &injected.truth.effect_details[0];
    assert!((effect.parameters["base_k_y"] - kb[0]).abs() <= 1e-9 * kb[0]);
    assert!((effect.parameters["base_m_z"] - mb).abs() <= 1e-9 * mb);
}

#[test]
fn effects_are_injected_and_recorded() {
    let m = Machine::from_toml_path(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/feng-hahn-1997.toml"
    ))
    .unwrap();
    let speeds: Vec<f64> = (5..=200).map(f64::from).collect();
    let base = unbalance_response(&m, &speeds, &EffectSet::none()).unwrap();
    assert!(base.truth.effects.is_empty());
    // Sensor delay on the left pedestal channels only.
    let tau = 0.35e-3;
    let r = unbalance_response(
        &m,
        &speeds,
        &EffectSet::none().with(EffectKind::SensorDelay, Some("left"), None),
    )
    .unwrap();
    let (mb, mr) = (base.measurements(), r.measurements());
    for (a, b) in mb.iter().zip(&mr) {
        let rot = if a.bearing == "left" {
            C::from_polar(1.0, -2.0 * PI * a.speed_hz * tau)
        } else {
            C::new(1.0, 0.0)
        };
        assert!((b.ped[0] - a.ped[0] * rot).norm() <= 1e-12 * a.ped[0].norm());
        assert_eq!(a.rel, b.rel);
    }
    assert_eq!(r.truth.effects, vec!["sensor_delay"]);
    assert_eq!(r.truth.effect_details[0].parameters["tau"], tau);
    // Runout: a constant vector of 25% of the median |rel| at that bearing.
    let r = unbalance_response(
        &m,
        &speeds,
        &EffectSet::none().with(EffectKind::ProbeRunout, Some("right"), None),
    )
    .unwrap();
    let d = &r.truth.effect_details[0];
    let ry = C::new(d.parameters["r_y_re"], d.parameters["r_y_im"]);
    let mut mags: Vec<f64> = base
        .bearings
        .iter()
        .flat_map(|row| [row[1].rel[0].norm(), row[1].rel[1].norm()])
        .collect();
    mags.sort_by(f64::total_cmp);
    let median = 0.5 * (mags[mags.len() / 2 - 1] + mags[mags.len() / 2]);
    assert!((ry.norm() - 0.25 * median).abs() < 1e-12 * median);
    for (a, b) in base.measurements().iter().zip(r.measurements()) {
        if a.bearing == "right" {
            assert!((b.rel[0] - a.rel[0] - ry).norm() < 1e-12 * ry.norm());
        }
    }
    // Structural effects change the physics and are recorded with their sizes.
    let set = EffectSet::none()
        .with(EffectKind::PedestalCrossCoupling, Some("left"), None)
        .with(EffectKind::PedestalMassAnisotropy, Some("right"), None)
        .with(EffectKind::StructuralDamping, Some("left"), None);
    let r = unbalance_response(&m, &speeds, &set).unwrap();
    let det = &r.truth.effect_details;
    assert_eq!(det[0].parameters["k_yz"], 0.25 * (10.0e6f64 * 8.0e6).sqrt());
    assert_eq!(det[1].parameters["m_z"], 1.3 * 60.0);
    assert_eq!(det[2].parameters["eta"], 0.06);
    assert_eq!(
        r.truth.effects,
        vec![
            "pedestal_cross_coupling",
            "pedestal_mass_anisotropy",
            "structural_damping"
        ]
    );
    let diff = (r.bearings[50][0].ped[0] - base.bearings[50][0].ped[0]).norm();
    assert!(diff > 1e-3 * base.bearings[50][0].ped[0].norm());
    // The truth's pedestals stay the base model's.
    assert_eq!(r.truth.pedestals[1].pedestal.m, 60.0);
}

#[test]
fn noise_is_seeded_and_sized() {
    let m = Machine::from_toml_path(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/feng-hahn-1997.toml"
    ))
    .unwrap();
    let speeds: Vec<f64> = (5..=200).map(f64::from).collect();
    let r = unbalance_response(&m, &speeds, &EffectSet::none()).unwrap();
    let clean = r.to_run_dir(None).unwrap();
    let a = r
        .to_run_dir(Some(Noise {
            fraction: 0.05,
            seed: 7,
        }))
        .unwrap();
    let b = r
        .to_run_dir(Some(Noise {
            fraction: 0.05,
            seed: 7,
        }))
        .unwrap();
    let c = r
        .to_run_dir(Some(Noise {
            fraction: 0.05,
            seed: 8,
        }))
        .unwrap();
    assert_eq!(a, b);
    assert_ne!(a, c);
    // Relative RMS of the noise on the left rel_y channel ≈ 5%.
    let (mut num, mut den) = (0.0, 0.0);
    for (x, y) in clean.measurements.iter().zip(&a.measurements) {
        if x.bearing == "left" {
            num += (y.rel[0] - x.rel[0]).norm_sqr();
            den += x.rel[0].norm_sqr();
        }
    }
    let ratio = (num / den).sqrt();
    assert!((ratio - 0.05).abs() < 0.01, "{ratio}");
}

#[test]
fn paper_machine_pedestals_resonate_inside_the_speed_range() {
    for file in ["feng-hahn-1997.toml", "feng-hahn-1997-damped.toml"] {
        let path = format!("{}/../examples/{file}", env!("CARGO_MANIFEST_DIR"));
        let m = Machine::from_toml_path(&path).unwrap();
        assert_eq!(m.bearing_names(), vec!["left", "right"]);
        for b in &m.bearings {
            let (fy, fz) = b.pedestal.unwrap().natural_frequencies_hz();
            assert!(
                (5.0..200.0).contains(&fy) && (5.0..200.0).contains(&fz),
                "{file} {}: {fy} {fz}",
                b.name
            );
        }
        let speeds: Vec<f64> = (5..=200).map(f64::from).collect();
        let r = unbalance_response(&m, &speeds, &EffectSet::none()).unwrap();
        // Measurable: peak pedestal motion above 1 µm, every reading above 0.1 nm.
        let peak = r
            .bearings
            .iter()
            .flat_map(|row| row.iter().map(|b| b.ped[0].norm()))
            .fold(0.0, f64::max);
        assert!(peak > 1e-6, "{file}: peak {peak}");
        for row in &r.bearings {
            for b in row {
                assert!(b.rel[0].norm() > 1e-10 && b.ped[1].norm() > 1e-10);
            }
        }
    }
}

/// A model large enough to be solved in several threads
/// (`budget::solver_threads`) gives exactly the sequential speed-by-speed
/// solution, in speed order.
#[test]
fn threaded_sweep_equals_the_sequential_solve() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/feng-hahn-1997-damped.toml"
    ))
    .unwrap()
    .replace("elements = 10", "elements = 1200");
    let m = Machine::from_toml_str(&text, "fine.toml").unwrap();
    let solver = plinth::sim::UnbalanceSolver::new(&m, &EffectSet::none()).unwrap();
    let n_dof = solver.assembly().n_dof;
    assert!(n_dof >= 4000, "{n_dof} DOFs: too small to be threaded");
    let speeds: Vec<f64> = (1..=12).map(|i| 17.0 * i as f64).collect();
    let threaded = solver.run(&speeds).unwrap();
    let mut work = solver.assembly().new_matrix();
    let mut x = vec![C::new(0.0, 0.0); n_dof];
    for (s, &hz) in speeds.iter().enumerate() {
        solver.solve_speed(hz, &mut work, &mut x).unwrap();
        for (b, got) in threaded.bearings[s].iter().enumerate() {
            let node = solver.assembly().node_dof[solver.assembly().bearing_node[b]];
            let p = solver.assembly().pedestal_dof[b].unwrap();
            assert_eq!(got.ped, [x[p], x[p + 1]], "speed {hz} Hz bearing {b}");
            assert_eq!(got.rel, [x[node] - x[p], x[node + 1] - x[p + 1]]);
        }
    }
}
