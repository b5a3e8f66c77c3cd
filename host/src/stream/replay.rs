//! Replaying simulated time signals to the box: the signals as the box's ADC
//! would have seen them, cut into protocol [`SampleBlock`]s, and a journal of
//! how far the box has acknowledged them so that a restarted host resumes
//! where the last one stopped.

use super::config::StreamConfig;
use crate::sim::signals::SignalSet;
use anyhow::{bail, Context, Result};
use plinth_shared::protocol::{
    KeyphasorEdge, SampleBlock, Samples, MAX_BLOCK_VALUES, MAX_KEYPHASOR_EDGES,
};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Sampled transducer voltages and keyphasor edges to replay: what the box's
/// ADC and keyphasor timer would have captured.
pub trait ReplaySource {
    /// Sample rate per channel [Hz].
    fn sample_rate_hz(&self) -> f64;
    /// The ADC channel of each column of a sample vector, in order.
    fn adc_channels(&self) -> &[u8];
    /// Number of sample vectors.
    fn sample_vectors(&self) -> usize;
    /// Transducer output [V] of column `column` in sample vector `vector`.
    fn volts(&self, vector: usize, column: usize) -> f32;
    /// Keyphasor edge times [sample periods from vector 0], increasing.
    fn keyphasor_edges(&self) -> &[f64];
}

/// Replay signals held in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct Signals {
    sample_rate_hz: f64,
    adc_channels: Vec<u8>,
    volts: Vec<f32>,
    edges: Vec<f64>,
}

impl Signals {
    /// Signals from interleaved voltages (`volts[k · channels + n]` is vector
    /// k of column n) [V], a sample rate [Hz] and keyphasor edge times
    /// [sample periods]; checks shapes and that the edges increase.
    pub fn new(
        sample_rate_hz: f64,
        adc_channels: Vec<u8>,
        volts: Vec<f32>,
        edges: Vec<f64>,
    ) -> Result<Self> {
        if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
            bail!("replay signals: sample rate {sample_rate_hz} Hz must be positive");
        }
        let n = adc_channels.len();
        if n == 0 {
            bail!("replay signals: no channels");
        }
        if !volts.len().is_multiple_of(n) {
            bail!(
                "replay signals: {} values are not a whole number of {n}-channel sample vectors",
                volts.len()
            );
        }
        if let Some(i) = volts.iter().position(|v| !v.is_finite()) {
            bail!(
                "replay signals: sample vector {}, column {} is not finite",
                i / n,
                i % n
            );
        }
        let k = volts.len() / n;
        for (i, w) in edges.windows(2).enumerate() {
            if w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater) {
                bail!(
                    "replay signals: keyphasor edge {} ({}) is not after edge {i} ({})",
                    i + 1,
                    w[1],
                    w[0]
                );
            }
        }
        if let Some((i, t)) = edges
            .iter()
            .enumerate()
            .find(|(_, t)| !(t.is_finite() && **t >= 0.0 && **t < k as f64))
        {
            bail!("replay signals: keyphasor edge {i} at {t} samples lies outside the {k} samples");
        }
        Ok(Self {
            sample_rate_hz,
            adc_channels,
            volts,
            edges,
        })
    }
}

impl ReplaySource for Signals {
    fn sample_rate_hz(&self) -> f64 {
        self.sample_rate_hz
    }
    fn adc_channels(&self) -> &[u8] {
        &self.adc_channels
    }
    fn sample_vectors(&self) -> usize {
        self.volts.len() / self.adc_channels.len()
    }
    fn volts(&self, vector: usize, column: usize) -> f32 {
        self.volts[vector * self.adc_channels.len() + column]
    }
    fn keyphasor_edges(&self) -> &[f64] {
        &self.edges
    }
}

/// A `plinth signals` signal set laid out as the configured ADC channels see
/// it: column c of a sample vector is the signal channel that measures what
/// configured channel c (in ADC order) measures.
#[derive(Clone, Debug)]
pub struct SignalSetReplay {
    set: SignalSet,
    columns: Vec<usize>,
    adc: Vec<u8>,
}

