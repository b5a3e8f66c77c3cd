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
//! with a natural cubic spline in speed (derivatives from the same spline).
//! The interpolation error is *measured*, not assumed: the machine is also
//! solved at the midpoint of every grid interval the run overlaps and at 17
//! speeds spread over the run, and the largest
//! |X_spline − X_solved| is recorded in the header, absolute [m] and relative
//! to that channel's largest |X| over the run. It falls as h⁴ and is set by
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

use super::inject::{EffectRequest, EffectSet};
use super::machine::Machine;
use super::response::{unbalance_response, SimError};
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

/// A linear speed ramp: from `start_hz` to `end_hz` at `rate_hz_per_s`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunDown {
    /// Speed at t = 0 [Hz].
    pub start_hz: f64,
    /// Speed at the end [Hz].
    pub end_hz: f64,
    /// Magnitude of the speed change per second [Hz/s] (> 0).
    pub rate_hz_per_s: f64,
}

impl RunDown {
    /// Parses `START:END:RATE` [Hz, Hz, Hz/s], e.g. `200:5:5`.
    pub fn parse(text: &str) -> Result<RunDown, SignalsError> {
        let parts: Vec<&str> = text.split(':').collect();
        let [a, b, c] = parts.as_slice() else {
            return Err(SignalsError::Request(format!(
                "--rundown {text:?}: use START:END:RATE [Hz:Hz:Hz/s], e.g. 200:5:5"
            )));
        };
        let num = |s: &str, what: &str| -> Result<f64, SignalsError> {
            s.trim().parse::<f64>().map_err(|_| {
                SignalsError::Request(format!("--rundown {text:?}: {what} {s:?} is not a number"))
            })
        };
        let r = RunDown {
            start_hz: num(a, "START")?,
            end_hz: num(b, "END")?,
            rate_hz_per_s: num(c, "RATE")?,
        };
        r.validate()
            .map_err(|m| SignalsError::Request(format!("--rundown {text:?}: {m}")))?;
        Ok(r)
    }

    /// Checks speeds are positive and distinct and the rate positive.
    pub fn validate(&self) -> Result<(), String> {
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if !(ok(self.start_hz) && ok(self.end_hz)) {
            return Err(format!(
                "speeds must be finite and > 0 Hz (got {} and {})",
                self.start_hz, self.end_hz
            ));
        }
        if self.start_hz == self.end_hz {
            return Err("START and END must differ".into());
        }
        if !ok(self.rate_hz_per_s) {
            return Err(format!(
                "RATE must be finite and > 0 Hz/s (got {})",
                self.rate_hz_per_s
            ));
        }
        Ok(())
    }

    /// Signed speed slope s [Hz/s]: negative for a run-down.
    pub fn slope(&self) -> f64 {
        if self.end_hz < self.start_hz {
            -self.rate_hz_per_s
        } else {
            self.rate_hz_per_s
        }
    }

    /// Duration [s].
    pub fn duration_s(&self) -> f64 {
        (self.end_hz - self.start_hz).abs() / self.rate_hz_per_s
    }

    /// Speed at time t [Hz].
    pub fn speed_hz(&self, t: f64) -> f64 {
        self.start_hz + self.slope() * t
    }

    /// Shaft angle at time t [rad], 0 at t = 0.
    pub fn angle_rad(&self, t: f64) -> f64 {
        TAU * t * (self.start_hz + 0.5 * self.slope() * t)
    }

    /// Time of keyphasor pulse j (shaft angle 2πj) [s], numerically stable
    /// root of f₀t + s·t²/2 = j.
    pub fn pulse_time(&self, j: u64) -> f64 {
        let j = j as f64;
        let f0 = self.start_hz;
        let disc = (f0 * f0 + 2.0 * self.slope() * j).max(0.0);
        2.0 * j / (f0 + disc.sqrt())
    }

    /// Number of complete revolutions within the run.
    pub fn revolutions(&self) -> u64 {
        let t = self.duration_s();
        (t * (self.start_hz + 0.5 * self.slope() * t))
            .floor()
            .max(0.0) as u64
    }
}

/// What a channel measures at its bearing (formats.md `rel`/`ped`, y/z).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ChannelQuantity {
    /// Rotor relative to pedestal, vertical.
    RelY,
    /// Rotor relative to pedestal, horizontal.
    RelZ,
    /// Absolute pedestal, vertical.
    PedY,
    /// Absolute pedestal, horizontal.
    PedZ,
}

impl ChannelQuantity {
    /// All four, in the order channels are laid out per bearing.
    pub const ALL: [ChannelQuantity; 4] = [Self::RelY, Self::RelZ, Self::PedY, Self::PedZ];

    /// The `measurements.csv` column stem, e.g. `rel_y`.
    pub fn name(self) -> &'static str {
        match self {
            Self::RelY => "rel_y",
            Self::RelZ => "rel_z",
            Self::PedY => "ped_y",
            Self::PedZ => "ped_z",
        }
    }

    /// This quantity's phasor [m] in a measurement row.
    pub fn of(self, m: &Measurement) -> C64 {
        match self {
            Self::RelY => m.rel[0],
            Self::RelZ => m.rel[1],
            Self::PedY => m.ped[0],
            Self::PedZ => m.ped[1],
        }
    }

    /// The wire protocol's name for it.
    pub fn to_protocol(self) -> plinth_shared::protocol::messages::Quantity {
        use plinth_shared::protocol::messages::Quantity as Q;
        match self {
            Self::RelY => Q::RelY,
            Self::RelZ => Q::RelZ,
            Self::PedY => Q::PedY,
            Self::PedZ => Q::PedZ,
        }
    }
}

/// What a channel's transducer measures (the one definition, shared with
/// the extractor and the wire protocol).
pub use plinth_shared::extractor::SensorKind;

