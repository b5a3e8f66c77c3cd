//! The CPU's 32-bit register and RAM accesses, by address (RM0090's
//! semantics for the bits the firmware uses; anything else panics).

use super::ad7606::push_recent;
use super::timer::Timer;
use super::{Hw, RAM_BASE, RAM_BYTES};
use plinth_firmware::acquisition::rm0090::{dma1, exti, gpiob, nvic, spi2, tim, usart2};

impl Hw {
    fn timer(&mut self, addr: usize) -> (&mut Timer, usize, bool) {
        if (tim::TIM3..tim::TIM3 + 0x400).contains(&addr) {
            (&mut self.tim3, addr - tim::TIM3, true)
        } else {
            (&mut self.tim5, addr - tim::TIM5, false)
        }
    }

    /// A 32-bit read by the CPU.
    pub fn read(&mut self, addr: usize) -> u32 {
        let now = self.now;
        let v = match addr {
            a if (RAM_BASE..RAM_BASE + RAM_BYTES).contains(&a) => {
                let i = a - RAM_BASE;
                u32::from_le_bytes([
                    self.ram[i],
                    self.ram[i + 1],
                    self.ram[i + 2],
                    self.ram[i + 3],
                ])
            }
            a if (tim::TIM3..tim::TIM3 + 0x400).contains(&a)
                || (tim::TIM5..tim::TIM5 + 0x400).contains(&a) =>
            {
                let (t, off, _) = self.timer(a);
                match off {
                    tim::CR1 => t.cr1,
                    tim::SR => t.sr,
                    tim::CNT => t.count(now),
                    tim::CCR2 => {
                        t.sr &= !tim::SR_CC2IF;
                        t.ccr2
                    }
                    tim::DIER => t.dier,
                    _ => panic!("model: read of timer register {a:#x}"),
                }
            }
            spi2::SR => {
                let s = &mut self.spi;
                if s.ovr && s.ovr_dr_read {
                    s.ovr = false;
                    s.ovr_dr_read = false;
                    // (this read still shows OVR)
                    return u32::from(s.rxne)
                        | (u32::from(s.tx.is_none()) << 1)
                        | spi2::SR_OVR
                        | (u32::from(s.shift.is_some()) << 7);
                }
                u32::from(s.rxne)
                    | (u32::from(s.tx.is_none()) << 1)
                    | if s.ovr { spi2::SR_OVR } else { 0 }
                    | (u32::from(s.shift.is_some() || s.tx.is_some()) << 7)
            }
            spi2::DR => {
                let w = self.spi.rx;
                self.spi_dr_read();
                u32::from(w)
            }
            spi2::CR1 => self.spi.cr1,
            spi2::CR2 => self.spi.cr2,
            dma1::LISR | dma1::HISR => {
                let streams = if addr == dma1::LISR { 0..4 } else { 4..8 };
                streams
                    .map(|n| self.dma[n].flags << dma1::flags(n).2)
                    .fold(0, |a, b| a | b)
            }
            a if (dma1::cr(0)..dma1::cr(8)).contains(&a) => {
                let n = (a - dma1::cr(0)) / 0x18;
                let s = &self.dma[n];
                match (a - dma1::cr(0)) % 0x18 {
                    0x00 => s.cr,
                    0x04 => s.ndtr,
                    _ => panic!("model: read of DMA register {a:#x}"),
                }
            }
            exti::IMR => self.exti_imr,
            exti::PR => self.exti_pr,
            exti::FTSR => self.exti_ftsr,
            gpiob::IDR => u32::from(self.adc.busy) | (u32::from(self.adc.cs_high) << 12),
            usart2::SR => {
                self.usart.sr_read = true;
                self.usart.errors | (u32::from(self.usart.rxne) << 5) | 1 << 7 | 1 << 6
            }
            usart2::DR => {
                let b = self.usart.rx;
                self.usart_dr_read();
                u32::from(b)
            }
            _ => panic!("model: read of unmodelled register {addr:#x}"),
        };
        self.update_requests();
        v
    }

