//! Sampled sensor signals of a simulated run-down (`plinth signals`), and the
//! signal-set file format the field box's replay and the firmware pipeline
//! tests read.
//!
//! # What is synthesised
//!
//! A run-down (or run-up) at a constant rate: speed f(t) = f₀ + s·t [Hz]
//! with s = ±rate, shaft angle θ(t) = 2π(f₀t + s·t²/2) [rad], t = 0 and θ = 0
//! at keyphasor pulse 0. Every channel is a transducer on one bearing
//! (formats.md axes: y vertical, z horizontal):
//!
//! - proximity probes see `rel` (rotor relative to pedestal) as displacement,
//!   riding on their gap voltage (e.g. 7.87 V/mm around −9 V);
//! - seismic sensors on the pedestal see `ped` as displacement, velocity or
//!   acceleration (accelerometers, velocity pick-ups).
//!
//! The displacement of a channel is x(t) = Re{X(Ω(t))·e^{iθ(t)}}, with X the
//! simulator's 1X phasor at the *instantaneous* speed, so its phase is
//! continuous through the run-down. Velocity and acceleration are the exact
//! time derivatives of that x(t) (speed-dependence of X included, Ω̈ = 0):
//!
//! - v = Re{(iΩX + Ω̇X′)·e^{iθ}},
//! - a = Re{(iΩ̇X − Ω²X + 2iΩΩ̇X′ + Ω̇²X″)·e^{iθ}},  X′ = dX/dΩ.
//!
//! Volts = offset + sensitivity·(quantity) + Gaussian noise, then an ADC
//! (default 16 bit bipolar ±10 V, as an AD7606): code = round(V/LSB) clamped
//! to [−2^(b−1), 2^(b−1) − 1], clipped samples counted per channel.
//!
//! # Response interpolation
//!
//! Solving the machine at every sample is pointless: the response is computed
//! on a uniform speed grid (default step 0.01 Hz, with 4 extra steps beyond
//! each end of the run) and each channel's complex phasor is interpolated
//! with a natural cubic spline in speed. Velocity and acceleration channels
//! need X′ and X″ too, which a cubic spline gives only to O(h²): they are
//! written from the model's own derivatives (five-point differences of
//! solves at each grid speed) through a quintic Hermite interpolant
//! ([`derivative`]). The interpolation error is *measured*, not assumed: the
//! machine is also solved at the midpoint of every grid interval the run
//! overlaps and at 17 speeds spread over the run, and the largest
//! |X_spline − X_solved| is recorded in the header, absolute [m] and relative
//! to that channel's largest |X| over the run; for velocity and acceleration
//! channels the relative figure is that of the sensed phasor (value and
//! derivatives against the differences there, plus the differences' own
//! Richardson error estimate), relative to its peak. It falls as h⁴ and is set by
//! the sharpest resonance: on the undamped paper machine (rotor-on-pedestal
//! modes at 27 and 45 Hz with almost no damping) 200→5 Hz gives 7.3e-3 at
//! 0.05 Hz and 5.4e-6 at 0.01 Hz (0.05 Hz suffices for the damped twin:
//! 7.8e-4).
//!
//! # The signal-set directory (format `plinth-signals`, version 1)
//!
//! - `signals.json`: the header ([`SignalHeader`]): sample rate, sample count,
//!   ADC (bits, full scale, volts per code), the run-down, and the channels in
//!   sample-vector order with bearing, quantity (`rel_y`, `rel_z`, `ped_y`,
//!   `ped_z`), sensor kind (`displacement`, `velocity`, `acceleration`),
//!   sensitivity [V/m, V/(m/s), V/(m/s²)], offset [V], noise [V RMS] and the
//!   number of clipped samples.
//! - `samples.i16`: raw ADC codes, little-endian i16, interleaved by sample
//!   vector (value k·N + n is sample k of channel n, as in the wire protocol's
//!   `SampleBlock`), no header: exactly samples × channels × 2 bytes.
//!   Volts = code × `adc.volts_per_code`.
//! - `keyphasor.csv`: `revolution,sample_position,time_s`, one row per pulse
//!   (shaft angle 2π·revolution), `sample_position` the pulse's time in
//!   sample periods since sample 0 (fractional: sub-sample resolution);
//!   sample k is taken at time (k − p₀)/rate, p₀ = position of pulse 0.
//! - `truth/`: a run directory (formats.md) with the noise-free phasors on
//!   the grid (what the spline interpolates), the bearing coefficients and
//!   `truth.json`: the answer extracted phasors are compared with
//!   ([`PhasorSpline`] interpolates it at any speed).
//!
//! # Modules
//!
//! [`rundown`] (kinematics), [`channel`] (channel and ADC model), [`format`]
//! (the directory format: reader and writer), [`spline`] (phasor splines in
//! speed), [`derivative`] (speed derivatives for velocity and acceleration), [`synthesis`] (sampling the response), [`cli`] (`plinth signals`).
//! Everything is re-exported here.