/// Parses a sensor kind on the command line (`displacement`/`proximity`,
/// `velocity`, `acceleration`).
pub fn parse_sensor_kind(text: &str) -> Result<SensorKind, String> {
    SensorKind::parse(text).ok_or_else(|| {
        format!("`{text}` is not a sensor kind (expected displacement, velocity or acceleration)")
    })
}

/// One channel of a signal set.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Channel {
    /// Name, `<bearing>_<quantity>`, e.g. `left_rel_y`.
    pub name: String,
    /// Bearing name (as in run directories).
    pub bearing: String,
    /// Index of the bearing in the machine's bearing order.
    pub bearing_index: usize,
    /// What it measures.
    pub quantity: ChannelQuantity,
    /// Transducer type.
    pub kind: SensorKind,
    /// Volts per unit of `kind`: V/m, V/(m/s) or V/(m/s²).
    pub sensitivity: f64,
    /// DC offset of the transducer output [V] (a probe's gap voltage).
    pub offset_v: f64,
    /// RMS of the white Gaussian noise added before the ADC [V].
    pub noise_v_rms: f64,
    /// Samples clipped at the ADC's full scale (written by the synthesiser).
    #[serde(default)]
    pub clipped_samples: u64,
    /// Largest spline interpolation error of this channel's displacement
    /// phasor over the run [m] (measured at grid midpoints).
    #[serde(default)]
    pub interpolation_error_m: f64,
    /// The same relative to the channel's largest |X| over the run [-].
    #[serde(default)]
    pub interpolation_error_rel: f64,
}

/// The ADC: a bipolar converter of `bits` bits over ±`full_scale_v`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Adc {
    /// Resolution [bits] (2..=16: codes are stored as i16).
    pub bits: u32,
    /// Full scale [V]: inputs beyond ±this clip.
    pub full_scale_v: f64,
    /// Volts per code [V] = full_scale_v / 2^(bits−1).
    pub volts_per_code: f64,
}

impl Adc {
    /// A `bits`-bit ADC over ±`full_scale_v` [V].
    pub fn new(bits: u32, full_scale_v: f64) -> Result<Adc, SignalsError> {
        if !(2..=16).contains(&bits) {
            return Err(SignalsError::Request(format!(
                "ADC bits must be 2..=16 (got {bits})"
            )));
        }
        if !(full_scale_v.is_finite() && full_scale_v > 0.0) {
            return Err(SignalsError::Request(format!(
                "ADC full scale must be finite and > 0 V (got {full_scale_v})"
            )));
        }
        Ok(Adc {
            bits,
            full_scale_v,
            volts_per_code: full_scale_v / f64::from(1u32 << (bits - 1)),
        })
    }

    /// The AD7606's ±10 V range at 16 bits.
    pub fn ad7606() -> Adc {
        Adc {
            bits: 16,
            full_scale_v: 10.0,
            volts_per_code: 10.0 / 32768.0,
        }
    }

    /// Code range (min, max).
    pub fn code_range(&self) -> (i32, i32) {
        let half = 1i32 << (self.bits - 1);
        (-half, half - 1)
    }

    /// Quantises `volts` [V]: (code, clipped).
    pub fn quantise(&self, volts: f64) -> (i16, bool) {
        let (lo, hi) = self.code_range();
        let c = (volts / self.volts_per_code).round();
        if c < f64::from(lo) {
            (lo as i16, true)
        } else if c > f64::from(hi) {
            (hi as i16, true)
        } else {
            (c as i16, false)
        }
    }
}

/// How the response is interpolated in speed (recorded in the header).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Interpolation {
    /// Method name (`natural_cubic_spline`).
    pub method: InterpolationMethod,
    /// Grid step [Hz].
    pub grid_step_hz: f64,
    /// Largest error over all channels relative to each channel's largest |X|.
    pub max_rel_error: f64,
}

/// Interpolation method of the response in speed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InterpolationMethod {
    /// Natural cubic spline through the grid in speed, per channel, complex.
    NaturalCubicSpline,
}

/// `signals.json`: everything about a signal set but the samples.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SignalHeader {
    /// Always [`FORMAT_NAME`].
    pub format: String,
    /// Format version ([`FORMAT_VERSION`]).
    pub version: u32,
    /// Machine name.
    pub machine: String,
    /// Sample rate per channel [Hz].
    pub sample_rate_hz: f64,
    /// Sample vectors (samples per channel).
    pub samples: u64,
    /// The converter.
    pub adc: Adc,
    /// The speed ramp.
    pub rundown: RunDown,
    /// Position of keyphasor pulse 0 (t = 0, θ = 0) in sample periods.
    pub t0_sample_position: f64,
    /// Keyphasor pulses in `keyphasor.csv`.
    pub keyphasor_pulses: u64,
    /// Channels in sample-vector order.
    pub channels: Vec<Channel>,
    /// How the response was interpolated in speed.
    pub interpolation: Interpolation,
    /// Seed of the noise (StdRng).
    pub seed: u64,
    /// Effects injected into the machine (formats.md names).
    #[serde(default)]
    pub effects: Vec<String>,
}

/// A whole signal set in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct SignalSet {
    /// The header.
    pub header: SignalHeader,
    /// ADC codes interleaved by sample vector (k·N + n).
    pub codes: Vec<i16>,
    /// Keyphasor pulse positions [sample periods since sample 0], increasing;
    /// pulse j is at shaft angle 2πj.
    pub keyphasor: Vec<f64>,
}

impl SignalSet {
    /// Number of channels.
    pub fn channels(&self) -> usize {
        self.header.channels.len()
    }

    /// Sample vectors.
    pub fn len(&self) -> usize {
        self.header.samples as usize
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.header.samples == 0
    }

