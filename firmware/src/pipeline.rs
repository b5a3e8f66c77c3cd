//! The running pipeline: sample vectors → 1X phasors (shared extractor) →
//! rel/ped phasors per bearing → bearing forces from the host's tables →
//! one recursive least-squares estimator per pedestal → outgoing frames.
//!
//! Fixed-size state only; nothing here blocks or allocates.

use crate::config::{Configuration, TABLE_ROWS};
use crate::source::{SampleBuffer, CHANNELS};
use plinth_shared::bearing::BearingTable;
use plinth_shared::extractor::{
    ConfigError, Event, ExtractorConfig, FaultKind, PhasorExtractor, Phasors,
};
use plinth_shared::phasor::{omega_from_hz, Phasor, Phasor2};
use plinth_shared::protocol::{
    BearingPhasors, DeviceCounters, DeviceMessage, EstimateFrame, PedestalEstimateEntry,
    PhasorFrame, WirePhasor, MAX_BEARINGS,
};
use plinth_shared::rls::PedestalRls;

/// Most extractor events one sample buffer can produce that are kept; more
/// (impossible at ≥ 64 samples per revolution) are counted as dropped.
const EVENTS_PER_BUFFER: usize = 8;

/// A phasor that was not measured (its channel is not configured).
const UNMEASURED: WirePhasor = WirePhasor {
    re: f32::NAN,
    im: f32::NAN,
};

/// Counts of what the pipeline saw, folded into the status frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PipelineCounters {
    /// Missing pulses and keyphasor timeouts.
    pub keyphasor_missing: u32,
    /// Extra pulses and irregular pulse trains.
    pub keyphasor_extra: u32,
    /// Revolutions dropped because a phasor came out non-finite.
    pub non_finite: u32,
    /// Bearing updates skipped because the speed lies outside its table.
    pub speed_outside_table: u32,
    /// Extractor events lost because too many came in one buffer.
    pub events_dropped: u32,
    /// Sample vectors lost before processing (overruns, missing blocks).
    pub samples_lost: u32,
}

impl PipelineCounters {
    /// Adds these counts to the protocol's status counters.
    pub fn fold_into(&self, c: &mut DeviceCounters) {
        c.keyphasor_missing = self.keyphasor_missing;
        c.keyphasor_extra = self.keyphasor_extra;
        c.overruns = self.samples_lost;
    }
}

/// What one bearing contributes: its channels and its pedestal estimator.
#[derive(Clone, Debug)]
struct BearingSlot {
    /// ADC channel of rel y, rel z, ped y, ped z (None: not measured).
    channels: [Option<u8>; 4],
    /// The pedestal's estimator (used when all four are measured).
    rls: PedestalRls<f32>,
}

/// The acquisition pipeline of one `Start` … `Stop` run.
#[derive(Clone, Debug)]
pub struct Pipeline {
    extractor: PhasorExtractor<CHANNELS>,
    bearings: [BearingSlot; MAX_BEARINGS],
    /// Revolution index of the last estimate update (for estimate frames).
    last_revolution: u32,
    /// What went wrong so far.
    pub counters: PipelineCounters,
}

impl Pipeline {
    /// A pipeline for `config` at `sample_rate_hz` [Hz].
    pub fn new(config: &Configuration, sample_rate_hz: f32) -> Result<Self, ConfigError> {
        let mut ec = ExtractorConfig::new(sample_rate_hz, config.sensors());
        ec.revolutions_per_output = config.revolutions_per_phasor;
        let extractor = PhasorExtractor::new(ec)?;
        let channels = config.bearing_channels();
        let scale = config.rls.parameter_scale();
        let lambda = config.rls.forgetting_factor;
        // Consecutive phasors share revolutions (the run-down correction's
        // differences): their errors correlate, negatively on balance, so
        // the independent-phasor variances are scaled by φ ≤ 1 (0.57 to 0.96,
        // see `long_run_factor`); of the pedestal's channels the largest φ,
        // the least reduction.
        let phi = |b: usize| {
            channels[b]
                .iter()
                .flatten()
                .map(|&c| extractor.long_run_factor(c as usize))
                .fold(0.0f32, f32::max)
        };
        let bearings = core::array::from_fn(|b| BearingSlot {
            channels: channels[b],
            rls: PedestalRls::new(scale, lambda).with_long_run_factor(phi(b)),
        });
        Ok(Self {
            extractor,
            bearings,
            last_revolution: 0,
            counters: PipelineCounters::default(),
        })
    }

