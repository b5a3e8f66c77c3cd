//! Synchronous unbalance response of a machine over a list of speeds, with
//! effects injected, and its conversion to a run directory.
//!
//! Unbalance m·e at angle φ (from +y towards +z at the keyphasor instant
//! t = 0) gives the rotating force f_y = m·e·Ω²·cos(Ωt + φ),
//! f_z = m·e·Ω²·sin(Ωt + φ), i.e. phasors F_y = m·e·Ω²·e^{iφ},
//! F_z = −i·F_y. Every phasor X here means x(t) = Re{X·e^{iΩt}} (formats.md).

use super::assembly::Assembly;
use super::banded::C64;
use super::inject::{effect_err, EffectSet};
use super::machine::{BearingModel, Machine, MachineError};
use super::pedestal::PedestalDynamics;
use crate::effects::EffectKind;
use crate::rundir::{EffectTruth, PedestalTruth, Truth};
use plinth_shared::bearing::BearingCoefficients;
use plinth_shared::phasor::Phasor2;
use std::collections::BTreeMap;

mod readings;
mod singular;

/// Why a simulation failed.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A problem with the machine or a request about it.
    #[error(transparent)]
    Machine(#[from] MachineError),
    /// An effect request that cannot be applied.
    #[error("effect {effect}: {message}")]
    Effect {
        /// Effect name.
        effect: String,
        /// What is wrong.
        message: String,
    },
    /// A bad speed list.
    #[error("speeds: {0}")]
    Speeds(String),
    /// The dynamic stiffness matrix is singular at a speed (an unsupported
    /// rigid-body mode or an undamped resonance hit exactly).
    #[error("the machine's dynamic stiffness is singular at {speed_hz} Hz ({detail})")]
    Singular {
        /// Speed [Hz].
        speed_hz: f64,
        /// Solver detail.
        detail: String,
    },
    /// The dynamic stiffness at a speed holds numbers beyond double
    /// precision's range (a machine-file value far too large).
    #[error("the machine's dynamic stiffness at {speed_hz} Hz cannot be solved in double precision ({detail})")]
    Overflow {
        /// Speed [Hz].
        speed_hz: f64,
        /// Which machine-file key, and why.
        detail: String,
    },
    /// A bad noise request.
    #[error("{0}")]
    Noise(String),
    /// Model assembly failed.
    #[error("model: {0}")]
    Model(String),
}

/// Response at one bearing and speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BearingResponse {
    /// Rotor relative to pedestal, x_shaft − x_ped (y, z) [m], as the
    /// physical motion (sensor effects not applied).
    pub rel: Phasor2<f64>,
    /// Absolute pedestal motion (y, z) [m] (zero on rigid ground).
    pub ped: Phasor2<f64>,
    /// Bearing coefficients at this speed, as simulated.
    pub coefficients: BearingCoefficients<f64>,
    /// The coefficients `bearings.csv` gives at this speed: the simulated
    /// ones, unless the effect `bearing_coefficients` writes a table for
    /// another bearing.
    pub table: BearingCoefficients<f64>,
}

/// Sensor-side effects applied when the response is read as measurements.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SensorEffects {
    /// Constant vector added to the `rel` readings (y, z) [m].
    pub runout: Phasor2<f64>,
    /// Delay of the `ped` channels [s].
    pub ped_delay: f64,
}

/// Seeded complex Gaussian measurement noise.
///
/// Each measured channel (rel_y, rel_z, ped_y, ped_z of each bearing) gets
/// n = σ·(a + i·b)/√2 with a, b independent standard normal (so E|n|² = σ²),
/// σ = `fraction` × the RMS of that channel's |phasor| over all speeds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Noise {
    /// Noise RMS relative to each channel's RMS over speed [-].
    pub fraction: f64,
    /// RNG seed (ChaCha12 `StdRng`; same seed and input, same noise).
    pub seed: u64,
}

