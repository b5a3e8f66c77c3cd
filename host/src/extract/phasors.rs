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
use super::edge_fit::{smooth, EdgeFit};
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
    /// The keyphasor edges' timing jitter and smoothing (its `times`
    /// emptied once used).
    pub edge_fit: EdgeFit,
}

/// The most memory one block of frames may take [bytes]: 16 MiB (a
/// recording of many channels is read in fewer frames at a time).
pub const BLOCK_BYTES: usize = 16 << 20;

/// The first pass's memory per keyphasor edge [bytes]: the edge times as
/// they are read (8, up to twice that while the list grows), and while
/// they are smoothed ([`smooth`]) the smoothed copy (8) and the periods
/// (8). The smoothed copy (8 per edge) is held through the second pass.
pub const EDGE_BYTES: u64 = 32;

/// What the smoothed edge list keeps through the second pass [bytes per
/// edge].
const HELD_EDGE_BYTES: u64 = 8;

/// What the extraction's memory is made of: a fixed part [bytes] (the
/// block buffers, the extractors, the channel checks), what every
/// keyphasor edge adds [bytes] (the first pass's edge list, see
/// [`EDGE_BYTES`]) and what every phasor output adds [bytes] (its phasors
/// and the run rows made from it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ExtractionMemory {
    /// Frames per block read.
    pub block_frames: usize,
    /// The fixed part [bytes].
    pub fixed: u64,
    /// Each output [bytes].
    pub per_output: u64,
}

impl ExtractionMemory {
    /// The memory of extracting `measured` channels in `bearings` bearings
    /// from a recording of `recorded` channels of `sample_bytes` bytes each
    /// (0: CSV), within `available` bytes (`None`: unknown).
    pub fn new(
        recorded: usize,
        sample_bytes: usize,
        measured: usize,
        bearings: usize,
        available: Option<u64>,
    ) -> Self {
        let groups = measured.div_ceil(GROUP) as u64;
        // The recording's block (file bytes and volts) and the groups' blocks.
        let per_frame = (recorded * (4 + sample_bytes)) as u64 + groups * (GROUP as u64) * 4;
        let block_bytes = available.map_or(BLOCK_BYTES as u64, |a| (a / 8).min(BLOCK_BYTES as u64));
        let block_frames = (block_bytes / per_frame.max(1)).clamp(1, BLOCK_FRAMES as u64) as usize;
        let fixed = groups
            .saturating_mul(std::mem::size_of::<PhasorExtractor<GROUP>>() as u64 + 64)
            .saturating_add(
                (measured as u64)
                    .saturating_mul(std::mem::size_of::<super::health::ChannelHealth>() as u64 + 8),
            )
            .saturating_add((recorded as u64).saturating_mul(24))
            .saturating_add(block_frames as u64 * per_frame);
        let per_output = 64
            + (measured as u64).saturating_mul(24)
            + (bearings as u64).saturating_mul(crate::sim::budget::TABLE_ROW_BYTES);
        ExtractionMemory {
            block_frames,
            fixed,
            per_output,
        }
    }

    /// The most outputs and faults [`Self::fixed`] and the smoothed list
    /// of `edges` keyphasor edges leave room for in `available` bytes
    /// (`None`: no bound known).
    fn most_outputs(&self, available: Option<u64>, edges: u64) -> Option<u64> {
        available.map(|a| {
            a.saturating_sub(self.fixed)
                .saturating_sub(edges.saturating_mul(HELD_EDGE_BYTES))
                / self.per_output
        })
    }

    /// The most keyphasor edges the first pass may list in `available`
    /// bytes besides [`Self::fixed`] (`None`: no bound known).
    fn most_edges(&self, available: Option<u64>) -> Option<u64> {
        available.map(|a| a.saturating_sub(self.fixed) / EDGE_BYTES)
    }
}

/// Runs the extraction over the whole recording; `progress` is told the
/// frames read after each block. Memory is checked against what the machine
/// has (`crate::sim::budget::available_bytes`).
pub fn extract(
    recording: &mut Recording,
    config: &Channels,
    progress: impl FnMut(u64),
) -> Result<Extraction> {
    extract_within(
        recording,
        config,
        progress,
        crate::sim::budget::available_bytes(),
    )
}