impl SignalSetReplay {
    /// Reads the signal set in `dir` and maps it onto `config`'s channels;
    /// every configured channel must be in the set with the same sensor kind
    /// and sensitivity (the box converts volts with the configured ones).
    pub fn load(dir: &Path, config: &StreamConfig) -> Result<Self> {
        let set = SignalSet::read(dir)?;
        Self::new(set, config).with_context(|| format!("replaying {}", dir.display()))
    }

    /// Maps an in-memory signal set onto `config`'s channels (see [`Self::load`]).
    pub fn new(set: SignalSet, config: &StreamConfig) -> Result<Self> {
        let mut columns = Vec::with_capacity(config.channels.len());
        for ch in &config.channels {
            let found =
                set.header.channels.iter().position(|s| {
                    s.bearing == ch.bearing && s.quantity.name() == ch.quantity.name()
                });
            let Some(col) = found else {
                bail!(
                    "configured ADC channel {} ({} {}) is not in the signal set (it has {})",
                    ch.adc,
                    ch.bearing,
                    ch.quantity,
                    set.header
                        .channels
                        .iter()
                        .map(|s| s.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                );
            };
            let s = &set.header.channels[col];
            let kind_matches = s.kind == ch.sensor;
            if !kind_matches {
                bail!(
                    "configured ADC channel {} ({} {}) is a {:?} sensor but the signal set's {} is {:?}",
                    ch.adc,
                    ch.bearing,
                    ch.quantity,
                    ch.sensor,
                    s.name,
                    s.kind
                );
            }
            if (s.sensitivity - ch.sensitivity).abs() > 1e-6 * ch.sensitivity.abs() {
                bail!(
                    "configured ADC channel {} ({} {}) has sensitivity {} {} but the signal set's {} was made with {}",
                    ch.adc,
                    ch.bearing,
                    ch.quantity,
                    ch.sensitivity,
                    ch.sensor.sensitivity_unit(),
                    s.name,
                    s.sensitivity
                );
            }
            columns.push(col);
        }
        let adc = config.channels.iter().map(|c| c.adc).collect();
        Ok(Self { set, columns, adc })
    }

    /// The signal set.
    pub fn set(&self) -> &SignalSet {
        &self.set
    }
}

impl ReplaySource for SignalSetReplay {
    fn sample_rate_hz(&self) -> f64 {
        self.set.header.sample_rate_hz
    }
    fn adc_channels(&self) -> &[u8] {
        &self.adc
    }
    fn sample_vectors(&self) -> usize {
        self.set.len()
    }
    fn volts(&self, vector: usize, column: usize) -> f32 {
        self.set.volts(vector, self.columns[column]) as f32
    }
    fn keyphasor_edges(&self) -> &[f64] {
        &self.set.keyphasor
    }
}

/// One block of the replay: sample vectors `start .. start + len` and the
/// keyphasor edges `edges` (indices into the source's edge list) inside it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BlockSpan {
    /// First sample vector.
    pub start: usize,
    /// Sample vectors in the block.
    pub len: usize,
    /// Edges inside the block.
    pub edges: std::ops::Range<usize>,
}

/// A replay cut into blocks that each fit one [`SampleBlock`] frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplayPlan {
    blocks: Vec<BlockSpan>,
    vectors: usize,
}

impl ReplayPlan {
    /// Cuts `source` into blocks of at most [`MAX_BLOCK_VALUES`] values and
    /// [`MAX_KEYPHASOR_EDGES`] edges.
    pub fn new(source: &dyn ReplaySource) -> Result<Self> {
        let n = source.adc_channels().len();
        if n == 0 || n > MAX_BLOCK_VALUES {
            bail!("replay signals: {n} channels do not fit a sample block");
        }
        let per_block = MAX_BLOCK_VALUES / n;
        let total = source.sample_vectors();
        let edges = source.keyphasor_edges();
        let mut blocks = Vec::with_capacity(total / per_block + 1);
        let mut start = 0usize;
        let mut e = 0usize;
        while start < total {
            let mut len = per_block.min(total - start);
            // Edges in [start, start + len).
            let first_edge = e;
            let mut last = e;
            while last < edges.len() && edges[last] < (start + len) as f64 {
                last += 1;
            }
            if last - first_edge > MAX_KEYPHASOR_EDGES {
                // Shorten the block to end just after the allowed edges.
                let cut = edges[first_edge + MAX_KEYPHASOR_EDGES].floor() as usize;
                len = cut.saturating_sub(start).max(1);
                last = first_edge;
                while last < edges.len() && edges[last] < (start + len) as f64 {
                    last += 1;
                }
                if last - first_edge > MAX_KEYPHASOR_EDGES {
                    bail!(
                        "replay signals: more than {MAX_KEYPHASOR_EDGES} keyphasor edges within one sample near sample {start}"
                    );
                }
            }
            blocks.push(BlockSpan {
                start,
                len,
                edges: first_edge..last,
            });
            e = last;
            start += len;
        }
        Ok(Self {
            blocks,
            vectors: total,
        })
    }