/// The unbalance response of a machine over speeds.
#[derive(Clone, Debug, PartialEq)]
pub struct Response {
    /// Machine name.
    pub machine_name: String,
    /// Speeds [Hz], as requested.
    pub speeds_hz: Vec<f64>,
    /// Bearing names, in machine order.
    pub bearing_names: Vec<String>,
    /// `bearings[s][b]`: response at speed s, bearing b.
    pub bearings: Vec<Vec<BearingResponse>>,
    /// `bases[s][j]`: absolute (y, z) 1X phasors [m] of base j (machine
    /// order) at speed s; empty rows when the machine has no base.
    pub bases: Vec<Vec<Phasor2<f64>>>,
    /// Axial node positions [m].
    pub node_positions: Vec<f64>,
    /// `shaft[s][node]`: shaft displacement phasors (y, z) [m] at every node
    /// (empty when solved without keeping them, [`UnbalanceSolver::run_with`]).
    pub shaft: Vec<Vec<Phasor2<f64>>>,
    /// Sensor effects per bearing (applied by [`Response::measurements`]).
    pub sensors: Vec<SensorEffects>,
    /// What the data were made from: pedestals and injected effects.
    pub truth: Truth,
}

/// What one speed's solve gives: bearing readings, base motion and, when
/// kept, the shaft's node motion (see [`Response`]).
struct SpeedSolution {
    bearings: Vec<BearingResponse>,
    bases: Vec<Phasor2<f64>>,
    shaft: Option<Vec<Phasor2<f64>>>,
}

/// A machine prepared for repeated solves: effects resolved into the model,
/// matrices assembled once.
#[derive(Clone, Debug)]
pub struct UnbalanceSolver {
    machine: Machine,
    assembly: Assembly,
    /// Unbalance phasor Σ m·e·e^{iφ} per shaft node [kg·m].
    unbalance: Vec<C64>,
    pedestals: Vec<Option<PedestalDynamics>>,
    details: Vec<EffectTruth>,
    sensor_requests: Vec<(EffectKind, Vec<usize>, f64)>,
    /// Per bearing, the model `bearings.csv` is written from when it is not
    /// the machine's (effect `bearing_coefficients`).
    written: Vec<Option<BearingModel>>,
}

impl UnbalanceSolver {
    /// Resolves `effects` on `machine` and assembles the model.
    pub fn new(machine: &Machine, effects: &EffectSet) -> Result<Self, SimError> {
        let super::inject::Resolved {
            machine: effective,
            pedestals,
            details,
            sensor_requests,
            written,
        } = super::inject::resolve(machine, effects)?;
        effective.validate()?;
        let assembly = Assembly::new(&effective, &pedestals).map_err(SimError::Model)?;
        let mut unbalance = vec![C64::new(0.0, 0.0); machine.node_positions.len()];
        for u in &machine.unbalances {
            unbalance[u.node] += C64::from_polar(u.magnitude, u.angle_deg.to_radians());
        }
        Ok(Self {
            machine: effective,
            assembly,
            unbalance,
            pedestals,
            details,
            sensor_requests,
            written,
        })
    }

    /// The assembled model.
    pub fn assembly(&self) -> &Assembly {
        &self.assembly
    }

    /// Pedestal dynamics actually simulated (effects applied), per bearing.
    pub fn pedestals(&self) -> &[Option<PedestalDynamics>] {
        &self.pedestals
    }

    /// Bearing coefficients of every bearing at `speed_hz` [Hz].
    pub fn bearing_coefficients(
        &self,
        speed_hz: f64,
    ) -> Result<Vec<BearingCoefficients<f64>>, SimError> {
        (0..self.machine.bearings.len())
            .map(|b| Ok(self.machine.bearing_coefficients(b, speed_hz)?))
            .collect()
    }

    /// Solves one speed [Hz]: the full DOF vector X (x(t) = Re{X e^{iΩt}})
    /// into `x` (length = DOF count), using `work` as the matrix storage
    /// (from `assembly().new_matrix()`); returns the bearing coefficients.
    pub fn solve_speed(
        &self,
        speed_hz: f64,
        work: &mut super::banded::BandMatrix,
        x: &mut [C64],
    ) -> Result<Vec<BearingCoefficients<f64>>, SimError> {
        let coefs = self.bearing_coefficients(speed_hz)?;
        let omega = std::f64::consts::TAU * speed_hz;
        let singular = |e: super::banded::BandError| self.solver_failure(&e, speed_hz);
        self.assembly
            .fill_and_factor(work, omega, &coefs)
            .map_err(singular)?;
        x.fill(C64::new(0.0, 0.0));
        let w2 = omega * omega;
        for (node, u) in self.unbalance.iter().enumerate() {
            let d = self.assembly.node_dof[node];
            x[d] = *u * w2;
            x[d + 1] = *u * w2 * C64::new(0.0, -1.0);
        }
        self.assembly
            .solve(work, omega, &coefs, x)
            .map_err(singular)?;
        // Terms below the pivots' overflow can still overflow in the
        // solution (or its refinement): never a run with inf or NaN in it.
        if let Some(column) = x
            .iter()
            .position(|v| !(v.re.is_finite() && v.im.is_finite()))
        {
            return Err(singular(super::banded::BandError::Overflow { column }));
        }
        Ok(coefs)
    }

