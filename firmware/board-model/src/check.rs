//! The truth check of a scenario. Every delivered sample vector says which
//! conversion it is (the source's sample count since its last restart,
//! plus its index in the buffer) and the model knows which conversion was
//! taken at that instant; every code carries its conversion and channel
//! ([`crate::hw::tag`]). A **silent corruption** is a delivered sample
//! whose conversion or channel differs, a delivered keyphasor edge more
//! than [`EDGE_TOLERANCE`] from every true edge (or a second one for the
//! same edge), or a gap reported with the wrong length. An **uncounted
//! loss** is a gap the buffer does not announce (`lost_before` 0), sample
//! periods neither delivered nor reported by the end (a silent stall), or
//! true keyphasor edges inside delivered samples that are missing beyond
//! what the counters (dropped edges, lost captures) account for.

use crate::hw::{untag, Hw, TAG_PERIOD};
use plinth_firmware::acquisition::adc_dma::AdcFaults;
use plinth_firmware::acquisition::dma_source::DmaSourceCounters;
use plinth_firmware::ad7606::Range;
use plinth_firmware::source::SampleBuffer;

/// Largest error of a delivered keyphasor edge that is still that edge
/// [samples] (the filter's phase gives ≤ 0.01; a slip gives ≥ 1).
pub const EDGE_TOLERANCE: f64 = 0.1;

/// What a scenario showed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Outcome {
    /// The box refused to sample (the read does not fit the period).
    pub refused: bool,
    /// Sample vectors delivered (each checked).
    pub delivered: u64,
    /// Keyphasor edges delivered (each checked).
    pub edges: u64,
    /// Silent corruptions (samples, edges, wrong gap lengths).
    pub corruptions: u64,
    /// Samples and edges lost without a counter saying so.
    pub uncounted: u64,
    /// Samples reported lost (`lost_before`).
    pub reported_lost: u64,
    /// Restarts after sequence faults.
    pub resyncs: u32,
    /// The hardware fault counters.
    pub faults: AdcFaults,
    /// Hardware faults the model saw that no counter shows (an SPI
    /// overrun with `spi_errors` 0).
    pub unreported: u64,
    /// Faults the box did not recover from as it should: a passing fault
    /// that needed the watchdog, or a permanent one with no sample and no
    /// watchdog reset.
    pub unrecovered: u64,
    /// Sequence faults a commanded stop/restart caused (a clean restart
    /// causes none).
    pub unclean: u64,
    /// The model's watchdog reset the box (the scenario ended there).
    pub watchdog_reset: bool,
    /// The first problem found, described.
    pub first_problem: Option<String>,
}

impl Outcome {
    /// The outcome of a refused acquisition.
    pub fn refused() -> Self {
        Self {
            refused: true,
            ..Self::default()
        }
    }

    /// Whether anything is wrong (a corruption, an uncounted loss, an
    /// unreported fault, a failed recovery).
    pub fn failed(&self) -> bool {
        self.corruptions + self.uncounted + self.unreported + self.unrecovered + self.unclean > 0
    }

    /// Records `text` as the first problem unless one is already there.
    pub fn problem(&mut self, text: impl FnOnce() -> String) {
        if self.first_problem.is_none() {
            self.first_problem = Some(text());
        }
    }
}

/// Checks delivered buffers as they come.
pub struct Checker {
    p: f64,
    /// True keyphasor rising edges [ticks].
    pulses: Vec<u64>,
    /// Model run of the previous delivered buffer, and its end.
    last: Option<(u32, u64)>,
    /// The run a Start command began.
    start_run: u32,
    /// Whether a buffer was delivered since that Start.
    since_start: bool,
    dropped_seen: u32,
    dropped: u64,
    true_edges: u64,
    matched: u64,
    out: Outcome,
}

impl Checker {
    /// A checker for `p` ticks per sample and true keyphasor edges `pulses`.
    pub fn new(p: f64, pulses: Vec<u64>) -> Self {
        Self {
            p,
            pulses,
            last: None,
            start_run: 0,
            since_start: false,
            dropped_seen: 0,
            dropped: 0,
            true_edges: 0,
            matched: 0,
            out: Outcome::default(),
        }
    }

    /// A Start command began `run`.
    pub fn started(&mut self, run: u32) {
        self.start_run = run;
        self.since_start = false;
        self.last = None;
        self.dropped_seen = 0;
    }

    /// Folds in the source's counters (which a Start resets).
    pub fn counters(&mut self, c: DmaSourceCounters) {
        let d = c.dropped_edges;
        self.dropped += u64::from(if d >= self.dropped_seen {
            d - self.dropped_seen
        } else {
            d
        });
        self.dropped_seen = d;
        self.out.resyncs = self.out.resyncs.max(c.resyncs);
    }

