//! The AD7606 in serial mode: CONVST → BUSY, the conversion's tagged
//! codes (every code says which conversion and channel it is), the
//! 128-bit output on DOUTA restarted by each CS falling edge.

use super::Hw;
use plinth_firmware::acquisition::rm0090::exti;

/// Conversions whose tags are unique (tag = 1 + channel + 8 · (g mod this)).
pub const TAG_PERIOD: u64 = 4000;

/// The code the AD7606 gives channel `c` of conversion `g` (since power-up):
/// the conversion and channel, recoverable from any delivered sample.
pub fn tag(g: u64, c: usize) -> i16 {
    (1 + c as u64 + 8 * (g % TAG_PERIOD)) as i16
}

/// (conversion mod [`TAG_PERIOD`], channel) of a code, if it is a tag.
pub fn untag(code: i16) -> Option<(u64, usize)> {
    if code < 1 || i64::from(code) > (8 * TAG_PERIOD) as i64 {
        return None;
    }
    let v = code as u64 - 1;
    Some((v / 8, (v % 8) as usize))
}

/// One conversion the AD7606 made.
#[derive(Clone, Copy, Debug)]
pub struct Conversion {
    /// Tick of its CONVST rising edge.
    pub tick: u64,
    /// TIM3 run (enables since power-up, from 1).
    pub run: u32,
    /// CONVST edges of that run before it (its sample index in the run).
    pub index: u64,
}

/// The AD7606 in serial mode, DOUTA only, CONVST A and B tied.
#[derive(Clone, Debug, Default)]
pub struct Adc {
    /// BUSY pin level.
    pub busy: bool,
    pub fall_at: Option<u64>,
    pub(super) converting: u64,
    /// Output register: conversion whose results are shifted out, and the
    /// tick it was loaded (the previous one before that).
    pub(super) output: Option<(u64, u64)>,
    pub(super) previous: Option<u64>,
    /// CS pin level (high = deselected).
    pub cs_high: bool,
    /// Ticks of the recent CS falling edges.
    pub(super) cs_falls: Vec<u64>,
    /// Ticks of the recent CS rising edges.
    pub(super) cs_rises: Vec<u64>,
    /// SCLK bits shifted since power-up, at the start of the frame in flight.
    pub(super) bits: u64,
    /// Bits shifted since power-up at each recent CS falling edge.
    pub(super) bits_at_fall: Vec<u64>,
}

impl Hw {
    /// CONVST rose: the AD7606 starts converting unless it is busy.
    pub(super) fn convst(&mut self, t: u64) {
        let index = self.tim3.edges;
        self.tim3.edges += 1;
        if index == 0 {
            self.run_starts.push(t);
        }
        if let Some((from, level)) = self.faults.busy_stuck {
            if t >= from {
                self.adc.busy = level;
                return;
            }
        }
        if self.adc.busy {
            return; // ignored during a conversion
        }
        self.adc.busy = true;
        self.adc.fall_at = Some(t + self.conversion_ticks);
        self.adc.converting = self.conversions.len() as u64;
        self.conversions.push(Conversion {
            tick: t,
            run: self.runs,
            index,
        });
    }

    /// BUSY fell: the results are in the output register; EXTI sees the edge.
    pub(super) fn busy_falls(&mut self, t: u64) {
        if let Some((from, _)) = self.faults.busy_stuck {
            if t >= from {
                return;
            }
        }
        self.adc.busy = false;
        self.adc.previous = self.adc.output.map(|o| o.0);
        self.adc.output = Some((self.adc.converting, t));
        if self.exti_ftsr & exti::LINE_BUSY != 0 {
            self.exti_pr |= exti::LINE_BUSY;
        }
    }

    /// The AD7606's DOUTA bit at tick `t`, SCLK bit number `bit` since
    /// power-up: bit (bits since the last CS fall) of the 128-bit output,
    /// 0 when CS is high or past the end.
    pub(super) fn douta(&self, t: u64, bit: u64) -> u16 {
        let Some(i) = self.adc.cs_falls.iter().rposition(|&f| f <= t) else {
            return 0;
        };
        let fall = self.adc.cs_falls[i];
        if self.adc.cs_rises.iter().any(|&r| r > fall && r <= t) {
            return 0;
        }
        let pos = bit - self.adc.bits_at_fall[i];
        if pos >= 128 {
            return 0;
        }
        let g = match self.adc.output {
            Some((g, at)) if at <= t => Some(g),
            _ => self.adc.previous,
        };
        let Some(g) = g else { return 0 };
        let code = tag(g, (pos / 16) as usize) as u16;
        (code >> (15 - pos % 16)) & 1
    }
}

/// Keeps the last few entries of an edge history.
pub(super) fn push_recent(v: &mut Vec<u64>, x: u64) {
    if v.len() >= 8 {
        v.remove(0);
    }
    v.push(x);
}