    /// Sample k of channel n in volts [V].
    pub fn volts(&self, k: usize, n: usize) -> f64 {
        f64::from(self.codes[k * self.channels() + n]) * self.header.adc.volts_per_code
    }

    /// Time of sample k [s] (t = 0 at keyphasor pulse 0).
    pub fn time_s(&self, k: usize) -> f64 {
        (k as f64 - self.header.t0_sample_position) / self.header.sample_rate_hz
    }

    /// Writes the signal set to `dir` (created if needed); the truth run
    /// directory is written separately ([`write_truth`]) or by [`synthesise_to`].
    pub fn write(&self, dir: &Path) -> Result<(), SignalsError> {
        std::fs::create_dir_all(dir).map_err(io_err(dir))?;
        let hp = dir.join(HEADER_FILE);
        let text = serde_json::to_string_pretty(&self.header)
            .map_err(|e| SignalsError::Request(format!("serialising the header: {e}")))?;
        std::fs::write(&hp, text + "\n").map_err(io_err(&hp))?;

        let sp = dir.join(SAMPLES_FILE);
        let f = std::fs::File::create(&sp).map_err(io_err(&sp))?;
        let mut w = BufWriter::with_capacity(1 << 20, f);
        for c in &self.codes {
            w.write_all(&c.to_le_bytes()).map_err(io_err(&sp))?;
        }
        w.flush().map_err(io_err(&sp))?;

        let kp = dir.join(KEYPHASOR_FILE);
        let f = std::fs::File::create(&kp).map_err(io_err(&kp))?;
        let mut w = BufWriter::new(f);
        writeln!(w, "revolution,sample_position,time_s").map_err(io_err(&kp))?;
        let fs = self.header.sample_rate_hz;
        let p0 = self.header.t0_sample_position;
        for (j, p) in self.keyphasor.iter().enumerate() {
            writeln!(w, "{j},{p:.17e},{:.17e}", (p - p0) / fs).map_err(io_err(&kp))?;
        }
        w.flush().map_err(io_err(&kp))?;
        Ok(())
    }

    /// Reads and checks a signal set (not the truth; see [`read_truth`]).
    pub fn read(dir: &Path) -> Result<SignalSet, SignalsError> {
        let hp = dir.join(HEADER_FILE);
        let text = std::fs::read_to_string(&hp).map_err(io_err(&hp))?;
        let header: SignalHeader = serde_json::from_str(&text).map_err(|e| SignalsError::Json {
            file: hp.clone(),
            line: e.line(),
            column: e.column(),
            message: e.to_string(),
        })?;
        check_header(&header, &hp)?;

        let sp = dir.join(SAMPLES_FILE);
        let n = header.channels.len() as u64;
        let expected = header
            .samples
            .checked_mul(n)
            .and_then(|v| v.checked_mul(2))
            .ok_or_else(|| SignalsError::Header {
                file: hp.clone(),
                message: "samples × channels overflows".into(),
            })?;
        let mut f = std::fs::File::open(&sp).map_err(io_err(&sp))?;
        let len = f.metadata().map_err(io_err(&sp))?.len();
        if len != expected {
            return Err(SignalsError::Samples {
                file: sp,
                offset: len.min(expected),
                message: format!(
                    "file is {len} bytes, the header describes {} samples × {n} channels × 2 bytes = {expected}",
                    header.samples
                ),
            });
        }
        let mut bytes = Vec::with_capacity(expected as usize);
        f.read_to_end(&mut bytes).map_err(io_err(&sp))?;
        if bytes.len() as u64 != expected {
            return Err(SignalsError::Samples {
                file: sp,
                offset: bytes.len() as u64,
                message: "file changed size while being read".into(),
            });
        }
        let codes: Vec<i16> = bytes
            .chunks_exact(2)
            .map(|b| i16::from_le_bytes([b[0], b[1]]))
            .collect();
        let (lo, hi) = header.adc.code_range();
        if let Some(i) = codes
            .iter()
            .position(|&c| i32::from(c) < lo || i32::from(c) > hi)
        {
            return Err(SignalsError::Samples {
                file: sp,
                offset: 2 * i as u64,
                message: format!(
                    "code {} is outside the {}-bit ADC range {lo}..={hi}",
                    codes[i], header.adc.bits
                ),
            });
        }

        let kp = dir.join(KEYPHASOR_FILE);
        let keyphasor = read_keyphasor(&kp, header.samples)?;
        if keyphasor.len() as u64 != header.keyphasor_pulses {
            return Err(SignalsError::Keyphasor {
                file: kp,
                line: keyphasor.len() + 1,
                message: format!(
                    "{} pulses, the header says {}",
                    keyphasor.len(),
                    header.keyphasor_pulses
                ),
            });
        }
        Ok(SignalSet {
            header,
            codes,
            keyphasor,
        })
    }
}

