//! Instruction counts of the box's hot paths, measured under
//! `qemu-system-arm -M netduinoplus2 -icount shift=10` (see
//! `scripts/bench-firmware.sh`).
//!
//! With `-icount shift=10` QEMU advances virtual time by 2¹⁰ ns per
//! instruction, so SysTick on the 168 MHz core clock advances 172.032 ticks
//! per instruction (DWT CYCCNT reads 0 under QEMU). SysTick is 24 bits
//! (≈ 97 500 instructions), so each measured block stays well below that and
//! larger figures are sums of blocks. The fixed cost of a measurement (the
//! two counter reads) is measured on an empty block and subtracted.
//!
//! Prints `BENCH <name> <value>` lines over semihosting, then exits.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("plinth-firmware-bench is an MCU image: run scripts/bench-firmware.sh");
    std::process::exit(2);
}

#[cfg(target_os = "none")]
mod image {
    use defmt_semihosting as _;
    use panic_semihosting as _;

    use core::f32::consts::TAU;
    use cortex_m::peripheral::{syst::SystClkSource, SYST};
    use cortex_m_rt::entry;
    use cortex_m_semihosting::{debug, hprintln};
    use plinth_firmware::acquisition::dma_source::{AcquisitionHardware, DmaSource};
    use plinth_firmware::acquisition::handover::{DoubleBuffer, HalfCompletions};
    use plinth_firmware::ad7606::Range;
    use plinth_firmware::source::{SampleBuffer, SampleSource};
    use plinth_shared::bearing::BearingCoefficients;
    use plinth_shared::extractor::{
        Event, ExtractorConfig, KeyphasorEdge, PhasorExtractor, Sensor,
    };
    use plinth_shared::phasor::Complex;
    use plinth_shared::protocol::{
        HostMessage, KeyphasorEdge as WireEdge, Receiver, SampleBlock, Samples, Transmitter,
        MAX_BLOCK_VALUES, MAX_FRAME_SIZE,
    };
    use plinth_shared::rls::PedestalRls;

    /// SysTick ticks per instruction at 168 MHz with -icount shift=10.
    const TICKS_PER_INSTRUCTION: f32 = 172.032;
    /// Channels of the box.
    const N: usize = 8;
    /// Samples per revolution of the synthetic signal (50 Hz at 51.2 kHz).
    const PERIOD: usize = 1024;
    /// Sample vectors per measured extractor block.
    const BLOCK: usize = 64;

    /// Sample vectors per DMA half (as in plinth-box).
    const HALF: usize = plinth_firmware::source::BUFFER_VECTORS;

    /// The DMA double buffer in RAM, filled by the CPU, with one keyphasor
    /// capture per half.
    struct RamHalves {
        memory: [[[i16; N]; HALF]; 2],
        done: HalfCompletions,
        capture: Option<u32>,
    }

    impl RamHalves {
        fn new() -> Self {
            Self {
                memory: [[[0; N]; HALF]; 2],
                done: HalfCompletions::new(),
                capture: None,
            }
        }

        /// Writes half `h` as the DMA would and counts it complete.
        fn fill_and_complete(&mut self, h: usize) {
            for (v, vector) in self.memory[h % 2].iter_mut().enumerate() {
                for (c, code) in vector.iter_mut().enumerate() {
                    *code = (libm::sinf((h * HALF + v) as f32 * 0.05 + c as f32) * 3000.0) as i16;
                }
            }
            self.capture = Some(((h * HALF + 40) * 1641 + 800) as u32);
            self.done.complete();
        }
    }

    impl DoubleBuffer for RamHalves {
        fn completed(&self) -> u32 {
            self.done.count()
        }
        fn read(&self, half: usize, vector: usize) -> [i16; N] {
            // Volatile and clamped, as plinth-box reads its DMA memory.
            let p: *const [i16; N] = &self.memory[half.min(1)][vector.min(HALF - 1)];
            // SAFETY: a reference to an element of the array just above.
            unsafe { p.read_volatile() }
        }
    }

    impl AcquisitionHardware for RamHalves {
        fn start(&mut self) -> u32 {
            self.done.reset();
            0
        }
        fn stop(&mut self) {}
        fn take_capture(&mut self) -> Option<u32> {
            self.capture.take()
        }
    }

