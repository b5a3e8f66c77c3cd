//! The phasors against the truth: constant speed at non-integer samples per
//! revolution, a 200 → 5 Hz run-down, DC and harmonics rejected, averaging
//! over R revolutions, and run-downs through a resonance.

use super::*;

#[test]
fn constant_speed_with_non_integer_samples_per_revolution() {
    let channels = three_sensors();
    for f in [5.3, 37.3, 199.7] {
        let shaft = RunDown {
            f0: f,
            rate: 0.0,
            offset: 0.41,
        };
        let run = simulate(
            configured(&channels),
            shaft,
            &channels,
            12.0 / f,
            1000,
            |_| {},
        );
        let n = run.phasors().count();
        assert!(n >= 6, "{f} Hz: only {n} outputs");
        assert!(run.faults().is_empty(), "{:?}", run.faults());
        let worst = check(&run, &channels, 1e-4);
        std::println!(
            "{f} Hz: worst relative errors {:.1e} {:.1e} {:.1e}",
            worst[0],
            worst[1],
            worst[2]
        );
    }
}

#[test]
fn run_down_200_to_5_hz_at_5_hz_per_s() {
    let channels = three_sensors();
    let shaft = RunDown {
        f0: 200.0,
        rate: 5.0,
        offset: 0.73,
    };
    let run = simulate(configured(&channels), shaft, &channels, 39.0, 4096, |_| {});
    assert!(run.faults().is_empty(), "{:?}", run.faults());
    // Every revolution but the first acquisition ones and the one still held back.
    let outputs = run.phasors().count();
    assert!(
        outputs + 6 >= run.edges.len(),
        "{outputs} outputs from {} edges",
        run.edges.len()
    );
    // Worst error per speed band, down to the slowest revolutions.
    let bands = [(150.0, 201.0), (50.0, 150.0), (15.0, 50.0), (5.0, 15.0)];
    for (lo, hi) in bands {
        let mut worst = [0.0f64; 3];
        let mut count = 0;
        for p in run
            .phasors()
            .filter(|p| p.speed_hz >= lo && p.speed_hz < hi)
        {
            count += 1;
            for c in 0..3 {
                worst[c] = worst[c].max(relative_error(p.displacement[c], channels[c].d));
            }
        }
        std::println!(
            "{lo}-{hi} Hz: {count} revolutions, worst relative errors {:.1e} {:.1e} {:.1e}",
            worst[0],
            worst[1],
            worst[2]
        );
        assert!(count > 0, "no revolution in {lo}-{hi} Hz");
    }
    check(&run, &channels, 1e-4);
}

#[test]
fn dc_and_harmonics_are_rejected_during_the_run_down() {
    // The same channel with and without a DC 10× and 2X, 3X as large as the
    // 1X: the difference must be below the accuracy target.
    let clean = Channel::new(Sensor::displacement(1.0), (1.0, 0.5));
    let dirty = clean.with_extras(11.0, (1.0, -0.7), (-0.6, 0.9));
    let channels = [clean, dirty];
    let shaft = RunDown {
        f0: 60.0,
        rate: 5.0,
        offset: 0.2,
    };
    let run = simulate(configured(&channels), shaft, &channels, 11.0, 777, |_| {});
    let worst = check(&run, &channels, 1e-4);
    std::println!("clean {:.1e}, with DC+2X+3X {:.1e}", worst[0], worst[1]);
    assert!(run.phasors().count() > 200);
}

