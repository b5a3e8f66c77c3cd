//! A response as the instruments and files give it: readings with the
//! sensor effects, `bearings.csv` rows, and a run directory with noise.

use super::{BearingResponse, Noise, Response, SimError};
use crate::rundir::{BearingRow, Measurement, RunDir};
use crate::sim::banded::C64;
use plinth_shared::bearing::BearingCoefficients;
use plinth_shared::phasor::Phasor2;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};

impl Response {
    /// The readings as instruments give them: `rel` plus runout, `ped` times
    /// e^{−iΩτ} (sensor delay), one row per (speed, bearing) in speed order.
    pub fn measurements(&self) -> Vec<Measurement> {
        let mut out = Vec::with_capacity(self.speeds_hz.len() * self.bearing_names.len());
        for (s, row) in self.bearings.iter().enumerate() {
            let omega = std::f64::consts::TAU * self.speeds_hz[s];
            for (b, r) in row.iter().enumerate() {
                let sen = self.sensors[b];
                let delay = C64::from_polar(1.0, -omega * sen.ped_delay);
                out.push(Measurement {
                    speed_hz: self.speeds_hz[s],
                    bearing: self.bearing_names[b].clone(),
                    rel: [r.rel[0] + sen.runout[0], r.rel[1] + sen.runout[1]],
                    ped: [r.ped[0] * delay, r.ped[1] * delay],
                    noise_sd: None,
                    written: None,
                });
            }
        }
        out
    }

    /// The bearing coefficients as `bearings.csv` rows (the written table,
    /// [`BearingResponse::table`]).
    pub fn bearing_rows(&self) -> Vec<BearingRow> {
        self.rows_of(|r| r.table)
    }

    /// The coefficients as simulated, as `bearings.csv` rows; they differ
    /// from [`Response::bearing_rows`] only under `bearing_coefficients`.
    pub fn true_bearing_rows(&self) -> Vec<BearingRow> {
        self.rows_of(|r| r.coefficients)
    }

    /// Whether `bearings.csv` differs from the simulated bearings.
    pub fn table_differs(&self) -> bool {
        self.bearings
            .iter()
            .flatten()
            .any(|r| r.table != r.coefficients)
    }

    fn rows_of(
        &self,
        pick: impl Fn(&BearingResponse) -> BearingCoefficients<f64>,
    ) -> Vec<BearingRow> {
        let mut out = Vec::new();
        for (s, row) in self.bearings.iter().enumerate() {
            for (b, r) in row.iter().enumerate() {
                out.push(BearingRow {
                    speed_hz: self.speeds_hz[s],
                    bearing: self.bearing_names[b].clone(),
                    coefficients: pick(r),
                });
            }
        }
        out
    }

    /// Shaft displacement phasors (y, z) [m] at `node` for every speed.
    pub fn node_response(&self, node: usize) -> Option<Vec<Phasor2<f64>>> {
        if node >= self.node_positions.len() || self.shaft.is_empty() {
            return None;
        }
        Some(self.shaft.iter().map(|row| row[node]).collect())
    }

    /// A run directory (measurements with sensor effects and optional noise,
    /// bearing coefficients, truth). Digit reduction happens when writing
    /// (`RunDir::write_with`).
    pub fn to_run_dir(&self, noise: Option<Noise>) -> Result<RunDir, SimError> {
        let mut measurements = self.measurements();
        if let Some(n) = noise {
            if !(n.fraction.is_finite() && n.fraction >= 0.0) {
                return Err(SimError::Noise(format!(
                    "--noise must be a finite fraction >= 0 (got {})",
                    n.fraction
                )));
            }
            add_noise(&mut measurements, &self.bearing_names, n);
        }
        Ok(RunDir {
            measurements,
            bearings: self.bearing_rows(),
            truth: Some(self.truth.clone()),
        })
    }
}

/// Adds seeded complex Gaussian noise (see [`Noise`]) to every channel.
fn add_noise(measurements: &mut [Measurement], bearings: &[String], noise: Noise) {
    let mut rng = rand::rngs::StdRng::seed_from_u64(noise.seed);
    for name in bearings {
        let idx: Vec<usize> = (0..measurements.len())
            .filter(|&i| &measurements[i].bearing == name)
            .collect();
        if idx.is_empty() {
            continue;
        }
        for ch in 0..4 {
            let get = |m: &Measurement| if ch < 2 { m.rel[ch] } else { m.ped[ch - 2] };
            let ms: f64 = idx
                .iter()
                .map(|&i| get(&measurements[i]).norm_sqr())
                .sum::<f64>()
                / idx.len() as f64;
            let sigma = noise.fraction * ms.sqrt() / std::f64::consts::SQRT_2;
            for &i in &idx {
                let a: f64 = StandardNormal.sample(&mut rng);
                let b: f64 = StandardNormal.sample(&mut rng);
                let n = C64::new(a * sigma, b * sigma);
                let m = &mut measurements[i];
                if ch < 2 {
                    m.rel[ch] += n;
                } else {
                    m.ped[ch - 2] += n;
                }
            }
        }
    }
}
