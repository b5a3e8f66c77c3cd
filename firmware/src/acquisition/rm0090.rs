//! The STM32F405/407 registers and bits the acquisition path uses, from the
//! reference manual RM0090 (section numbers in each doc line). The code
//! reaches them through [`crate::clock::Registers`] (address access): the
//! MCU's memory map on the board, the host's board model in the tests.

/// DMA1 (RM0090 10.5).
pub mod dma1 {
    /// DMA1 base address.
    pub const BASE: usize = 0x4002_6000;
    /// Low interrupt status register (streams 0-3).
    pub const LISR: usize = BASE;
    /// High interrupt status register (streams 4-7).
    pub const HISR: usize = BASE + 0x04;
    /// Low interrupt flag clear register (write 1 to clear).
    pub const LIFCR: usize = BASE + 0x08;
    /// High interrupt flag clear register (write 1 to clear).
    pub const HIFCR: usize = BASE + 0x0C;
    /// Stream `n`'s configuration register.
    #[inline]
    pub const fn cr(n: usize) -> usize {
        BASE + 0x10 + 0x18 * n
    }
    /// Stream `n`'s number of data items (remaining) register.
    #[inline]
    pub const fn ndtr(n: usize) -> usize {
        cr(n) + 0x04
    }
    /// Stream `n`'s peripheral address register.
    #[inline]
    pub const fn par(n: usize) -> usize {
        cr(n) + 0x08
    }
    /// Stream `n`'s memory 0 address register.
    #[inline]
    pub const fn m0ar(n: usize) -> usize {
        cr(n) + 0x0C
    }
    /// Stream `n`'s memory 1 address register (double-buffer mode).
    #[inline]
    pub const fn m1ar(n: usize) -> usize {
        cr(n) + 0x10
    }
    /// Stream `n`'s FIFO control register.
    #[inline]
    pub const fn fcr(n: usize) -> usize {
        cr(n) + 0x14
    }
    /// The status (and clear) register of stream `n`, and the shift of its
    /// flags in it.
    #[inline]
    pub const fn flags(n: usize) -> (usize, usize, u32) {
        let shift = [0, 6, 16, 22][n % 4];
        if n < 4 {
            (LISR, LIFCR, shift)
        } else {
            (HISR, HIFCR, shift)
        }
    }
    /// Flag (before the stream's shift): FIFO error.
    pub const FEIF: u32 = 1 << 0;
    /// Flag: direct-mode error.
    pub const DMEIF: u32 = 1 << 2;
    /// Flag: transfer error.
    pub const TEIF: u32 = 1 << 3;
    /// Flag: half transfer.
    pub const HTIF: u32 = 1 << 4;
    /// Flag: transfer complete.
    pub const TCIF: u32 = 1 << 5;
    /// Every flag of a stream.
    pub const ALL_FLAGS: u32 = FEIF | DMEIF | TEIF | HTIF | TCIF;
    /// SxCR: stream enable.
    pub const CR_EN: u32 = 1 << 0;
    /// SxCR: direct-mode error interrupt enable.
    pub const CR_DMEIE: u32 = 1 << 1;
    /// SxCR: transfer error interrupt enable.
    pub const CR_TEIE: u32 = 1 << 2;
    /// SxCR: half transfer interrupt enable.
    pub const CR_HTIE: u32 = 1 << 3;
    /// SxCR: transfer complete interrupt enable.
    pub const CR_TCIE: u32 = 1 << 4;
    /// SxCR: direction memory to peripheral (DIR = 01; 00 is peripheral to memory).
    pub const CR_DIR_M2P: u32 = 0b01 << 6;
    /// SxCR: circular mode.
    pub const CR_CIRC: u32 = 1 << 8;
    /// SxCR: memory address increment.
    pub const CR_MINC: u32 = 1 << 10;
    /// SxCR: peripheral data size 16 bit (PSIZE = 01).
    pub const CR_PSIZE_16: u32 = 0b01 << 11;
    /// SxCR: memory data size 16 bit (MSIZE = 01).
    pub const CR_MSIZE_16: u32 = 0b01 << 13;
    /// SxCR: priority level (PL, 2 bits).
    #[inline]
    pub const fn cr_pl(level: u32) -> u32 {
        (level & 0b11) << 16
    }
    /// SxCR: double-buffer mode.
    pub const CR_DBM: u32 = 1 << 18;
    /// SxCR: current target (memory 1 when set).
    pub const CR_CT: u32 = 1 << 19;
    /// SxCR: channel selection (CHSEL, 3 bits).
    #[inline]
    pub const fn cr_chsel(channel: u32) -> u32 {
        (channel & 0b111) << 25
    }
}

