//! The extraction loop: recording blocks → keyphasor edges → the box's own
//! phasor extractor (`plinth_shared::extractor::PhasorExtractor`, one per
//! group of the box's [`GROUP`] channels, all fed the same edges) → phasors
//! with their noise.
//!
//! The extractor runs exactly as on the box: R revolutions per output, its
//! run-down correction, seismic conversion and noise estimate (the scatter
//! between revolutions, `plinth_shared::extractor` module `noise`: the one
//! definition of a phasor's noise). The outputs of the groups are matched by
//! revolution; a fault (missing or extra pulse) drops a partial average
//! inside the extractor, as on the box.

use super::channels::Channels;
use super::keyphasor::{EdgeDetector, MIN_SAMPLES_PER_REVOLUTION};
use super::recording::Recording;
use anyhow::{bail, Result};
use plinth_shared::extractor::{
    Event, ExtractorConfig, Fault, FaultKind, KeyphasorEdge, PhasorExtractor, Phasors, Sensor,
};
use plinth_shared::phasor::Phasor;

/// Channels per extractor: the box's channel count.
pub const GROUP: usize = plinth_firmware::source::CHANNELS;

/// Frames per block read from the recording.
pub const BLOCK_FRAMES: usize = 4096;

/// One output phasor set: every configured channel's displacement phasor.
#[derive(Clone, Debug, PartialEq)]
pub struct Output {
    /// Mean speed over its revolutions [Hz].
    pub speed_hz: f64,
    /// Time of its last closing edge [s from the recording's first sample].
    pub time_s: f64,
    /// Displacement phasor of each configured channel [m], in `Channels::channels` order.
    pub displacement: Vec<Phasor>,
    /// Noise standard deviation of each [m], sqrt(E|n|²) of the complex
    /// noise: the shared extractor's estimate from the scatter between
    /// revolutions (`None` if it is not finite).
    pub noise_sd: Vec<Option<f64>>,
}

/// Everything an extraction found.
#[derive(Clone, Debug, Default)]
pub struct Extraction {
    /// The phasors, in time order.
    pub outputs: Vec<Output>,
    /// Keyphasor faults as the box reports them.
    pub faults: Vec<Fault>,
    /// Keyphasor edges detected.
    pub edges: u64,
    /// Frames read.
    pub frames: u64,
    /// Sample rate [Hz].
    pub sample_rate_hz: f64,
    /// Frames of the first and the last keyphasor edge.
    pub keyphasor_span: Option<(f64, f64)>,
}

