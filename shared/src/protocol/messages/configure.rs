//! What the host configures: channels, averaging, the recursive estimate,
//! the bearing table.

use super::*;

/// How a channel's transducer measures vibration: the extractor's kind
/// (one definition; encoded as its variant index, Displacement = 0,
/// Velocity = 1, Acceleration = 2).
pub use crate::extractor::SensorKind;

/// Which displacement a channel measures at its bearing (formats.md: `rel` is
/// rotor minus pedestal, `ped` is absolute pedestal; y vertical, z horizontal).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Quantity {
    /// Rotor relative to pedestal, vertical.
    RelY,
    /// Rotor relative to pedestal, horizontal.
    RelZ,
    /// Absolute pedestal, vertical.
    PedY,
    /// Absolute pedestal, horizontal.
    PedZ,
}

/// Configuration of one ADC channel.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelConfig {
    /// ADC channel index (0-based, < [`Capabilities::max_channels`]).
    pub channel: u8,
    /// Transducer type, which fixes the unit of `sensitivity`.
    pub kind: SensorKind,
    /// Transducer output per unit of measured motion: V/m, V/(m/s) or
    /// V/(m/s²) according to `kind`.
    pub sensitivity: f32,
    /// Bearing index (0-based, < [`Capabilities::max_bearings`]).
    pub bearing: u8,
    /// What the channel measures at that bearing.
    pub quantity: Quantity,
}

/// Host → box: the complete channel configuration (replaces the previous one).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChannelSet {
    /// The configured channels; channels not listed are unused.
    pub channels: heapless::Vec<ChannelConfig, MAX_CHANNELS>,
}

/// Host → box: revolution averaging of the phasor extractor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Averaging {
    /// Revolutions averaged into one phasor frame (≥ 1).
    pub revolutions_per_phasor: u16,
}

/// Host → box: settings of the per-pedestal recursive least squares.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RlsSettings {
    /// Forgetting factor λ per speed (all four equations of a phasor frame
    /// alike), in (0, 1]; 1 = never forget.
    pub forgetting_factor: f32,
    /// Stiffness column scale [N/m].
    pub scale_k: f32,
    /// Mass column scale \[kg].
    pub scale_m: f32,
    /// Damping column scale [N·s/m].
    pub scale_c: f32,
}

impl RlsSettings {
    /// The column scales as the estimator takes them.
    pub fn parameter_scale(&self) -> ParameterScale<f32> {
        ParameterScale {
            k: self.scale_k,
            m: self.scale_m,
            c: self.scale_c,
        }
    }

    /// Settings from a forgetting factor λ and column scales.
    pub fn new(forgetting_factor: f32, scale: ParameterScale<f32>) -> Self {
        Self {
            forgetting_factor,
            scale_k: scale.k,
            scale_m: scale.m,
            scale_c: scale.c,
        }
    }
}

/// One row of a bearing table: the coefficients at one speed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BearingTableRow {
    /// Rotor speed \[Hz]; rows must increase in speed across the whole table.
    pub speed_hz: f32,
    /// Coefficients at that speed: k [N/m], c [N·s/m].
    pub coefficients: BearingCoefficients<f32>,
}

/// Host → box: consecutive rows `first_row ..` of one bearing's table.
///
/// A table of `total_rows` rows is sent as chunks in order; a chunk with
/// `first_row == 0` starts the table afresh, and the table is complete (and
/// used) once `first_row + rows.len() == total_rows`. The box refuses a chunk
/// that does not continue the table it is building.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BearingTableChunk {
    /// Bearing index (0-based).
    pub bearing: u8,
    /// Number of rows in the whole table.
    pub total_rows: u16,
    /// Index in the table of `rows[0]`.
    pub first_row: u16,
    /// The rows of this chunk (at least one).
    pub rows: heapless::Vec<BearingTableRow, MAX_TABLE_ROWS_PER_CHUNK>,
}

impl BearingTableChunk {
    /// Splits a whole table for `bearing` into chunks of at most
    /// [`MAX_TABLE_ROWS_PER_CHUNK`] rows, in sending order (nothing for an
    /// empty table). Fails when the table has more than `u16::MAX` rows.
    pub fn split(
        bearing: u8,
        table: &[BearingTableRow],
    ) -> Result<impl Iterator<Item = Self> + '_, TableTooLong> {
        let total_rows =
            u16::try_from(table.len()).map_err(|_| TableTooLong { rows: table.len() })?;
        Ok(table
            .chunks(MAX_TABLE_ROWS_PER_CHUNK)
            .enumerate()
            .map(move |(i, rows)| {
                let mut v = heapless::Vec::new();
                for r in rows {
                    // Cannot fail: `chunks` yields at most the capacity.
                    let _ = v.push(*r);
                }
                Self {
                    bearing,
                    total_rows,
                    // i · MAX_TABLE_ROWS_PER_CHUNK < total_rows ≤ u16::MAX.
                    first_row: (i * MAX_TABLE_ROWS_PER_CHUNK) as u16,
                    rows: v,
                }
            }))
    }

    /// True when this chunk ends the table.
    pub fn is_last(&self) -> bool {
        self.first_row as usize + self.rows.len() == self.total_rows as usize
    }
}

/// A bearing table too long to describe in [`BearingTableChunk`]s.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TableTooLong {
    /// Rows in the table.
    pub rows: usize,
}
