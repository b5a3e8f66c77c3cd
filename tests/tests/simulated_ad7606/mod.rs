//! A simulated AD7606 and capture timer for the firmware's driver: an
//! embedded-hal 1.0 SPI device, CONVST and BUSY pins and a free-running
//! 32-bit timer with keyphasor input capture, sharing one state as on the
//! board, serving a simulator signal set's i16 codes sample by sample and
//! its keyphasor times.

use embedded_hal::digital::{ErrorType as PinErrorType, InputPin, OutputPin};
use embedded_hal::spi::{ErrorKind, ErrorType as SpiErrorType, Operation, SpiDevice};
use plinth::sim::signals::SignalSet;
use plinth_firmware::adc_source::CaptureTimer;
use std::cell::RefCell;
use std::convert::Infallible;
use std::rc::Rc;

/// Timer ticks per sample period: TIM2 at 84 MHz over 51.2 kHz, rounded
/// (the simulated timer clock is 1641 × the sample rate).
pub const TICKS_PER_SAMPLE: u32 = 1641;
/// BUSY polls that read high after each CONVST edge (≈ 4 µs conversion).
const BUSY_POLLS: u32 = 3;
/// Timer count at `start()`: the 32-bit counter wraps during the run.
const TIMER_START: u32 = u32::MAX - 40_000_000;

/// The simulated AD7606 and capture timer: one state shared by the SPI
/// device, the pins and the timer, as on the board.
pub struct Hardware {
    /// The signal set whose codes and keyphasor the hardware serves.
    pub set: SignalSet,
    /// Timer count now [ticks] (wrapping like the 32-bit counter).
    clock: u32,
    /// Sample periods since TIMER_START at `clock`.
    slot: u64,
    /// CONVST level.
    convst_high: bool,
    /// The sample latched by the last CONVST rising edge, not yet read.
    latched: Option<usize>,
    /// BUSY polls left that read high.
    busy_left: u32,
    /// Next keyphasor pulse not yet taken.
    pub next_pulse: usize,
    /// Conversions served.
    pub conversions: usize,
}

impl Hardware {
    /// Hardware serving `set` from its first sample, the timer at
    /// TIMER_START, nothing converted or captured yet.
    pub fn serving(set: SignalSet) -> Shared {
        Rc::new(RefCell::new(Hardware {
            set,
            clock: TIMER_START,
            slot: 0,
            convst_high: false,
            latched: None,
            busy_left: 0,
            next_pulse: 0,
            conversions: 0,
        }))
    }

    /// Timer count of keyphasor pulse j [ticks], rounded to the tick.
    fn pulse_tick(&self, j: usize) -> u32 {
        let ticks = (self.set.keyphasor[j] * f64::from(TICKS_PER_SAMPLE)).round() as u64;
        TIMER_START.wrapping_add(ticks as u32)
    }

    /// Sample periods since TIMER_START of keyphasor pulse j, in ticks.
    fn pulse_ticks_from_start(&self, j: usize) -> u64 {
        (self.set.keyphasor[j] * f64::from(TICKS_PER_SAMPLE)).round() as u64
    }
}

/// The one state the SPI device, the pins and the timer share.
pub type Shared = Rc<RefCell<Hardware>>;

/// The SPI device (DOUTA, CS framed): 8 big-endian 16-bit words per
/// conversion, only after a CONVST edge and with BUSY low.
pub struct SimSpi(pub Shared);
/// The CONVST output.
pub struct SimConvst(pub Shared);
/// The BUSY input.
pub struct SimBusy(pub Shared);
/// The free-running timer with keyphasor input capture.
pub struct SimTimer(pub Shared);

impl SpiErrorType for SimSpi {
    type Error = ErrorKind;
}

impl SpiDevice for SimSpi {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), ErrorKind> {
        let mut hw = self.0.borrow_mut();
        for op in operations {
            let Operation::Read(buf) = op else {
                return Err(ErrorKind::Other); // the AD7606 has no DIN in use
            };
            assert_eq!(buf.len(), 16, "one conversion is 8 words of 16 bits");
            assert_eq!(hw.busy_left, 0, "read while BUSY is high");
            let k = hw.latched.take().expect("SPI read without a conversion");
            let n = hw.set.channels();
            for (c, pair) in buf.chunks_exact_mut(2).enumerate() {
                pair.copy_from_slice(&hw.set.codes[k * n + c].to_be_bytes());
            }
            hw.conversions += 1;
            // The main loop comes back exactly at the next slot while there
            // are samples left; at the end the timer stays put.
            if k + 1 < hw.set.len() {
                hw.clock = hw.clock.wrapping_add(TICKS_PER_SAMPLE);
                hw.slot += 1;
            }
        }
        Ok(())
    }
}

impl PinErrorType for SimConvst {
    type Error = Infallible;
}

impl OutputPin for SimConvst {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.0.borrow_mut().convst_high = false;
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        let mut hw = self.0.borrow_mut();
        if !hw.convst_high {
            // Rising edge: sample all eight inputs now.
            let k = hw.slot as usize;
            assert!(k < hw.set.len(), "conversion after the end of the run");
            assert!(hw.latched.is_none(), "conversion result never read");
            hw.latched = Some(k);
            hw.busy_left = BUSY_POLLS;
        }
        hw.convst_high = true;
        Ok(())
    }
}

impl PinErrorType for SimBusy {
    type Error = Infallible;
}

impl InputPin for SimBusy {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        let mut hw = self.0.borrow_mut();
        let high = hw.busy_left > 0;
        hw.busy_left = hw.busy_left.saturating_sub(1);
        Ok(high)
    }
    fn is_low(&mut self) -> Result<bool, Infallible> {
        self.is_high().map(|h| !h)
    }
}

impl CaptureTimer for SimTimer {
    fn now(&mut self) -> u32 {
        self.0.borrow().clock
    }
    fn take_edge(&mut self) -> Option<u32> {
        let mut hw = self.0.borrow_mut();
        let j = hw.next_pulse;
        // Captured only once the counter has passed it.
        if j < hw.set.keyphasor.len()
            && hw.pulse_ticks_from_start(j) <= hw.slot * u64::from(TICKS_PER_SAMPLE)
        {
            hw.next_pulse += 1;
            Some(hw.pulse_tick(j))
        } else {
            None
        }
    }
}
