//! What the box streams: 1X phasors, pedestal estimates, status.

use super::*;

/// A 1X phasor as a real/imaginary pair on the wire.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WirePhasor {
    /// Real part (unit of the quantity, m for displacements).
    pub re: f32,
    /// Imaginary part (same unit).
    pub im: f32,
}

impl From<Complex<f32>> for WirePhasor {
    fn from(c: Complex<f32>) -> Self {
        Self { re: c.re, im: c.im }
    }
}

impl From<WirePhasor> for Complex<f32> {
    fn from(p: WirePhasor) -> Self {
        Complex::new(p.re, p.im)
    }
}

/// The 1X phasors at one bearing, (y, z) each, in m (formats.md convention:
/// q(t) = Re{Q·e^{iΩt}}, t = 0 at the keyphasor).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BearingPhasors {
    /// Bearing index (0-based).
    pub bearing: u8,
    /// Rotor relative to pedestal, (y, z) \[m].
    pub rel: [WirePhasor; 2],
    /// Absolute pedestal, (y, z) \[m].
    pub ped: [WirePhasor; 2],
    /// Noise of each `rel` phasor, (y, z): sqrt(E|n|²) of its complex noise
    /// \[m] (formats.md's `rel_y_sd`, `rel_z_sd`); NaN where not measured.
    pub rel_sd: [f32; 2],
    /// Noise of each `ped` phasor, (y, z) \[m] (`ped_y_sd`, `ped_z_sd`).
    pub ped_sd: [f32; 2],
}

/// Box → host: one revolution-average of 1X phasors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhasorFrame {
    /// Index since `Start` (wrapping) of the first revolution in the average.
    pub revolution: u32,
    /// Revolutions averaged.
    pub revolutions: u16,
    /// Mean rotor speed over the averaged revolutions \[Hz].
    pub speed_hz: f32,
    /// Phasors per configured bearing.
    pub bearings: heapless::Vec<BearingPhasors, MAX_BEARINGS>,
}

/// One pedestal's estimate on the wire: θ = (k_y [N/m], k_z [N/m], m \[kg],
/// c_y [N·s/m], c_z [N·s/m]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PedestalEstimateEntry {
    /// Bearing index (0-based) of the pedestal.
    pub bearing: u8,
    /// Parameter values in θ order.
    pub theta: [f32; PARAMETERS],
    /// Standard errors in θ order, same units; NaN when not yet estimable.
    pub std_err: [f32; PARAMETERS],
    /// Number of equations folded in (effective, with forgetting).
    pub equations: f32,
    /// Σ(whitened residual)²/(n − 5): 1 when the residuals are as large as
    /// the phasors' noise says (dimensionless); NaN while n ≤ 5.
    pub reduced_chi_square: f32,
    /// Equations scaled down because their squares would overflow f32.
    pub rescaled: u32,
    /// Equations rejected as not finite.
    pub rejected: u32,
}

impl PedestalEstimateEntry {
    /// The entry for the pedestal at `bearing`.
    pub fn new(bearing: u8, e: &PedestalEstimate<f32>) -> Self {
        Self {
            bearing,
            theta: e.theta,
            std_err: e.std_err,
            equations: e.equations,
            reduced_chi_square: e.reduced_chi_square,
            rescaled: e.rescaled,
            rejected: e.rejected,
        }
    }

    /// The estimate in the estimator's own type.
    pub fn estimate(&self) -> PedestalEstimate<f32> {
        PedestalEstimate {
            theta: self.theta,
            std_err: self.std_err,
            equations: self.equations,
            reduced_chi_square: self.reduced_chi_square,
            rescaled: self.rescaled,
            rejected: self.rejected,
        }
    }
}

/// Box → host: the current estimates of every pedestal that has one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EstimateFrame {
    /// Index since `Start` of the last revolution folded in.
    pub revolution: u32,
    /// Per pedestal.
    pub pedestals: heapless::Vec<PedestalEstimateEntry, MAX_BEARINGS>,
}

/// What the box is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DeviceState {
    /// No session: waiting for a `Hello` with a matching version.
    AwaitingHello,
    /// Session open, stopped: configuration accepted.
    Idle,
    /// Acquiring and processing.
    Running,
}

/// The box's health counters, all since the session opened (saturating).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct DeviceCounters {
    /// ADC DMA buffer overruns (samples lost before processing).
    pub overruns: u32,
    /// Blocks or frames dropped because a queue was full.
    pub queue_full_drops: u32,
    /// Keyphasor pulses missing (a revolution far longer than expected).
    pub keyphasor_missing: u32,
    /// Extra keyphasor pulses (a revolution far shorter than expected).
    pub keyphasor_extra: u32,
    /// Frames sent to the host.
    pub frames_sent: u32,
    /// Commands answered with a `Nack`.
    pub commands_rejected: u32,
    /// Samples at the ADC's limits, per configured channel (index = channel).
    pub adc_saturation: heapless::Vec<u32, MAX_CHANNELS>,
}

/// Box → host: periodic health report.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct StatusFrame {
    /// Current state.
    pub state: DeviceState,
    /// Time since boot \[ms] (wrapping).
    pub uptime_ms: u32,
    /// Processing counters.
    pub counters: DeviceCounters,
    /// The box's receive-side link statistics (frames from the host).
    pub link: LinkStats,
    /// Sample clock, previous reset, acquisition faults.
    pub health: BoxHealth,
}