    /// Solves every speed of `speeds_hz` (checked finite and ≥ 0), in
    /// [`super::budget::solver_threads`] threads for a large model (speeds
    /// are independent; each thread has its own working matrix), reporting
    /// the number of speeds done through `done` from the calling thread.
    /// Results are in speed order and identical to a sequential solve.
    fn solve_speeds(
        &self,
        speeds_hz: &[f64],
        keep_shaft: bool,
        done: &mut dyn FnMut(usize),
    ) -> Result<Vec<SpeedSolution>, SimError> {
        let threads = super::budget::solver_threads(self.assembly.n_dof, speeds_hz.len());
        let chunk = speeds_hz.len().div_ceil(threads.max(1)).max(1);
        let finished = std::sync::atomic::AtomicUsize::new(0);
        let run_chunk = |speeds: &[f64], report: &mut dyn FnMut(usize)| {
            let mut work = self.assembly.new_matrix();
            let mut x = vec![C64::new(0.0, 0.0); self.assembly.n_dof];
            let mut out = Vec::with_capacity(speeds.len());
            for &s in speeds {
                out.push(self.solve_one(s, keep_shaft, &mut work, &mut x)?);
                let n = finished.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                report(n);
            }
            Ok::<_, SimError>(out)
        };
        let mut chunks = speeds_hz.chunks(chunk);
        let first = chunks.next().unwrap_or(&[]);
        let results: Vec<Result<Vec<SpeedSolution>, SimError>> = std::thread::scope(|scope| {
            let handles: Vec<_> = chunks
                .map(|c| scope.spawn(|| run_chunk(c, &mut |_| {})))
                .collect();
            let mut all = vec![run_chunk(first, done)];
            for h in handles {
                all.push(h.join().unwrap_or_else(|_| {
                    Err(SimError::Model("a solver thread panicked".to_string()))
                }));
            }
            all
        });
        let mut out = Vec::with_capacity(speeds_hz.len());
        for r in results {
            out.extend(r?);
        }
        done(out.len());
        Ok(out)
    }

    /// One speed [Hz] solved into its bearing readings, base motion and
    /// (with `keep_shaft`) shaft node motion.
    fn solve_one(
        &self,
        speed_hz: f64,
        keep_shaft: bool,
        work: &mut super::banded::BandMatrix,
        x: &mut [C64],
    ) -> Result<SpeedSolution, SimError> {
        let coefs = self.solve_speed(speed_hz, work, x)?;
        let mut bearings = Vec::with_capacity(coefs.len());
        for (b, coefficients) in coefs.into_iter().enumerate() {
            let sd = self.assembly.node_dof[self.assembly.bearing_node[b]];
            let ped = match self.assembly.pedestal_dof[b] {
                Some(p) => [x[p], x[p + 1]],
                None => [C64::new(0.0, 0.0); 2],
            };
            let table = match &self.written[b] {
                Some(model) => {
                    written_coefficients(&self.machine.bearings[b].name, model, speed_hz)?
                }
                None => coefficients,
            };
            bearings.push(BearingResponse {
                rel: [x[sd] - ped[0], x[sd + 1] - ped[1]],
                ped,
                coefficients,
                table,
            });
        }
        let shaft = keep_shaft.then(|| {
            (0..self.machine.node_positions.len())
                .map(|n| {
                    let d = self.assembly.node_dof[n];
                    [x[d], x[d + 1]]
                })
                .collect()
        });
        Ok(SpeedSolution {
            bearings,
            bases: self.assembly.bases.motion(x),
            shaft,
        })
    }

    /// The machine's bases for `truth.json`.
    fn base_truth(&self) -> Vec<crate::rundir::BaseTruth> {
        super::base::truth(&self.machine)
    }

    /// Unbalance response at every speed in `speeds_hz` [Hz].
    pub fn run(&self, speeds_hz: &[f64]) -> Result<Response, SimError> {
        self.run_with(speeds_hz, true, &mut |_| {})
    }

