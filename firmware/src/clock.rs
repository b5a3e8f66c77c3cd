//! The STM32F405/407 clock tree the box runs on: what to program (PLL
//! factors, flash wait states, bus prescalers), the bring-up sequence with
//! its fall-backs when an oscillator does not start, and what the buses then
//! run at. Written against a [`Registers`] trait so that the host tests run
//! the sequence on a simulated RCC; `stm32::configure_clocks` runs it on the
//! real registers.
//!
//! Target: SYSCLK = HCLK = 168 MHz (the M4F's maximum), APB1 = 42 MHz,
//! APB2 = 84 MHz, USB/SDIO = 48 MHz, from the PLL fed by the crystal (HSE)
//! or, if the crystal does not start, by the 16 MHz internal RC (HSI).

/// Internal RC oscillator frequency [Hz].
pub const HSI_HZ: u32 = 16_000_000;
/// Core clock the box aims for [Hz].
pub const TARGET_SYSCLK_HZ: u32 = 168_000_000;
/// QEMU's netduinoplus2 core clock [Hz]: fixed by the model, which has no
/// RCC (its registers read 0 and writes are ignored).
pub const EMULATOR_SYSCLK_HZ: u32 = 168_000_000;

/// Where the core clock comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum ClockSource {
    /// The PLL from the crystal.
    PllFromHse,
    /// The PLL from the internal RC: the crystal did not start (timing then
    /// drifts with the RC's ±1 %: worth a look at the board).
    PllFromHsi,
    /// The internal RC alone: the PLL did not lock (the box runs at 16 MHz,
    /// ~25 % load for 8 channels at 51.2 kHz).
    Hsi,
    /// No RCC present (QEMU): the emulator's fixed clock.
    Emulator,
}

impl ClockSource {
    /// How the box reports this source to the host.
    pub fn sample_clock(self) -> plinth_shared::protocol::SampleClock {
        use plinth_shared::protocol::SampleClock;
        match self {
            ClockSource::PllFromHse => SampleClock::Crystal,
            ClockSource::PllFromHsi => SampleClock::RcOscillator,
            ClockSource::Hsi => SampleClock::RcOscillatorNoPll,
            ClockSource::Emulator => SampleClock::Emulated,
        }
    }
}

/// The bus frequencies the box ends up with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct Clocks {
    /// Core clock, also HCLK and what SysTick counts [Hz].
    pub sysclk_hz: u32,
    /// APB1 clock (TIM2-5 run at twice it when it is divided) [Hz].
    pub pclk1_hz: u32,
    /// APB2 clock (USART1, SPI1) [Hz].
    pub pclk2_hz: u32,
    /// Where SYSCLK comes from.
    pub source: ClockSource,
}

impl Clocks {
    /// The clocks straight after reset: everything on the 16 MHz HSI.
    pub const RESET: Clocks = Clocks {
        sysclk_hz: HSI_HZ,
        pclk1_hz: HSI_HZ,
        pclk2_hz: HSI_HZ,
        source: ClockSource::Hsi,
    };

    /// The emulator's clocks (QEMU ignores the USART's baud divider).
    pub const EMULATOR: Clocks = Clocks {
        sysclk_hz: EMULATOR_SYSCLK_HZ,
        pclk1_hz: EMULATOR_SYSCLK_HZ / 4,
        pclk2_hz: EMULATOR_SYSCLK_HZ / 2,
        source: ClockSource::Emulator,
    };
}

/// 32-bit register access by address (the MCU's memory map, or a model).
pub trait Registers {
    /// Reads the register at `addr`.
    fn read(&mut self, addr: usize) -> u32;
    /// Writes `value` to the register at `addr`.
    fn write(&mut self, addr: usize, value: u32);
    /// Read-modify-write of the bits in `mask`.
    fn modify(&mut self, addr: usize, mask: u32, value: u32) {
        let old = self.read(addr);
        self.write(addr, (old & !mask) | (value & mask));
    }
}