#[test]
fn averaging_over_r_revolutions() {
    // D grows with shaft angle, so each revolution has its own phasor: the
    // average must be the mean of the R displacements in the middle of each
    // revolution and the speed R over their duration.
    let growth = 1e-3; // per rad
    let channel =
        Channel::new(Sensor::displacement(1.0), (0.8, -0.3)).with_envelope(Envelope::Growth {
            g1: C64::new(growth, 0.0),
            g2: C64::new(0.0, 0.0),
        });
    let shaft = RunDown {
        f0: 30.0,
        rate: 5.0,
        offset: 0.6,
    };
    let r = 4u16;
    let mut config = configured(&[channel]);
    config.revolutions_per_output = r;
    let run = simulate(config, shaft, &[channel], 3.0, 2048, |_| {});
    let mut outputs = 0;
    let mut last_id = 0;
    for p in run.phasors() {
        assert_eq!(p.revolutions, r);
        // Edge count c is the edge at θ = 2π(c − 1); the R revolutions of this
        // output are those closed by edges c − R + 1 … c, revolution n
        // starting at θ = 2π(n − 1), i.e. φ = 2π(n − 1 + offset).
        let mut want = C64::new(0.0, 0.0);
        for n in (p.revolution - r as u32)..p.revolution {
            let mid = TAU * (n as f64 - 1.0 + shaft.offset) + core::f64::consts::PI;
            want += channel.displacement(0.0, mid);
        }
        let want = want / r as f64;
        let err = relative_error(p.displacement[0], (want.re, want.im));
        assert!(err < 1e-5, "revolution {}: {err:.2e}", p.revolution);
        let speed = FS * r as f64 / run.duration(p);
        assert!((p.speed_hz as f64 - speed).abs() / speed < 1e-6);
        assert!(p.revolution >= last_id + r as u32);
        last_id = p.revolution;
        outputs += 1;
    }
    assert!(outputs >= 15, "{outputs}");
}

/// The three sensors through a resonance (ζ = 2 %) during a run-down at
/// `rate` [Hz/s]: every revolution's displacement phasor against the
/// response at the revolution's speed, relative to the peak response.
fn through_a_resonance(rate: f64) -> [f64; 3] {
    let resonance = Envelope::Resonance {
        natural_hz: 45.0,
        zeta: 0.02,
    };
    let channels = three_sensors().map(|c| c.with_envelope(resonance));
    let shaft = RunDown {
        f0: 60.0,
        rate,
        offset: 0.37,
    };
    let run = simulate(
        configured(&channels),
        shaft,
        &channels,
        25.0 / rate,
        4096,
        |_| {},
    );
    assert!(run.faults().is_empty(), "{:?}", run.faults());
    let mut worst = [0.0f64; 3];
    let mut count = 0;
    for p in run.phasors() {
        let f = p.speed_hz as f64;
        count += 1;
        for (c, ch) in channels.iter().enumerate() {
            let want = ch.displacement(f, 0.0);
            let peak = C64::new(ch.d.0, ch.d.1).norm() / (2.0 * 0.02);
            let got = C64::new(p.displacement[c].re as f64, p.displacement[c].im as f64);
            worst[c] = worst[c].max((got - want).norm() / peak);
        }
    }
    assert!(
        count as f64 > 0.9 * 25.0 * 45.0 / rate,
        "{count} revolutions"
    );
    std::println!(
        "{rate} Hz/s through 45 Hz, ζ = 2 %: worst error / peak {:.1e} {:.1e} {:.1e}",
        worst[0],
        worst[1],
        worst[2]
    );
    worst
}

#[test]
fn a_field_run_down_through_a_resonance_gives_the_response_at_speed() {
    // 1 Hz/s: a large machine coasting down; the phasor changes by up to
    // 2.5 % per revolution at the peak.
    for (c, w) in through_a_resonance(1.0).iter().enumerate() {
        assert!(*w < 1e-4, "channel {c}: {w:.2e}");
    }
}

#[test]
fn a_fast_run_down_through_a_resonance_gives_the_response_at_speed() {
    // 4 Hz/s: up to 10 % per revolution; the cubic remainder grows as the
    // cube of that.
    for (c, w) in through_a_resonance(4.0).iter().enumerate() {
        assert!(*w < 1e-3, "channel {c}: {w:.2e}");
    }
}