    /// Processes one buffer of samples; phasor and estimate frames go to
    /// `emit` in time order.
    pub fn process(
        &mut self,
        buf: &SampleBuffer,
        tables: &[BearingTable<TABLE_ROWS, f32>; MAX_BEARINGS],
        emit: &mut impl FnMut(DeviceMessage),
    ) {
        if buf.lost_before > 0 {
            // The time base broke: the open revolution cannot be trusted.
            self.counters.samples_lost = self.counters.samples_lost.saturating_add(buf.lost_before);
            self.extractor.reset();
        }
        let mut events: heapless::Vec<Event<CHANNELS>, EVENTS_PER_BUFFER> = heapless::Vec::new();
        let mut dropped = 0u32;
        let result = self
            .extractor
            .update_block(&buf.samples, &buf.edges, &mut |e| {
                if events.push(e).is_err() {
                    dropped += 1;
                }
            });
        if result.is_err() {
            // Sources only produce sorted, in-range edges; if one ever did
            // not, the block was not processed at all: count it as lost.
            self.counters.samples_lost = self
                .counters
                .samples_lost
                .saturating_add(buf.samples.len() as u32);
        }
        self.counters.events_dropped = self.counters.events_dropped.saturating_add(dropped);
        for event in &events {
            match event {
                Event::Phasors(p) => self.revolution(p, tables, emit),
                Event::Fault(f) => {
                    let c = match f.kind {
                        FaultKind::MissingPulse | FaultKind::Timeout => {
                            &mut self.counters.keyphasor_missing
                        }
                        FaultKind::ExtraPulse | FaultKind::IrregularPulses => {
                            &mut self.counters.keyphasor_extra
                        }
                        FaultKind::NonFinite => &mut self.counters.non_finite,
                    };
                    *c = c.saturating_add(1);
                }
            }
        }
    }

    /// One averaged set of phasors: a phasor frame, then the pedestal
    /// updates and an estimate frame.
    fn revolution(
        &mut self,
        p: &Phasors<CHANNELS>,
        tables: &[BearingTable<TABLE_ROWS, f32>; MAX_BEARINGS],
        emit: &mut impl FnMut(DeviceMessage),
    ) {
        // Revolution r spans edges r+1 → r+2 (edge counts from 1), so the
        // last one closed at edge count E is E − 2 and the average began R − 1
        // revolutions earlier.
        let last = p.revolution.wrapping_sub(2);
        let first = last.wrapping_sub(u32::from(p.revolutions.saturating_sub(1)));
        let at = |ch: Option<u8>| -> Option<Phasor> {
            ch.map(|c| p.displacement[c as usize % CHANNELS])
        };
        let wire = |q: Option<Phasor>| q.map(WirePhasor::from).unwrap_or(UNMEASURED);
        let sd =
            |ch: Option<u8>| -> f32 { ch.map_or(f32::NAN, |c| p.noise_sd[c as usize % CHANNELS]) };

        let mut frame = PhasorFrame {
            revolution: first,
            revolutions: p.revolutions,
            speed_hz: p.speed_hz,
            bearings: heapless::Vec::new(),
        };
        for (b, slot) in self.bearings.iter().enumerate() {
            if slot.channels.iter().all(Option::is_none) {
                continue;
            }
            let q = slot.channels.map(at);
            let _ = frame.bearings.push(BearingPhasors {
                bearing: b as u8,
                rel: [wire(q[0]), wire(q[1])],
                ped: [wire(q[2]), wire(q[3])],
                rel_sd: [sd(slot.channels[0]), sd(slot.channels[1])],
                ped_sd: [sd(slot.channels[2]), sd(slot.channels[3])],
            });
        }
        emit(DeviceMessage::Phasors(frame));

        let omega = omega_from_hz(p.speed_hz);
        let mut estimates = EstimateFrame {
            revolution: last,
            pedestals: heapless::Vec::new(),
        };
        for (b, slot) in self.bearings.iter_mut().enumerate() {
            let q = slot.channels.map(at);
            let (Some(ry), Some(rz), Some(py), Some(pz)) = (q[0], q[1], q[2], q[3]) else {
                continue;
            };
            match tables[b].at(p.speed_hz) {
                Ok(coefficients) => {
                    let rel: Phasor2 = [ry, rz];
                    let ped: Phasor2 = [py, pz];
                    // The phasor's own sd: the extractor pools the scatter
                    // over the last revolutions, so it is steady enough to
                    // weigh by (`plinth_shared::extractor::NoisePool`).
                    let sds = slot.channels.map(sd);
                    slot.rls.update_weighted(
                        omega,
                        &ped,
                        &rel,
                        &coefficients,
                        [sds[0], sds[1]],
                        [sds[2], sds[3]],
                    );
                }
                Err(_) => {
                    self.counters.speed_outside_table =
                        self.counters.speed_outside_table.saturating_add(1);
                }
            }
            if let Ok(e) = slot.rls.estimate() {
                let _ = estimates
                    .pedestals
                    .push(PedestalEstimateEntry::new(b as u8, &e));
            }
        }
        self.last_revolution = last;
        if !estimates.pedestals.is_empty() {
            emit(DeviceMessage::Estimates(estimates));
        }
    }

    /// The current estimates of every pedestal that has one (sent at Stop).
    pub fn estimates(&self) -> EstimateFrame {
        let mut frame = EstimateFrame {
            revolution: self.last_revolution,
            pedestals: heapless::Vec::new(),
        };
        for (b, slot) in self.bearings.iter().enumerate() {
            if let Ok(e) = slot.rls.estimate() {
                let _ = frame
                    .pedestals
                    .push(PedestalEstimateEntry::new(b as u8, &e));
            }
        }
        frame
    }
}
