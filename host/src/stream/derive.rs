//! The run directory re-derived from the whole raw byte log: every phasor
//! frame that ever arrived, including those received by an earlier host
//! process that crashed or was killed, becomes rows of `measurements.csv`,
//! with the box's noise of each phasor as formats.md's `*_sd` columns.

use super::config::{BearingTables, StreamConfig};
use crate::rundir::{BearingRow, Measurement, RunDir};
use plinth_shared::phasor::{Complex, Phasor2};
use plinth_shared::protocol::{DeviceMessage, EstimateFrame, LinkStats, PhasorFrame, Receiver};
use std::collections::BTreeMap;

/// What the raw log holds, decoded.
#[derive(Clone, Debug)]
pub struct Derived {
    /// `measurements.csv` and `bearings.csv`.
    pub run: RunDir,
    /// Link counters over the whole log.
    pub link: LinkStats,
    /// Phasor frames in the log.
    pub phasor_frames: usize,
    /// Rows merged because a bearing had the same speed twice (averaged,
    /// weighted by revolutions).
    pub merged_rows: usize,
    /// Rows dropped: non-finite numbers, an unconfigured bearing index, or a
    /// speed outside the bearing table (no force can be computed there).
    pub dropped_rows: Vec<String>,
    /// The last estimate frame in the log.
    pub last_estimates: Option<EstimateFrame>,
    /// Box sessions seen (restarts of its sequence numbering + 1).
    pub sessions: u32,
}

/// A number the box sent in single precision, as the shortest decimal that
/// reads back as it (so the CSV shows `12.5`, not `12.5000000000001`).
pub fn widen(x: f32) -> f64 {
    format!("{x:e}").parse().unwrap_or(f64::NAN)
}

fn phasor(p: &plinth_shared::protocol::WirePhasor) -> Complex<f64> {
    Complex::new(widen(p.re), widen(p.im))
}

/// Decodes `raw` (a whole raw log) into a run directory for the configured
/// bearings and tables.
pub fn derive(raw: &[u8], config: &StreamConfig, tables: &BearingTables) -> Derived {
    let mut rx = Receiver::<DeviceMessage>::new();
    let mut frames: Vec<PhasorFrame> = Vec::new();
    let mut last_estimates = None;
    for frame in rx.feed(raw).flatten() {
        match frame.message {
            DeviceMessage::Phasors(p) => frames.push(p),
            DeviceMessage::Estimates(e) => last_estimates = Some(e),
            _ => {}
        }
    }
    let link = *rx.stats();

    // Group by (bearing, speed): (weight, Σ w·rel, Σ w·ped, Σ w²·sd² of
    // rel y, rel z, ped y, ped z, or None once one is not a valid sd).
    type Acc = (f64, Phasor2<f64>, Phasor2<f64>, Option<[f64; 4]>);
    let zero = Complex::new(0.0, 0.0);
    let mut order: Vec<(String, u32)> = Vec::new();
    let mut rows: BTreeMap<(String, u32), (f64, Acc, usize)> = BTreeMap::new();
    let mut dropped = Vec::new();
    let mut merged = 0;
    for (i, f) in frames.iter().enumerate() {
        let speed = widen(f.speed_hz);
        for b in &f.bearings {
            let Some(name) = config.bearings.get(b.bearing as usize) else {
                dropped.push(format!(
                    "phasor frame {i} (revolution {}): bearing index {} is not configured",
                    f.revolution, b.bearing
                ));
                continue;
            };
            let rel = [phasor(&b.rel[0]), phasor(&b.rel[1])];
            let ped = [phasor(&b.ped[0]), phasor(&b.ped[1])];
            let finite = speed.is_finite()
                && speed > 0.0
                && rel
                    .iter()
                    .chain(&ped)
                    .all(|c| c.re.is_finite() && c.im.is_finite());
            if !finite {
                dropped.push(format!(
                    "phasor frame {i} (revolution {}), bearing {name}: non-finite or non-positive values",
                    f.revolution
                ));
                continue;
            }
            let table = tables.rows_of(name);
            let inside = match (table.first(), table.last()) {
                (Some(lo), Some(hi)) => speed >= lo.speed_hz && speed <= hi.speed_hz,
                _ => false,
            };
            if !inside {
                dropped.push(format!(
                    "phasor frame {i} (revolution {}), bearing {name}: {speed} Hz is outside its bearing table",
                    f.revolution
                ));
                continue;
            }
            let w = f.revolutions.max(1) as f64;
            let key = (name.clone(), f.speed_hz.to_bits());
            let entry = rows.entry(key.clone()).or_insert_with(|| {
                order.push(key.clone());
                (speed, (0.0, [zero; 2], [zero; 2], Some([0.0; 4])), 0)
            });
            let (_, acc, count) = entry;
            acc.0 += w;
            for k in 0..2 {
                acc.1[k] += rel[k] * w;
                acc.2[k] += ped[k] * w;
            }
            // The noise of a revolution-weighted mean: sqrt(Σ w²·sd²)/Σ w.
            let sds = [b.rel_sd[0], b.rel_sd[1], b.ped_sd[0], b.ped_sd[1]].map(widen);
            acc.3 = match acc.3 {
                Some(mut v) if sds.iter().all(|s| s.is_finite() && *s >= 0.0) => {
                    for (v, s) in v.iter_mut().zip(sds) {
                        *v += w * w * s * s;
                    }
                    Some(v)
                }
                _ => None,
            };
            *count += 1;
            if *count > 1 {
                merged += 1;
            }
        }
    }
    let measurements = order
        .iter()
        .filter_map(|key| rows.get(key).map(|r| (key, r)))
        .map(
            |((name, _), (speed, (w, rel, ped, noise), _))| Measurement {
                speed_hz: *speed,
                bearing: name.clone(),
                rel: [rel[0] / *w, rel[1] / *w],
                ped: [ped[0] / *w, ped[1] / *w],
                noise_sd: noise.map(|v| v.map(|v| v.sqrt() / *w)),
            },
        )
        .collect();
    let bearings: Vec<BearingRow> = tables.rows.clone();
    Derived {
        run: RunDir {
            measurements,
            bearings,
            truth: None,
        },
        link,
        phasor_frames: frames.len(),
        merged_rows: merged,
        dropped_rows: dropped,
        last_estimates,
        sessions: link.restarts + u32::from(link.frames_ok > 0),
    }
}
