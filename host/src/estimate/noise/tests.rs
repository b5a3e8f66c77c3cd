use super::*;
use rand::{Rng, SeedableRng};

fn normal(rng: &mut rand::rngs::StdRng) -> f64 {
    rng.sample::<f64, _>(rand_distr::StandardNormal)
}

#[test]
fn digits_of_printed_numbers() {
    assert_eq!(written_digits(1.23e-6), Some((3, -6)));
    assert_eq!(written_digits(-4.5e-9), Some((2, -9)));
    assert_eq!(written_digits(1.0), Some((1, 0)));
    assert_eq!(written_digits(0.0), None);
    let v: f64 = "1.23456789012e-5".parse().unwrap();
    assert_eq!(written_digits(v), Some((12, -5)));
}

#[test]
fn ulp_follows_each_values_magnitude() {
    let q = ColumnDigits {
        digits: 3,
        lowest_digit_exponent: -12,
    };
    assert!((q.ulp(1.23e-6) - 1e-8).abs() < 1e-20);
    assert!((q.ulp(-9.87e-9) - 1e-11).abs() < 1e-23);
    let f = ColumnDigits {
        digits: 7,
        lowest_digit_exponent: -9,
    };
    assert!((f.ulp(1.234567e-3) - 1e-9).abs() < 1e-21);
}

/// A lightly damped resonance sampled at 1 Hz: its curvature is not noise.
fn resonance(f: f64) -> Complex<f64> {
    let (fn_, zeta) = (60.0, 0.02);
    let r = f / fn_;
    Complex::new(1e-6, 0.0) / Complex::new(1.0 - r * r, 2.0 * zeta * r)
}

#[test]
fn resonance_curvature_is_not_read_as_noise() {
    let series: Vec<_> = (10..=150)
        .map(|f| (f as f64, resonance(f as f64)))
        .collect();
    let peak = resonance(60.0).norm();
    // The law's sd at a magnitude of 1e-6 m (the response's far from the
    // resonance).
    let sd = scatter_law(&series).unwrap().sd(1e-6);
    assert!(sd < 1e-4 * peak, "{sd:e} vs peak {peak:e}");
}

#[test]
fn constant_noise_level_is_recovered_through_a_resonance() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    let sigma = 2e-8;
    let mut estimates = Vec::new();
    for _ in 0..20 {
        let series: Vec<_> = (10..=150)
            .map(|f| {
                let n = Complex::new(normal(&mut rng), normal(&mut rng)) * sigma;
                (f as f64, resonance(f as f64) + n)
            })
            .collect();
        // Over a decade of magnitude either law may describe the
        // scatter; the level it implies must be the noise's.
        let law = scatter_law(&series).unwrap();
        let ms = series
            .iter()
            .map(|(_, z)| law.sd(z.norm()).powi(2))
            .sum::<f64>()
            / series.len() as f64;
        estimates.push(ms.sqrt() / sigma);
    }
    let mean = estimates.iter().sum::<f64>() / estimates.len() as f64;
    assert!((mean - 1.0).abs() < 0.08, "{mean}");
}

#[test]
fn relative_noise_law_is_recognised() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let series: Vec<_> = (0..200)
        .map(|j| {
            let f = 5.0 + j as f64;
            let z = Complex::from_polar(1e-8 * f * f / 25.0, f / 40.0);
            let n = Complex::new(normal(&mut rng), normal(&mut rng));
            (f, z + n * (0.01 * z.norm()))
        })
        .collect();
    // The law's family has a floor too (a fraction plus a floor): the
    // fraction is the noise's, and a floor, if any, leaves the law within
    // 3× of the noise at the smallest reading (it was 10× smaller than
    // the largest).
    let law = scatter_law(&series).unwrap();
    let (s, floor) = match law {
        Scatter::Relative(s) => (s, 0.0),
        Scatter::Mixed { fraction, floor } => (fraction, floor),
        other => panic!("relative noise read as {other:?}"),
    };
    assert!((s - 0.01).abs() < 0.0015, "{s}");
    assert!(floor < 3.0 * 0.01 * series[0].1.norm(), "{law:?}");
}