    /// A delivered buffer whose first vector the source places at sample
    /// `first` of its current run.
    pub fn delivered(&mut self, hw: &Hw, buf: &SampleBuffer, first: u64, c: DmaSourceCounters) {
        self.counters(c);
        let run = hw.runs;
        let lost = u64::from(buf.lost_before);
        let n = buf.samples.len() as u64;
        self.out.reported_lost += lost;
        // The time index the pipeline will use must agree with the claim.
        match self.last {
            Some((r, end)) if r == run => {
                if first < end || lost != first - end {
                    self.gap_error(lost, first - end.min(first), run, first);
                }
            }
            None if !self.since_start && run == self.start_run => {
                if lost != first {
                    self.gap_error(lost, first, run, first);
                }
            }
            _ => {
                // A restart after a fault: a gap of unknown length, which
                // must be announced.
                if lost == 0 {
                    self.out.uncounted += 1;
                    self.out.problem(|| {
                        format!("run {run}: restart gap not announced (lost_before 0)")
                    });
                }
            }
        }
        self.since_start = true;
        self.last = Some((run, first + n));
        // Every sample.
        let step = Range::PlusMinus10V.volts_per_code();
        for (i, v) in buf.samples.iter().enumerate() {
            let index = first + i as u64;
            let truth = conversion_at(hw, run, index);
            let bad = v.iter().enumerate().find_map(|(ch, &x)| {
                let code = (x / step).round() as i16;
                match (untag(code), truth) {
                    (Some((g, c)), Some(t)) if g == t % TAG_PERIOD && c == ch => None,
                    (got, _) => Some((ch, got)),
                }
            });
            self.out.delivered += 1;
            if let Some((ch, got)) = bad {
                self.out.corruptions += 1;
                self.out.problem(|| {
                    format!(
                        "run {run} sample {index} channel {ch}: got {got:?}, truth conversion {truth:?}"
                    )
                });
            }
        }
        // Every edge, and the true edges inside these samples.
        let Some(&t0) = hw.run_starts.get(run as usize - 1) else {
            return;
        };
        let pos_of = |tick: u64| (tick as f64 - t0 as f64) / self.p;
        let lo = if lost > 0 {
            first as f64
        } else {
            first as f64 - 1.0
        };
        let hi = (first + n) as f64 - 1.0;
        self.true_edges += self
            .pulses
            .iter()
            .filter(|&&t| t >= t0 && (lo..hi).contains(&pos_of(t)))
            .count() as u64;
        let mut used: Option<usize> = None;
        for e in &buf.edges {
            self.out.edges += 1;
            let pos = (first + e.index as u64) as f64 - 1.0 + f64::from(e.fraction);
            let nearest = self
                .pulses
                .iter()
                .enumerate()
                .filter(|(_, &t)| t >= t0)
                .min_by(|a, b| {
                    (pos_of(*a.1) - pos)
                        .abs()
                        .total_cmp(&(pos_of(*b.1) - pos).abs())
                });
            match nearest {
                Some((k, &t)) if (pos_of(t) - pos).abs() <= EDGE_TOLERANCE && used != Some(k) => {
                    used = Some(k);
                    self.matched += 1;
                }
                other => {
                    self.out.corruptions += 1;
                    let want = other.map(|(_, &t)| pos_of(t));
                    self.out.problem(|| {
                        format!("run {run}: keyphasor edge at sample {pos:.4}, nearest true edge {want:?}")
                    });
                }
            }
        }
    }

    fn gap_error(&mut self, lost: u64, gap: u64, run: u32, first: u64) {
        if lost == 0 {
            self.out.uncounted += gap;
        } else {
            self.out.corruptions += 1;
        }
        self.out.problem(|| {
            format!("run {run}: buffer at sample {first} reports {lost} lost, the gap is {gap}")
        });
    }

    /// The end: silent stalls, missing edges, unreported overruns.
    /// `allowance` [ticks] is how far behind the source may legitimately
    /// be; after a watchdog `reset` (which the next boot reports) the
    /// samples since the last delivery are not a silent stall.
    pub fn finish(
        mut self,
        hw: &Hw,
        c: DmaSourceCounters,
        faults: AdcFaults,
        allowance: u64,
        reset: bool,
    ) -> Outcome {
        self.counters(c);
        self.out.faults = faults;
        if hw.spi_overruns > 0 && faults.spi_errors == 0 {
            self.out.unreported += u64::from(hw.spi_overruns);
            let n = hw.spi_overruns;
            self.out
                .problem(|| format!("{n} SPI overruns in the hardware, spi_errors 0 (unreported)"));
        }
        let run = hw.runs;
        let delivered_to = match self.last {
            Some((r, end)) if r == run => end,
            _ => 0,
        };
        let due = hw.tim3.edges.saturating_sub(allowance / self.p as u64);
        if due > delivered_to && !reset {
            let n = due - delivered_to;
            self.out.uncounted += n;
            self.out.problem(|| {
                format!("run {run}: {n} sample periods neither delivered nor reported lost (a silent stall)")
            });
        }
        let missing = self.true_edges.saturating_sub(self.matched);
        let counted = self.dropped + u64::from(faults.lost_captures);
        if missing > counted {
            self.out.uncounted += missing - counted;
            self.out.problem(|| {
                format!(
                    "{missing} keyphasor edges missing from delivered samples, {counted} counted"
                )
            });
        }
        self.out
    }
}

/// The conversion (number since power-up) taken at sample `index` of TIM3
/// run `run`.
fn conversion_at(hw: &Hw, run: u32, index: u64) -> Option<u64> {
    hw.conversions
        .binary_search_by(|c| (c.run, c.index).cmp(&(run, index)))
        .ok()
        .map(|g| g as u64)
}