/// RCC clock control register.
pub const RCC_CR: usize = 0x4002_3800;
/// RCC PLL configuration register.
pub const RCC_PLLCFGR: usize = 0x4002_3804;
/// RCC clock configuration register.
pub const RCC_CFGR: usize = 0x4002_3808;
/// Flash access control register.
pub const FLASH_ACR: usize = 0x4002_3C00;
/// RCC_CR: HSI on.
pub const CR_HSION: u32 = 1 << 0;
/// RCC_CR: HSI ready.
pub const CR_HSIRDY: u32 = 1 << 1;
/// RCC_CR: HSE (crystal oscillator) on.
pub const CR_HSEON: u32 = 1 << 16;
/// RCC_CR: HSE ready.
pub const CR_HSERDY: u32 = 1 << 17;
/// RCC_CR: main PLL on.
pub const CR_PLLON: u32 = 1 << 24;
/// RCC_CR: main PLL locked.
pub const CR_PLLRDY: u32 = 1 << 25;
/// RCC_CFGR: system clock switch SW (bits 1:0); its status SWS is 2 bits up.
pub const CFGR_SW_MASK: u32 = 0b11;
/// RCC_CFGR: SW = PLL.
pub const CFGR_SW_PLL: u32 = 0b10;
/// RCC_CFGR: AHB prescaler (HPRE, bits 7:4), APB1 (PPRE1, 12:10), APB2
/// (PPRE2, 15:13).
pub const CFGR_PRESCALERS_MASK: u32 = 0xF << 4 | 0b111 << 10 | 0b111 << 13;
/// RCC_CFGR: AHB /1, APB1 /4 (PPRE1 = 101), APB2 /2 (PPRE2 = 100).
pub const CFGR_PRESCALERS: u32 = 0b101 << 10 | 0b100 << 13;
/// FLASH_ACR: prefetch, instruction and data caches (LATENCY in bits 2:0).
pub const ACR_CACHES: u32 = 1 << 8 | 1 << 9 | 1 << 10;
/// Reads of a ready bit before giving up: ≥ 10 ms at 16 MHz (HSE start-up
/// is ~2 ms, PLL lock ~0.1 ms).
pub const READY_POLLS: u32 = 50_000;

/// Whether the bits `mask` of `addr` read `value` within [`READY_POLLS`].
fn wait_for(regs: &mut impl Registers, addr: usize, mask: u32, value: u32) -> bool {
    (0..READY_POLLS).any(|_| regs.read(addr) & mask == value)
}

/// Runs the core at 168 MHz from the PLL, fed by the `hse_hz` [Hz] crystal
/// (`None`: no crystal fitted) or else by the 16 MHz HSI; APB1 at 42 MHz,
/// APB2 at 84 MHz, flash wait states and caches to match. Every wait is
/// bounded: a crystal that does not start leaves the PLL on the HSI, a PLL
/// that does not lock or a switch that does not happen leaves the core on
/// the HSI at 16 MHz; the returned [`Clocks`] say which. With no RCC
/// (QEMU: RCC_CR reads 0, which real silicon never does, coming out of
/// reset on the running HSI) nothing is written and the emulator's fixed
/// clock is returned.
pub fn configure(regs: &mut impl Registers, hse_hz: Option<u32>) -> Clocks {
    if regs.read(RCC_CR) & (CR_HSION | CR_HSIRDY) != CR_HSION | CR_HSIRDY {
        return Clocks::EMULATOR;
    }
    let crystal = hse_hz.and_then(|f| PllPlan::for_input(f).map(|p| (f, p)));
    let hse = crystal.filter(|_| {
        regs.modify(RCC_CR, CR_HSEON, CR_HSEON);
        let up = wait_for(regs, RCC_CR, CR_HSERDY, CR_HSERDY);
        if !up {
            regs.modify(RCC_CR, CR_HSEON, 0);
        }
        up
    });
    let (input_hz, plan, source) = match hse {
        Some((f, plan)) => (f, plan, ClockSource::PllFromHse),
        None => match PllPlan::for_input(HSI_HZ) {
            Some(plan) => (HSI_HZ, plan, ClockSource::PllFromHsi),
            None => return Clocks::RESET,
        },
    };
    // The PLL may only be reconfigured while it is off.
    regs.modify(RCC_CR, CR_PLLON, 0);
    if !wait_for(regs, RCC_CR, CR_PLLRDY, 0) {
        return Clocks::RESET;
    }
    regs.write(RCC_PLLCFGR, plan.pllcfgr(source == ClockSource::PllFromHse));
    regs.modify(RCC_CR, CR_PLLON, CR_PLLON);
    if !wait_for(regs, RCC_CR, CR_PLLRDY, CR_PLLRDY) {
        regs.modify(RCC_CR, CR_PLLON, 0);
        return Clocks::RESET;
    }
    let sysclk = plan.sysclk_hz(input_hz);
    // Slow the flash and the buses down before speeding the core up.
    regs.write(FLASH_ACR, ACR_CACHES | flash_wait_states(sysclk));
    regs.modify(RCC_CFGR, CFGR_PRESCALERS_MASK, CFGR_PRESCALERS);
    regs.modify(RCC_CFGR, CFGR_SW_MASK, CFGR_SW_PLL);
    if !wait_for(regs, RCC_CFGR, CFGR_SW_MASK << 2, CFGR_SW_PLL << 2) {
        // Still on the HSI: back to the reset prescalers, as RESET says.
        regs.modify(RCC_CFGR, CFGR_SW_MASK | CFGR_PRESCALERS_MASK, 0);
        return Clocks::RESET;
    }
    with_pll(sysclk, source)
}

