//! The measurements of a run directory arranged for the discrepancy workflow:
//! one speed-sorted series of 1X phasors per bearing, with the complex bearing
//! stiffness K* = K_b + iΩ·C_b at each measured speed and the noise standard
//! deviation of every real number (see [`super::noise`]).

use super::noise::{BearingNoise, ColumnDigits, NoiseModel, CHANNELS};
use crate::estimate::noise::Quantisation;
use crate::estimate::pedestal::{data_alone_sd, unscale};
use crate::identify::{estimator::fit_ml, observations, Options as IdentifyOptions, PedestalFit};
use crate::rundir::{Measurement, RunDir};
use anyhow::{anyhow, bail, Context, Result};
use num_complex::Complex;
use plinth_shared::phasor::{omega_from_hz, Phasor2};

/// Complex 2×2 matrix indexed `[row][col]` over (y, z).
pub type Complex2x2 = [[Complex<f64>; 2]; 2];

/// One bearing at one speed.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// Rotor speed [Hz].
    pub speed_hz: f64,
    /// Rotor speed [rad/s].
    pub omega: f64,
    /// Rotor displacement relative to the pedestal, (y, z) [m].
    pub rel: Phasor2<f64>,
    /// Absolute pedestal displacement, (y, z) [m].
    pub ped: Phasor2<f64>,
    /// Complex bearing stiffness K_b + iΩ·C_b [N/m], so that F = K*·rel.
    pub kstar: Complex2x2,
    /// Noise standard deviation [m] of each real number, in the order of
    /// [`CHANNELS`] (rel y re, rel y im, rel z re, rel z im, ped y re, ...).
    pub sigma: [f64; 8],
}

impl Point {
    /// The force the bearing transmits to the pedestal [N]: F = K*·rel.
    pub fn force(&self) -> Phasor2<f64> {
        mul(&self.kstar, &self.rel)
    }

    /// The measured value of real channel `c` (order of [`CHANNELS`]) [m].
    pub fn channel(&self, c: usize) -> f64 {
        let z = if c < 4 {
            self.rel[c / 2]
        } else {
            self.ped[(c - 4) / 2]
        };
        if c.is_multiple_of(2) {
            z.re
        } else {
            z.im
        }
    }
}

/// Complex 2×2 matrix times a (y, z) phasor pair.
pub fn mul(a: &Complex2x2, x: &Phasor2<f64>) -> Phasor2<f64> {
    [
        a[0][0] * x[0] + a[0][1] * x[1],
        a[1][0] * x[0] + a[1][1] * x[1],
    ]
}

/// All bearings of a run, speed-aligned.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// Bearing names in order of first appearance in `measurements.csv`
    /// (neighbouring bearings are neighbours in this order).
    pub bearings: Vec<String>,
    /// Sorted distinct measured speeds [Hz].
    pub speeds_hz: Vec<f64>,
    /// `points[b][j]`: bearing `b` at `speeds_hz[j]`, when measured there.
    pub points: Vec<Vec<Option<Point>>>,
    /// The measurement noise model the standard deviations come from.
    pub noise: NoiseModel,
    /// Per bearing, the maximum-likelihood fit of the paper's five-parameter
    /// model that decided the noise (`plinth identify`'s default fit).
    pub base_fits: Vec<PedestalFit>,
}

