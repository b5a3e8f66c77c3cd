//! The main loop's watchdog hook: every pass feeds it, so a pass that hangs
//! resets the box.

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
