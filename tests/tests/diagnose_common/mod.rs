//! A pedestal-level run-down generator for the `diagnose` tests: exact
//! frequency-domain solution of a small rotor-bearing-pedestal machine
//! (one rotor mass per bearing, rotor masses joined by shaft springs,
//! speed-dependent cross-coupled oil-film-like bearings, pedestals with every
//! effect of `plinth::effects`), then sensor effects, noise and rounding.
#![allow(dead_code)]

use nalgebra::{DMatrix, DVector};
use num_complex::Complex;
use plinth::rundir::{BearingRow, Measurement, RunDir};
use plinth_shared::bearing::BearingCoefficients;
use rand::{Rng, SeedableRng};

type C = Complex<f64>;

/// One pedestal of the generated machine.
#[derive(Clone, Debug)]
pub struct Ped {
    pub k_y: f64,
    pub k_z: f64,
    pub m: f64,
    pub c_y: f64,
    pub c_z: f64,
}

/// A hidden effect.
#[derive(Clone, Debug)]
pub enum Effect {
    None,
    /// Extra viscous damping c_y, c_z on a pedestal (for a base without c).
    PedestalDamping {
        bearing: usize,
        c_y: f64,
        c_z: f64,
    },
    Structural {
        bearing: usize,
        eta: f64,
    },
    CrossCoupling {
        bearing: usize,
        k_yz: f64,
    },
    MassAnisotropy {
        bearing: usize,
        m_y: f64,
        m_z: f64,
    },
    /// Runout as a fraction of the bearing's RMS rel reading, at a phase.
    Runout {
        bearing: usize,
        fraction: f64,
    },
    Delay {
        bearing: usize,
        tau: f64,
    },
    Foundation {
        a: usize,
        b: usize,
        k_c: f64,
    },
}

/// A generated machine.
#[derive(Clone, Debug)]
pub struct Machine {
    pub names: Vec<String>,
    pub pedestals: Vec<Ped>,
    /// Rotor mass lumped at each bearing [kg].
    pub rotor_mass: Vec<f64>,
    /// Shaft spring between neighbouring rotor masses [N/m].
    pub shaft_k: f64,
    /// Nominal bearing stiffness [N/m] and damping [N·s/m].
    pub bearing_k: f64,
    pub bearing_c: f64,
    /// Unbalance m·e [kg·m] and phase [rad] per bearing.
    pub unbalance: Vec<(f64, f64)>,
    /// Speeds [Hz].
    pub speeds: Vec<f64>,
}

impl Machine {
    /// A two-bearing machine with pedestal resonances in the speed range
    /// (a reconstruction in the spirit of the paper's).
    pub fn paper_like() -> Self {
        Self {
            names: vec!["left".into(), "right".into()],
            pedestals: vec![
                Ped {
                    k_y: 8.0e6,
                    k_z: 6.0e6,
                    m: 100.0,
                    c_y: 90.0,
                    c_z: 70.0,
                },
                Ped {
                    k_y: 1.0e7,
                    k_z: 7.0e6,
                    m: 120.0,
                    c_y: 100.0,
                    c_z: 80.0,
                },
            ],
            rotor_mass: vec![150.0, 180.0],
            shaft_k: 4.0e7,
            bearing_k: 3.0e7,
            bearing_c: 6.0e4,
            unbalance: vec![(2.0e-4, 0.3), (1.5e-4, 2.0)],
            speeds: (0..180).map(|i| 10.0 + i as f64).collect(),
        }
    }

    /// A three-bearing machine of different sizes and speed range.
    pub fn three_bearing() -> Self {
        Self {
            names: vec!["B1".into(), "B2".into(), "B3".into()],
            pedestals: vec![
                Ped {
                    k_y: 2.5e7,
                    k_z: 1.8e7,
                    m: 300.0,
                    c_y: 300.0,
                    c_z: 250.0,
                },
                Ped {
                    k_y: 3.0e7,
                    k_z: 2.2e7,
                    m: 420.0,
                    c_y: 400.0,
                    c_z: 350.0,
                },
                Ped {
                    k_y: 2.0e7,
                    k_z: 1.5e7,
                    m: 260.0,
                    c_y: 200.0,
                    c_z: 220.0,
                },
            ],
            rotor_mass: vec![400.0, 700.0, 350.0],
            shaft_k: 1.2e8,
            bearing_k: 8.0e7,
            bearing_c: 1.5e5,
            unbalance: vec![(5.0e-4, 0.0), (8.0e-4, 1.2), (4.0e-4, -2.0)],
            speeds: (0..150).map(|i| 5.0 + 0.8 * i as f64).collect(),
        }
    }

