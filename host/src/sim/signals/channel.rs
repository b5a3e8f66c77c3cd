//! The channel and ADC model: what a channel measures, its transducer
//! kind and sensitivity, gap voltage and noise, and the converter that
//! quantises and clips it.

use super::*;

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
    /// Largest |sensitivity × reading| over the run [V]: the 1X signal's
    /// peak before noise and offset (written by the synthesiser).
    #[serde(default)]
    pub signal_peak_v: f64,
    /// Largest interpolation error of this channel's displacement phasor
    /// over the run [m] (measured at grid midpoints).
    #[serde(default)]
    pub interpolation_error_m: f64,
    /// The error of what the channel is written from, relative to its peak
    /// over the run [-]: the displacement phasor's for displacement
    /// channels; the sensed velocity or acceleration phasor's (value and
    /// speed derivatives, [`super::derivative`]) for the others.
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
