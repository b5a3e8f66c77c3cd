//! The configuration as the box receives it: the check against what the
//! box said it can do, and the configuration commands in sending order.

use super::{BearingTables, Quantity, StreamConfig};
use anyhow::{bail, Result};
use plinth_shared::protocol::{
    self, BearingTableChunk, BearingTableRow, Capabilities, ChannelConfig, ChannelSet, HostMessage,
};

impl StreamConfig {
    /// Checks the configuration against what the box said it can do.
    pub fn check_capabilities(&self, caps: &Capabilities, tables: &BearingTables) -> Result<()> {
        if let Some(ch) = self.channels.iter().find(|c| c.adc >= caps.max_channels) {
            bail!(
                "ADC channel {} is configured but the box has only {} channels (0..={})",
                ch.adc,
                caps.max_channels,
                caps.max_channels.saturating_sub(1)
            );
        }
        if self.bearings.len() > caps.max_bearings as usize {
            bail!(
                "{} bearings are configured but the box processes at most {}",
                self.bearings.len(),
                caps.max_bearings
            );
        }
        for b in &self.bearings {
            let n = tables.rows_of(b).len();
            if n > caps.bearing_table_capacity as usize {
                bail!(
                    "bearing {b:?} has {n} rows in {} but the box holds at most {} per bearing",
                    self.bearings_csv.display(),
                    caps.bearing_table_capacity
                );
            }
        }
        Ok(())
    }

    /// The configuration commands for the box, in sending order: channels,
    /// averaging, RLS settings, then every bearing's table in chunks.
    pub fn device_commands(&self, tables: &BearingTables) -> Result<Vec<HostMessage>> {
        let mut set = ChannelSet {
            channels: Default::default(),
        };
        for ch in &self.channels {
            let bearing = self.bearing_index(&ch.bearing).unwrap_or(0);
            let entry = ChannelConfig {
                channel: ch.adc,
                kind: ch.sensor,
                sensitivity: ch.sensitivity as f32,
                bearing: bearing as u8,
                quantity: match ch.quantity {
                    Quantity::RelY => protocol::Quantity::RelY,
                    Quantity::RelZ => protocol::Quantity::RelZ,
                    Quantity::PedY => protocol::Quantity::PedY,
                    Quantity::PedZ => protocol::Quantity::PedZ,
                },
            };
            if set.channels.push(entry).is_err() {
                bail!("more than {} channels configured", protocol::MAX_CHANNELS);
            }
        }
        let mut out = vec![
            HostMessage::ConfigureChannels(set),
            HostMessage::ConfigureAveraging(protocol::Averaging {
                revolutions_per_phasor: self.averaging.revolutions,
            }),
            HostMessage::ConfigureRls(protocol::RlsSettings {
                forgetting_factor: self.rls.forgetting_factor as f32,
                scale_k: self.rls.k_scale as f32,
                scale_m: self.rls.m_scale as f32,
                scale_c: self.rls.c_scale as f32,
            }),
        ];
        for (index, b) in self.bearings.iter().enumerate() {
            let rows: Vec<BearingTableRow> = tables
                .rows_of(b)
                .iter()
                .map(|r| BearingTableRow {
                    speed_hz: r.speed_hz as f32,
                    coefficients: r.coefficients.cast::<f32>(),
                })
                .collect();
            // f32 rounding must not merge two listed speeds.
            if let Some(w) = rows.windows(2).find(|w| w[1].speed_hz <= w[0].speed_hz) {
                bail!(
                    "{}: bearing {b:?} lists speeds {} Hz and {} Hz, which are not distinct in single precision",
                    self.bearings_csv.display(),
                    w[0].speed_hz,
                    w[1].speed_hz
                );
            }
            let chunks = BearingTableChunk::split(index as u8, &rows)
                .map_err(|e| anyhow::anyhow!("bearing {b:?}: {} table rows is too many", e.rows))?;
            out.extend(chunks.map(HostMessage::BearingTable));
        }
        Ok(out)
    }
}