    /// Number of blocks.
    pub fn len(&self) -> usize {
        self.blocks.len()
    }

    /// True when there is nothing to replay.
    pub fn is_empty(&self) -> bool {
        self.blocks.is_empty()
    }

    /// Total sample vectors.
    pub fn sample_vectors(&self) -> usize {
        self.vectors
    }

    /// The block spans.
    pub fn spans(&self) -> &[BlockSpan] {
        &self.blocks
    }

    /// Index of the block starting at sample vector `vector`, if one does.
    pub fn block_starting_at(&self, vector: usize) -> Option<usize> {
        if vector == self.vectors {
            return Some(self.blocks.len());
        }
        self.blocks.binary_search_by_key(&vector, |b| b.start).ok()
    }

    /// The protocol message of block `index`, numbered for a box that was
    /// started at sample vector `box_origin` of the replay.
    pub fn block(&self, source: &dyn ReplaySource, index: usize, box_origin: usize) -> SampleBlock {
        let span = &self.blocks[index];
        let n = source.adc_channels().len();
        let mut block = SampleBlock {
            first_sample: (span.start.wrapping_sub(box_origin)) as u32,
            channels: n as u8,
            samples: Samples::Volts(Default::default()),
            keyphasor_edges: Default::default(),
        };
        if let Samples::Volts(values) = &mut block.samples {
            for k in span.start..span.start + span.len {
                for c in 0..n {
                    // Cannot overflow: len · n ≤ MAX_BLOCK_VALUES by construction.
                    let _ = values.push(source.volts(k, c));
                }
            }
        }
        for &t in &source.keyphasor_edges()[span.edges.clone()] {
            let offset = (t - span.start as f64) as f32;
            // f32 rounding may put an edge just below 0 or at len: clamp inside.
            let offset = offset.clamp(0.0, (span.len as f32) * (1.0 - f32::EPSILON));
            // Cannot overflow: at most MAX_KEYPHASOR_EDGES edges per span.
            let _ = block.keyphasor_edges.push(KeyphasorEdge {
                offset_samples: offset,
            });
        }
        block
    }
}

/// File name of the replay journal inside a run directory.
pub const JOURNAL_FILE: &str = "replay-journal.json";

/// How far a replay got: written as the box acknowledges blocks, read by a
/// restarted host to resume.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ReplayJournal {
    /// The replayed signals file.
    pub signals: PathBuf,
    /// Total sample vectors in it (to tell another file from the same one).
    pub sample_vectors: usize,
    /// Sample vectors the box has acknowledged (all before this one).
    pub acknowledged: usize,
    /// Sample vector at which the box was last started (its sample 0).
    pub box_origin: usize,
    /// The box was started and not stopped since.
    pub started: bool,
    /// Every block was acknowledged and the box stopped.
    pub finished: bool,
}

impl ReplayJournal {
    /// Reads the journal in `dir`, if there is one.
    pub fn read(dir: &Path) -> Result<Option<Self>> {
        let path = dir.join(JOURNAL_FILE);
        match std::fs::read_to_string(&path) {
            Ok(text) => serde_json::from_str(&text)
                .map(Some)
                .with_context(|| format!("{}: not a replay journal", path.display())),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(e).with_context(|| format!("cannot read {}", path.display())),
        }
    }

