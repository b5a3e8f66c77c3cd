//! The reported noise of each phasor against the real scatter of phasors
//! made from signals with known white noise.
//!
//! The extractor is linear in the samples for given keyphasor edges, so the
//! noise of each output is exactly the noisy run's phasor minus the clean
//! run's (same signal, same edges): the real error of every output, with no
//! model of it. Over a run the reported sd² must average to the real |error|².

use super::*;
use crate::testing::Gauss;

/// Per channel: sqrt(Σ reported sd² / Σ real |error|²) over the outputs, and
/// how many outputs.
fn reported_over_real(
    revolutions: u16,
    shaft: RunDown,
    channels: &[Channel; 3],
    seconds: f64,
    noise_volts: [f64; 3],
    seed: u64,
) -> ([f64; 3], usize) {
    let mut config = ExtractorConfig::new(FS as f32, channels.map(|c| c.sensor));
    config.revolutions_per_output = revolutions;
    let clean = simulate(config, shaft, channels, seconds, 4096, |_| {});
    let mut gauss = Gauss(seed);
    let noisy = simulate_with_noise(
        config,
        shaft,
        channels,
        seconds,
        4096,
        |_| {},
        |c| noise_volts[c] * gauss.next(),
    );
    assert!(noisy.faults().is_empty(), "{:?}", noisy.faults());
    let (mut reported, mut real, mut floor) = ([0.0f64; 3], [0.0f64; 3], [0.0f64; 3]);
    let mut outputs = 0;
    // Outputs whose revolutions all came before the fourth after lock-on
    // carry an upper bound (lower differences include trend): not compared.
    let early = 4usize.div_ceil(usize::from(revolutions)) - 1;
    for (a, b) in clean.phasors().zip(noisy.phasors()).skip(early) {
        assert_eq!(a.revolution, b.revolution);
        for c in 0..3 {
            let e = b.displacement[c] - a.displacement[c];
            real[c] += f64::from(e.norm_sqr());
            reported[c] += f64::from(b.noise_sd[c]).powi(2);
            floor[c] += f64::from(a.noise_sd[c]).powi(2);
        }
        outputs += 1;
    }
    for c in 0..3 {
        // The clean run's own sd is f32 rounding and the trend's quartic
        // remainder: far below the noise.
        assert!(
            floor[c] < 0.01 * reported[c],
            "channel {c}: clean {} vs noisy {}",
            floor[c],
            reported[c]
        );
    }
    (
        core::array::from_fn(|c| (reported[c] / real[c]).sqrt()),
        outputs,
    )
}

fn check_ratio(label: &str, ratios: [f64; 3], outputs: usize, tolerance: f64) {
    std::println!("{label}: reported/real noise sd {ratios:.3?} over {outputs} outputs");
    for (c, r) in ratios.iter().enumerate() {
        assert!(
            (r - 1.0).abs() < tolerance,
            "{label}, channel {c}: reported/real {r:.3}"
        );
    }
}

#[test]
fn reported_noise_matches_the_scatter_of_averaged_phasors() {
    // 4 revolutions per output, a coast-down 50 → 30 Hz at 1 Hz/s, the
    // three sensor kinds with 2 mV of white noise (a 16-bit ADC at ±10 V
    // has 0.3 mV steps).
    let shaft = RunDown {
        f0: 50.0,
        rate: 1.0,
        offset: 0.21,
    };
    let channels = three_sensors();
    let (ratios, outputs) = reported_over_real(4, shaft, &channels, 20.0, [2e-3, 2e-3, 2e-3], 17);
    assert!(outputs > 150, "{outputs}");
    check_ratio("R = 4, 1 Hz/s", ratios, outputs, 0.15);
}

#[test]
fn reported_noise_of_single_revolutions_through_a_resonance() {
    // One revolution per output: the run-down correction's differences
    // amplify the noise (the gain G > 1), and the phasor changes by up to
    // 2.5 % per revolution through the resonance: neither is noise that the
    // report may miss or invent.
    let resonance = Envelope::Resonance {
        natural_hz: 45.0,
        zeta: 0.02,
    };
    let channels = three_sensors().map(|c| c.with_envelope(resonance));
    let shaft = RunDown {
        f0: 50.0,
        rate: 1.0,
        offset: 0.63,
    };
    let (ratios, outputs) = reported_over_real(1, shaft, &channels, 8.0, [5e-3, 1e-3, 1e-3], 5);
    assert!(outputs > 300, "{outputs}");
    check_ratio("R = 1, through 45 Hz at 1 Hz/s", ratios, outputs, 0.15);
}
