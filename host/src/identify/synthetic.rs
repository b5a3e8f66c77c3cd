//! Synthetic run-downs that satisfy the paper's pedestal model (eq. 3)
//! exactly, for tests, examples and benchmarks of the identification.
//!
//! Each bearing carries its share of a rigid rotor (mass M_r [kg]) with a
//! rotating unbalance u [kg·m]; the rotor sits in an oil-film-like bearing
//! (speed-dependent, cross-coupled K_b and C_b, listed in a coarse speed
//! table and interpolated as the reader does) on a pedestal
//! (k − Ω²m + iΩc per direction). Per speed the 4×4 complex system
//!
//! ```text
//! (B − Ω²M_r)·x_r − B·x_p = u·Ω²·(e^{iφ}, −i·e^{iφ})
//!        −B·x_r + (B + D)·x_p = 0,      B = K_b + iΩC_b, D = diag(k − Ω²m + iΩc)
//! ```
//!
//! is solved for the rotor and pedestal motion; `rel` = x_r − x_p, the force
//! is F = B·rel and the written `ped` is recomputed as D⁻¹·F, so the data meet
//! eq. 3 to the last bit whatever the solver's rounding. This is test data,
//! not the machine simulator (`crate::sim`): the bearings are not coupled
//! through a flexible rotor.

use crate::estimate::Pedestal;
use crate::rundir::{BearingRow, BearingSchedule, Measurement, PedestalTruth, RunDir, Truth};
use nalgebra::{DMatrix, DVector};
use plinth_shared::bearing::BearingCoefficients;
use plinth_shared::phasor::{omega_from_hz, Complex};

/// The recipe of a synthetic run-down.
#[derive(Clone, Debug, PartialEq)]
pub struct SyntheticRun {
    /// The pedestals, one per bearing (their `bearing` names the bearing).
    pub pedestals: Vec<PedestalTruth>,
    /// Measurement speeds [Hz].
    pub speeds_hz: Vec<f64>,
    /// Speeds [Hz] listed in `bearings.csv` (must cover `speeds_hz`).
    pub bearing_grid_hz: Vec<f64>,
    /// Rotor mass carried by each bearing [kg], in the order of `pedestals`.
    pub rotor_mass_kg: Vec<f64>,
    /// Unbalance at each bearing [kg·m], in the order of `pedestals`.
    pub unbalance_kg_m: Vec<f64>,
    /// Angle of each unbalance from the keyphasor [rad].
    pub unbalance_angle_rad: Vec<f64>,
}

/// Why a synthetic run could not be made.
#[derive(Debug, thiserror::Error)]
pub enum SyntheticError {
    /// The recipe's per-bearing lists differ in length from `pedestals`.
    #[error("rotor_mass_kg, unbalance_kg_m and unbalance_angle_rad need one entry per pedestal")]
    Lengths,
    /// A measurement speed is outside the bearing grid.
    #[error(transparent)]
    OutOfRange(#[from] crate::rundir::OutOfRange),
    /// The rotor-bearing-pedestal equations are singular at a speed.
    #[error("the system is singular at {speed_hz} Hz for bearing `{bearing}`")]
    Singular {
        /// Speed [Hz].
        speed_hz: f64,
        /// Bearing.
        bearing: String,
    },
}

/// `n` evenly spaced values from `a` to `b` inclusive.
pub fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    match n {
        0 => Vec::new(),
        1 => vec![a],
        _ => (0..n)
            .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
            .collect(),
    }
}

/// Oil-film-like coefficients of bearing number `index` at `speed_hz` [Hz]:
/// direct stiffness rising with speed, cross-coupled stiffness k_yz > 0,
/// k_zy < 0 growing with speed, damping falling with speed, small
/// cross-coupled damping. K in N/m, C in N·s/m.
pub fn oil_film_coefficients(index: usize, speed_hz: f64) -> BearingCoefficients<f64> {
    let g = 1.0 + 0.25 * index as f64;
    let s = speed_hz / 100.0;
    BearingCoefficients {
        k: [
            [g * (2.0e7 + 1.0e7 * s), g * 0.8e7 * s],
            [-g * (2.0e6 + 1.2e7 * s), g * (1.2e7 + 0.6e7 * s)],
        ],
        c: [
            [g * 4.0e4 / (1.0 + s), g * 3.0e3 / (1.0 + s)],
            [g * 3.0e3 / (1.0 + s), g * 3.0e4 / (1.0 + s)],
        ],
    }
}

