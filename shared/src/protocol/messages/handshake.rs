//! Opening a session: `Hello`, its answers, and what the box says of itself.

use super::*;

/// Host → box: opens a session.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Hello {
    /// The host's [`PROTOCOL_VERSION`] (frozen: first field).
    pub protocol_version: u16,
    /// A number the host chose for this session; echoed in the answer so that
    /// the host can tell the answer to this `Hello` from a stale one.
    pub host_nonce: u32,
}

/// Box → host: the session is open; what the box is and can do.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HelloAck {
    /// The box's [`PROTOCOL_VERSION`] (frozen: first field), equal to the host's.
    pub protocol_version: u16,
    /// The `host_nonce` of the `Hello` this answers.
    pub host_nonce: u32,
    /// Version of the firmware image.
    pub firmware_version: FirmwareVersion,
    /// Limits of this box.
    pub capabilities: Capabilities,
    /// Sample clock, previous reset, faults so far.
    pub health: BoxHealth,
}

/// Box → host: the `Hello` spoke another protocol version; nothing but a new
/// `Hello` is accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct VersionMismatch {
    /// The box's [`PROTOCOL_VERSION`] (frozen: first field).
    pub device_protocol_version: u16,
    /// The version the host's `Hello` carried.
    pub host_protocol_version: u16,
    /// The `host_nonce` of the refused `Hello`.
    pub host_nonce: u32,
}

/// Semantic version of the firmware image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FirmwareVersion {
    /// Incompatible changes.
    pub major: u16,
    /// Compatible additions.
    pub minor: u16,
    /// Fixes.
    pub patch: u16,
}

/// What one box can do; the host must stay within these limits.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Capabilities {
    /// ADC channels available (≤ [`MAX_CHANNELS`]).
    pub max_channels: u8,
    /// Bearings (= pedestals) the box can process (≤ [`MAX_BEARINGS`]).
    pub max_bearings: u8,
    /// Rows each bearing's coefficient table can hold.
    pub bearing_table_capacity: u16,
    /// ADC sample rate per channel \[Hz].
    pub sample_rate_hz: f32,
    /// ADC step: an ADC code c stands for the voltage c · this \[V].
    pub adc_volts_per_code: f32,
}