fn check_header(h: &SignalHeader, file: &Path) -> Result<(), SignalsError> {
    let bad = |message: String| SignalsError::Header {
        file: file.to_path_buf(),
        message,
    };
    if h.format != FORMAT_NAME {
        return Err(bad(format!(
            "format: expected {FORMAT_NAME:?}, got {:?}",
            h.format
        )));
    }
    if h.version != FORMAT_VERSION {
        return Err(bad(format!(
            "version: this build reads version {FORMAT_VERSION}, the file is version {}",
            h.version
        )));
    }
    if !(h.sample_rate_hz.is_finite() && h.sample_rate_hz > 0.0) {
        return Err(bad(format!(
            "sample_rate_hz: must be finite and > 0 (got {})",
            h.sample_rate_hz
        )));
    }
    let adc = Adc::new(h.adc.bits, h.adc.full_scale_v).map_err(|e| bad(format!("adc: {e}")))?;
    if (adc.volts_per_code - h.adc.volts_per_code).abs() > 1e-12 * adc.volts_per_code {
        return Err(bad(format!(
            "adc.volts_per_code: {} does not match {} bits over ±{} V ({})",
            h.adc.volts_per_code, h.adc.bits, h.adc.full_scale_v, adc.volts_per_code
        )));
    }
    h.rundown
        .validate()
        .map_err(|m| bad(format!("rundown: {m}")))?;
    if h.channels.is_empty() {
        return Err(bad("channels: none".into()));
    }
    if !h.t0_sample_position.is_finite() {
        return Err(bad("t0_sample_position: not finite".into()));
    }
    for (i, c) in h.channels.iter().enumerate() {
        if !(c.sensitivity.is_finite() && c.sensitivity > 0.0) {
            return Err(bad(format!(
                "channels[{i}].sensitivity: must be finite and > 0 (got {})",
                c.sensitivity
            )));
        }
        if !(c.offset_v.is_finite() && c.noise_v_rms.is_finite() && c.noise_v_rms >= 0.0) {
            return Err(bad(format!(
                "channels[{i}]: offset_v and noise_v_rms must be finite, noise >= 0"
            )));
        }
    }
    Ok(())
}

fn read_keyphasor(file: &Path, samples: u64) -> Result<Vec<f64>, SignalsError> {
    let text = std::fs::read_to_string(file).map_err(io_err(file))?;
    let bad = |line: usize, message: String| SignalsError::Keyphasor {
        file: file.to_path_buf(),
        line,
        message,
    };
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, h)) if h.trim() == "revolution,sample_position,time_s" => {}
        _ => {
            return Err(bad(
                1,
                "header must be `revolution,sample_position,time_s`".into(),
            ))
        }
    }
    let mut out: Vec<f64> = Vec::new();
    for (i, line) in lines {
        let ln = i + 1;
        if line.trim().is_empty() {
            continue;
        }
        let cols: Vec<&str> = line.split(',').collect();
        if cols.len() != 3 {
            return Err(bad(ln, format!("expected 3 columns, got {}", cols.len())));
        }
        let rev: u64 = cols[0].trim().parse().map_err(|_| {
            bad(
                ln,
                format!("column 1 (revolution): {:?} is not an integer", cols[0]),
            )
        })?;
        if rev != out.len() as u64 {
            return Err(bad(
                ln,
                format!("column 1 (revolution): expected {}, got {rev}", out.len()),
            ));
        }
        let p: f64 = cols[1].trim().parse().map_err(|_| {
            bad(
                ln,
                format!("column 2 (sample_position): {:?} is not a number", cols[1]),
            )
        })?;
        if !p.is_finite() || p < 0.0 || p >= samples as f64 {
            return Err(bad(
                ln,
                format!("column 2 (sample_position): {p} is outside the samples 0..{samples}"),
            ));
        }
        if let Some(&prev) = out.last() {
            if p <= prev {
                return Err(bad(
                    ln,
                    format!(
                        "column 2 (sample_position): {p} is not after the previous pulse {prev}"
                    ),
                ));
            }
        }
        out.push(p);
    }
    Ok(out)
}

/// Reads the truth run directory of a signal set.
pub fn read_truth(dir: &Path) -> Result<RunDir, SignalsError> {
    Ok(RunDir::read(dir.join(TRUTH_DIR))?)
}

/// Writes the truth run directory of a signal set (full precision).
pub fn write_truth(dir: &Path, truth: &RunDir) -> Result<(), SignalsError> {
    Ok(truth.write(dir.join(TRUTH_DIR))?)
}

/// A natural cubic spline of complex values on a sorted grid.
#[derive(Clone, Debug, PartialEq)]
pub struct ComplexSpline {
    x: Vec<f64>,
    y: Vec<C64>,
    /// Second derivatives at the knots.
    m: Vec<C64>,
}

impl ComplexSpline {
    /// Natural cubic spline through (x, y); x strictly increasing, ≥ 2 points.
    pub fn new(x: Vec<f64>, y: Vec<C64>) -> Result<ComplexSpline, String> {
        let n = x.len();
        if n < 2 || y.len() != n {
            return Err(format!(
                "spline needs ≥ 2 points and as many values (got {n}, {})",
                y.len()
            ));
        }
        if x.iter().any(|v| !v.is_finite()) || x.windows(2).any(|w| w[1] <= w[0]) {
            return Err("spline abscissae must be finite and strictly increasing".into());
        }
        let mut m = vec![C64::new(0.0, 0.0); n];
        if n > 2 {
            // Tridiagonal system for interior second derivatives (Thomas).
            let k = n - 2;
            let mut diag = vec![0.0; k];
            let mut rhs = vec![C64::new(0.0, 0.0); k];
            let mut upper = vec![0.0; k];
            let mut lower = vec![0.0; k];
            for i in 1..n - 1 {
                let h0 = x[i] - x[i - 1];
                let h1 = x[i + 1] - x[i];
                lower[i - 1] = h0;
                diag[i - 1] = 2.0 * (h0 + h1);
                upper[i - 1] = h1;
                rhs[i - 1] = 6.0 * ((y[i + 1] - y[i]) / h1 - (y[i] - y[i - 1]) / h0);
            }
            for i in 1..k {
                let w = lower[i] / diag[i - 1];
                diag[i] -= w * upper[i - 1];
                let r = rhs[i - 1] * w;
                rhs[i] -= r;
            }
            m[k] = rhs[k - 1] / diag[k - 1];
            for i in (0..k - 1).rev() {
                m[i + 1] = (rhs[i] - m[i + 2] * upper[i]) / diag[i];
            }
        }
        Ok(ComplexSpline { x, y, m })
    }