/// PLL factors: f_VCO = f_in·N/M, SYSCLK = f_VCO/P, 48 MHz clock = f_VCO/Q.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PllPlan {
    /// Input divider M (2..=63), for a 1-2 MHz VCO input (1 MHz here: less
    /// jitter, RM0090 6.3.2).
    pub m: u32,
    /// VCO multiplier N (50..=432), for a 100-432 MHz VCO.
    pub n: u32,
    /// SYSCLK divider P (2, 4, 6 or 8).
    pub p: u32,
    /// USB/SDIO divider Q (2..=15).
    pub q: u32,
}

impl PllPlan {
    /// Factors for 168 MHz SYSCLK and 48 MHz from an input of `input_hz`
    /// [Hz]; `None` unless the input is a whole number of MHz in 4..=26
    /// (the HSE crystal range; the HSI is 16).
    pub fn for_input(input_hz: u32) -> Option<Self> {
        if !input_hz.is_multiple_of(1_000_000) || !(4_000_000..=26_000_000).contains(&input_hz) {
            return None;
        }
        // VCO 336 MHz: /2 = 168 MHz, /7 = 48 MHz.
        Some(Self {
            m: input_hz / 1_000_000,
            n: 336,
            p: 2,
            q: 7,
        })
    }

    /// SYSCLK [Hz] these factors give from `input_hz` [Hz].
    pub fn sysclk_hz(&self, input_hz: u32) -> u32 {
        input_hz / self.m * self.n / self.p
    }

    /// The RCC_PLLCFGR value (PLLSRC bit 22 set for the HSE).
    pub fn pllcfgr(&self, from_hse: bool) -> u32 {
        self.m | self.n << 6 | (self.p / 2 - 1) << 16 | u32::from(from_hse) << 22 | self.q << 24
    }
}

/// Flash wait states for `sysclk_hz` [Hz] at 2.7-3.6 V: one per 30 MHz
/// (RM0090 table 10), 5 at 168 MHz.
pub fn flash_wait_states(sysclk_hz: u32) -> u32 {
    sysclk_hz.saturating_sub(1) / 30_000_000
}

/// The clocks with the PLL running at `sysclk_hz` [Hz] from `source`, with
/// APB1 at /4 and APB2 at /2 (42 and 84 MHz at 168 MHz, their maxima).
pub fn with_pll(sysclk_hz: u32, source: ClockSource) -> Clocks {
    Clocks {
        sysclk_hz,
        pclk1_hz: sysclk_hz / 4,
        pclk2_hz: sysclk_hz / 2,
        source,
    }
}

/// USART baud-rate register for `baud` [bit/s] from the bus clock
/// `pclk_hz` [Hz] with 16× oversampling: f/baud in 12.4 fixed point, i.e.
/// f/baud rounded (RM0090 30.3.4).
pub fn usart_brr(pclk_hz: u32, baud: u32) -> u32 {
    ((pclk_hz + baud / 2) / baud.max(1)) & 0xFFFF
}

#[cfg(test)]
mod tests {
    use super::*;

    extern crate std;
    use std::collections::BTreeMap;
    use std::vec::Vec;

