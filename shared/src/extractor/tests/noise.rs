//! The reported noise of each phasor against the real scatter of phasors
//! made from signals with known white noise.
//!
//! The extractor is linear in the samples for given keyphasor edges, so the
//! noise of each output is exactly the noisy run's phasor minus the clean
//! run's (same signal, same edges): the real error of every output, with no
//! model of it. Three checks per channel over the outputs of a run:
//!
//! - the variance: Σ reported sd² against Σ real |error|²;
//! - what a fit's χ² sees: the mean of |error|²/sd² must be 1 (a reported
//!   sd that is right on average but erratic makes it larger: 1/sd² is
//!   convex);
//! - the correlation between neighbouring outputs: |Σ error|² over blocks
//!   of consecutive outputs against the block length × the mean |error|²,
//!   the long-run factor φ a fit applies to its parameter variances.

use super::*;
use crate::testing::Gauss;

/// Outputs per block for the measured long-run factor.
const BLOCK: usize = 16;

/// Per-channel sums over the outputs of one or more runs.
#[derive(Default)]
struct Calibration {
    reported: [f64; 3],
    real: [f64; 3],
    whitened: [f64; 3],
    blocks: [f64; 3],
    block_count: usize,
    outputs: usize,
}

impl Calibration {
    /// sqrt(Σ sd² / Σ |error|²) per channel.
    fn sd_ratio(&self) -> [f64; 3] {
        core::array::from_fn(|c| (self.reported[c] / self.real[c]).sqrt())
    }
    /// mean(|error|²/sd²) per channel.
    fn chi2(&self) -> [f64; 3] {
        core::array::from_fn(|c| self.whitened[c] / self.outputs as f64)
    }
    /// mean |Σ_block error|² / (BLOCK · mean |error|²) per channel.
    fn phi(&self) -> [f64; 3] {
        core::array::from_fn(|c| {
            (self.blocks[c] / self.block_count as f64)
                / (BLOCK as f64 * self.real[c] / self.outputs as f64)
        })
    }

    /// Adds one run of `seconds` with `noise_volts` of white noise per channel.
    fn run(
        &mut self,
        revolutions: u16,
        shaft: RunDown,
        channels: &[Channel; 3],
        seconds: f64,
        noise_volts: [f64; 3],
        seed: u64,
    ) {
        let mut config = configured(channels);
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
        // Outputs before the pool has seen half its revolutions of fourth
        // differences carry a rougher estimate: not compared.
        let early = (usize::from(POOLED_REVOLUTIONS) / 2 + 3).div_ceil(usize::from(revolutions));
        let mut floor = [0.0f64; 3];
        let mut reported = [0.0f64; 3];
        let mut block = [ZERO; 3];
        let mut in_block = 0;
        for (a, b) in clean.phasors().zip(noisy.phasors()).skip(early) {
            assert_eq!(a.revolution, b.revolution);
            for c in 0..3 {
                let e = b.displacement[c] - a.displacement[c];
                let sd2 = f64::from(b.noise_sd[c]).powi(2);
                self.real[c] += f64::from(e.norm_sqr());
                self.reported[c] += sd2;
                reported[c] += sd2;
                self.whitened[c] += f64::from(e.norm_sqr()) / sd2;
                floor[c] += f64::from(a.noise_sd[c]).powi(2);
                block[c] += e;
            }
            self.outputs += 1;
            in_block += 1;
            if in_block == BLOCK {
                for c in 0..3 {
                    self.blocks[c] += f64::from(block[c].norm_sqr());
                }
                self.block_count += 1;
                block = [ZERO; 3];
                in_block = 0;
            }
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
    }

    fn check(&self, label: &str, revolutions: u16, channels: &[Channel; 3], tolerance: f64) {
        let (ratio, chi2, phi) = (self.sd_ratio(), self.chi2(), self.phi());
        let predicted: [f64; 3] = core::array::from_fn(|c| {
            let kind = channels[c].sensor.kind;
            f64::from(long_run_factor(
                revolutions,
                average_noise_gain(kind, revolutions),
            ))
        });
        std::println!(
            "{label}: {} outputs; reported/real sd {ratio:.3?}; mean |error|²/sd² {chi2:.3?}; long-run factor measured {phi:.2?} (blocks of {BLOCK}), predicted {predicted:.2?}",
            self.outputs
        );
        for c in 0..3 {
            assert!(
                (ratio[c] - 1.0).abs() < tolerance,
                "{label}, channel {c}: reported/real sd {:.3}",
                ratio[c]
            );
            assert!(
                (chi2[c] - 1.0).abs() < tolerance,
                "{label}, channel {c}: mean |error|²/sd² {:.3}",
                chi2[c]
            );
        }
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
    let mut cal = Calibration::default();
    for seed in [17, 18, 19] {
        cal.run(4, shaft, &channels, 20.0, [2e-3, 2e-3, 2e-3], seed);
    }
    assert!(cal.outputs > 500, "{}", cal.outputs);
    cal.check("R = 4, 1 Hz/s", 4, &channels, 0.12);
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
    let mut cal = Calibration::default();
    for (seed, offset) in [(5, 0.63), (6, 0.1), (7, 0.35), (8, 0.87)] {
        let shaft = RunDown {
            f0: 50.0,
            rate: 1.0,
            offset,
        };
        cal.run(1, shaft, &channels, 8.0, [5e-3, 1e-3, 1e-3], seed);
    }
    assert!(cal.outputs > 1250, "{}", cal.outputs);
    cal.check("R = 1, through 45 Hz at 1 Hz/s", 1, &channels, 0.12);
}

#[test]
fn reported_noise_follows_a_fast_run_down() {
    // 10 Hz/s from 60 to 12 Hz: the per-revolution variance changes by 5×
    // (displacement) to 125× (acceleration) over the run, 20 % across the
    // pool at the low end; the pool works at the speed law of white noise.
    let shaft = RunDown {
        f0: 60.0,
        rate: 10.0,
        offset: 0.37,
    };
    let channels = three_sensors();
    let mut cal = Calibration::default();
    for seed in 29..45 {
        cal.run(2, shaft, &channels, 4.8, [2e-3, 2e-3, 2e-3], seed);
    }
    assert!(cal.outputs > 1000, "{}", cal.outputs);
    cal.check("R = 2, 60 → 12 Hz at 10 Hz/s", 2, &channels, 0.15);
}