    /// Range of the abscissae.
    pub fn range(&self) -> (f64, f64) {
        (self.x[0], self.x[self.x.len() - 1])
    }

    /// Interval index containing x (clamped to the ends).
    fn interval(&self, x: f64) -> usize {
        let n = self.x.len();
        match self.x.partition_point(|&k| k <= x) {
            0 => 0,
            i if i >= n => n - 2,
            i => i - 1,
        }
    }

    /// Value, first and second derivative at `x` (cubic extension beyond the
    /// ends: callers keep x inside [`ComplexSpline::range`]).
    pub fn eval(&self, x: f64) -> (C64, C64, C64) {
        let i = self.interval(x);
        let h = self.x[i + 1] - self.x[i];
        let a = (self.x[i + 1] - x) / h;
        let b = (x - self.x[i]) / h;
        let (y0, y1, m0, m1) = (self.y[i], self.y[i + 1], self.m[i], self.m[i + 1]);
        let v = y0 * a + y1 * b + (m0 * (a * a * a - a) + m1 * (b * b * b - b)) * (h * h / 6.0);
        let d = (y1 - y0) / h + (m1 * (3.0 * b * b - 1.0) - m0 * (3.0 * a * a - 1.0)) * (h / 6.0);
        let dd = m0 * a + m1 * b;
        (v, d, dd)
    }
}

/// The truth phasors of a run directory interpolated in speed: one spline
/// per (bearing, quantity).
#[derive(Clone, Debug, PartialEq)]
pub struct PhasorSpline {
    splines: BTreeMap<(String, ChannelQuantity), ComplexSpline>,
}

impl PhasorSpline {
    /// Builds splines from measurement rows (each bearing's speeds strictly
    /// increasing after sorting, ≥ 2 of them).
    pub fn from_measurements(rows: &[Measurement]) -> Result<PhasorSpline, String> {
        let mut by_bearing: BTreeMap<&str, Vec<&Measurement>> = BTreeMap::new();
        for r in rows {
            by_bearing.entry(r.bearing.as_str()).or_default().push(r);
        }
        let mut splines = BTreeMap::new();
        for (b, mut rs) in by_bearing {
            rs.sort_by(|p, q| p.speed_hz.total_cmp(&q.speed_hz));
            let x: Vec<f64> = rs.iter().map(|r| r.speed_hz).collect();
            for q in ChannelQuantity::ALL {
                let y: Vec<C64> = rs.iter().map(|r| q.of(r)).collect();
                let s =
                    ComplexSpline::new(x.clone(), y).map_err(|e| format!("bearing {b}: {e}"))?;
                splines.insert((b.to_string(), q), s);
            }
        }
        Ok(PhasorSpline { splines })
    }

    /// The spline of one channel.
    pub fn get(&self, bearing: &str, quantity: ChannelQuantity) -> Option<&ComplexSpline> {
        self.splines.get(&(bearing.to_string(), quantity))
    }

    /// Displacement phasor [m] of (bearing, quantity) at `speed_hz`, `None`
    /// for an unknown channel or a speed outside the grid.
    pub fn at(&self, bearing: &str, quantity: ChannelQuantity, speed_hz: f64) -> Option<C64> {
        let s = self.get(bearing, quantity)?;
        let (lo, hi) = s.range();
        (speed_hz >= lo && speed_hz <= hi).then(|| s.eval(speed_hz).0)
    }
}

/// Everything `plinth signals` can be told.
#[derive(Clone, Debug, PartialEq)]
pub struct SignalOptions {
    /// The speed ramp.
    pub rundown: RunDown,
    /// Sample rate per channel [Hz].
    pub sample_rate_hz: f64,
    /// The converter.
    pub adc: Adc,
    /// Proximity probe sensitivity [V/m] (7.87 V/mm = 7870 V/m).
    pub probe_sensitivity: f64,
    /// Proximity probe gap voltage [V] (DC the vibration rides on).
    pub probe_gap_v: f64,
    /// Noise on the probe channels [V RMS].
    pub probe_noise_v: f64,
    /// Transducer type on the pedestals.
    pub seismic_kind: SensorKind,
    /// Seismic sensitivity [V/m, V/(m/s) or V/(m/s²) as the kind].
    pub seismic_sensitivity: f64,
    /// Noise on the seismic channels [V RMS].
    pub seismic_noise_v: f64,
    /// Speed grid step of the precomputed response [Hz].
    pub grid_step_hz: f64,
    /// Position of keyphasor pulse 0 in sample periods, in [0, 1).
    pub t0_sample_position: f64,
    /// Noise seed.
    pub seed: u64,
}

impl Default for SignalOptions {
    fn default() -> Self {
        Self {
            rundown: RunDown {
                start_hz: 200.0,
                end_hz: 5.0,
                rate_hz_per_s: 5.0,
            },
            sample_rate_hz: 51_200.0,
            adc: Adc::ad7606(),
            probe_sensitivity: 7870.0,
            probe_gap_v: -9.0,
            probe_noise_v: 1e-3,
            seismic_kind: SensorKind::Acceleration,
            seismic_sensitivity: default_seismic_sensitivity(SensorKind::Acceleration),
            seismic_noise_v: 1e-3,
            grid_step_hz: 0.01,
            t0_sample_position: 0.5,
            seed: 1,
        }
    }
}

/// Typical field sensitivity of a seismic sensor kind: 100 mV/g
/// accelerometer (0.0102 V/(m/s²)), 20 mV/(mm/s) velocity pick-up
/// (20 V/(m/s)), or a 7.87 V/mm displacement sensor.
pub fn default_seismic_sensitivity(kind: SensorKind) -> f64 {
    match kind {
        SensorKind::Acceleration => 0.1 / super::machine::STANDARD_GRAVITY,
        SensorKind::Velocity => 20.0,
        SensorKind::Displacement => 7870.0,
    }
}

