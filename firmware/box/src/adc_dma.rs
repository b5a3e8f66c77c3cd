//! The acquisition hardware of the reference board, behind
//! [`AcquisitionHardware`]: TIM3 paces CONVST, BUSY's falling edge (EXTI0)
//! starts an 8-word SPI2 read by DMA, the SPI2 receive DMA (DMA1 stream 3,
//! channel 0) fills a double buffer, TIM5 timestamps the keyphasor.
//!
//! Which interrupt touches what: `busy_fell` owns DMA1 stream 4 (SPI2 TX)
//! and the CS pin; `adc_half` owns stream 3's flags and [`COMPLETIONS`];
//! `keyphasor` owns TIM5's capture registers and the capture queue's
//! producer; this type (idle) owns the rest and stops every interrupt
//! source before reconfiguring. DMA1's flag-clear registers are write-1-
//! to-clear, so writes for different streams never race.

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicU32, Ordering};
use heapless::spsc::Consumer;
use plinth_firmware::acquisition::dma_source::AcquisitionHardware;
use plinth_firmware::acquisition::handover::{DoubleBuffer, HalfCompletions};
use plinth_firmware::acquisition::pacing::ConvstTiming;
use plinth_firmware::source::{BUFFER_VECTORS, CHANNELS};
use stm32f4xx_hal::pac;

/// Sample vectors per DMA half: one pipeline buffer (96 vectors, 1.9 ms at
/// 51.2 kHz; two halves are 3 KiB).
pub const HALF_VECTORS: usize = BUFFER_VECTORS;
/// 16-bit words per half.
const HALF_WORDS: usize = HALF_VECTORS * CHANNELS;
/// Capture queue slots (a heapless spsc queue holds one fewer).
pub const CAPTURE_SLOTS: usize = 32;

/// Capture ticks between the CONVST timer's first rising edge and the
/// count TIM5 latches for an edge at that instant: the TI2 input filter
/// (8 samples at f_CK_INT) and resynchronisation (2 ticks) delay the
/// capture, TIM5 starting on TIM3's trigger (1 tick later) advances it:
/// +9 ticks, 0.0055 sample at 51.2 kHz. An estimate from RM0090's
/// description; the hardware-in-the-loop procedure measures it.
pub const CAPTURE_OFFSET_TICKS: u32 = 9;

/// The two halves the SPI receive DMA writes (16-bit words, 4-aligned).
#[repr(C, align(4))]
pub struct AdcMemory(UnsafeCell<[[[i16; CHANNELS]; HALF_VECTORS]; 2]>);

// SAFETY: written only by the DMA, read only by the idle task through
// volatile reads; the hand-over protocol (handover.rs) decides which half
// may be read.
unsafe impl Sync for AdcMemory {}

/// The DMA's target.
pub static ADC_MEMORY: AdcMemory = AdcMemory(UnsafeCell::new([[[0; CHANNELS]; HALF_VECTORS]; 2]));

/// The word the SPI2 transmit DMA clocks out (the AD7606 ignores DIN in
/// serial read mode).
pub static TX_DUMMY: u16 = 0;

/// Halves the receive DMA completed (written by the `adc_half` interrupt).
pub static COMPLETIONS: HalfCompletions = HalfCompletions::new();

/// BUSY fell while the previous 8-word read was still running: that
/// conversion was not read, so the source restarts acquisition (counted in
/// its `resyncs`, the samples since its last half as overruns).
pub static LATE_READS: AtomicU32 = AtomicU32::new(0);
/// DMA transfer errors on the ADC streams.
pub static DMA_ERRORS: AtomicU32 = AtomicU32::new(0);
/// Keyphasor edges lost in the capture hardware (overcapture) or queue.
pub static LOST_CAPTURES: AtomicU32 = AtomicU32::new(0);

/// Adds one to a counter owned by one interrupt (load and store: no
/// read-modify-write needed).
pub fn bump(counter: &AtomicU32) {
    counter.store(
        counter.load(Ordering::Relaxed).wrapping_add(1),
        Ordering::Relaxed,
    );
}

/// DMA1, whose streams are shared out as described in the module doc.
pub fn dma1() -> &'static pac::dma1::RegisterBlock {
    // SAFETY: the register block is static; each stream is used by one
    // context (module doc), flag clears are write-1-to-clear.
    unsafe { &*pac::DMA1::ptr() }
}