/// Per bearing and channel of the undamped paper machine simulated by
/// `plinth::sim` at `speeds` [Hz]: the noise-free phasors [m], speed by
/// speed.
fn paper_machine(speeds: &[f64]) -> Vec<[Vec<Complex<f64>>; 4]> {
    use crate::sim::{unbalance_response, EffectSet, Machine};
    let machine = Machine::from_toml_path(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/feng-hahn-1997.toml"
    ))
    .expect("machine file");
    let run = unbalance_response(&machine, speeds, &EffectSet::none())
        .expect("sim")
        .to_run_dir(None)
        .expect("run");
    run.measured_bearings()
        .into_iter()
        .map(|b| {
            let mut rows: Vec<_> = run.measurements.iter().filter(|m| m.bearing == b).collect();
            rows.sort_by(|a, b| a.speed_hz.total_cmp(&b.speed_hz));
            std::array::from_fn(|ch| rows.iter().map(|m| complex_value(m, ch)).collect())
        })
        .collect()
}

/// Over every bearing and channel of the paper machine at `speeds`, with
/// noise of sd `sd(|X|, channel RMS)` [m] on each real part drawn from
/// `seed`: per channel, the ratio of the law's RMS sd to the true RMS sd
/// and the worst ratio at one speed (the larger of ratio and 1/ratio).
fn law_against_truth(speeds: &[f64], seed: u64, sd: impl Fn(f64, f64) -> f64) -> Vec<(f64, f64)> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut out = Vec::new();
    for bearing in paper_machine(speeds) {
        for exact in bearing {
            let rms = (exact.iter().map(|z| z.norm_sqr()).sum::<f64>() / exact.len() as f64).sqrt();
            let truth: Vec<f64> = exact.iter().map(|z| sd(z.norm(), rms)).collect();
            let series: Vec<(f64, Complex<f64>)> = speeds
                .iter()
                .zip(&exact)
                .zip(&truth)
                .map(|((f, z), s)| {
                    (
                        *f,
                        z + Complex::new(normal(&mut rng), normal(&mut rng)) * *s,
                    )
                })
                .collect();
            let law = scatter_law(&series).expect("a law");
            let got: Vec<f64> = exact.iter().map(|z| law.sd(z.norm())).collect();
            let ms = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64;
            let level = (ms(&got) / ms(&truth)).sqrt();
            let worst = got
                .iter()
                .zip(&truth)
                .map(|(g, t)| (g / t).max(t / g))
                .fold(1.0, f64::max);
            out.push((level, worst));
        }
    }
    out
}

#[test]
fn white_noise_level_is_recovered_on_a_resonant_machine() {
    // The undamped paper machine every 2.5 Hz (its pedestal modes not
    // resolved), 1 % of each channel's RMS: over 5 seeds × 8 channels the
    // mean level is the noise's within 10 % (the cubic of session 23 read
    // 1.1-1.7×), and each within 0.6-1.6× (the sampling spread of a level
    // from 79 speeds, a quartic leaving 2 of every 7 degrees of freedom).
    let speeds: Vec<f64> = (0..79).map(|i| 5.0 + 2.5 * f64::from(i)).collect();
    let levels: Vec<Vec<f64>> = (0..5)
        .map(|seed| {
            law_against_truth(&speeds, 40 + seed, |_, rms| 0.01 * rms)
                .into_iter()
                .map(|(level, _)| level)
                .collect()
        })
        .collect();
    let all: Vec<f64> = levels.iter().flatten().copied().collect();
    let mean = all.iter().sum::<f64>() / all.len() as f64;
    let ok = (mean - 1.0).abs() < 0.1 && all.iter().all(|l| (0.6..1.6).contains(l));
    assert!(
        ok,
        "mean {mean:.3}; levels per seed and channel: {levels:.2?}"
    );
}