    /// An RCC and flash interface: oscillators that come up after a number
    /// of reads (or never), the clock switch that follows SW, and a log of
    /// every write.
    struct SimRcc {
        regs: BTreeMap<usize, u32>,
        /// Reads of RCC_CR after HSEON until HSERDY (None: never).
        hse_after: Option<u32>,
        /// Reads after PLLON until PLLRDY (None: never).
        pll_after: Option<u32>,
        hse_reads: u32,
        pll_reads: u32,
        writes: Vec<(usize, u32)>,
    }

    impl SimRcc {
        fn new(hse_after: Option<u32>, pll_after: Option<u32>) -> Self {
            let mut regs = BTreeMap::new();
            regs.insert(RCC_CR, 0x0000_0083); // reset: HSION | HSIRDY | trim
            regs.insert(RCC_PLLCFGR, 0x2400_3010);
            regs.insert(RCC_CFGR, 0);
            regs.insert(FLASH_ACR, 0);
            Self {
                regs,
                hse_after,
                pll_after,
                hse_reads: 0,
                pll_reads: 0,
                writes: Vec::new(),
            }
        }
        fn get(&self, addr: usize) -> u32 {
            self.regs.get(&addr).copied().unwrap_or(0)
        }
    }

    impl Registers for SimRcc {
        fn read(&mut self, addr: usize) -> u32 {
            if addr == RCC_CR {
                let mut cr = self.get(RCC_CR);
                if cr & CR_HSEON != 0 {
                    self.hse_reads += 1;
                    if self.hse_after.is_some_and(|n| self.hse_reads > n) {
                        cr |= CR_HSERDY;
                    }
                } else {
                    cr &= !CR_HSERDY;
                }
                if cr & CR_PLLON != 0 {
                    self.pll_reads += 1;
                    if self.pll_after.is_some_and(|n| self.pll_reads > n) {
                        cr |= CR_PLLRDY;
                    }
                } else {
                    cr &= !CR_PLLRDY;
                }
                self.regs.insert(RCC_CR, cr);
            }
            if addr == RCC_CFGR {
                // SWS follows SW once the PLL is locked (or SW is the HSI).
                let mut cfgr = self.get(RCC_CFGR);
                let sw = cfgr & CFGR_SW_MASK;
                let locked = self.get(RCC_CR) & CR_PLLRDY != 0;
                if sw != CFGR_SW_PLL || locked {
                    cfgr = (cfgr & !(CFGR_SW_MASK << 2)) | sw << 2;
                }
                self.regs.insert(RCC_CFGR, cfgr);
            }
            self.get(addr)
        }
        fn write(&mut self, addr: usize, value: u32) {
            self.writes.push((addr, value));
            // Ready flags are read-only.
            let keep = if addr == RCC_CR {
                CR_HSIRDY | CR_HSERDY | CR_PLLRDY
            } else {
                0
            };
            let old = self.get(addr);
            self.regs.insert(addr, (value & !keep) | (old & keep));
        }
    }

    /// Where in the write log the flash latency and the switch to the PLL are.
    fn order(rcc: &SimRcc) -> (usize, usize) {
        let latency = rcc
            .writes
            .iter()
            .position(|&(a, v)| a == FLASH_ACR && v & 7 == 5);
        let switch = rcc
            .writes
            .iter()
            .position(|&(a, v)| a == RCC_CFGR && v & CFGR_SW_MASK == CFGR_SW_PLL);
        (latency.expect("latency set"), switch.expect("switched"))
    }

    #[test]
    fn a_healthy_board_runs_at_168_mhz_from_the_crystal() {
        let mut rcc = SimRcc::new(Some(300), Some(20));
        let clocks = configure(&mut rcc, Some(8_000_000));
        assert_eq!(clocks, with_pll(168_000_000, ClockSource::PllFromHse));
        let cfgr = rcc.get(RCC_PLLCFGR);
        assert_eq!(cfgr, PllPlan::for_input(8_000_000).unwrap().pllcfgr(true));
        let (latency, switch) = order(&rcc);
        assert!(latency < switch, "flash slowed before the core speeds up");
        assert_eq!(rcc.get(RCC_CFGR) & CFGR_PRESCALERS_MASK, CFGR_PRESCALERS);
        assert_eq!(rcc.get(FLASH_ACR), ACR_CACHES | 5);
    }