/// SPI2 receive stream.
pub const RX_STREAM: usize = 3;
/// SPI2 transmit stream.
pub const TX_STREAM: usize = 4;

/// TIM3 (CONVST), TIM5 (capture), SPI2 and DMA1 streams 3 and 4.
pub struct AdcDma {
    tim3: pac::TIM3,
    tim5: pac::TIM5,
    spi: pac::SPI2,
    timing: ConvstTiming,
    captures: Consumer<'static, u32, CAPTURE_SLOTS>,
}

impl AdcDma {
    /// Configures the timers, SPI2 and the DMA streams (clocks enabled,
    /// pins in their alternate functions); nothing runs until
    /// [`AcquisitionHardware::start`].
    pub fn new(
        tim3: pac::TIM3,
        tim5: pac::TIM5,
        spi: pac::SPI2,
        timing: ConvstTiming,
        captures: Consumer<'static, u32, CAPTURE_SLOTS>,
    ) -> Self {
        // CONVST: TIM3 channel 1, PWM mode 2 (low, then high from CCR1 to
        // the end of the period), TRGO on enable to start TIM5.
        tim3.cr1().write(|w| w.arpe().enabled());
        tim3.psc().write(|w| w.psc().set(timing.prescaler));
        tim3.arr().write(|w| w.arr().set(timing.auto_reload as u16));
        tim3.ccr1().write(|w| w.ccr().set(timing.compare as u16));
        tim3.ccmr1_output()
            .write(|w| w.oc1m().pwm_mode2().oc1pe().enabled());
        tim3.ccer().write(|w| w.cc1e().set_bit());
        tim3.cr2().write(|w| w.mms().enable());
        tim3.egr().write(|w| w.ug().update());
        // Keyphasor: TIM5 channel 2 captures TI2's rising edges, filtered
        // over 8 clock ticks; the counter runs free over 32 bits from the
        // trigger of TIM3's enable (ITR1).
        tim5.psc().write(|w| w.psc().set(0));
        tim5.arr().write(|w| w.arr().set(u32::MAX));
        tim5.ccmr1_input()
            .write(|w| w.cc2s().ti2().ic2f().fck_int_n8());
        tim5.ccer().write(|w| w.cc2e().set_bit());
        tim5.smcr().write(|w| w.ts().itr1().sms().trigger_mode());
        tim5.egr().write(|w| w.ug().update());
        tim5.sr().write(|w| unsafe { w.bits(0) });
        tim5.dier().write(|w| w.cc2ie().enabled());
        // SPI2: master, mode 2 (clock idles high, data taken on the falling
        // edge, as the AD7606 shifts on the rising one), 42 MHz / 4 =
        // 10.5 MHz, 16-bit frames MSB first, CS by GPIO, both DMA requests.
        spi.cr1().write(|w| {
            w.mstr()
                .master()
                .cpol()
                .idle_high()
                .cpha()
                .first_edge()
                .br()
                .div4()
                .dff()
                .sixteen_bit()
                .ssm()
                .enabled()
                .ssi()
                .slave_not_selected()
        });
        spi.cr2()
            .write(|w| w.rxdmaen().enabled().txdmaen().enabled());
        spi.cr1().modify(|_, w| w.spe().enabled());
        Self {
            tim3,
            tim5,
            spi,
            timing,
            captures,
        }
    }

    /// The CONVST timing in use.
    pub fn timing(&self) -> ConvstTiming {
        self.timing
    }

    /// Disables a DMA stream and waits (bounded) until it has stopped.
    fn disable_stream(n: usize) {
        let st = dma1().st(n);
        st.cr().modify(|_, w| w.en().disabled());
        for _ in 0..1000 {
            if st.cr().read().en().is_disabled() {
                break;
            }
        }
    }

    /// Clears every flag of a stream (LIFCR for 0-3, HIFCR for 4-7).
    pub fn clear_stream_flags(n: usize) {
        let shift = [0, 6, 16, 22][n % 4];
        let bits = 0b11_1101u32 << shift;
        // SAFETY: write-1-to-clear bits of stream n only.
        if n < 4 {
            dma1().lifcr().write(|w| unsafe { w.bits(bits) });
        } else {
            dma1().hifcr().write(|w| unsafe { w.bits(bits) });
        }
    }
}