#[test]
fn mixed_noise_law_is_recovered_through_a_resonance() {
    // The undamped paper machine every 1 Hz (its modes sampled a few points
    // per bandwidth) with a probe's noise: 1 % of |X| plus a floor of 0.1 %
    // of the channel's RMS, sds adding in quadrature. Neither one sd nor an
    // sd proportional to |X| describes it (the channels' magnitudes span
    // two decades or more: either is 3× off at one end); over 5 seeds × 8
    // channels the mean RMS level is the noise's within 10 %, and the
    // law's sd is within 2.5× of the noise's at every speed.
    let speeds: Vec<f64> = (5..=200).map(f64::from).collect();
    let law = |m: f64, rms: f64| (0.01 * m).hypot(0.001 * rms);
    let got: Vec<Vec<(f64, f64)>> = (0..5)
        .map(|seed| law_against_truth(&speeds, 60 + seed, law))
        .collect();
    let all: Vec<(f64, f64)> = got.iter().flatten().copied().collect();
    let mean = all.iter().map(|x| x.0).sum::<f64>() / all.len() as f64;
    let ok = (mean - 1.0).abs() < 0.1 && all.iter().all(|x| x.1 < 2.5);
    assert!(
        ok,
        "mean {mean:.3}; (level, worst) per seed and channel: {got:.2?}"
    );
}

#[test]
fn a_law_term_the_data_do_not_need_is_dropped() {
    // One sd at every speed: the law is one sd (no fraction taken up from
    // the resonance's model error), on the paper machine every 1 Hz.
    let speeds: Vec<f64> = (5..=200).map(f64::from).collect();
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    for bearing in paper_machine(&speeds) {
        for exact in bearing {
            let rms = (exact.iter().map(|z| z.norm_sqr()).sum::<f64>() / exact.len() as f64).sqrt();
            let series: Vec<(f64, Complex<f64>)> = speeds
                .iter()
                .zip(&exact)
                .map(|(f, z)| {
                    let n = Complex::new(normal(&mut rng), normal(&mut rng));
                    (*f, z + n * (0.01 * rms))
                })
                .collect();
            let law = scatter_law(&series).expect("a law");
            assert!(matches!(law, Scatter::Absolute(_)), "{law:?}");
        }
    }
}

/// The undamped paper machine simulated by `plinth::sim` on `speeds`
/// (`START:STOP:STEP` [Hz]), written with 12 significant digits (rounded)
/// and read back as `plinth identify` reads it: the speeds listed as bad,
/// per bearing.
fn listed_on_exact_12_digit_paper_run(speeds: &str) -> Vec<(String, Vec<f64>)> {
    use crate::rundir::{DigitsMode, RunDir, WriteOptions};
    use crate::sim::{cli::parse_speeds, unbalance_response, EffectSet, Machine};
    let machine = Machine::from_toml_path(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/feng-hahn-1997.toml"
    ))
    .expect("machine file");
    let speeds = parse_speeds(speeds).expect("speeds");
    let run = unbalance_response(&machine, &speeds, &EffectSet::none())
        .expect("sim")
        .to_run_dir(None)
        .expect("run");
    let dir = tempfile::tempdir().expect("temporary directory");
    run.write_with(
        dir.path(),
        &WriteOptions {
            digits: Some(12),
            digits_mode: DigitsMode::Round,
        },
    )
    .expect("written");
    let read = RunDir::read(dir.path()).expect("read back");
    let id = crate::identify::identify_run(&read, &crate::identify::Options::default())
        .expect("identify");
    id.noise
        .into_iter()
        .map(|(b, n)| (b, n.outlier_speeds_hz))
        .collect()
}

/// Exact runs written with 12 digits carry only their rounding, ulp²/12 of
/// each number's own ulp, which varies tenfold with the leading digits at
/// one |X|. The variance function's one fraction per channel is below it
/// where the leading digits are small (52.6 Hz on the right pedestal of
/// these grids, bench_trust "paper-undamped digits 12" seeds 8 and 15): its
/// variances are floored by the digits, and no speed is listed.
#[test]
fn an_exact_12_digit_run_lists_no_speed() {
    for grid in ["5.5668:200:2.6156", "7.4131:200:2.3779"] {
        for (bearing, listed) in listed_on_exact_12_digit_paper_run(grid) {
            assert!(listed.is_empty(), "{grid}: {bearing} lists {listed:?}");
        }
    }
}