/// [`extract`] within `available` bytes of memory (`None`: unbounded): the
/// channels are checked against it before anything is allocated, and the
/// phasors and faults as they accumulate.
pub fn extract_within(
    recording: &mut Recording,
    config: &Channels,
    mut progress: impl FnMut(u64),
    available: Option<u64>,
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
    let memory = ExtractionMemory::new(
        n,
        recording.sample_bytes(),
        config.channels.len(),
        config.bearings.len(),
        available,
    );
    crate::sim::budget::check_input(
        &format!(
            "{file}: {} measuring channels ([[channel]] entries of the channels file) over {n} recorded channels",
            config.channels.len()
        ),
        memory.fixed,
        available,
    )
    .map_err(|e| anyhow::anyhow!("{e}: is it the right channels file?"))?;
    let block_frames = memory.block_frames;
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
    // First pass: the keyphasor edges alone (one number per revolution),
    // smoothed over their neighbours (`edge_fit`): the extractor is fed the
    // smoothed times.
    let fit = {
        let mut first = recording.reopen()?;
        let mut detector = EdgeDetector::new(&config.keyphasor);
        let mut buf = Vec::with_capacity(block_frames * n);
        let mut times = Vec::new();
        let mut position = 0u64;
        loop {
            let frames = first.read(&mut buf, block_frames)?;
            if frames == 0 {
                break;
            }
            for k in 0..frames {
                if let Some(fraction) = detector.push(f64::from(buf[k * n + kp])) {
                    times.push((position + k as u64) as f64 - 1.0 + f64::from(fraction));
                }
            }
            position += frames as u64;
            if let Some(most) = memory.most_edges(available) {
                if times.len() as u64 > most {
                    bail!(
                        "{file}: {} keyphasor edges by {:.3} s: listing them for the edge smoothing ({EDGE_BYTES} bytes an edge) needs more than the {} of memory this machine has available besides the {} the extraction's buffers take: split the recording",
                        times.len(),
                        position as f64 / fs,
                        bytes(available.unwrap_or(0)),
                        bytes(memory.fixed)
                    );
                }
            }
        }
        smooth(&times)
    };
    let most_outputs = memory.most_outputs(available, fit.times.len() as u64);
    let mut next_edge = 0usize;
    let mut detector = EdgeDetector::new(&config.keyphasor);
    let mut result = Extraction {
        sample_rate_hz: fs,
        ..Extraction::default()
    };
    let mut buf = Vec::with_capacity(block_frames * n);
    let mut blocks: Vec<Vec<[f32; GROUP]>> = vec![Vec::with_capacity(block_frames); groups];
    let mut edges: Vec<KeyphasorEdge> = Vec::new();
    let mut events: Vec<Vec<Event<GROUP>>> = vec![Vec::new(); groups];
    let mut last_edge: Option<f64> = None;
    let mut short_periods = 0u32;
    let mut first_edge: Option<f64> = None;
    // The last revolution's length [samples], for the flat-top check.
    let mut revolution: Option<f64> = None;
    let mut health = vec![super::health::ChannelHealth::default(); config.channels.len()];
    loop {
        let frames = recording.read(&mut buf, block_frames)?;
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
        // The smoothed edges ending in this block: edge time s ends in frame
        // ⌊s⌋ + 1 at fraction s − ⌊s⌋.
        let end_frame = first_frame + frames as u64;
        while let Some(&s) = fit.times.get(next_edge) {
            let frame = s.floor() + 1.0;
            if frame >= end_frame as f64 {
                break;
            }
            let index = (frame - first_frame as f64).max(0.0) as usize;
            let fraction = ((s - s.floor()) as f32).clamp(0.0, 1.0 - f32::EPSILON);
            if edges.last().is_none_or(|e: &KeyphasorEdge| {
                e.index < index || (e.index == index && e.fraction < fraction)
            }) {
                edges.push(KeyphasorEdge { index, fraction });
            }
            next_edge += 1;
        }
        for k in 0..frames {
            if let Some(fraction) = detector.push(f64::from(buf[k * n + kp])) {
                let at = (first_frame + k as u64) as f64 - 1.0 + f64::from(fraction);
                first_edge.get_or_insert(at);
                if let Some(prev) = last_edge.replace(at) {
                    revolution = Some(at - prev);
                    if at - prev < MIN_SAMPLES_PER_REVOLUTION {
                        short_periods += 1;
                        if short_periods >= 3 {
                            bail!(
                                "{file}: the sample rate {fs} Hz is too low for the speed at {:.3} s: keyphasor pulses {:.1} samples apart ({:.1} Hz), but the extractor needs at least {MIN_SAMPLES_PER_REVOLUTION} samples per revolution (a sample rate of at least {:.0} Hz); or the keyphasor gives more than one pulse per revolution (a second mark, both edges of a keyway: check [keyphasor] threshold_v and edge)",
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
        collect(&events, &mut result, config.channels.len(), &fit);
        result.frames += frames as u64;
        if let Some(most) = most_outputs {
            let held = result.outputs.len() as u64
                + (result.faults.len() as u64 * std::mem::size_of::<Fault>() as u64)
                    .div_ceil(memory.per_output);
            if held > most {
                bail!(
                    "{file}: {} phasors and {} keyphasor faults by {:.3} s ({} channels, {} revolutions a phasor): holding them needs more than the {} MB of memory this machine has available: give more `revolutions` per phasor in the channels file, or split the recording",
                    result.outputs.len(),
                    result.faults.len(),
                    result.frames as f64 / fs,
                    config.channels.len(),
                    config.revolutions,
                    available.unwrap_or(0) >> 20
                );
            }
        }
        progress(result.frames);
    }
    result.edges = detector.edges;
    result.edge_fit = EdgeFit {
        times: Vec::new(),
        ..fit
    };
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

/// `b` bytes in MB (kB below 1 MB), for messages.
fn bytes(b: u64) -> String {
    if b >= 1 << 20 {
        format!("{} MB", b >> 20)
    } else {
        format!("{} kB", b.div_ceil(1 << 10))
    }
}

/// Matches the groups' events by revolution into outputs.
/// Each phasor's noise sd takes the smoothed keyphasor's remaining timing
/// error as a part proportional to |phasor| (the same phase error on every
/// channel: not in the scatter between revolutions, which the smoothing
/// made smooth).
fn collect(events: &[Vec<Event<GROUP>>], result: &mut Extraction, channels: usize, fit: &EdgeFit) {
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
                let speed_hz = f64::from(p.speed_hz);
                let phase = fit.residual_phase_rad(fs / speed_hz);
                for (sd, d) in noise_sd.iter_mut().zip(&displacement) {
                    if let Some(sd) = sd {
                        let q2 = f64::from(d.re).powi(2) + f64::from(d.im).powi(2);
                        *sd = (*sd * *sd + q2 * phase * phase).sqrt();
                    }
                }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Five channels (two `rel`, two `ped` probes of bearing B1, the
    /// keyphasor) at 6400 Hz, a constant 50 Hz for 2 s: 100 revolutions.
    fn recording(dir: &std::path::Path) -> (std::path::PathBuf, Channels) {
        recording_of(dir, 12_800, 1)
    }

    /// [`recording`] of `samples` samples (128 a revolution) and
    /// `revolutions` a phasor.
    fn recording_of(
        dir: &std::path::Path,
        samples: u32,
        revolutions: u32,
    ) -> (std::path::PathBuf, Channels) {
        let mut text = String::from("time_s,r45,r135,p45,p135,kp\n");
        for i in 0..samples {
            let t = f64::from(i) / 6400.0;
            let w = 2.0 * std::f64::consts::PI * 50.0 * t;
            let kp = if i % 128 < 8 { -10.0 } else { 0.0 };
            text.push_str(&format!(
                "{t:.9},{:.6},{:.6},{:.6},{:.6},{kp}\n",
                (w - 0.3).cos(),
                (w + 1.2).cos(),
                0.2 * (w - 0.5).cos(),
                0.2 * (w + 1.0).cos()
            ));
        }
        let path = dir.join("rec.csv");
        std::fs::write(&path, text).unwrap();
        let mut toml = format!(
            "revolutions = {revolutions}\n[keyphasor]\nchannel = 4\nthreshold_v = -5.0\nedge = \"falling\"\n",
        );
        for (index, (quantity, angle)) in [("rel", 45), ("rel", 135), ("ped", 45), ("ped", 135)]
            .iter()
            .enumerate()
        {
            toml.push_str(&format!(
                "[[channel]]\nindex = {index}\nbearing = \"B1\"\nquantity = \"{quantity}\"\nangle_deg = {angle}.0\nsensor = \"proximity\"\nsensitivity = 7.87\nsensitivity_unit = \"V/mm\"\n"
            ));
        }
        (path, Channels::parse(&toml, "channels.toml").unwrap())
    }

    #[test]
    fn phasors_beyond_the_memory_budget_are_refused_and_smaller_blocks_change_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let (path, config) = recording(dir.path());
        let run = |available: Option<u64>| {
            let mut r = Recording::open(&path, None).unwrap();
            extract_within(&mut r, &config, |_| {}, available)
        };
        let reference = run(None).unwrap();
        let k = reference.outputs.len() as u64;
        assert!(k > 50, "{k} outputs");
        let (mut refused_outputs, mut refused_channels, mut passed) = (0, 0, 0);
        for kib in [4u64, 16, 32, 64, 128, 256, 1024, 4096] {
            let a = kib << 10;
            let m = ExtractionMemory::new(5, 0, 4, 1, Some(a));
            assert!(m.block_frames >= 1 && m.block_frames <= BLOCK_FRAMES);
            match run(Some(a)) {
                Ok(e) => {
                    assert!(
                        m.fixed <= a && k <= m.most_outputs(Some(a), 100).unwrap(),
                        "{kib} KiB"
                    );
                    assert_eq!(e.outputs, reference.outputs, "{kib} KiB");
                    passed += 1;
                }
                Err(e) => {
                    let e = e.to_string();
                    if m.fixed > a {
                        assert!(
                            e.contains("4 measuring channels") && e.contains("rec.csv"),
                            "{e}"
                        );
                        refused_channels += 1;
                    } else if m.most_edges(Some(a)).unwrap() < 100 {
                        assert!(
                            e.contains("keyphasor edges") && e.contains("rec.csv"),
                            "{e}"
                        );
                        refused_outputs += 1;
                    } else {
                        assert!(k > m.most_outputs(Some(a), 100).unwrap(), "{kib} KiB: {e}");
                        assert!(e.contains("phasors") && e.contains("`revolutions`"), "{e}");
                        refused_outputs += 1;
                    }
                }
            }
        }
        assert!(
            refused_outputs > 0 && refused_channels > 0 && passed > 0,
            "{refused_outputs} {refused_channels} {passed}"
        );
    }

    #[test]
    fn an_edge_list_beyond_the_memory_budget_is_refused_before_the_phasors() {
        // 10 s at 50 Hz: 500 keyphasor edges (16 kB listed) but, at 100
        // revolutions a phasor, only 4 phasors (under 5 kB of rows).
        let dir = tempfile::tempdir().unwrap();
        let (path, config) = recording_of(dir.path(), 64_000, 100);
        let run = |available: Option<u64>| {
            let mut r = Recording::open(&path, None).unwrap();
            extract_within(&mut r, &config, |_| {}, available)
        };
        let reference = run(None).unwrap();
        assert!(reference.edges >= 499, "{} edges", reference.edges);
        let outputs = reference.outputs.len() as u64;
        assert!((1..=5).contains(&outputs), "{outputs} outputs");
        let edges = reference.edges;
        // A budget with room for the phasors and the smoothed edges, not for
        // the edge list while it is smoothed.
        let room = |kib: u64| {
            let a = kib << 10;
            let m = ExtractionMemory::new(5, 0, 4, 1, Some(a));
            (a, m, a.saturating_sub(m.fixed))
        };
        let (a, _, _) = (1..4096)
            .map(room)
            .find(|&(_, m, r)| {
                r < edges * EDGE_BYTES && r > outputs * m.per_output + edges * HELD_EDGE_BYTES
            })
            .expect("a budget between the phasors' and the edges' needs");
        let e = run(Some(a))
            .expect_err("edges beyond the budget")
            .to_string();
        assert!(
            e.contains("rec.csv") && e.contains("keyphasor edges") && e.contains(" kB of memory"),
            "{e}"
        );
        // With room for them it runs, unchanged.
        let (a, _, _) = (1..4096)
            .map(room)
            .find(|&(_, m, r)| r > edges * EDGE_BYTES + outputs * m.per_output)
            .unwrap();
        assert_eq!(run(Some(a)).unwrap().outputs, reference.outputs);
    }

    #[test]
    fn many_recorded_channels_are_read_in_blocks_of_bounded_memory() {
        // 65 535 channels of 64-bit samples: one frame is 786 420 bytes.
        let m = ExtractionMemory::new(65_535, 8, 8, 2, None);
        assert_eq!(m.block_frames, BLOCK_BYTES / (65_535 * 12 + 32));
        assert!(m.fixed < 2 * BLOCK_BYTES as u64, "{}", m.fixed);
        let m = ExtractionMemory::new(9, 3, 8, 2, None);
        assert_eq!(m.block_frames, BLOCK_FRAMES);
    }
}