    /// Runs `f` and returns the SysTick ticks it took.
    #[inline(never)]
    fn ticks(mut f: impl FnMut()) -> u32 {
        let start = SYST::get_current();
        f();
        let end = SYST::get_current();
        start.wrapping_sub(end) & 0x00FF_FFFF
    }

    /// Instructions of `f`, net of the measurement's own cost.
    fn instructions(overhead: u32, f: impl FnMut()) -> f32 {
        ticks(f).saturating_sub(overhead) as f32 / TICKS_PER_INSTRUCTION
    }

    /// One synthetic sample vector: 1X plus DC on every channel [V].
    fn sample(k: usize) -> [f32; N] {
        let theta = TAU * (k % PERIOD) as f32 / PERIOD as f32;
        core::array::from_fn(|c| 0.5 * libm::cosf(theta + 0.3 * c as f32) - 1.0 + 0.01 * c as f32)
    }

    #[entry]
    fn main() -> ! {
        let Some(mut cp) = cortex_m::Peripherals::take() else {
            cortex_m::asm::udf()
        };
        cp.SYST.set_clock_source(SystClkSource::Core);
        cp.SYST.set_reload(0x00FF_FFFF);
        cp.SYST.clear_current();
        cp.SYST.enable_counter();
        let overhead = ticks(|| {});
        hprintln!("BENCH overhead_ticks {}", overhead);

        // ---- phasor extractor, 8 channels ----
        let sensors = [Sensor::displacement(7870.0); N];
        let Ok(mut ex) = PhasorExtractor::<N>::new(ExtractorConfig::new(51_200.0, sensors)) else {
            hprintln!("BENCH error extractor config");
            debug::exit(debug::EXIT_FAILURE);
            cortex_m::asm::udf()
        };
        let mut buf = [[0.0f32; N]; PERIOD];
        for (k, v) in buf.iter_mut().enumerate() {
            *v = sample(k);
        }
        let mut phasors = 0u32;
        let mut sink = |e: Event<N>| {
            if let Event::Phasors(_) = e {
                phasors += 1;
            }
        };
        let edge = [KeyphasorEdge {
            index: 0,
            fraction: 0.25,
        }];
        // Lock on: a few revolutions with an edge at the start of each.
        for _ in 0..5 {
            let _ = ex.update_block(&buf, &edge, &mut sink);
        }
        if !ex.is_tracking() {
            hprintln!("BENCH error extractor not tracking");
        }
        // Steady state between edges: blocks of 64 vectors.
        let mut between = 0.0f32;
        let mut measured = 0usize;
        // One revolution = edge block + 15 plain blocks.
        let mut revolution = 0.0f32;
        for rev in 0..4 {
            for b in 0..PERIOD / BLOCK {
                let block = &buf[b * BLOCK..(b + 1) * BLOCK];
                let edges: &[KeyphasorEdge] = if b == 0 { &edge } else { &[] };
                let n = instructions(overhead, || {
                    let _ = ex.update_block(block, edges, &mut sink);
                });
                revolution += n;
                if b != 0 && rev > 0 {
                    between += n;
                    measured += BLOCK * N;
                }
            }
        }
        let per_sample_steady = between / measured as f32;
        let per_sample_all = revolution / (4 * PERIOD * N) as f32;
        hprintln!(
            "BENCH extractor_instr_per_channel_sample_between_edges {}",
            per_sample_steady
        );
        hprintln!(
            "BENCH extractor_instr_per_channel_sample_with_edges {}",
            per_sample_all
        );
        hprintln!("BENCH extractor_revolutions_emitted {}", phasors);

        // ---- pedestal RLS: one speed = 4 equations, weighted by the noise
        // of its phasors (the pipeline's path) ----
        let mut rls = PedestalRls::<f32>::default();
        let theta = [8.0e6f32, 6.0e6, 150.0, 2000.0, 1500.0];
        let bearing = BearingCoefficients::isotropic(2.0e8f32, 2.0e4);
        let mut update = 0.0f32;
        let mut plain = PedestalRls::<f32>::default();
        let mut plain_update = 0.0f32;
        let mut estimate = 0.0f32;
        let updates = 50;
        for i in 0..updates {
            let f = 20.0 + i as f32;
            let w = TAU * f;
            let rel = [
                Complex::from_polar(1e-5, 0.1 * i as f32),
                Complex::from_polar(2e-5, -0.2 * i as f32),
            ];
            let force = bearing.force(w, &rel);
            let dyn_y = Complex::new(theta[0] - w * w * theta[2], w * theta[3]);
            let dyn_z = Complex::new(theta[1] - w * w * theta[2], w * theta[4]);
            let ped = [force[0] / dyn_y, force[1] / dyn_z];
            let rel_sd = [1e-8f32, 2e-8];
            let ped_sd = [3e-9f32, 4e-9];
            update += instructions(overhead, || {
                let _ = rls.update_weighted(w, &ped, &rel, &bearing, rel_sd, ped_sd);
            });
            plain_update += instructions(overhead, || {
                let _ = plain.update(w, &ped, &force);
            });
        }
        hprintln!(
            "BENCH rls_instr_per_unweighted_update {}",
            plain_update / updates as f32
        );
        for _ in 0..10 {
            estimate += instructions(overhead, || {
                let _ = core::hint::black_box(rls.estimate());
            });
        }
        hprintln!("BENCH rls_instr_per_update {}", update / updates as f32);
        hprintln!(
            "BENCH rls_instr_per_equation {}",
            update / (4 * updates) as f32
        );
        hprintln!("BENCH rls_instr_per_estimate {}", estimate / 10.0);

        // ---- one received replay frame: 96 ADC codes, 1 edge ----
        let mut codes = heapless::Vec::<i16, MAX_BLOCK_VALUES>::new();
        for k in 0..MAX_BLOCK_VALUES {
            let _ = codes.push((libm::sinf(k as f32 * 0.1) * 3000.0) as i16);
        }
        let mut edges = heapless::Vec::new();
        let _ = edges.push(WireEdge {
            offset_samples: 3.5,
        });
        let block = HostMessage::Samples(SampleBlock {
            first_sample: 0,
            channels: N as u8,
            samples: Samples::AdcCodes(codes),
            keyphasor_edges: edges,
        });
        let mut wire = [0u8; MAX_FRAME_SIZE];
        let mut tx = Transmitter::new();
        let len = match tx.encode(&block, &mut wire) {
            Ok((_, bytes)) => bytes.len(),
            Err(_) => 0,
        };
        let mut rx = Receiver::<HostMessage>::new();
        let mut frames = 0u32;
        let mut receive = 0.0f32;
        let repeats = 10;
        for _ in 0..repeats {
            // Each repeat is a new session's first frame (seq 0 again).
            rx.reset();
            receive += instructions(overhead, || {
                for &b in &wire[..len] {
                    if let Some(Ok(_)) = rx.push_byte(b) {
                        frames += 1;
                    }
                }
            });
        }
        hprintln!("BENCH frame_bytes {}", len);
        hprintln!("BENCH frames_decoded {}", frames);
        hprintln!("BENCH receive_instr_per_frame {}", receive / repeats as f32);
        hprintln!(
            "BENCH receive_instr_per_byte {}",
            receive / (repeats * len) as f32
        );

        // ---- the board's acquisition consumer: one DMA half taken ----
        let mut source = DmaSource::new(RamHalves::new(), HALF, 1641, Range::PlusMinus10V);
        source.start().unwrap();
        let mut out = SampleBuffer::default();
        let mut taken = 0.0f32;
        let halves = 20;
        for h in 0..halves {
            source.hardware_mut().fill_and_complete(h);
            taken += instructions(overhead, || {
                out.clear();
                source.poll(&mut out);
            });
        }
        if out.samples.len() != HALF || out.edges.len() != 1 {
            hprintln!("BENCH error acquisition took {} vectors", out.samples.len());
        }
        hprintln!("BENCH acquisition_instr_per_half {}", taken / halves as f32);
        hprintln!(
            "BENCH acquisition_instr_per_vector {}",
            taken / (halves * HALF) as f32
        );
        debug::exit(debug::EXIT_SUCCESS);
        cortex_m::asm::udf()
    }
}