    /// A 32-bit write by the CPU.
    pub fn write(&mut self, addr: usize, v: u32) {
        let now = self.now;
        match addr {
            a if (RAM_BASE..RAM_BASE + RAM_BYTES).contains(&a) => {
                let i = a - RAM_BASE;
                self.ram[i..i + 4].copy_from_slice(&v.to_le_bytes());
            }
            a if (tim::TIM3..tim::TIM3 + 0x400).contains(&a)
                || (tim::TIM5..tim::TIM5 + 0x400).contains(&a) =>
            {
                let trigger = self.tim5.smcr & 0b111 == tim::SMCR_SMS_TRIGGER;
                let (t, off, is_tim3) = self.timer(a);
                let was = t.running();
                let mut started = false;
                match off {
                    tim::CR1 => {
                        let c = t.count(now);
                        t.cr1 = v;
                        t.rebase(now, c);
                        if is_tim3 {
                            if !was && t.running() {
                                t.edges = 0;
                                t.schedule_compare(now);
                                started = true;
                            } else if !t.running() {
                                t.next_compare = None;
                            }
                        }
                    }
                    tim::CR2 => t.cr2 = v,
                    tim::SMCR => t.smcr = v,
                    tim::DIER => t.dier = v,
                    tim::SR => t.sr &= v,
                    tim::EGR => {
                        if v & tim::EGR_UG != 0 {
                            t.rebase(now, 0);
                            if is_tim3 {
                                t.schedule_compare(now);
                            }
                        }
                    }
                    tim::CCMR1 => t.ccmr1 = v,
                    tim::CCER => t.ccer = v,
                    tim::CNT => {
                        t.rebase(now, v);
                        if is_tim3 {
                            t.schedule_compare(now);
                        }
                    }
                    tim::PSC => t.psc = v,
                    tim::ARR => t.arr = v,
                    tim::CCR1 => t.ccr1 = v,
                    _ => panic!("model: write of timer register {a:#x}"),
                }
                if started {
                    self.runs += 1;
                    if trigger {
                        self.tim5_start = Some(now + 1);
                    }
                }
            }
            spi2::CR1 => self.spi.cr1 = v,
            spi2::CR2 => self.spi.cr2 = v,
            spi2::DR => self.spi.tx = Some(v as u16),
            dma1::LIFCR | dma1::HIFCR => {
                let streams = if addr == dma1::LIFCR { 0..4 } else { 4..8 };
                for n in streams {
                    self.dma[n].flags &= !((v >> dma1::flags(n).2) & dma1::ALL_FLAGS);
                }
            }
            a if (dma1::cr(0)..dma1::cr(8)).contains(&a) => {
                let n = (a - dma1::cr(0)) / 0x18;
                let s = &mut self.dma[n];
                match (a - dma1::cr(0)) % 0x18 {
                    0x00 => {
                        if s.cr & dma1::CR_EN == 0 && v & dma1::CR_EN != 0 {
                            s.reload = s.ndtr;
                        }
                        if s.cr & dma1::CR_EN != 0 {
                            // Only EN can change while enabled.
                            s.cr = (s.cr & !dma1::CR_EN) | (v & dma1::CR_EN);
                        } else {
                            s.cr = v;
                        }
                    }
                    0x04 if s.cr & dma1::CR_EN == 0 => s.ndtr = v & 0xFFFF,
                    0x08 if s.cr & dma1::CR_EN == 0 => s.par = v,
                    0x0C if s.cr & dma1::CR_EN == 0 => s.m0ar = v,
                    0x10 if s.cr & dma1::CR_EN == 0 => s.m1ar = v,
                    0x14 if s.cr & dma1::CR_EN == 0 => s.fcr = v,
                    _ => {} // ignored while the stream runs, as on silicon
                }
            }
            exti::IMR => self.exti_imr = v,
            exti::FTSR => self.exti_ftsr = v,
            exti::PR => self.exti_pr &= !v,
            gpiob::BSRR => {
                if v & gpiob::CS != 0 && !self.adc.cs_high {
                    self.adc.cs_high = true;
                    push_recent(&mut self.adc.cs_rises, now);
                }
                if v & (gpiob::CS << 16) != 0 && self.adc.cs_high {
                    self.adc.cs_high = false;
                    // Bits shifted by now: those of the frame in flight
                    // that have passed.
                    let bits = match self.spi.shift {
                        Some((start, _)) => self.adc.bits + (now - start) / self.bit_ticks().max(1),
                        None => self.adc.bits,
                    };
                    push_recent(&mut self.adc.cs_falls, now);
                    push_recent(&mut self.adc.bits_at_fall, bits);
                }
            }
            nvic::ICPR0 => self.nvic_clear |= u64::from(v),
            0xE000_E284 => self.nvic_clear |= u64::from(v) << 32,
            usart2::BRR => self.usart.brr = v,
            usart2::CR1 => self.usart.cr1 = v,
            usart2::CR3 => self.usart.cr3 = v,
            usart2::DR => self.usart.sent.push(v as u8),
            _ => panic!("model: write of unmodelled register {addr:#x} = {v:#x}"),
        }
        self.update_requests();
    }
}