#[test]
fn magnitude_positive_says_what_the_hypot_says() {
    let parts = [
        0.0,
        -0.0,
        f64::MIN_POSITIVE,
        5e-324,
        -5e-324,
        1.0,
        -3.5e300,
        f64::MAX,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
    ];
    for re in parts {
        for im in parts {
            let z = Complex::new(re, im);
            assert_eq!(magnitude_positive(z), z.norm() > 0.0, "{z}");
        }
    }
}

#[test]
fn channels_sharing_windows_get_the_laws_each_gets_alone() {
    // Two channels of one series of speeds, one with a point whose smooth
    // value is zero (no sample there: other windows), sharing one cache.
    let mut rng = rand::rngs::StdRng::seed_from_u64(27);
    let speeds: Vec<f64> = (0..80).map(|i| 10.0 + 0.5 * i as f64).collect();
    let fits = local_fits(&speeds);
    let noisy = |rng: &mut rand::rngs::StdRng, scale: f64| -> Vec<Complex<f64>> {
        speeds
            .iter()
            .map(|f| {
                Complex::new(1e-6 / f, 2e-6 / (f * f))
                    + scale * Complex::new(normal(rng), normal(rng))
            })
            .collect()
    };
    let a = noisy(&mut rng, 1e-9);
    let mut b = noisy(&mut rng, 3e-9);
    let c = noisy(&mut rng, 2e-9);
    b[40..47].fill(Complex::new(0.0, 0.0));
    let mut cache = WindowCache::default();
    for values in [&a, &b, &c, &a] {
        let alone = scatter_law_of(&fits, values);
        assert!(alone.is_some());
        assert_eq!(scatter_law_with(&fits, values, &mut cache).0, alone);
    }
}

/// A table's rounding (`resolution.csv`) is each number's floor: the
/// digits' variance of numbers written in full precision is far below it,
/// the scatter's law never takes them under it, and it follows a number
/// through a sign change or a swap of channels (convention corrections),
/// not through a changed value.
#[test]
fn a_tables_rounding_floors_every_source() {
    let sd = [1e-9, 2e-9, 3e-9, 4e-9];
    let rows: Vec<Measurement> = (10..=60)
        .map(|f| {
            let x = resonance(f as f64);
            let mut m = Measurement {
                speed_hz: f as f64,
                bearing: "B".into(),
                rel: [x, x * Complex::new(0.3, 0.7)],
                ped: [x * 0.01, x * Complex::new(0.0, 0.02)],
                noise_sd: None,
                written: None,
            };
            m.set_resolution(sd);
            m
        })
        .collect();
    let refs: Vec<&Measurement> = rows.iter().collect();
    let columns = ColumnDigits::of_rows(&refs);
    let noise = BearingNoise::estimate(&refs, &columns, Quantisation::Rounding);
    assert_eq!(noise.source, NoiseSource::Digits);
    for (d, s) in noise
        .digits_var
        .iter()
        .zip(noise.scatter_var.as_ref().unwrap())
    {
        for c in 0..8 {
            let floor = 0.5 * sd[c / 2] * sd[c / 2];
            assert!(
                (d[c] - floor).abs() < 1e-12 * floor,
                "{c}: {} vs {floor:e}",
                d[c]
            );
            assert!(s[c] >= d[c]);
        }
    }
    // Negated and swapped: the same floor, channel for channel.
    let m = &rows[5];
    let mut moved = m.clone();
    moved.rel = [-m.rel[1], m.rel[0].conj()];
    assert_eq!(table_variance(&moved, 0), 0.5 * sd[1] * sd[1]);
    assert_eq!(table_variance(&moved, 3), 0.5 * sd[0] * sd[0]);
    // A value changed since carries none.
    moved.ped[0] *= 3.0;
    assert_eq!(table_variance(&moved, 4), 0.0);
}