    #[test]
    fn no_crystal_runs_the_pll_from_the_rc() {
        let mut rcc = SimRcc::new(None, Some(20));
        let clocks = configure(&mut rcc, Some(8_000_000));
        assert_eq!(clocks, with_pll(168_000_000, ClockSource::PllFromHsi));
        assert_eq!(rcc.get(RCC_CR) & CR_HSEON, 0, "dead oscillator off");
        assert_eq!((rcc.get(RCC_PLLCFGR) >> 22) & 1, 0, "PLL source HSI");
        assert_eq!(rcc.get(RCC_PLLCFGR) & 0x3F, 16);
        // A board declared without a crystal never tries it.
        let mut rcc = SimRcc::new(Some(0), Some(20));
        assert_eq!(configure(&mut rcc, None).source, ClockSource::PllFromHsi);
        assert_eq!(rcc.hse_reads, 0);
    }

    #[test]
    fn a_pll_that_does_not_lock_leaves_the_core_on_the_rc() {
        let mut rcc = SimRcc::new(Some(10), None);
        let clocks = configure(&mut rcc, Some(8_000_000));
        assert_eq!(clocks, Clocks::RESET);
        assert_eq!(rcc.get(RCC_CR) & CR_PLLON, 0);
        assert_eq!(rcc.get(RCC_CFGR) & CFGR_SW_MASK, 0, "never switched");
    }

    #[test]
    fn no_rcc_means_the_emulator() {
        struct Nothing;
        impl Registers for Nothing {
            fn read(&mut self, _: usize) -> u32 {
                0
            }
            fn write(&mut self, _: usize, _: u32) {
                panic!("nothing is written under the emulator");
            }
        }
        assert_eq!(configure(&mut Nothing, Some(8_000_000)), Clocks::EMULATOR);
    }

    #[test]
    fn pll_gives_168_and_48_mhz_from_the_crystal_or_the_rc() {
        for input in [8_000_000, 12_000_000, 16_000_000, 25_000_000] {
            let plan = PllPlan::for_input(input).unwrap();
            assert_eq!(plan.sysclk_hz(input), TARGET_SYSCLK_HZ);
            let vco = input / plan.m * plan.n;
            assert!((100_000_000..=432_000_000).contains(&vco));
            assert_eq!(vco / plan.q, 48_000_000);
            assert_eq!(input / plan.m, 1_000_000);
        }
        assert_eq!(PllPlan::for_input(7_372_800), None);
        assert_eq!(PllPlan::for_input(30_000_000), None);
    }

    #[test]
    fn pllcfgr_fields_are_where_rm0090_puts_them() {
        let plan = PllPlan::for_input(8_000_000).unwrap();
        let v = plan.pllcfgr(true);
        assert_eq!(v & 0x3F, 8);
        assert_eq!((v >> 6) & 0x1FF, 336);
        assert_eq!((v >> 16) & 0b11, 0, "P = 2");
        assert_eq!((v >> 22) & 1, 1, "HSE");
        assert_eq!((v >> 24) & 0xF, 7);
        assert_eq!((plan.pllcfgr(false) >> 22) & 1, 0, "HSI");
    }

    #[test]
    fn wait_states_follow_the_voltage_range_table() {
        assert_eq!(flash_wait_states(16_000_000), 0);
        assert_eq!(flash_wait_states(30_000_000), 0);
        assert_eq!(flash_wait_states(30_000_001), 1);
        assert_eq!(flash_wait_states(168_000_000), 5);
    }

    #[test]
    fn buses_stay_within_their_maxima() {
        let c = with_pll(TARGET_SYSCLK_HZ, ClockSource::PllFromHse);
        assert_eq!(c.pclk1_hz, 42_000_000);
        assert_eq!(c.pclk2_hz, 84_000_000);
    }

    #[test]
    fn baud_divider_is_within_half_a_percent() {
        for (pclk, baud) in [
            (16_000_000, 115_200),
            (84_000_000, 115_200),
            (84_000_000, 921_600),
        ] {
            let brr = usart_brr(pclk, baud);
            let actual = pclk as f64 / brr as f64;
            assert!((actual / baud as f64 - 1.0).abs() < 5e-3, "{pclk} {baud}");
        }
    }
}
