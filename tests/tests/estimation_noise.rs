//! The noise model `identify` estimates (its `noise` object) and the fits it
//! gives, on run directories written to files from the simulator: the `*_sd`
//! columns when present, the digits of 2-digit data, and the scatter of
//! full-precision noisy data with its level set by the fit's χ².

use plinth::estimate::noise::NoiseSource;
use plinth::identify::{identify_run, Options, Parameter, WarningKind};
use plinth::rundir::RunDir;
use plinth::sim::{unbalance_response, EffectSet, Machine, Noise};
use plinth_tests::{rel_err, write_run};

fn simulated(path: &str) -> plinth::sim::Response {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let machine = Machine::from_toml_path(root.join(path)).expect("machine file");
    let speeds: Vec<f64> = (5..=200).map(f64::from).collect();
    unbalance_response(&machine, &speeds, &EffectSet::none()).expect("simulation")
}

/// RMS over speeds of |phasor| of each channel (rel y, rel z, ped y, ped z).
fn channel_rms(run: &RunDir, bearing: &str) -> [f64; 4] {
    let rows: Vec<_> = run
        .measurements
        .iter()
        .filter(|m| m.bearing == bearing)
        .collect();
    std::array::from_fn(|ch| {
        let ms = rows
            .iter()
            .map(|m| {
                if ch < 2 {
                    m.rel[ch].norm_sqr()
                } else {
                    m.ped[ch - 2].norm_sqr()
                }
            })
            .sum::<f64>()
            / rows.len() as f64;
        ms.sqrt()
    })
}

#[test]
fn two_digit_data_give_k_and_m_to_0_3_percent_and_c_to_10_percent() {
    for path in [
        "tests/machines/field-coast-down.toml",
        "tests/machines/three-bearing-tabulated.toml",
        "examples/feng-hahn-1997-damped.toml",
    ] {
        let run = simulated(path).to_run_dir(None).unwrap();
        let dir = write_run(&run, Some(2));
        let run = RunDir::read(dir.path()).unwrap();
        let id = identify_run(&run, &Options::default()).unwrap();
        assert_eq!(id.estimator, "ml");
        for t in &run.truth.as_ref().unwrap().pedestals {
            let p = id.pedestal(&t.bearing).unwrap();
            let noise = &id.noise[&t.bearing];
            assert_eq!(noise.source, NoiseSource::Digits, "{path} {}", t.bearing);
            assert!(!noise.scale_estimated);
            for (param, truth) in [
                (Parameter::Ky, t.pedestal.k_y),
                (Parameter::Kz, t.pedestal.k_z),
                (Parameter::M, t.pedestal.m),
            ] {
                let e = rel_err(p.pedestal.get(param), truth);
                assert!(e < 0.003, "{path} {} {}: {e:.4}", t.bearing, param.name());
            }
            for (param, truth) in [
                (Parameter::Cy, t.pedestal.c_y),
                (Parameter::Cz, t.pedestal.c_z),
            ] {
                let e = rel_err(p.pedestal.get(param), truth);
                let se = p.std_err.theta()[param as usize];
                if path.contains("feng-hahn") {
                    // The paper's pedestals have ζ ≈ 0.1 %: at 2 digits the
                    // bound on c_y is 14 % of it (`plinth accuracy`), so no
                    // estimator promises 10 %; ML must be within 3σ.
                    assert!(
                        (p.pedestal.get(param) - truth).abs() < 3.0 * se,
                        "{path} {} {}: {} ± {se} vs {truth}",
                        t.bearing,
                        param.name(),
                        p.pedestal.get(param)
                    );
                } else {
                    assert!(e < 0.10, "{path} {} {}: {e:.4}", t.bearing, param.name());
                }
            }
        }
    }
}

#[test]
fn full_precision_noisy_data_use_the_scatter_at_the_right_level() {
    let response = simulated("tests/machines/three-bearing-tabulated.toml");
    let clean = response.to_run_dir(None).unwrap();
    let fraction = 0.01;
    let run = response
        .to_run_dir(Some(Noise { fraction, seed: 3 }))
        .unwrap();
    let dir = write_run(&run, None);
    let run = RunDir::read(dir.path()).unwrap();
    let id = identify_run(&run, &Options::default()).unwrap();
    for (bearing, noise) in &id.noise {
        assert_eq!(noise.source, NoiseSource::Scatter, "{bearing}");
        assert!(noise.scale_estimated);
        let rms = channel_rms(&clean, bearing);
        for (ch, name) in ["rel_y", "rel_z", "ped_y", "ped_z"].iter().enumerate() {
            let want = fraction * rms[ch];
            let got = noise.sd[*name];
            assert!(
                (got / want - 1.0).abs() < 0.25,
                "{bearing} {name}: estimated sd {got:.3e} vs true {want:.3e}"
            );
        }
    }
}