/// Runs the extraction over the whole recording; `progress` is told the
/// frames read after each block.
pub fn extract(
    recording: &mut Recording,
    config: &Channels,
    mut progress: impl FnMut(u64),
) -> Result<Extraction> {
    let file = recording.file.clone();
    let fs = recording.sample_rate_hz;
    let n = recording.channels;
    let kp = config.keyphasor.channel;
    for (i, c) in
        std::iter::once((usize::MAX, kp)).chain(config.channels.iter().map(|c| c.index).enumerate())
    {
        if c >= n {
            let what = if i == usize::MAX {
                "keyphasor.channel".to_string()
            } else {
                format!("channel[{i}].index")
            };
            bail!(
                "{what}: channel {c} is beyond the recording: {file} has {n} channels (0..={})",
                n - 1
            );
        }
    }
    let max_speed = fs / MIN_SAMPLES_PER_REVOLUTION;
    let min_speed = config.min_speed_hz.max(fs / 4_000_000.0);
    if min_speed >= max_speed {
        bail!(
            "{file}: sample rate {fs} Hz is too low: the extractor needs {MIN_SAMPLES_PER_REVOLUTION} samples per revolution, so at most {max_speed:.3} Hz, below min_speed_hz {min_speed}"
        );
    }
    let groups = config.channels.len().div_ceil(GROUP);
    let mut extractors = Vec::with_capacity(groups);
    for g in 0..groups {
        let mut sensors = [Sensor::displacement(1.0); GROUP];
        for (j, c) in config
            .channels
            .iter()
            .skip(g * GROUP)
            .take(GROUP)
            .enumerate()
        {
            sensors[j] = Sensor {
                kind: c.kind,
                sensitivity: c.sensitivity_si as f32,
            };
        }
        let mut ec = ExtractorConfig::new(fs as f32, sensors);
        ec.revolutions_per_output = config.revolutions;
        ec.min_speed_hz = min_speed as f32;
        ec.max_speed_hz = max_speed as f32;
        ec.period_tolerance = config.period_tolerance as f32;
        ec.max_acceleration_hz_per_s = config.max_acceleration_hz_per_s as f32;
        extractors.push(
            PhasorExtractor::new(ec)
                .map_err(|e| anyhow::anyhow!("{file}: extractor settings refused: {e:?}"))?,
        );
    }
    let mut detector = EdgeDetector::new(&config.keyphasor);
    let mut result = Extraction {
        sample_rate_hz: fs,
        ..Extraction::default()
    };
    let mut buf = Vec::with_capacity(BLOCK_FRAMES * n);
    let mut blocks: Vec<Vec<[f32; GROUP]>> = vec![Vec::with_capacity(BLOCK_FRAMES); groups];
    let mut edges: Vec<KeyphasorEdge> = Vec::new();
    let mut events: Vec<Vec<Event<GROUP>>> = vec![Vec::new(); groups];
    let mut last_edge: Option<f64> = None;
    let mut short_periods = 0u32;
    let mut first_edge: Option<f64> = None;
    // The last revolution's length [samples], for the flat-top check.
    let mut revolution: Option<f64> = None;
    let mut health = vec![super::health::ChannelHealth::default(); config.channels.len()];
    loop {
        let frames = recording.read(&mut buf, BLOCK_FRAMES)?;
        if frames == 0 {
            break;
        }
        let first_frame = result.frames;
        // Clipping on a measuring channel ends the extraction.
        for (i, c) in config.channels.iter().enumerate() {
            let clip = recording.clipping[c.index];
            if let Some(at) = clip.first_frame {
                bail!(
                    "{file}: channel {} (channel[{i}]: bearing `{}`, {} at {}°) is clipped from {:.6} s (frame {at}) on: its samples reach the converter's full scale, so its 1X phasors would be wrong; lower the gain or leave the channel out",
                    c.index,
                    c.placement.bearing,
                    c.placement.quantity.name(),
                    c.placement.angle_deg,
                    at as f64 / fs
                );
            }
        }
        edges.clear();
        for k in 0..frames {
            if let Some(fraction) = detector.push(f64::from(buf[k * n + kp])) {
                edges.push(KeyphasorEdge { index: k, fraction });
                let at = (first_frame + k as u64) as f64 - 1.0 + f64::from(fraction);
                first_edge.get_or_insert(at);
                if let Some(prev) = last_edge.replace(at) {
                    revolution = Some(at - prev);
                    if at - prev < MIN_SAMPLES_PER_REVOLUTION {
                        short_periods += 1;
                        if short_periods >= 3 {
                            bail!(
                                "{file}: the sample rate {fs} Hz is too low for the speed at {:.3} s: keyphasor pulses {:.1} samples apart ({:.1} Hz), but the extractor needs at least {MIN_SAMPLES_PER_REVOLUTION} samples per revolution (a sample rate of at least {:.0} Hz)",
                                at / fs,
                                at - prev,
                                fs / (at - prev),
                                MIN_SAMPLES_PER_REVOLUTION * fs / (at - prev)
                            );
                        }
                    } else {
                        short_periods = 0;
                    }
                }
            }
        }
        for (h, c) in health.iter_mut().zip(&config.channels) {
            for k in 0..frames {
                h.push(first_frame + k as u64, buf[k * n + c.index], revolution);
            }
        }
        for (g, block) in blocks.iter_mut().enumerate() {
            block.clear();
            let idx: Vec<usize> = config
                .channels
                .iter()
                .skip(g * GROUP)
                .take(GROUP)
                .map(|c| c.index)
                .collect();
            for k in 0..frames {
                let row = &buf[k * n..(k + 1) * n];
                let mut v = [0.0f32; GROUP];
                for (j, &c) in idx.iter().enumerate() {
                    v[j] = row[c];
                }
                block.push(v);
            }
            events[g].clear();
            let sink = &mut events[g];
            extractors[g]
                .update_block(block, &edges, &mut |e| sink.push(e))
                .map_err(|e| {
                    anyhow::anyhow!("{file}: keyphasor edges refused at frame {first_frame}: {e:?}")
                })?;
        }
        collect(&events, &mut result, config.channels.len());
        result.frames += frames as u64;
        progress(result.frames);
    }
    result.edges = detector.edges;
    result.keyphasor_span = first_edge.zip(last_edge);
    if detector.edges == 0 {
        let k = &config.keyphasor;
        bail!(
            "{file}: no keyphasor edges on channel {} ({:?} through {} V with {} V hysteresis): the channel spans {:.4} .. {:.4} V{}",
            k.channel,
            k.edge,
            k.threshold_v,
            k.hysteresis_v,
            detector.range.0,
            detector.range.1,
            if detector.range.0 > k.threshold_v || detector.range.1 < k.threshold_v {
                ", which does not reach the threshold"
            } else {
                ""
            }
        );
    }
    for (i, (h, c)) in health.iter_mut().zip(&config.channels).enumerate() {
        let what = format!(
            "channel {} (channel[{i}]: bearing `{}`, {} at {}°)",
            c.index,
            c.placement.bearing,
            c.placement.quantity.name(),
            c.placement.angle_deg
        );
        h.finish(&what, fs, revolution)
            .map_err(|e| anyhow::anyhow!("{file}: {e}"))?;
    }
    Ok(result)
}