    fn max_speed(&self) -> f64 {
        self.speeds.iter().copied().fold(0.0, f64::max)
    }

    /// Oil-film-like coefficients: stiffening with speed, cross-coupled.
    pub fn bearing(&self, b: usize, speed: f64) -> BearingCoefficients<f64> {
        let s = speed / self.max_speed();
        let k = self.bearing_k * (1.0 + 0.1 * b as f64);
        let c = self.bearing_c;
        BearingCoefficients {
            k: [
                [k * (1.0 + 0.6 * s), 0.35 * k * s],
                [-0.45 * k * s, 0.8 * k * (1.0 + 0.4 * s)],
            ],
            c: [[c * (1.0 - 0.3 * s), 0.1 * c * s], [0.1 * c * s, 0.9 * c]],
        }
    }
}

/// How the data are written.
#[derive(Clone, Copy, Debug)]
pub struct Writing {
    /// Significant digits (None = full precision).
    pub digits: Option<usize>,
    /// Relative complex noise level (σ per component = level·|phasor|/√2).
    pub noise: f64,
    pub seed: u64,
}

fn round_sig(v: f64, digits: usize) -> f64 {
    format!("{:.*e}", digits - 1, v).parse().unwrap()
}

/// The exact machine response: (rel, ped) per bearing per speed.
pub fn respond(machine: &Machine, effect: &Effect) -> Vec<Vec<([C; 2], [C; 2])>> {
    let nb = machine.names.len();
    let n = 4 * nb; // rotor (y,z) + pedestal (y,z) per bearing
    let mut out = vec![Vec::new(); nb];
    for &f in &machine.speeds {
        let w = std::f64::consts::TAU * f;
        let mut a = DMatrix::from_element(n, n, C::new(0.0, 0.0));
        let mut rhs = DVector::from_element(n, C::new(0.0, 0.0));
        let r = |b: usize, d: usize| 4 * b + d;
        let p = |b: usize, d: usize| 4 * b + 2 + d;
        for b in 0..nb {
            let bc = machine.bearing(b, f);
            // Rotor mass and bearing.
            for d in 0..2 {
                a[(r(b, d), r(b, d))] += C::new(-w * w * machine.rotor_mass[b], 0.0);
                for e in 0..2 {
                    let kb = C::new(bc.k[d][e], w * bc.c[d][e]);
                    a[(r(b, d), r(b, e))] += kb;
                    a[(r(b, d), p(b, e))] -= kb;
                    a[(p(b, d), p(b, e))] += kb;
                    a[(p(b, d), r(b, e))] -= kb;
                }
            }
            // Shaft spring to the next rotor mass.
            if b + 1 < nb {
                for d in 0..2 {
                    let ks = C::new(machine.shaft_k, 0.0);
                    a[(r(b, d), r(b, d))] += ks;
                    a[(r(b + 1, d), r(b + 1, d))] += ks;
                    a[(r(b, d), r(b + 1, d))] -= ks;
                    a[(r(b + 1, d), r(b, d))] -= ks;
                }
            }
            // Pedestal with effects.
            let ped = &machine.pedestals[b];
            let mut eta = 0.0;
            let mut k_yz = 0.0;
            let (mut m_y, mut m_z) = (ped.m, ped.m);
            let (mut c_y, mut c_z) = (ped.c_y, ped.c_z);
            match *effect {
                Effect::Structural { bearing, eta: e } if bearing == b => eta = e,
                Effect::CrossCoupling { bearing, k_yz: k } if bearing == b => k_yz = k,
                Effect::MassAnisotropy {
                    bearing,
                    m_y: y,
                    m_z: z,
                } if bearing == b => {
                    m_y = y;
                    m_z = z;
                }
                Effect::PedestalDamping {
                    bearing,
                    c_y: y,
                    c_z: z,
                } if bearing == b => {
                    c_y = y;
                    c_z = z;
                }
                _ => {}
            }
            let loss = C::new(1.0, eta);
            a[(p(b, 0), p(b, 0))] += loss * ped.k_y - w * w * m_y + C::new(0.0, w * c_y);
            a[(p(b, 1), p(b, 1))] += loss * ped.k_z - w * w * m_z + C::new(0.0, w * c_z);
            a[(p(b, 0), p(b, 1))] += loss * k_yz;
            a[(p(b, 1), p(b, 0))] += loss * k_yz;
            // Unbalance: forward rotating force, y = cos, z = sin.
            let (me, phase) = machine.unbalance[b];
            let u = C::from_polar(me * w * w, phase);
            rhs[r(b, 0)] = u;
            rhs[r(b, 1)] = u * C::new(0.0, -1.0);
        }
        if let Effect::Foundation { a: pa, b: pb, k_c } = *effect {
            for d in 0..2 {
                let k = C::new(k_c, 0.0);
                a[(p(pa, d), p(pa, d))] += k;
                a[(p(pb, d), p(pb, d))] += k;
                a[(p(pa, d), p(pb, d))] -= k;
                a[(p(pb, d), p(pa, d))] -= k;
            }
        }
        let x = a.lu().solve(&rhs).expect("machine matrix singular");
        for (b, o) in out.iter_mut().enumerate() {
            let ped = [x[p(b, 0)], x[p(b, 1)]];
            let rel = [x[r(b, 0)] - ped[0], x[r(b, 1)] - ped[1]];
            o.push((rel, ped));
        }
    }
    out
}