    /// Writes the journal into `dir` atomically (write, then rename).
    pub fn write(&self, dir: &Path) -> Result<()> {
        let path = dir.join(JOURNAL_FILE);
        let tmp = dir.join(format!("{JOURNAL_FILE}.tmp"));
        let text =
            serde_json::to_string_pretty(self).context("cannot encode the replay journal")?;
        std::fs::write(&tmp, text + "\n")
            .and_then(|()| std::fs::rename(&tmp, &path))
            .with_context(|| format!("cannot write {}", path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn signals(vectors: usize, channels: usize, edges: Vec<f64>) -> Signals {
        let volts = (0..vectors * channels).map(|i| i as f32).collect();
        Signals::new(1000.0, (0..channels as u8).collect(), volts, edges).unwrap()
    }

    #[test]
    fn blocks_cover_every_sample_and_edge_once() {
        let edges: Vec<f64> = (0..40).map(|i| 3.25 + 7.5 * i as f64).collect();
        let s = signals(301, 8, edges.clone());
        let plan = ReplayPlan::new(&s).unwrap();
        let mut next = 0;
        let mut seen_edges = Vec::new();
        for (i, span) in plan.spans().iter().enumerate() {
            assert_eq!(span.start, next);
            assert!(span.len * 8 <= MAX_BLOCK_VALUES);
            next += span.len;
            let b = plan.block(&s, i, 0);
            assert_eq!(b.sample_vectors().unwrap(), span.len);
            assert_eq!(b.first_sample as usize, span.start);
            for e in &b.keyphasor_edges {
                seen_edges.push(span.start as f64 + e.offset_samples as f64);
            }
            if let Samples::Volts(v) = &b.samples {
                assert_eq!(v[0], (span.start * 8) as f32);
            }
        }
        assert_eq!(next, 301);
        assert_eq!(seen_edges.len(), edges.len());
        for (a, b) in seen_edges.iter().zip(&edges) {
            assert!((a - b).abs() < 1e-3);
        }
        assert_eq!(plan.block_starting_at(12), Some(1));
        assert_eq!(plan.block_starting_at(301), Some(plan.len()));
        assert_eq!(plan.block_starting_at(13), None);
        // Renumbered for a box started at block 2.
        assert_eq!(plan.block(&s, 3, 24).first_sample, 12);
    }

    #[test]
    fn dense_edges_shorten_blocks() {
        // An edge every 1.1 samples: 96 values of 1 channel hold ~87 edges.
        let edges: Vec<f64> = (0..80).map(|i| 0.5 + 1.1 * i as f64).collect();
        let s = signals(100, 1, edges);
        let plan = ReplayPlan::new(&s).unwrap();
        for (i, _) in plan.spans().iter().enumerate() {
            let b = plan.block(&s, i, 0);
            assert!(b.keyphasor_edges.len() <= MAX_KEYPHASOR_EDGES);
            b.sample_vectors().unwrap();
        }
        let total: usize = plan.spans().iter().map(|b| b.edges.len()).sum();
        assert_eq!(total, 80);
    }

    #[test]
    fn bad_signals_are_refused() {
        assert!(Signals::new(0.0, vec![0], vec![0.0], vec![]).is_err());
        assert!(Signals::new(1.0, vec![0, 1], vec![0.0; 3], vec![]).is_err());
        assert!(Signals::new(1.0, vec![0], vec![0.0, f32::NAN], vec![]).is_err());
        let e = Signals::new(1.0, vec![0], vec![0.0; 4], vec![2.0, 1.0]).unwrap_err();
        assert!(e.to_string().contains("not after"), "{e}");
        assert!(Signals::new(1.0, vec![0], vec![0.0; 4], vec![4.0]).is_err());
    }

    #[test]
    fn journal_round_trips() {
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(ReplayJournal::read(dir.path()).unwrap(), None);
        let j = ReplayJournal {
            signals: "sig".into(),
            sample_vectors: 10,
            acknowledged: 4,
            box_origin: 2,
            started: true,
            finished: false,
        };
        j.write(dir.path()).unwrap();
        assert_eq!(ReplayJournal::read(dir.path()).unwrap(), Some(j));
    }
}
