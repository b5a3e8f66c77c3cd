//! Rotor-bearing-pedestal machine simulator: reads a machine file
//! ([`machine`], TOML, SI units), builds a Timoshenko finite-element model of
//! the rotor with rigid disks, bearings (speed tables or short-bearing oil
//! films) and pedestals on rigid ground or on bases ([`base`]), injects the effects of
//! `crate::effects`, and computes the synchronous unbalance response over a
//! list of speeds with one banded complex LU per speed.
//!
//! Axes (formats.md): x along the rotor, y vertical (up), z horizontal;
//! positive spin about +x, forward whirl from +y towards +z. Phasors:
//! q(t) = Re{Q·e^{iΩt}}, t = 0 at the keyphasor, at which instant an
//! unbalance of angle φ points φ from +y towards +z.
//!
//! Typical use:
//! ```no_run
//! use plinth::sim::{Machine, EffectSet, unbalance_response};
//! let machine = Machine::from_toml_path("examples/feng-hahn-1997.toml")?;
//! let speeds: Vec<f64> = (5..=200).map(f64::from).collect();
//! let response = unbalance_response(&machine, &speeds, &EffectSet::none())?;
//! let run = response.to_run_dir(None)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
pub mod assembly;
pub mod banded;
pub mod base;
pub mod budget;
pub mod cli;
pub mod disk;
pub mod inject;
pub mod machine;
pub mod machine_file;
pub mod modal;
pub mod oil_film;
pub mod pedestal;
pub mod predict;
pub mod refine;
pub mod response;
pub mod signals;
pub mod static_load;
pub mod timoshenko;

pub use inject::{default_size, EffectRequest, EffectSet};
pub use machine::{Bearing, BearingModel, Machine, MachineError, Unbalance};
pub use pedestal::PedestalDynamics;
pub use response::{
    unbalance_response, BearingResponse, Noise, Response, SensorEffects, SimError, UnbalanceSolver,
};
