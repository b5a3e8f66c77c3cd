//! A progress line on stderr for long batch commands (`simulate`, ...).
//!
//! Shown only when stderr is a terminal and the work has run for more than a
//! second, redrawn at most five times a second, and erased at the end, so
//! that scripts, pipes and `--json` on stdout never see it.

use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

/// A throttled `LABEL: DONE/TOTAL (PCT %), ELAPSED s` line on stderr.
#[derive(Debug)]
pub struct Ticker {
    label: String,
    total: usize,
    enabled: bool,
    started: Instant,
    last: Option<Instant>,
    shown: bool,
}

impl Ticker {
    /// A ticker over `total` steps; `enabled` false never prints (e.g.
    /// `--quiet`); stderr not being a terminal disables it too.
    pub fn new(label: &str, total: usize, enabled: bool) -> Ticker {
        Ticker {
            label: label.to_string(),
            total,
            enabled: enabled && std::io::stderr().is_terminal(),
            started: Instant::now(),
            last: None,
            shown: false,
        }
    }

    /// `done` of the total steps are finished.
    pub fn tick(&mut self, done: usize) {
        if !self.enabled {
            return;
        }
        let now = Instant::now();
        if now - self.started < Duration::from_secs(1)
            || self
                .last
                .is_some_and(|t| now - t < Duration::from_millis(200))
        {
            return;
        }
        self.last = Some(now);
        self.shown = true;
        let pct = 100.0 * done as f64 / self.total.max(1) as f64;
        let mut err = std::io::stderr().lock();
        let _ = write!(
            err,
            "\r{}: {done}/{} ({pct:.0} %), {:.1} s\x1b[K",
            self.label,
            self.total,
            self.started.elapsed().as_secs_f64()
        );
        let _ = err.flush();
    }

    /// Erases the line (if it was shown).
    pub fn finish(&mut self) {
        if self.shown {
            let mut err = std::io::stderr().lock();
            let _ = write!(err, "\r\x1b[K");
            let _ = err.flush();
            self.shown = false;
        }
    }
}

impl Drop for Ticker {
    fn drop(&mut self) {
        self.finish();
    }
}
