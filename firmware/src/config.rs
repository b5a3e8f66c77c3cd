//! The acquisition configuration the host sends before `Start`: channel map
//! and sensors, revolution averaging, RLS settings and the bearing tables.
//! Every command is validated here and refused with the protocol's reason.

use crate::source::{ChannelLayout, CHANNELS};
use plinth_shared::bearing::{BearingTable, BearingTableError};
use plinth_shared::extractor::Sensor;
use plinth_shared::protocol::{
    Averaging, BearingTableChunk, ChannelConfig, ChannelSet, NackReason, Quantity, RlsSettings,
    MAX_BEARINGS,
};
use plinth_shared::regression::ParameterScale;

/// Rows each bearing's coefficient table holds.
pub const TABLE_ROWS: usize = 48;

/// Progress of one bearing's table download.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TableState {
    /// No chunk received.
    Empty,
    /// Chunks received up to (not including) row `next` of `total`.
    Building {
        /// Rows in the whole table.
        total: u16,
        /// Next row expected.
        next: u16,
    },
    /// The whole table is in.
    Complete,
}

/// The configuration of a session (kept across Stop/Start).
#[derive(Clone, Debug)]
pub struct Configuration {
    /// Configured channels, in the order the host sent them.
    pub channels: heapless::Vec<ChannelConfig, CHANNELS>,
    /// Revolutions averaged into one phasor frame (≥ 1).
    pub revolutions_per_phasor: u16,
    /// RLS forgetting factor λ in (0, 1] and column scales.
    pub rls: RlsSettings,
    /// Bearing coefficient tables, speed [Hz] → k [N/m], c [N·s/m].
    pub tables: [BearingTable<TABLE_ROWS, f32>; MAX_BEARINGS],
    /// Download progress of each table.
    pub table_state: [TableState; MAX_BEARINGS],
}

impl Default for Configuration {
    fn default() -> Self {
        Self::new()
    }
}

/// True when `x` is finite and strictly positive.
fn positive(x: f32) -> bool {
    x.is_finite() && x > 0.0
}

impl Configuration {
    /// No channels, one revolution per phasor, λ = 1 and default scales.
    pub fn new() -> Self {
        Self {
            channels: heapless::Vec::new(),
            revolutions_per_phasor: 1,
            rls: RlsSettings::new(1.0, ParameterScale::default()),
            tables: core::array::from_fn(|_| BearingTable::new()),
            table_state: [TableState::Empty; MAX_BEARINGS],
        }
    }

    /// Replaces the channel set after checking every entry: ADC channel
    /// below [`CHANNELS`] and listed once, bearing below [`MAX_BEARINGS`],
    /// each (bearing, quantity) measured once, sensitivity finite and > 0.
    pub fn set_channels(&mut self, set: &ChannelSet) -> Result<(), NackReason> {
        if set.channels.len() > CHANNELS {
            return Err(NackReason::BadChannel);
        }
        for (i, c) in set.channels.iter().enumerate() {
            if c.channel as usize >= CHANNELS {
                return Err(NackReason::BadChannel);
            }
            if c.bearing as usize >= MAX_BEARINGS {
                return Err(NackReason::BadBearing);
            }
            if !positive(c.sensitivity) {
                return Err(NackReason::BadValue);
            }
            let earlier = &set.channels[..i];
            if earlier.iter().any(|e| {
                e.channel == c.channel || (e.bearing == c.bearing && e.quantity == c.quantity)
            }) {
                return Err(NackReason::BadChannel);
            }
        }
        self.channels.clear();
        for c in &set.channels {
            // Cannot fail: the length was checked above.
            let _ = self.channels.push(*c);
        }
        Ok(())
    }

    /// Sets the revolution averaging (≥ 1).
    pub fn set_averaging(&mut self, a: &Averaging) -> Result<(), NackReason> {
        if a.revolutions_per_phasor == 0 {
            return Err(NackReason::BadValue);
        }
        self.revolutions_per_phasor = a.revolutions_per_phasor;
        Ok(())
    }