pub mod channel;
pub mod cli;
pub mod derivative;
pub mod format;
pub mod rundown;
pub mod spline;
pub mod synthesis;

#[cfg(test)]
mod tests;

pub use channel::*;
pub use cli::*;
pub use derivative::*;
pub use format::*;
pub use rundown::*;
pub use spline::*;
pub use synthesis::*;

use super::inject::EffectSet;
use super::machine::Machine;
use super::response::SimError;
use crate::rundir::{Measurement, RunDir, RunDirError};
use anyhow::Context;
use num_complex::Complex;
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::f64::consts::TAU;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};

type C64 = Complex<f64>;

/// Name in the header's `format` field.
pub const FORMAT_NAME: &str = "plinth-signals";
/// Version of the format this code writes and reads.
pub const FORMAT_VERSION: u32 = 1;
/// Header file of a signal set.
pub const HEADER_FILE: &str = "signals.json";
/// Sample file of a signal set.
pub const SAMPLES_FILE: &str = "samples.i16";
/// Keyphasor file of a signal set.
pub const KEYPHASOR_FILE: &str = "keyphasor.csv";
/// Truth run directory inside a signal set.
pub const TRUTH_DIR: &str = "truth";
/// Most response solves of the speed grid (a grid step too small for the
/// run is refused, not allocated).
pub const MAX_GRID_POINTS: usize = 200_000;
/// Largest interpolation error accepted, relative to each channel's peak
/// over the run: a grid step that cannot represent the response is refused.
pub const MAX_INTERPOLATION_ERROR: f64 = 0.1;
/// Speeds spread over the run (besides the grid midpoints) at which the
/// interpolation error is measured.
pub const CHECK_SPEEDS: usize = 16;

/// A problem reading, writing or making a signal set, naming the file and
/// where in it.
#[derive(Debug, thiserror::Error)]
pub enum SignalsError {
    /// The file could not be opened, read or written.
    #[error("{}: {source}", file.display())]
    Io {
        /// The file.
        file: PathBuf,
        /// The operating-system error.
        #[source]
        source: std::io::Error,
    },
    /// The header is not valid JSON for the format.
    #[error("{}:{line}:{column}: {message}", file.display())]
    Json {
        /// The file.
        file: PathBuf,
        /// Line [1-based].
        line: usize,
        /// Column [1-based].
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// The header parses but breaks the format (wrong version, bad values).
    #[error("{}: {message}", file.display())]
    Header {
        /// The file.
        file: PathBuf,
        /// What is wrong, naming the field.
        message: String,
    },
    /// The sample file has the wrong size.
    #[error("{}: byte offset {offset}: {message}", file.display())]
    Samples {
        /// The file.
        file: PathBuf,
        /// Byte offset where the file departs from the header's description.
        offset: u64,
        /// What is wrong.
        message: String,
    },
    /// A keyphasor row is malformed.
    #[error("{}:{line}: {message}", file.display())]
    Keyphasor {
        /// The file.
        file: PathBuf,
        /// Line [1-based].
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The truth run directory could not be read or written.
    #[error(transparent)]
    Truth(#[from] RunDirError),
    /// The simulation failed.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The requested signals cannot be made.
    #[error("{0}")]
    Request(String),
}

fn io_err(file: &Path) -> impl FnOnce(std::io::Error) -> SignalsError + '_ {
    move |source| SignalsError::Io {
        file: file.to_path_buf(),
        source,
    }
}
