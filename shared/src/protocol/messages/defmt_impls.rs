//! `defmt::Format` for the types holding a `heapless::Vec` (heapless 0.8
//! only supports defmt 0.3, so these are written out).
use super::*;

impl defmt::Format for ChannelSet {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "ChannelSet {{ channels: {=[?]} }}",
            self.channels.as_slice()
        )
    }
}

impl defmt::Format for BearingTableChunk {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "BearingTableChunk {{ bearing: {=u8}, total_rows: {=u16}, first_row: {=u16}, rows: {=usize} }}",
            self.bearing,
            self.total_rows,
            self.first_row,
            self.rows.len()
        )
    }
}

impl defmt::Format for SampleBlock {
    fn format(&self, f: defmt::Formatter) {
        let kind = match self.samples {
            Samples::AdcCodes(_) => "codes",
            Samples::Volts(_) => "volts",
        };
        defmt::write!(
            f,
            "SampleBlock {{ first_sample: {=u32}, channels: {=u8}, values: {=usize} {=str}, edges: {=[?]} }}",
            self.first_sample,
            self.channels,
            self.samples.len(),
            kind,
            self.keyphasor_edges.as_slice()
        )
    }
}

impl defmt::Format for PhasorFrame {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "PhasorFrame {{ revolution: {=u32}, revolutions: {=u16}, speed_hz: {=f32}, bearings: {=[?]} }}",
            self.revolution,
            self.revolutions,
            self.speed_hz,
            self.bearings.as_slice()
        )
    }
}

impl defmt::Format for EstimateFrame {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "EstimateFrame {{ revolution: {=u32}, pedestals: {=[?]} }}",
            self.revolution,
            self.pedestals.as_slice()
        )
    }
}

impl defmt::Format for DeviceCounters {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "DeviceCounters {{ overruns: {=u32}, queue_full_drops: {=u32}, keyphasor_missing: {=u32}, keyphasor_extra: {=u32}, frames_sent: {=u32}, commands_rejected: {=u32}, adc_saturation: {=[?]} }}",
            self.overruns,
            self.queue_full_drops,
            self.keyphasor_missing,
            self.keyphasor_extra,
            self.frames_sent,
            self.commands_rejected,
            self.adc_saturation.as_slice()
        )
    }
}

impl defmt::Format for StatusFrame {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "StatusFrame {{ state: {}, uptime_ms: {=u32}, counters: {}, link: {}, health: {} }}",
            self.state,
            self.uptime_ms,
            self.counters,
            self.link,
            self.health
        )
    }
}