    /// Sets the RLS settings: λ in (0, 1], scales finite and > 0.
    pub fn set_rls(&mut self, s: &RlsSettings) -> Result<(), NackReason> {
        let lambda_ok = s.forgetting_factor > 0.0 && s.forgetting_factor <= 1.0;
        if !lambda_ok || !positive(s.scale_k) || !positive(s.scale_m) || !positive(s.scale_c) {
            return Err(NackReason::BadValue);
        }
        self.rls = *s;
        Ok(())
    }

    /// Adds one chunk of a bearing table; a chunk with `first_row == 0`
    /// starts the table afresh, any other must continue it.
    pub fn add_table_chunk(&mut self, chunk: &BearingTableChunk) -> Result<(), NackReason> {
        let b = chunk.bearing as usize;
        if b >= MAX_BEARINGS {
            return Err(NackReason::BadBearing);
        }
        if chunk.rows.is_empty() || chunk.total_rows == 0 {
            return Err(NackReason::BadValue);
        }
        if chunk.total_rows as usize > TABLE_ROWS {
            return Err(NackReason::TableFull);
        }
        let end = chunk.first_row as usize + chunk.rows.len();
        if end > chunk.total_rows as usize {
            return Err(NackReason::TableOutOfOrder);
        }
        if chunk.first_row == 0 {
            self.tables[b].clear();
            self.table_state[b] = TableState::Building {
                total: chunk.total_rows,
                next: 0,
            };
        }
        match self.table_state[b] {
            TableState::Building { total, next }
                if total == chunk.total_rows && next == chunk.first_row => {}
            _ => return Err(NackReason::TableOutOfOrder),
        }
        for row in &chunk.rows {
            let finite = row.coefficients.k.iter().flatten().all(|x| x.is_finite())
                && row.coefficients.c.iter().flatten().all(|x| x.is_finite());
            let refused = if !finite {
                Some(NackReason::BadValue)
            } else {
                match self.tables[b].push(row.speed_hz, row.coefficients) {
                    Ok(()) => None,
                    Err(BearingTableError::Full) => Some(NackReason::TableFull),
                    Err(_) => Some(NackReason::TableNotIncreasing),
                }
            };
            if let Some(reason) = refused {
                // A broken table is never used: the host starts it over.
                self.tables[b].clear();
                self.table_state[b] = TableState::Empty;
                return Err(reason);
            }
        }
        self.table_state[b] = if end == chunk.total_rows as usize {
            TableState::Complete
        } else {
            TableState::Building {
                total: chunk.total_rows,
                next: end as u16,
            }
        };
        Ok(())
    }

    /// Whether acquisition can start: at least one channel, and a complete
    /// bearing table for every bearing that has a channel.
    pub fn ready(&self) -> bool {
        !self.channels.is_empty()
            && self
                .channels
                .iter()
                .all(|c| self.table_state[c.bearing as usize] == TableState::Complete)
    }

    /// The order of replayed values: ADC channel of each configured channel.
    pub fn layout(&self) -> ChannelLayout {
        let mut layout = ChannelLayout::default();
        for c in &self.channels {
            let _ = layout.adc_channel.push(c.channel);
        }
        layout
    }

    /// The transducer on every ADC channel; unconfigured channels get a
    /// 1 V/m displacement placeholder whose phasors are never reported.
    pub fn sensors(&self) -> [Sensor; CHANNELS] {
        let mut sensors = [Sensor::displacement(1.0); CHANNELS];
        for c in &self.channels {
            sensors[c.channel as usize % CHANNELS] = Sensor {
                kind: c.kind,
                sensitivity: c.sensitivity,
            };
        }
        sensors
    }

    /// For each bearing, the ADC channel measuring rel y, rel z, ped y, ped z.
    pub fn bearing_channels(&self) -> [[Option<u8>; 4]; MAX_BEARINGS] {
        let mut map = [[None; 4]; MAX_BEARINGS];
        for c in &self.channels {
            let q = match c.quantity {
                Quantity::RelY => 0,
                Quantity::RelZ => 1,
                Quantity::PedY => 2,
                Quantity::PedZ => 3,
            };
            map[c.bearing as usize % MAX_BEARINGS][q] = Some(c.channel);
        }
        map
    }
}