/// Synthesises the signal set of `machine` (with `effects`) and its truth run
/// directory (noise-free phasors on the speed grid).
pub fn synthesise(
    machine: &Machine,
    effects: &EffectSet,
    opts: &SignalOptions,
) -> Result<(SignalSet, RunDir), SignalsError> {
    let r = opts.rundown;
    r.validate()
        .map_err(|m| SignalsError::Request(format!("run-down: {m}")))?;
    let fs = opts.sample_rate_hz;
    if !(fs.is_finite() && fs > 0.0) {
        return Err(SignalsError::Request(format!(
            "sample rate must be finite and > 0 Hz (got {fs})"
        )));
    }
    let max_speed = r.start_hz.max(r.end_hz);
    if fs < 8.0 * max_speed {
        return Err(SignalsError::Request(format!(
            "sample rate {fs} Hz is below 8 samples per revolution at {max_speed} Hz"
        )));
    }
    let step = opts.grid_step_hz;
    if !(step.is_finite() && step > 0.0) {
        return Err(SignalsError::Request(format!(
            "grid step must be finite and > 0 Hz (got {step})"
        )));
    }
    if !(0.0..1.0).contains(&opts.t0_sample_position) {
        return Err(SignalsError::Request(format!(
            "t0 sample position must be in [0, 1) (got {})",
            opts.t0_sample_position
        )));
    }
    for (what, v) in [
        ("probe sensitivity", opts.probe_sensitivity),
        ("seismic sensitivity", opts.seismic_sensitivity),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(SignalsError::Request(format!(
                "{what} must be finite and > 0 (got {v})"
            )));
        }
    }
    for (what, v) in [
        ("probe noise", opts.probe_noise_v),
        ("seismic noise", opts.seismic_noise_v),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(SignalsError::Request(format!(
                "{what} must be finite and >= 0 V (got {v})"
            )));
        }
    }
    if !opts.probe_gap_v.is_finite() {
        return Err(SignalsError::Request(
            "probe gap voltage must be finite".into(),
        ));
    }

    // Sample count: every sample time within [−p0/fs, duration].
    let duration = r.duration_s();
    let samples = ((duration * fs + opts.t0_sample_position).floor() as u64) + 1;
    if samples.saturating_mul(machine.bearings.len() as u64 * 4) > 2_000_000_000 {
        return Err(SignalsError::Request(format!(
            "{samples} samples × {} channels is too large",
            machine.bearings.len() * 4
        )));
    }

    // Speed grid covering the run with 4 steps of margin each side.
    let lo = r.start_hz.min(r.end_hz);
    let hi = max_speed;
    let g0 = ((lo / step).floor() - 4.0).max(0.0) * step;
    let g0 = if g0 <= 0.0 { step.min(lo / 2.0) } else { g0 };
    let points = ((hi - g0) / step).ceil() + 5.0;
    if points > MAX_GRID_POINTS as f64 {
        return Err(SignalsError::Request(format!(
            "grid step {step} Hz needs {points:.3e} response solves over {g0}..{hi} Hz; at most {MAX_GRID_POINTS} are made: use a step of at least {:.3e} Hz",
            (hi - g0) / (MAX_GRID_POINTS as f64 - 5.0)
        )));
    }
    let n_grid = points as usize;
    let grid: Vec<f64> = (0..n_grid).map(|i| g0 + i as f64 * step).collect();
    let response = unbalance_response(machine, &grid, effects)?;
    let truth = response.to_run_dir(None)?;
    let spline =
        PhasorSpline::from_measurements(&truth.measurements).map_err(SignalsError::Request)?;

    // Measure the interpolation error where the run is: at the midpoint of
    // every grid interval the run overlaps and at CHECK_SPEEDS speeds spread
    // over the run (a grid coarser than the run has no midpoint inside it).
    let mut checks: Vec<f64> = grid
        .windows(2)
        .filter(|w| w[1] >= lo && w[0] <= hi)
        .map(|w| 0.5 * (w[0] + w[1]))
        .collect();
    checks.extend((0..=CHECK_SPEEDS).map(|i| lo + (hi - lo) * i as f64 / CHECK_SPEEDS as f64));
    checks.sort_by(f64::total_cmp);
    checks.dedup();
    let check_rows = unbalance_response(machine, &checks, effects)?.measurements();

    // Channels: per bearing rel_y, rel_z (probes), ped_y, ped_z (seismic).
    let mut channels = Vec::new();
    for (bi, b) in machine.bearings.iter().enumerate() {
        for q in ChannelQuantity::ALL {
            let probe = matches!(q, ChannelQuantity::RelY | ChannelQuantity::RelZ);
            let mut max_x: f64 = 0.0;
            for m in truth
                .measurements
                .iter()
                .chain(&check_rows)
                .filter(|m| m.bearing == b.name)
            {
                if m.speed_hz >= lo && m.speed_hz <= hi {
                    max_x = max_x.max(q.of(m).norm());
                }
            }
            let mut err: f64 = 0.0;
            for m in check_rows.iter().filter(|m| m.bearing == b.name) {
                if let Some(v) = spline.at(&b.name, q, m.speed_hz) {
                    err = err.max((v - q.of(m)).norm());
                }
            }
            channels.push(Channel {
                name: format!("{}_{}", b.name, q.name()),
                bearing: b.name.clone(),
                bearing_index: bi,
                quantity: q,
                kind: if probe {
                    SensorKind::Displacement
                } else {
                    opts.seismic_kind
                },
                sensitivity: if probe {
                    opts.probe_sensitivity
                } else {
                    opts.seismic_sensitivity
                },
                offset_v: if probe { opts.probe_gap_v } else { 0.0 },
                noise_v_rms: if probe {
                    opts.probe_noise_v
                } else {
                    opts.seismic_noise_v
                },
                clipped_samples: 0,
                interpolation_error_m: err,
                interpolation_error_rel: if max_x > 0.0 { err / max_x } else { 0.0 },
            });
        }
    }
    if let Some(c) = channels.iter().find(|c| {
        c.interpolation_error_rel.is_nan() || c.interpolation_error_rel > MAX_INTERPOLATION_ERROR
    }) {
        return Err(SignalsError::Request(format!(
            "grid step {step} Hz cannot represent the response: channel {} is interpolated with an error of {:.2e} of its peak (measured at {} speeds over the run; at most {MAX_INTERPOLATION_ERROR} accepted): use a smaller --grid-step (the error falls as step⁴)",
            c.name,
            c.interpolation_error_rel,
            checks.len()
        )));
    }
    let n = channels.len();
    let chan_splines: Vec<&ComplexSpline> = channels
        .iter()
        .map(|c| {
            spline
                .get(&c.bearing, c.quantity)
                .ok_or_else(|| SignalsError::Request(format!("no response for channel {}", c.name)))
        })
        .collect::<Result<_, _>>()?;

    let mut rng = StdRng::seed_from_u64(opts.seed);
    let normal = Normal::new(0.0, 1.0)
        .map_err(|e| SignalsError::Request(format!("noise distribution: {e}")))?;
    let mut codes = vec![0i16; samples as usize * n];
    let omega_dot = TAU * r.slope();
    for k in 0..samples as usize {
        let t = (k as f64 - opts.t0_sample_position) / fs;
        let f = r.speed_hz(t);
        let omega = TAU * f;
        let rot = C64::from_polar(1.0, r.angle_rad(t));
        for (ci, c) in channels.iter_mut().enumerate() {
            let (x, dxdf, d2xdf2) = chan_splines[ci].eval(f);
            // Derivatives with respect to Ω = 2πf.
            let dx = dxdf / TAU;
            let d2x = d2xdf2 / (TAU * TAU);
            let i = C64::i();
            let phasor = match c.kind {
                SensorKind::Displacement => x,
                SensorKind::Velocity => i * omega * x + dx * omega_dot,
                SensorKind::Acceleration => {
                    i * omega_dot * x - x * (omega * omega)
                        + i * (2.0 * omega * omega_dot) * dx
                        + d2x * (omega_dot * omega_dot)
                }
            };
            let value = (phasor * rot).re;
            let noise = if c.noise_v_rms > 0.0 {
                c.noise_v_rms * normal.sample(&mut rng)
            } else {
                0.0
            };
            let volts = c.offset_v + c.sensitivity * value + noise;
            let (code, clipped) = opts.adc.quantise(volts);
            if clipped {
                c.clipped_samples += 1;
            }
            codes[k * n + ci] = code;
        }
    }

    let mut keyphasor = Vec::new();
    let pulses = r.revolutions();
    for j in 0..=pulses {
        let p = r.pulse_time(j) * fs + opts.t0_sample_position;
        if p < samples as f64 {
            keyphasor.push(p);
        }
    }
    let max_rel_error = channels
        .iter()
        .map(|c| c.interpolation_error_rel)
        .fold(0.0, f64::max);
    let header = SignalHeader {
        format: FORMAT_NAME.into(),
        version: FORMAT_VERSION,
        machine: machine.name.clone(),
        sample_rate_hz: fs,
        samples,
        adc: opts.adc,
        rundown: r,
        t0_sample_position: opts.t0_sample_position,
        keyphasor_pulses: keyphasor.len() as u64,
        channels,
        interpolation: Interpolation {
            method: InterpolationMethod::NaturalCubicSpline,
            grid_step_hz: step,
            max_rel_error,
        },
        seed: opts.seed,
        effects: truth
            .truth
            .as_ref()
            .map(|t| t.effects.clone())
            .unwrap_or_default(),
    };
    Ok((
        SignalSet {
            header,
            codes,
            keyphasor,
        },
        truth,
    ))
}