/// SPI2 (RM0090 28.5).
pub mod spi2 {
    /// SPI2 base address.
    pub const BASE: usize = 0x4000_3800;
    /// Control register 1.
    pub const CR1: usize = BASE;
    /// Control register 2.
    pub const CR2: usize = BASE + 0x04;
    /// Status register.
    pub const SR: usize = BASE + 0x08;
    /// Data register.
    pub const DR: usize = BASE + 0x0C;
    /// CR1: clock phase (0: data captured on the first edge).
    pub const CR1_CPHA: u32 = 1 << 0;
    /// CR1: clock polarity (1: SCK idles high).
    pub const CR1_CPOL: u32 = 1 << 1;
    /// CR1: master.
    pub const CR1_MSTR: u32 = 1 << 2;
    /// CR1: baud rate divider f_PCLK / 2^(BR+1) (BR, 3 bits).
    #[inline]
    pub const fn cr1_br(br: u32) -> u32 {
        (br & 0b111) << 3
    }
    /// CR1: the BR field.
    pub const CR1_BR_MASK: u32 = 0b111 << 3;
    /// CR1: SPI enable.
    pub const CR1_SPE: u32 = 1 << 6;
    /// CR1: internal slave select.
    pub const CR1_SSI: u32 = 1 << 8;
    /// CR1: software slave management.
    pub const CR1_SSM: u32 = 1 << 9;
    /// CR1: 16-bit frames.
    pub const CR1_DFF: u32 = 1 << 11;
    /// CR2: receive DMA request enable.
    pub const CR2_RXDMAEN: u32 = 1 << 0;
    /// CR2: transmit DMA request enable.
    pub const CR2_TXDMAEN: u32 = 1 << 1;
    /// CR2: error interrupt enable (OVR, MODF, CRCERR).
    pub const CR2_ERRIE: u32 = 1 << 5;
    /// SR: receive buffer not empty.
    pub const SR_RXNE: u32 = 1 << 0;
    /// SR: transmit buffer empty.
    pub const SR_TXE: u32 = 1 << 1;
    /// SR: mode fault.
    pub const SR_MODF: u32 = 1 << 5;
    /// SR: overrun (a word arrived while RXNE was still set; cleared by
    /// reading DR then SR).
    pub const SR_OVR: u32 = 1 << 6;
    /// SR: busy (a frame is being shifted).
    pub const SR_BSY: u32 = 1 << 7;
}

/// General-purpose timers TIM3 and TIM5 (RM0090 18.4).
pub mod tim {
    /// TIM3 base address (CONVST).
    pub const TIM3: usize = 0x4000_0400;
    /// TIM5 base address (keyphasor capture, 32 bit).
    pub const TIM5: usize = 0x4000_0C00;
    /// Control register 1.
    pub const CR1: usize = 0x00;
    /// Control register 2.
    pub const CR2: usize = 0x04;
    /// Slave mode control register.
    pub const SMCR: usize = 0x08;
    /// DMA/interrupt enable register.
    pub const DIER: usize = 0x0C;
    /// Status register (flags cleared by writing 0, writing 1 changes nothing).
    pub const SR: usize = 0x10;
    /// Event generation register.
    pub const EGR: usize = 0x14;
    /// Capture/compare mode register 1.
    pub const CCMR1: usize = 0x18;
    /// Capture/compare enable register.
    pub const CCER: usize = 0x20;
    /// Counter.
    pub const CNT: usize = 0x24;
    /// Prescaler.
    pub const PSC: usize = 0x28;
    /// Auto-reload register.
    pub const ARR: usize = 0x2C;
    /// Capture/compare register 1.
    pub const CCR1: usize = 0x34;
    /// Capture/compare register 2.
    pub const CCR2: usize = 0x38;
    /// CR1: counter enable.
    pub const CR1_CEN: u32 = 1 << 0;
    /// CR1: auto-reload preload enable.
    pub const CR1_ARPE: u32 = 1 << 7;
    /// CR2: master mode "enable" (TRGO = CEN), MMS = 001.
    pub const CR2_MMS_ENABLE: u32 = 0b001 << 4;
    /// SMCR: slave mode "trigger" (SMS = 110: the trigger sets CEN).
    pub const SMCR_SMS_TRIGGER: u32 = 0b110;
    /// SMCR: trigger input ITR1 (TS = 001: TIM3's TRGO for TIM5).
    pub const SMCR_TS_ITR1: u32 = 0b001 << 4;
    /// DIER: capture/compare 2 interrupt enable.
    pub const DIER_CC2IE: u32 = 1 << 2;
    /// SR: capture/compare 2 flag (cleared by reading CCR2).
    pub const SR_CC2IF: u32 = 1 << 2;
    /// SR: capture 2 overcapture (an edge came while CC2IF was set).
    pub const SR_CC2OF: u32 = 1 << 10;
    /// EGR: update generation (loads PSC and ARR).
    pub const EGR_UG: u32 = 1 << 0;
    /// CCMR1: channel 1 PWM mode 2 (OC1M = 111) with preload (OC1PE).
    pub const CCMR1_OC1_PWM2: u32 = 0b111 << 4 | 1 << 3;
    /// CCMR1: channel 2 input on TI2 (CC2S = 01).
    pub const CCMR1_CC2S_TI2: u32 = 0b01 << 8;
    /// CCMR1: channel 2 input filter (IC2F, 4 bits).
    #[inline]
    pub const fn ccmr1_ic2f(filter: u32) -> u32 {
        (filter & 0xF) << 12
    }
    /// CCER: channel 1 output enable.
    pub const CCER_CC1E: u32 = 1 << 0;
    /// CCER: channel 2 capture enable.
    pub const CCER_CC2E: u32 = 1 << 4;
}

