//! The fixes of issue 18 that a test can switch off, one at a time, to show
//! that the board model's fault matrix catches the fault each one fixes
//! (crate `plinth-board-model`, `board-faults --revert NAME`). The box
//! never reverts anything: [`Revert::None`] everywhere in `plinth-box`.

/// One fix switched off (a runtime knob used only by tests and the bench).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Revert {
    /// Every fix in place (the box).
    #[default]
    None,
    /// `busy_fell` does not compare TIM5's count with the time this
    /// conversion's BUSY can fall: two BUSY edges merged while interrupts
    /// were masked go unseen.
    SlipDetector,
    /// SPI2's error interrupt stays disabled: an overrun is never counted
    /// as one.
    SpiErrorInterrupt,
    /// `stop` disables the SPI DMA requests without waiting for the
    /// conversion and the read in flight to end, and leaves the words the
    /// DMA did not take in SPI2's DR (no drain of DR/SR).
    StopDrain,
    /// The idle loop feeds the watchdog on every pass, whether acquisition
    /// progresses or not.
    WatchdogFeeding,
    /// The SPI prescaler is fixed at /4 and a read that does not fit the
    /// sample period is not refused.
    PrescalerRefusal,
}

impl Revert {
    /// Every fix that can be reverted.
    pub const ALL: [Revert; 5] = [
        Revert::SlipDetector,
        Revert::SpiErrorInterrupt,
        Revert::StopDrain,
        Revert::WatchdogFeeding,
        Revert::PrescalerRefusal,
    ];

    /// The name on the bench's command line (`--revert NAME`).
    pub fn name(self) -> &'static str {
        match self {
            Revert::None => "none",
            Revert::SlipDetector => "slip-detector",
            Revert::SpiErrorInterrupt => "spi-error-irq",
            Revert::StopDrain => "stop-drain",
            Revert::WatchdogFeeding => "watchdog-feeding",
            Revert::PrescalerRefusal => "prescaler-refusal",
        }
    }

    /// The fix named `name` ([`Revert::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        core::iter::once(Revert::None)
            .chain(Self::ALL)
            .find(|r| r.name() == name)
    }
}
