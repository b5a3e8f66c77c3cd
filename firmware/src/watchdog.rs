//! The main loop's watchdog hook: a pass that hangs resets the box; on the
//! board, acquisition that stops making progress does too
//! ([`ProgressWatch`]).

use crate::revert::Revert;

/// Something that must be fed regularly or it resets the MCU.
pub trait Watchdog {
    /// Restarts the watchdog's countdown.
    fn feed(&mut self);
}

/// No watchdog (host tests).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoWatchdog;

impl Watchdog for NoWatchdog {
    fn feed(&mut self) {}
}

/// Decides whether the idle loop may feed the watchdog: always while
/// acquisition is stopped on purpose; while it runs, only if the DMA
/// completed a half within the last `limit_ms` [ms] (a BUSY line stuck,
/// or restarts that never deliver, end in a watchdog reset that the next
/// boot reports).
#[derive(Clone, Copy, Debug)]
pub struct ProgressWatch {
    limit_ms: u32,
    /// Feeds on every pass (the policy before issue 18; tests only).
    every_pass: bool,
    last: u32,
    since_ms: u32,
}

impl ProgressWatch {
    /// A watch that tolerates `limit_ms` [ms] without progress.
    pub const fn new(limit_ms: u32) -> Self {
        Self {
            limit_ms,
            every_pass: false,
            last: 0,
            since_ms: 0,
        }
    }

    /// The same watch with `revert` applied: [`Revert::WatchdogFeeding`]
    /// feeds on every pass (tests only: the board model shows what that
    /// misses).
    pub const fn with_revert(mut self, revert: Revert) -> Self {
        self.every_pass = matches!(revert, Revert::WatchdogFeeding);
        self
    }

    /// Whether to feed now (`now_ms` [ms], wrapping): `running` says
    /// whether acquisition should run, `progress` is the half-completion
    /// count.
    pub fn should_feed(&mut self, running: bool, progress: u32, now_ms: u32) -> bool {
        if self.every_pass || !running || progress != self.last {
            self.last = progress;
            self.since_ms = now_ms;
            return true;
        }
        now_ms.wrapping_sub(self.since_ms) < self.limit_ms
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fed_while_stopped_or_progressing_starved_by_a_stall() {
        let mut w = ProgressWatch::new(100);
        assert!(w.should_feed(false, 0, 0));
        assert!(w.should_feed(false, 0, 10_000));
        assert!(w.should_feed(true, 1, 10_001));
        assert!(w.should_feed(true, 1, 10_100));
        assert!(!w.should_feed(true, 1, 10_101));
        assert!(w.should_feed(true, 2, 10_200));
        assert!(w.should_feed(false, 2, 20_000));
        let mut old = ProgressWatch::new(100).with_revert(Revert::WatchdogFeeding);
        assert!(old.should_feed(true, 1, 0));
        assert!(old.should_feed(true, 1, 10_000));
    }
}