/// External interrupt controller (RM0090 12.3).
pub mod exti {
    /// EXTI base address.
    pub const BASE: usize = 0x4001_3C00;
    /// Interrupt mask register (1: line unmasked).
    pub const IMR: usize = BASE;
    /// Falling trigger selection register.
    pub const FTSR: usize = BASE + 0x0C;
    /// Pending register (write 1 to clear).
    pub const PR: usize = BASE + 0x14;
    /// Line 0: BUSY on PB0.
    pub const LINE_BUSY: u32 = 1 << 0;
}

/// GPIO port B (RM0090 8.4): BUSY in, CS out.
pub mod gpiob {
    /// GPIOB base address.
    pub const BASE: usize = 0x4002_0400;
    /// Input data register.
    pub const IDR: usize = BASE + 0x10;
    /// Bit set/reset register (low half sets, high half resets).
    pub const BSRR: usize = BASE + 0x18;
    /// PB0: the AD7606's BUSY.
    pub const BUSY: u32 = 1 << 0;
    /// PB12: the AD7606's CS.
    pub const CS: u32 = 1 << 12;
}

/// USART2 (RM0090 30.6).
pub mod usart2 {
    /// USART2 base address.
    pub const BASE: usize = 0x4000_4400;
    /// Status register.
    pub const SR: usize = BASE;
    /// Data register.
    pub const DR: usize = BASE + 0x04;
    /// Baud rate register.
    pub const BRR: usize = BASE + 0x08;
    /// Control register 1.
    pub const CR1: usize = BASE + 0x0C;
    /// Control register 3.
    pub const CR3: usize = BASE + 0x14;
    /// SR: framing, noise and overrun errors (PE is off: 8N1).
    pub const SR_ERRORS: u32 = 0b1110;
    /// CR1: USART, transmitter and receiver enable.
    pub const CR1_UE_TE_RE: u32 = 1 << 13 | 1 << 3 | 1 << 2;
    /// CR3: receive and transmit DMA enable.
    pub const CR3_DMAR_DMAT: u32 = 1 << 6 | 1 << 7;
}

/// Cortex-M NVIC (ARMv7-M B3.4): clear-pending registers.
pub mod nvic {
    /// Interrupt clear-pending register 0 (IRQ 0-31).
    pub const ICPR0: usize = 0xE000_E280;
    /// Interrupt number of EXTI line 0.
    pub const IRQ_EXTI0: u32 = 6;
    /// Interrupt number of DMA1 stream 3.
    pub const IRQ_DMA1_STREAM3: u32 = 14;
    /// Interrupt number of DMA1 stream 5.
    pub const IRQ_DMA1_STREAM5: u32 = 16;
    /// Interrupt number of SPI2.
    pub const IRQ_SPI2: u32 = 36;
    /// Interrupt number of TIM5.
    pub const IRQ_TIM5: u32 = 50;
}