/// Matches the groups' events by revolution into outputs.
fn collect(events: &[Vec<Event<GROUP>>], result: &mut Extraction, channels: usize) {
    let fs = result.sample_rate_hz;
    let mut others: Vec<std::collections::VecDeque<&Event<GROUP>>> =
        events.iter().skip(1).map(|e| e.iter().collect()).collect();
    for e in &events[0] {
        match e {
            Event::Fault(f) => result.faults.push(*f),
            Event::Phasors(p) => {
                let mut found: Vec<&Phasors<GROUP>> = vec![p];
                for q in others.iter_mut() {
                    while let Some(o) = q.pop_front() {
                        match o {
                            Event::Phasors(op) if op.revolution == p.revolution => {
                                found.push(op);
                                break;
                            }
                            Event::Phasors(op) if op.revolution > p.revolution => {
                                q.push_front(o);
                                break;
                            }
                            Event::Fault(f) if f.kind == FaultKind::NonFinite => {
                                result.faults.push(*f)
                            }
                            _ => {}
                        }
                    }
                }
                if found.len() < events.len() {
                    // A group lost this output (a non-finite phasor there).
                    continue;
                }
                let mut displacement: Vec<Phasor> =
                    found.iter().flat_map(|g| g.displacement).collect();
                let mut noise_sd: Vec<Option<f64>> = found
                    .iter()
                    .flat_map(|g| g.noise_sd)
                    .map(|s| s.is_finite().then_some(f64::from(s)))
                    .collect();
                displacement.truncate(channels);
                noise_sd.truncate(channels);
                result.outputs.push(Output {
                    speed_hz: f64::from(p.speed_hz),
                    time_s: p.end.sample as f64 / fs,
                    displacement,
                    noise_sd,
                });
            }
        }
    }
}
