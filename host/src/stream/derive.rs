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
                written: None,
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

#[cfg(test)]
mod tests {
    use super::*;
    use plinth_shared::bearing::BearingCoefficients;
    use plinth_shared::protocol::{BearingPhasors, Transmitter, WirePhasor, MAX_FRAME_SIZE};
    use std::path::Path;

    const CONFIG: &str = r#"
bearings = "bearings.csv"
[[channels]]
adc = 0
bearing = "left"
quantity = "rel_y"
sensor = "proximity"
sensitivity = 7870.0
[[channels]]
adc = 1
bearing = "left"
quantity = "rel_z"
sensor = "proximity"
sensitivity = 7870.0
[[channels]]
adc = 2
bearing = "left"
quantity = "ped_y"
sensor = "velocity"
sensitivity = 20.0
[[channels]]
adc = 3
bearing = "left"
quantity = "ped_z"
sensor = "velocity"
sensitivity = 20.0
"#;

    fn frame(revolutions: u16, speed_hz: f32, sd: [f32; 4]) -> DeviceMessage {
        let p = |re: f32| WirePhasor { re, im: -re };
        let mut f = PhasorFrame {
            revolution: 0,
            revolutions,
            speed_hz,
            bearings: Default::default(),
        };
        f.bearings
            .push(BearingPhasors {
                bearing: 0,
                rel: [p(1e-6), p(2e-6)],
                ped: [p(3e-7), p(4e-7)],
                rel_sd: [sd[0], sd[1]],
                ped_sd: [sd[2], sd[3]],
            })
            .unwrap();
        DeviceMessage::Phasors(f)
    }

    fn derived(frames: &[DeviceMessage]) -> Derived {
        let config = StreamConfig::parse(CONFIG, Path::new(".")).unwrap();
        let tables = BearingTables {
            rows: [10.0, 100.0]
                .map(|speed_hz| BearingRow {
                    speed_hz,
                    bearing: "left".into(),
                    coefficients: BearingCoefficients::isotropic(1e8, 1e4),
                })
                .to_vec(),
        };
        let mut tx = Transmitter::new();
        let mut raw = Vec::new();
        for f in frames {
            let mut buf = [0u8; MAX_FRAME_SIZE];
            raw.extend_from_slice(tx.encode(f, &mut buf).unwrap().1);
        }
        derive(&raw, &config, &tables)
    }

    #[test]
    fn the_box_noise_becomes_the_sd_columns_and_merges_as_a_weighted_mean() {
        // Two frames at one speed (a dwell), 4 and 2 revolutions: the row is
        // their revolution-weighted mean, whose noise is sqrt(Σw²sd²)/Σw.
        let d = derived(&[
            frame(4, 50.0, [1e-8, 2e-8, 3e-9, 4e-9]),
            frame(2, 50.0, [2e-8, 2e-8, 6e-9, 0.0]),
            frame(4, 40.0, [5e-9, 5e-9, 5e-9, 5e-9]),
        ]);
        assert_eq!(d.run.measurements.len(), 2);
        let sd = d.run.measurements[0].noise_sd.expect("noise columns");
        let want = |a: f64, b: f64| (16.0 * a * a + 4.0 * b * b).sqrt() / 6.0;
        let got_want = [
            (sd[0], want(1e-8, 2e-8)),
            (sd[1], want(2e-8, 2e-8)),
            (sd[2], want(3e-9, 6e-9)),
            (sd[3], want(4e-9, 0.0)),
        ];
        for (i, (g, w)) in got_want.iter().enumerate() {
            assert!((g - w).abs() < 1e-6 * w, "{i}: {g} vs {w}");
        }
        assert!(d.run.measurements[1].noise_sd.is_some());
    }

    #[test]
    fn a_phasor_without_a_valid_noise_has_no_sd() {
        let d = derived(&[frame(4, 50.0, [1e-8, f32::NAN, 3e-9, 4e-9])]);
        assert_eq!(d.run.measurements.len(), 1);
        assert_eq!(d.run.measurements[0].noise_sd, None);
    }
}