    /// [`UnbalanceSolver::run`] with `keep_shaft` (false: [`Response::shaft`]
    /// stays empty, saving 32 bytes per node and speed on long shafts) and
    /// `done(speeds solved so far)` called after every speed (progress).
    pub fn run_with(
        &self,
        speeds_hz: &[f64],
        keep_shaft: bool,
        done: &mut dyn FnMut(usize),
    ) -> Result<Response, SimError> {
        for (i, &s) in speeds_hz.iter().enumerate() {
            if !(s.is_finite() && s >= 0.0) {
                return Err(SimError::Speeds(format!(
                    "speed #{i} is {s} Hz: speeds must be finite and >= 0"
                )));
            }
        }
        let nb = self.machine.bearings.len();
        let solved = self.solve_speeds(speeds_hz, keep_shaft, done)?;
        let mut bearings = Vec::with_capacity(speeds_hz.len());
        let mut bases = Vec::with_capacity(speeds_hz.len());
        let mut shaft = Vec::with_capacity(speeds_hz.len());
        for one in solved {
            bearings.push(one.bearings);
            bases.push(one.bases);
            if let Some(sh) = one.shaft {
                shaft.push(sh);
            }
        }
        // Sensor effects, now that the typical readings are known.
        let mut sensors = vec![SensorEffects::default(); nb];
        let mut details = self.details.clone();
        for (kind, targets, size) in &self.sensor_requests {
            for &b in targets {
                let mut params = BTreeMap::new();
                match kind {
                    EffectKind::ProbeRunout => {
                        let mut mags: Vec<f64> = bearings
                            .iter()
                            .flat_map(|row: &Vec<BearingResponse>| {
                                [row[b].rel[0].norm(), row[b].rel[1].norm()]
                            })
                            .collect();
                        mags.sort_by(f64::total_cmp);
                        let median = if mags.is_empty() {
                            0.0
                        } else if mags.len() % 2 == 1 {
                            mags[mags.len() / 2]
                        } else {
                            0.5 * (mags[mags.len() / 2 - 1] + mags[mags.len() / 2])
                        };
                        let a = size * median;
                        let r = [
                            C64::from_polar(a, 30f64.to_radians()),
                            C64::from_polar(a, -60f64.to_radians()),
                        ];
                        sensors[b].runout =
                            [sensors[b].runout[0] + r[0], sensors[b].runout[1] + r[1]];
                        params.insert("r_y_re".into(), r[0].re);
                        params.insert("r_y_im".into(), r[0].im);
                        params.insert("r_z_re".into(), r[1].re);
                        params.insert("r_z_im".into(), r[1].im);
                    }
                    EffectKind::SensorDelay => {
                        sensors[b].ped_delay += size;
                        params.insert("tau".into(), *size);
                    }
                    _ => continue,
                }
                details.push(EffectTruth {
                    name: kind.name().into(),
                    bearing: self.machine.bearings[b].name.clone(),
                    parameters: params,
                });
            }
        }
        let mut effects: Vec<String> = Vec::new();
        for d in &details {
            if !effects.contains(&d.name) {
                effects.push(d.name.clone());
            }
        }
        let pedestals = self
            .machine
            .bearings
            .iter()
            .filter_map(|b| {
                b.pedestal.map(|pedestal| PedestalTruth {
                    bearing: b.name.clone(),
                    pedestal,
                })
            })
            .collect();
        Ok(Response {
            machine_name: self.machine.name.clone(),
            speeds_hz: speeds_hz.to_vec(),
            bearing_names: self.machine.bearing_names(),
            bearings,
            bases,
            node_positions: self.machine.node_positions.clone(),
            shaft,
            sensors,
            truth: Truth {
                pedestals,
                effects,
                effect_details: details,
                bases: self.base_truth(),
            },
        })
    }
}

/// Coefficients of the written (not simulated) bearing `model` of bearing
/// `name` at `speed_hz` [Hz] (effect `bearing_coefficients`).
fn written_coefficients(
    name: &str,
    model: &BearingModel,
    speed_hz: f64,
) -> Result<BearingCoefficients<f64>, SimError> {
    model
        .coefficients_at(name, speed_hz)
        .map_err(|e| effect_err(EffectKind::BearingCoefficients, e.to_string()))
}

/// Unbalance response of `machine` at `speeds_hz` [Hz] with `effects` injected.
pub fn unbalance_response(
    machine: &Machine,
    speeds_hz: &[f64],
    effects: &EffectSet,
) -> Result<Response, SimError> {
    UnbalanceSolver::new(machine, effects)?.run(speeds_hz)
}
