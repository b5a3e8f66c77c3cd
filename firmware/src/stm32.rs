//! STM32F4 registers the image touches: the clock tree (PLL to 168 MHz),
//! the USART1 host link with the clocks and pins it needs, and the
//! independent watchdog. This is the one module with `unsafe`: every access
//! is a volatile read or write of a documented memory-mapped register.
//!
//! The same code runs on an STM32F405/407 board and under
//! `qemu-system-arm -M netduinoplus2`, whose first serial port is USART1 at
//! 0x4001_1000. QEMU does not model RCC or GPIO (reads give 0, writes are
//! ignored): the clock set-up recognises that (RCC_CR reads 0, which real
//! silicon never does: HSI on and ready after reset) and every wait on a
//! status bit is bounded.
#![allow(unsafe_code)]

use crate::clock::{self, Clocks};
use crate::link::ByteLink;
use crate::watchdog::Watchdog;

/// RCC AHB1 peripheral clock enable register (GPIOAEN = bit 0).
const RCC_AHB1ENR: usize = 0x4002_3830;
/// RCC APB2 peripheral clock enable register (USART1EN = bit 4).
const RCC_APB2ENR: usize = 0x4002_3844;
/// GPIOA mode register (two bits per pin, 0b10 = alternate function).
const GPIOA_MODER: usize = 0x4002_0000;
/// GPIOA alternate function register for pins 8..15 (four bits per pin).
const GPIOA_AFRH: usize = 0x4002_0024;

/// USART1 base address.
const USART1: usize = 0x4001_1000;
/// Status register offset.
const SR: usize = 0x00;
/// Data register offset.
const DR: usize = 0x04;
/// Baud rate register offset.
const BRR: usize = 0x08;
/// Control register 1 offset.
const CR1: usize = 0x0C;

/// SR: read data register not empty.
const SR_RXNE: u32 = 1 << 5;
/// SR: transmit data register empty.
const SR_TXE: u32 = 1 << 7;
/// SR: overrun, noise, framing and parity errors.
const SR_ERRORS: u32 = 0b1111;
/// CR1: USART enable.
const CR1_UE: u32 = 1 << 13;
/// CR1: transmitter enable.
const CR1_TE: u32 = 1 << 3;
/// CR1: receiver enable.
const CR1_RE: u32 = 1 << 2;

/// Reads a 32-bit peripheral register.
#[inline(always)]
fn read(addr: usize) -> u32 {
    // SAFETY: `addr` is one of the constant, aligned STM32F4 register
    // addresses above; reading them has no side effect beyond the documented
    // one (reading DR clears RXNE, which is what the caller wants).
    unsafe { core::ptr::read_volatile(addr as *const u32) }
}

/// Writes a 32-bit peripheral register.
#[inline(always)]
fn write(addr: usize, value: u32) {
    // SAFETY: as in `read`; the values written are those the reference
    // manual (RM0090) gives for the configuration below.
    unsafe { core::ptr::write_volatile(addr as *mut u32, value) }
}

/// Sets bits in a register (read-modify-write; single-threaded init only).
fn set_bits(addr: usize, mask: u32, value: u32) {
    write(addr, (read(addr) & !mask) | value);
}

/// The memory-mapped registers themselves (and RAM the DMA writes), for
/// [`clock::configure`] and the acquisition code.
#[derive(Clone, Copy, Debug)]
pub struct Mmio;

// Inlined: the interrupt handlers call these once per register access
// (an out-of-line call would cost a branch, a return and the spills
// around it at every access).
impl clock::Registers for Mmio {
    #[inline(always)]
    fn read(&mut self, addr: usize) -> u32 {
        read(addr)
    }
    #[inline(always)]
    fn write(&mut self, addr: usize, value: u32) {
        write(addr, value)
    }
}

/// [`clock::configure`] on the real registers: call once, first thing in
/// `main`.
pub fn configure_clocks(hse_hz: Option<u32>) -> Clocks {
    clock::configure(&mut Mmio, hse_hz)
}

/// USART1 on PA9 (TX) / PA10 (RX), 8N1, polled.
#[derive(Debug)]
pub struct Usart1 {
    receive_errors: u32,
}

impl Usart1 {
    /// Enables the clocks and pins and starts USART1 at `baud` [bit/s] from
    /// the APB2 clock `pclk2_hz` [Hz] ([`Clocks::pclk2_hz`]).
    ///
    /// Only call this once: the returned value owns the peripheral.
    pub fn init(pclk2_hz: u32, baud: u32) -> Self {
        set_bits(RCC_AHB1ENR, 1, 1);
        set_bits(RCC_APB2ENR, 1 << 4, 1 << 4);
        // PA9, PA10: alternate function 7 (USART1).
        set_bits(GPIOA_MODER, 0b1111 << 18, 0b1010 << 18);
        set_bits(GPIOA_AFRH, 0xFF << 4, 0x77 << 4);
        write(USART1 + BRR, clock::usart_brr(pclk2_hz, baud));
        write(USART1 + CR1, CR1_UE | CR1_TE | CR1_RE);
        Self { receive_errors: 0 }
    }
}

impl ByteLink for Usart1 {
    fn read_byte(&mut self) -> Option<u8> {
        let sr = read(USART1 + SR);
        if sr & SR_ERRORS != 0 {
            // Reading SR then DR clears the error flags (RM0090 30.6.1); the
            // byte that came with an error is not trusted.
            self.receive_errors = self.receive_errors.wrapping_add(1);
            let _ = read(USART1 + DR);
            return None;
        }
        if sr & SR_RXNE != 0 {
            Some(read(USART1 + DR) as u8)
        } else {
            None
        }
    }

    fn write_byte(&mut self, byte: u8) -> bool {
        if read(USART1 + SR) & SR_TXE == 0 {
            return false;
        }
        write(USART1 + DR, u32::from(byte));
        true
    }

    fn receive_errors(&self) -> u32 {
        self.receive_errors
    }
}

/// IWDG key register.
const IWDG_KR: usize = 0x4000_3000;
/// IWDG prescaler register.
const IWDG_PR: usize = 0x4000_3004;
/// IWDG reload register.
const IWDG_RLR: usize = 0x4000_3008;
/// DBGMCU APB1 freeze register (DBG_IWDG_STOP = bit 12).
const DBGMCU_APB1_FZ: usize = 0xE004_2008;

/// The independent watchdog, clocked by the ~32 kHz LSI.
#[derive(Debug)]
pub struct Iwdg(());

impl Iwdg {
    /// Starts the watchdog with a timeout of about `timeout_ms` [ms]
    /// (prescaler 32: 1 ms per count, at most 4095 ms). It stops while a
    /// debugger halts the core. Once started it cannot be stopped.
    pub fn start(timeout_ms: u32) -> Self {
        set_bits(DBGMCU_APB1_FZ, 1 << 12, 1 << 12);
        write(IWDG_KR, 0xCCCC); // start
        write(IWDG_KR, 0x5555); // unlock PR and RLR
        write(IWDG_PR, 0b011); // LSI / 32
        write(IWDG_RLR, timeout_ms.clamp(1, 0xFFF));
        write(IWDG_KR, 0xAAAA); // reload
        Self(())
    }
}

impl Watchdog for Iwdg {
    fn feed(&mut self) {
        write(IWDG_KR, 0xAAAA);
    }
}
