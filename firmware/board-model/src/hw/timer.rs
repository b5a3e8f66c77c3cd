//! TIM3 and TIM5 (the parts the firmware uses): counting, PWM compare
//! (CONVST), input capture behind TIM5's digital filter.

use super::Hw;
use plinth_firmware::acquisition::rm0090::tim;

/// A general-purpose timer (the parts of TIM3/TIM5 the firmware uses).
#[derive(Clone, Debug, Default)]
pub struct Timer {
    pub cr1: u32,
    pub cr2: u32,
    pub smcr: u32,
    pub dier: u32,
    pub sr: u32,
    pub ccmr1: u32,
    pub ccer: u32,
    pub psc: u32,
    pub arr: u32,
    pub ccr1: u32,
    pub ccr2: u32,
    /// Counter at `since` (when running).
    pub(super) cnt: u32,
    pub(super) since: u64,
    /// Tick of the next compare match (TIM3: CONVST rising edge).
    pub next_compare: Option<u64>,
    /// CONVST edges since the last enable.
    pub edges: u64,
}

impl Timer {
    pub(super) fn running(&self) -> bool {
        self.cr1 & tim::CR1_CEN != 0
    }
    pub(super) fn period(&self) -> u64 {
        u64::from(self.arr) + 1
    }
    /// The counter at `now`.
    pub fn count(&self, now: u64) -> u32 {
        if !self.running() {
            return self.cnt;
        }
        let n = u64::from(self.cnt) + (now - self.since) / (u64::from(self.psc) + 1);
        if self.arr == u32::MAX {
            n as u32
        } else {
            (n % self.period()) as u32
        }
    }
    pub(super) fn rebase(&mut self, now: u64, cnt: u32) {
        self.cnt = cnt;
        self.since = now;
    }
    /// Schedules the next compare match of channel 1 (PWM mode 2: CONVST
    /// rises when the counter reaches CCR1).
    pub(super) fn schedule_compare(&mut self, now: u64) {
        if !self.running() {
            self.next_compare = None;
            return;
        }
        let c = u64::from(self.count(now));
        let p = self.period();
        let mut d = (u64::from(self.ccr1) + p - c % p) % p;
        if d == 0 {
            d = p;
        }
        self.next_compare = Some(now + d * (u64::from(self.psc) + 1));
    }
}

impl Hw {
    /// TIM5 latches a (filtered, resynchronised) keyphasor edge.
    pub(super) fn capture(&mut self, t: u64) {
        if self.tim5.ccer & tim::CCER_CC2E == 0 {
            return;
        }
        if self.tim5.sr & tim::SR_CC2IF != 0 {
            self.tim5.sr |= tim::SR_CC2OF;
        }
        self.tim5.ccr2 = self.tim5.count(t);
        self.tim5.sr |= tim::SR_CC2IF;
    }
}

/// Ticks at which TIM5's channel 2 latches the rising edges of an input
/// with `transitions` (tick, level) through the digital filter (f_DTS/32,
/// N = 8: the output changes after 8 equal samples taken every 32 ticks)
/// and 2 ticks of resynchronisation.
pub fn filtered_captures(transitions: &[(u64, bool)], step: u64, n: u64) -> Vec<u64> {
    let mut out = Vec::new();
    let (mut run_level, mut run_count, mut output) = (false, 0u64, false);
    for (i, &(t, level)) in transitions.iter().enumerate() {
        let end = transitions.get(i + 1).map_or(t + 1_000_000, |x| x.0);
        let first = t.div_ceil(step) * step;
        if first >= end {
            continue; // no sample sees this level
        }
        let samples = (end - 1 - first) / step + 1;
        let before = if level == run_level { run_count } else { 0 };
        run_level = level;
        run_count = before + samples;
        if run_count >= n && output != level {
            output = level;
            if level {
                let k = n.saturating_sub(before + 1);
                out.push(first + k * step + 2);
            }
        }
    }
    out
}