impl Prepared {
    /// Arranges a run directory; fails on a bearing without coefficients at a
    /// measured speed, non-finite numbers or too few speeds to identify.
    pub fn from_run(run: &RunDir) -> Result<Self> {
        if run.measurements.is_empty() {
            bail!("measurements.csv holds no rows");
        }
        let mut bearings: Vec<String> = Vec::new();
        for m in &run.measurements {
            if !bearings.contains(&m.bearing) {
                bearings.push(m.bearing.clone());
            }
        }
        let mut speeds_hz: Vec<f64> = run.measurements.iter().map(|m| m.speed_hz).collect();
        speeds_hz.sort_by(f64::total_cmp);
        speeds_hz.dedup();
        let schedules = run.bearing_schedules();
        let mut points: Vec<Vec<Option<Point>>> = vec![vec![None; speeds_hz.len()]; bearings.len()];
        for (row, m) in run.measurements.iter().enumerate() {
            let finite = m.speed_hz.is_finite()
                && m.speed_hz > 0.0
                && m.rel
                    .iter()
                    .chain(&m.ped)
                    .all(|z| z.re.is_finite() && z.im.is_finite());
            if !finite {
                bail!(
                    "measurements.csv row {} (bearing {}, {} Hz): speed must be positive and every phasor finite",
                    row + 1,
                    m.bearing,
                    m.speed_hz
                );
            }
            let b = bearings.iter().position(|n| *n == m.bearing).unwrap_or(0);
            let j = speeds_hz.partition_point(|&s| s < m.speed_hz);
            let coefficients = schedules
                .get(&m.bearing)
                .ok_or_else(|| {
                    anyhow!("bearings.csv has no coefficients for bearing {}", m.bearing)
                })?
                .at(m.speed_hz)
                .with_context(|| format!("bearings.csv, bearing {}", m.bearing))?;
            let omega = omega_from_hz(m.speed_hz);
            let mut kstar = [[Complex::new(0.0, 0.0); 2]; 2];
            for (r, row_k) in kstar.iter_mut().enumerate() {
                for (c, v) in row_k.iter_mut().enumerate() {
                    *v = Complex::new(coefficients.k[r][c], omega * coefficients.c[r][c]);
                }
            }
            let mut point = Point {
                speed_hz: m.speed_hz,
                omega,
                rel: m.rel,
                ped: m.ped,
                kstar,
                sigma: [0.0; 8],
            };
            for c in 0..CHANNELS.len() {
                point.sigma[c] = 0.0;
            }
            points[b][j] = Some(point);
        }
        let columns = ColumnDigits::of_run(&run.measurements);
        let mut noises = Vec::with_capacity(bearings.len());
        let mut base_fits = Vec::with_capacity(bearings.len());
        for (b, name) in bearings.iter().enumerate() {
            let mut rows: Vec<&Measurement> = run
                .measurements
                .iter()
                .filter(|m| &m.bearing == name)
                .collect();
            rows.sort_by(|x, y| x.speed_hz.total_cmp(&y.speed_hz));
            // The written digits cannot tell rounding from truncation: the
            // significance tests take truncation's mean square (ulp²/3), which
            // bounds both, so that a truncation bias is not named an effect.
            let mut noise = BearingNoise::estimate(&rows, &columns, Quantisation::Truncation);
            let schedule = schedules
                .get(name)
                .ok_or_else(|| anyhow!("bearings.csv has no coefficients for bearing {name}"))?;
            let obs = observations(&rows, schedule, &noise)
                .with_context(|| format!("bearings.csv, bearing {name}"))?;
            let options = IdentifyOptions {
                quantisation: Quantisation::Truncation,
                ..IdentifyOptions::default()
            };
            let (fit, _) = fit_ml(name, &obs, &mut noise, &options)
                .with_context(|| format!("fitting the base model of bearing {name}"))?;
            // The noise from the data alone (module docs of `noise`).
            unscale(&mut noise);
            for (m, var) in rows.iter().zip(&noise.var) {
                let j = speeds_hz.partition_point(|&s| s < m.speed_hz);
                if let Some(p) = points[b].get_mut(j).and_then(Option::as_mut) {
                    let magnitude: [f64; 8] = std::array::from_fn(|c| point_magnitude(p, c));
                    p.sigma = data_alone_sd(var, &magnitude);
                }
            }
            noises.push(noise);
            base_fits.push(fit);
        }
        let noise = NoiseModel {
            columns,
            bearings: noises,
        };
        for (b, name) in bearings.iter().enumerate() {
            let n = points[b].iter().flatten().count();
            if n < 3 {
                bail!(
                    "bearing {name}: only {n} speeds measured; the pedestal model needs at least 3"
                );
            }
        }
        Ok(Self {
            bearings,
            speeds_hz,
            points,
            noise,
            base_fits,
        })
    }

    /// Index of a bearing by name.
    pub fn bearing_index(&self, name: &str) -> Option<usize> {
        self.bearings.iter().position(|b| b == name)
    }
}

/// |phasor| [m] of the complex channel real channel `c` belongs to.
pub fn point_magnitude(p: &Point, c: usize) -> f64 {
    if c < 4 {
        p.rel[c / 2].norm()
    } else {
        p.ped[(c - 4) / 2].norm()
    }
}