impl SyntheticRun {
    /// Plinth's reconstruction of the paper's machine: pedestals `left`
    /// (k_y 10, k_z 8 MN/m, m 150 kg) and `right` (k_y 6, k_z 7 MN/m,
    /// m 120 kg), all four resonances between 35 and 42 Hz; damping c_y, c_z
    /// = 100, 80 and 70, 90 N·s/m when `damped`, else zero; `speeds` speeds
    /// from 5 to 200 Hz; bearing table every 10 Hz from 0 to 200 Hz.
    pub fn paper_like(damped: bool, speeds: usize) -> Self {
        let c = |v: f64| if damped { v } else { 0.0 };
        Self {
            pedestals: vec![
                PedestalTruth {
                    bearing: "left".into(),
                    pedestal: Pedestal {
                        k_y: 10.0e6,
                        k_z: 8.0e6,
                        m: 150.0,
                        c_y: c(100.0),
                        c_z: c(80.0),
                    },
                },
                PedestalTruth {
                    bearing: "right".into(),
                    pedestal: Pedestal {
                        k_y: 6.0e6,
                        k_z: 7.0e6,
                        m: 120.0,
                        c_y: c(70.0),
                        c_z: c(90.0),
                    },
                },
            ],
            speeds_hz: linspace(5.0, 200.0, speeds),
            bearing_grid_hz: linspace(0.0, 200.0, 21),
            rotor_mass_kg: vec![250.0, 300.0],
            unbalance_kg_m: vec![2.0e-4, 1.5e-4],
            unbalance_angle_rad: vec![0.0, 2.0],
        }
    }

    /// The run directory (with `truth.json`), measurements ordered by speed
    /// then bearing, bearing rows by bearing then speed.
    pub fn build(&self) -> Result<RunDir, SyntheticError> {
        let n = self.pedestals.len();
        if self.rotor_mass_kg.len() != n
            || self.unbalance_kg_m.len() != n
            || self.unbalance_angle_rad.len() != n
        {
            return Err(SyntheticError::Lengths);
        }
        let mut bearings = Vec::new();
        let mut schedules = Vec::new();
        for (index, p) in self.pedestals.iter().enumerate() {
            let rows: Vec<(f64, BearingCoefficients<f64>)> = self
                .bearing_grid_hz
                .iter()
                .map(|&f| (f, oil_film_coefficients(index, f)))
                .collect();
            bearings.extend(rows.iter().map(|&(speed_hz, coefficients)| BearingRow {
                speed_hz,
                bearing: p.bearing.clone(),
                coefficients,
            }));
            schedules.push(BearingSchedule::new(rows));
        }
        let mut measurements = Vec::new();
        for &speed_hz in &self.speeds_hz {
            for (index, p) in self.pedestals.iter().enumerate() {
                measurements.push(self.measurement(index, p, &schedules[index], speed_hz)?);
            }
        }
        Ok(RunDir {
            measurements,
            bearings,
            truth: Some(Truth {
                pedestals: self.pedestals.clone(),
                effects: Vec::new(),
                effect_details: Vec::new(),
                bases: Vec::new(),
            }),
        })
    }

    fn measurement(
        &self,
        index: usize,
        p: &PedestalTruth,
        schedule: &BearingSchedule,
        speed_hz: f64,
    ) -> Result<Measurement, SyntheticError> {
        let omega = omega_from_hz(speed_hz);
        let w2 = omega * omega;
        let coefficients = schedule.at(speed_hz)?;
        let b =
            |i: usize, j: usize| Complex::new(coefficients.k[i][j], omega * coefficients.c[i][j]);
        let d = [0, 1].map(|d| p.pedestal.dynamic_stiffness(d, omega));
        let mr = Complex::new(w2 * self.rotor_mass_kg[index], 0.0);
        let zero = Complex::new(0.0, 0.0);
        #[rustfmt::skip]
        let a = DMatrix::from_row_slice(4, 4, &[
            b(0, 0) - mr, b(0, 1),      -b(0, 0),       -b(0, 1),
            b(1, 0),      b(1, 1) - mr, -b(1, 0),       -b(1, 1),
            -b(0, 0),     -b(0, 1),     b(0, 0) + d[0], b(0, 1),
            -b(1, 0),     -b(1, 1),     b(1, 0),        b(1, 1) + d[1],
        ]);
        let u = Complex::from_polar(
            self.unbalance_kg_m[index] * w2,
            self.unbalance_angle_rad[index],
        );
        let rhs = DVector::from_column_slice(&[u, u * Complex::new(0.0, -1.0), zero, zero]);
        let singular = || SyntheticError::Singular {
            speed_hz,
            bearing: p.bearing.clone(),
        };
        let x = a.lu().solve(&rhs).ok_or_else(singular)?;
        if x.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
            return Err(singular());
        }
        let rel = [x[0] - x[2], x[1] - x[3]];
        let force = coefficients.force(omega, &rel);
        // Recompute ped from eq. 3 so that it holds exactly.
        let ped = [force[0] / d[0], force[1] / d[1]];
        Ok(Measurement {
            speed_hz,
            bearing: p.bearing.clone(),
            rel,
            ped,
            noise_sd: None,
            written: None,
        })
    }
}