/// [`synthesise`] and write the signal set with its truth to `dir`.
pub fn synthesise_to(
    machine: &Machine,
    effects: &EffectSet,
    opts: &SignalOptions,
    dir: &Path,
) -> Result<SignalSet, SignalsError> {
    let (set, truth) = synthesise(machine, effects, opts)?;
    set.write(dir)?;
    write_truth(dir, &truth)?;
    Ok(set)
}

/// Command-line arguments of `plinth signals`.
#[derive(clap::Args, Debug)]
pub struct SignalsArgs {
    /// Machine file (TOML, SI units; see the `plinth::sim::machine` docs).
    pub machine: PathBuf,
    /// Signal-set directory to write (created if needed).
    #[arg(long)]
    pub out: PathBuf,
    /// Speed ramp START:END:RATE [Hz:Hz:Hz/s] (linear; END < START is a run-down).
    #[arg(long, default_value = "200:5:5")]
    pub rundown: String,
    /// Sample rate per channel [Hz].
    #[arg(long, default_value_t = 51_200.0)]
    pub rate: f64,
    /// Proximity probe sensitivity [V/mm].
    #[arg(long, default_value_t = 7.87)]
    pub probe_v_per_mm: f64,
    /// Proximity probe gap voltage [V].
    #[arg(long, default_value_t = -9.0, allow_hyphen_values = true)]
    pub probe_gap: f64,
    /// Probe channel noise [mV RMS].
    #[arg(long, default_value_t = 1.0)]
    pub probe_noise_mv: f64,
    /// Transducer on the pedestals.
    #[arg(long, value_parser = parse_sensor_kind, default_value = "acceleration")]
    pub seismic: SensorKind,
    /// Seismic sensitivity [V/(m/s²), V/(m/s) or V/m]; default by kind:
    /// 100 mV/g, 20 mV/(mm/s), 7.87 V/mm.
    #[arg(long)]
    pub seismic_sensitivity: Option<f64>,
    /// Seismic channel noise [mV RMS].
    #[arg(long, default_value_t = 1.0)]
    pub seismic_noise_mv: f64,
    /// ADC resolution [bits].
    #[arg(long, default_value_t = 16)]
    pub adc_bits: u32,
    /// ADC full scale [±V].
    #[arg(long, default_value_t = 10.0)]
    pub adc_range: f64,
    /// Speed step of the precomputed response [Hz].
    #[arg(long, default_value_t = 0.01)]
    pub grid_step: f64,
    /// Noise seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Effect to inject: NAME[:BEARING][=SIZE] (repeatable).
    #[arg(long = "effect")]
    pub effects: Vec<String>,
}

