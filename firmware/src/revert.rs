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
    /// `stop` leaves the words the DMA did not take in SPI2's DR and OVR
    /// set (no drain of DR/SR); it still waits for BUSY low and SPI idle.
    StopDrain,
    /// `stop` does not wait for the conversion in flight to end (BUSY
    /// low) before it clears EXTI0's pending bit; its other steps stay.
    StopWaitBusy,
    /// `stop` disables the SPI DMA requests and the streams without
    /// waiting for the read in flight to end (transmit stream done, SPI
    /// idle); its other steps stay.
    StopWaitSpiIdle,
    /// The idle loop feeds the watchdog on every pass, whether acquisition
    /// progresses or not.
    WatchdogFeeding,
    /// The SPI prescaler is fixed at /4 and a read that does not fit the
    /// sample period is not refused.
    PrescalerRefusal,
}

impl Revert {
    /// Every fix that can be reverted.
    pub const ALL: [Revert; 7] = [
        Revert::SlipDetector,
        Revert::SpiErrorInterrupt,
        Revert::StopDrain,
        Revert::StopWaitBusy,
        Revert::StopWaitSpiIdle,
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
            Revert::StopWaitBusy => "stop-wait-busy",
            Revert::StopWaitSpiIdle => "stop-wait-spi-idle",
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