/// True noise columns (1 % of each channel's RMS, the simulator's noise)
/// are used, pass χ², and their shape is kept: over five seeds (ten fits)
/// at most one shape rejection, the columns' shape test being a parametric
/// bootstrap at size 1e-3 (measured false rejections 1/570 fits, docs/estimation.md
/// "Session 41 (lowsnr17)"; seed 9's right bearing is rejected at the
/// bootstrap's floor, p = 1e-3). Columns claiming a third of the noise are
/// then said to misdescribe it and the ± grow to what the data show.
#[test]
fn noise_columns_are_used_and_checked_by_chi2() {
    let response = simulated("tests/machines/field-coast-down.toml");
    let clean = response.to_run_dir(None).unwrap();
    let fraction = 0.01;
    let sd_of = |bearing: &str| -> [f64; 4] {
        let rms = channel_rms(&clean, bearing);
        std::array::from_fn(|ch| fraction * rms[ch])
    };
    let mut rejected = Vec::new();
    let mut accepted = None;
    for seed in 9..=13 {
        let mut run = response.to_run_dir(Some(Noise { fraction, seed })).unwrap();
        for m in &mut run.measurements {
            m.noise_sd = Some(sd_of(&m.bearing));
        }
        let dir = write_run(&run, None);
        let read = RunDir::read(dir.path()).unwrap();
        let id = identify_run(&read, &Options::default()).unwrap();
        for p in &id.pedestals {
            let noise = &id.noise[&p.bearing];
            assert_eq!(noise.source, NoiseSource::Columns);
            assert!(
                noise.p_value > 1e-3,
                "seed {seed} {}: χ² p {}",
                p.bearing,
                noise.p_value
            );
            if p.has_warning(WarningKind::NoiseScaleMismatch) {
                rejected.push(format!("seed {seed} {}", p.bearing));
            } else {
                assert!(p.trusted, "seed {seed} {}", p.bearing);
            }
        }
        if accepted.is_none()
            && id
                .pedestals
                .iter()
                .all(|p| !p.has_warning(WarningKind::NoiseScaleMismatch))
        {
            accepted = Some((run, id));
        }
    }
    assert!(
        rejected.len() <= 1,
        "true columns' shape rejected on {rejected:?}"
    );
    let (mut run, id) = accepted.expect("a seed whose columns are all kept");
    // Columns claiming a third of the real noise: χ² says so, and the
    // standard errors grow to what the data show.
    for m in &mut run.measurements {
        m.noise_sd = Some(sd_of(&m.bearing).map(|s| s / 3.0));
    }
    let dir = write_run(&run, None);
    let read = RunDir::read(dir.path()).unwrap();
    let small = identify_run(&read, &Options::default()).unwrap();
    for (p, q) in small.pedestals.iter().zip(&id.pedestals) {
        assert!(
            p.has_warning(WarningKind::NoiseScaleMismatch),
            "{}",
            p.bearing
        );
        let ratio = p.std_err.k_y / q.std_err.k_y;
        assert!((ratio - 1.0).abs() < 0.1, "{}: {ratio}", p.bearing);
    }
}

#[test]
fn ols_stays_the_papers_fit_and_compare_ols_reports_its_efficiency() {
    let run = simulated("tests/machines/field-coast-down.toml")
        .to_run_dir(None)
        .unwrap();
    let dir = write_run(&run, Some(3));
    let run = RunDir::read(dir.path()).unwrap();
    let ols = identify_run(&run, &Options::default().ols()).unwrap();
    assert_eq!(ols.estimator, "ols");
    let ml = identify_run(
        &run,
        &Options {
            compare_ols: true,
            ..Options::default()
        },
    )
    .unwrap();
    for (o, m) in ols.pedestals.iter().zip(&ml.pedestals) {
        assert!(o.ols.is_none());
        let cmp = m.ols.as_ref().expect("the OLS comparison");
        for p in Parameter::ALL {
            assert_eq!(cmp.estimate[p.name()], o.pedestal.get(p));
            let eff = cmp.efficiency[p.name()];
            assert!(eff > 0.0 && eff <= 1.0 + 1e-9, "{}: {eff}", p.name());
        }
    }
}

#[test]
fn diagnose_base_fit_is_identifys_fit_and_its_floor_is_a_floor() {
    let run = simulated("examples/feng-hahn-1997-damped.toml")
        .to_run_dir(None)
        .unwrap();
    let dir = write_run(&run, Some(3));
    let run = RunDir::read(dir.path()).unwrap();
    let id = identify_run(&run, &Options::default()).unwrap();
    let out = plinth::diagnose::diagnose(&run, &plinth::diagnose::Options::default()).unwrap();
    let d = &out.diagnosis;
    assert!(d.effects_added.is_empty(), "{:?}", d.effects_added);
    for p in &d.pedestals_before {
        let fit = id.pedestal(&p.bearing).unwrap();
        for param in Parameter::ALL {
            let v = p.values[param.name()];
            assert!(
                rel_err(v, fit.pedestal.get(param)) < 1e-9,
                "{} {}: diagnose {v} vs identify {}",
                p.bearing,
                param.name(),
                fit.pedestal.get(param)
            );
        }
    }
    // Clean 3-digit data: the gap is the rounding's, and the floor says so
    // (the floor takes truncation's ulp²/3, which bounds rounding's ulp²/12).
    let (gap, floor) = (d.gap_before, d.noise.gap_floor_before);
    assert!(
        gap <= floor && floor <= 2.5 * gap,
        "gap {gap} vs floor {floor}"
    );
}