/// Generates a run directory with `effect` hidden in it.
pub fn generate(machine: &Machine, effect: &Effect, writing: Writing) -> RunDir {
    let mut resp = respond(machine, effect);
    // Sensor effects.
    match *effect {
        Effect::Runout { bearing, fraction } => {
            let rms = |d: usize| {
                (resp[bearing]
                    .iter()
                    .map(|(rel, _)| rel[d].norm_sqr())
                    .sum::<f64>()
                    / resp[bearing].len() as f64)
                    .sqrt()
            };
            let r = [
                C::from_polar(fraction * rms(0), 0.7),
                C::from_polar(fraction * rms(1), -2.1),
            ];
            for (rel, _) in &mut resp[bearing] {
                rel[0] += r[0];
                rel[1] += r[1];
            }
        }
        Effect::Delay { bearing, tau } => {
            for (j, (_, ped)) in resp[bearing].iter_mut().enumerate() {
                let w = std::f64::consts::TAU * machine.speeds[j];
                let f = C::from_polar(1.0, -w * tau);
                ped[0] *= f;
                ped[1] *= f;
            }
        }
        _ => {}
    }
    let mut rng = rand::rngs::StdRng::seed_from_u64(writing.seed);
    let mut write = |z: C| -> C {
        let mut z = z;
        if writing.noise > 0.0 {
            let s = writing.noise * z.norm() / 2f64.sqrt();
            z += C::new(
                s * rng.sample::<f64, _>(rand_distr::StandardNormal),
                s * rng.sample::<f64, _>(rand_distr::StandardNormal),
            );
        }
        match writing.digits {
            Some(d) => C::new(round_sig(z.re, d), round_sig(z.im, d)),
            None => z,
        }
    };
    let mut run = RunDir::default();
    for (j, &f) in machine.speeds.iter().enumerate() {
        for (b, name) in machine.names.iter().enumerate() {
            let (rel, ped) = resp[b][j];
            run.measurements.push(Measurement {
                speed_hz: f,
                bearing: name.clone(),
                rel: [write(rel[0]), write(rel[1])],
                ped: [write(ped[0]), write(ped[1])],
                noise_sd: None,
                written: None,
            });
            run.bearings.push(BearingRow {
                speed_hz: f,
                bearing: name.clone(),
                coefficients: machine.bearing(b, f),
            });
        }
    }
    run
}