impl DoubleBuffer for AdcDma {
    fn completed(&self) -> u32 {
        COMPLETIONS.count()
    }

    fn read(&self, half: usize, vector: usize) -> [i16; CHANNELS] {
        let half = half.min(1);
        let vector = vector.min(HALF_VECTORS - 1);
        // SAFETY: in bounds (clamped above); the DMA writes this memory
        // concurrently, hence volatile; whether the copy stands is decided
        // by the hand-over's completion check.
        unsafe {
            let base = ADC_MEMORY.0.get().cast::<[i16; CHANNELS]>();
            base.add(half * HALF_VECTORS + vector).read_volatile()
        }
    }
}

impl AcquisitionHardware for AdcDma {
    fn start(&mut self) -> u32 {
        self.stop();
        COMPLETIONS.reset();
        let dr = self.spi.dr().as_ptr() as u32;
        let memory = ADC_MEMORY.0.get() as u32;
        // Receive: SPI2 DR → the two halves, double-buffer mode, 16-bit.
        let rx = dma1().st(RX_STREAM);
        Self::clear_stream_flags(RX_STREAM);
        rx.par().write(|w| unsafe { w.bits(dr) });
        rx.m0ar().write(|w| unsafe { w.bits(memory) });
        rx.m1ar()
            .write(|w| unsafe { w.bits(memory + 2 * HALF_WORDS as u32) });
        rx.ndtr().write(|w| w.ndt().set(HALF_WORDS as u16));
        rx.fcr().write(|w| w.dmdis().clear_bit());
        rx.cr().write(|w| {
            w.chsel()
                .set(0)
                .dbm()
                .enabled()
                .ct()
                .memory0()
                .pl()
                .very_high()
                .msize()
                .bits16()
                .psize()
                .bits16()
                .minc()
                .incremented()
                .pinc()
                .fixed()
                .dir()
                .peripheral_to_memory()
                .tcie()
                .enabled()
                .teie()
                .enabled()
        });
        // Transmit: the dummy word, 8 times per conversion (armed by the
        // BUSY interrupt).
        let tx = dma1().st(TX_STREAM);
        Self::clear_stream_flags(TX_STREAM);
        tx.par().write(|w| unsafe { w.bits(dr) });
        tx.m0ar()
            .write(|w| unsafe { w.bits(core::ptr::addr_of!(TX_DUMMY) as u32) });
        tx.fcr().write(|w| w.dmdis().clear_bit());
        tx.cr().write(|w| {
            w.chsel()
                .set(0)
                .pl()
                .high()
                .msize()
                .bits16()
                .psize()
                .bits16()
                .minc()
                .fixed()
                .pinc()
                .fixed()
                .dir()
                .memory_to_peripheral()
        });
        // Stale received words out of the SPI.
        let _ = self.spi.dr().read();
        let _ = self.spi.sr().read();
        rx.cr().modify(|_, w| w.en().enabled());
        while self.captures.dequeue().is_some() {}
        self.tim5.cnt().write(|w| w.cnt().set(0));
        self.tim5.sr().write(|w| unsafe { w.bits(0) });
        self.tim3.cnt().write(|w| w.cnt().set(0));
        // Go: TIM3 counts, its TRGO starts TIM5 on the same clock.
        self.tim3.cr1().modify(|_, w| w.cen().enabled());
        self.timing
            .first_rise_ticks
            .wrapping_add(CAPTURE_OFFSET_TICKS)
    }

    fn stop(&mut self) {
        self.tim3.cr1().modify(|_, w| w.cen().disabled());
        self.tim5.cr1().modify(|_, w| w.cen().disabled());
        Self::disable_stream(TX_STREAM);
        Self::disable_stream(RX_STREAM);
    }

    fn take_capture(&mut self) -> Option<u32> {
        self.captures.dequeue()
    }

    fn sequence_faults(&self) -> u32 {
        LATE_READS
            .load(Ordering::Relaxed)
            .wrapping_add(DMA_ERRORS.load(Ordering::Relaxed))
    }
}