/// Runs `plinth signals`.
pub fn signals(args: &SignalsArgs) -> anyhow::Result<()> {
    let machine = Machine::from_toml_path(&args.machine)?;
    let mut effects = EffectSet::none();
    for e in &args.effects {
        let req: EffectRequest = e.parse().map_err(anyhow::Error::msg)?;
        effects.requests.push(req);
    }
    let opts = SignalOptions {
        rundown: RunDown::parse(&args.rundown)?,
        sample_rate_hz: args.rate,
        adc: Adc::new(args.adc_bits, args.adc_range)?,
        probe_sensitivity: args.probe_v_per_mm * 1e3,
        probe_gap_v: args.probe_gap,
        probe_noise_v: args.probe_noise_mv * 1e-3,
        seismic_kind: args.seismic,
        seismic_sensitivity: args
            .seismic_sensitivity
            .unwrap_or_else(|| default_seismic_sensitivity(args.seismic)),
        seismic_noise_v: args.seismic_noise_mv * 1e-3,
        grid_step_hz: args.grid_step,
        t0_sample_position: 0.5,
        seed: args.seed,
    };
    let set = synthesise_to(&machine, &effects, &opts, &args.out)
        .with_context(|| format!("making signals of {}", args.machine.display()))?;
    let h = &set.header;
    println!(
        "{}: {} samples x {} channels at {} Hz ({:.1} s), {} keyphasor pulses -> {}",
        h.machine,
        h.samples,
        h.channels.len(),
        h.sample_rate_hz,
        h.samples as f64 / h.sample_rate_hz,
        h.keyphasor_pulses,
        args.out.display()
    );
    println!(
        "response interpolation: {} Hz grid, largest error {:.2e} of channel peak",
        h.interpolation.grid_step_hz, h.interpolation.max_rel_error
    );
    for c in h.channels.iter().filter(|c| c.clipped_samples > 0) {
        eprintln!(
            "warning: {}: {} samples clipped at ±{} V",
            c.name, c.clipped_samples, h.adc.full_scale_v
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pulses_are_at_whole_revolutions() {
        let r = RunDown {
            start_hz: 200.0,
            end_hz: 5.0,
            rate_hz_per_s: 5.0,
        };
        for j in [0u64, 1, 10, 1000, r.revolutions()] {
            let t = r.pulse_time(j);
            assert!((r.angle_rad(t) / TAU - j as f64).abs() < 1e-9, "pulse {j}");
        }
        // Total revolutions: mean speed × duration = 102.5 Hz × 39 s.
        assert_eq!(r.revolutions(), 3997);
        assert!(r.pulse_time(r.revolutions()) <= r.duration_s());
    }

    #[test]
    fn spline_is_exact_for_cubics_inside_and_has_derivatives() {
        // A natural spline reproduces a linear function exactly.
        let x: Vec<f64> = (0..20).map(|i| i as f64 * 0.5).collect();
        let y: Vec<C64> = x.iter().map(|&v| C64::new(2.0 * v + 1.0, -v)).collect();
        let s = ComplexSpline::new(x, y).unwrap();
        let (v, d, dd) = s.eval(3.3);
        assert!((v - C64::new(7.6, -3.3)).norm() < 1e-12);
        assert!((d - C64::new(2.0, -1.0)).norm() < 1e-12);
        assert!(dd.norm() < 1e-12);
        // A smooth function: error O(h⁴) away from the ends.
        let x: Vec<f64> = (0..200).map(|i| i as f64 * 0.05).collect();
        let y: Vec<C64> = x.iter().map(|&v| C64::from_polar(1.0, v)).collect();
        let s = ComplexSpline::new(x, y).unwrap();
        let (v, d, _) = s.eval(5.0123);
        assert!((v - C64::from_polar(1.0, 5.0123)).norm() < 1e-6);
        assert!((d - C64::i() * C64::from_polar(1.0, 5.0123)).norm() < 1e-4);
    }

    #[test]
    fn adc_quantises_and_clips() {
        let adc = Adc::ad7606();
        assert_eq!(adc.quantise(0.0), (0, false));
        assert_eq!(adc.quantise(10.0 / 32768.0 * 3.4), (3, false));
        assert_eq!(adc.quantise(10.0), (32767, true));
        assert_eq!(adc.quantise(-10.0), (-32768, false));
        assert_eq!(adc.quantise(-11.0), (-32768, true));
        assert!(Adc::new(17, 10.0).is_err());
    }

    #[test]
    fn rundown_parses_and_rejects() {
        let r = RunDown::parse("200:5:5").unwrap();
        assert_eq!(r.slope(), -5.0);
        assert_eq!(r.duration_s(), 39.0);
        assert!(RunDown::parse("200:5").is_err());
        assert!(RunDown::parse("200:0:5").is_err());
        assert!(RunDown::parse("200:5:-1").is_err());
        assert!(RunDown::parse("5:5:1").is_err());
    }
}
