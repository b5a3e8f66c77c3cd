//! A panic or a hard fault leaves a record in RAM that no start-up code
//! touches (the `.uninit` section of cortex-m-rt), then resets the MCU;
//! the next boot reports it (defmt, and `previous_reset` in `HelloAck` and
//! every `Status`) and clears it.
//!
//! The record is words read and written with volatile accesses only: the
//! RAM is never initialised by Rust, so it is never read as a Rust value
//! (which would be undefined behaviour); the magic word and a check word
//! tell a record from power-up garbage. A second panic while one is being
//! recorded (a panic in the panic handler) resets at once ([`begin`]).

use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;
use core::sync::atomic::{AtomicBool, Ordering};

/// Marks a valid record.
const MAGIC: u32 = 0x504C_4E54; // "PLNT"
/// Bytes kept of the file name (its end) and of the message.
const FILE_BYTES: usize = 48;
const MESSAGE_BYTES: usize = 64;
/// Words: magic, kind, line (or PC), file length, message length, file,
/// message, check.
const WORDS: usize = 5 + FILE_BYTES / 4 + MESSAGE_BYTES / 4 + 1;

/// What ended the previous boot.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum Kind {
    /// A panic: file, line, message.
    Panic,
    /// A hard fault: the faulting PC in `line`.
    HardFault,
}

#[link_section = ".uninit.plinth_panic_record"]
static mut RECORD: MaybeUninit<[u32; WORDS]> = MaybeUninit::uninit();

/// Set by the first panic.
static PANICKING: AtomicBool = AtomicBool::new(false);

/// Word `i` of the record.
fn word(i: usize) -> u32 {
    // SAFETY: in bounds of RECORD (i < WORDS at every call); a volatile
    // read of RAM the program owns, never turned into a Rust value other
    // than the u32 it returns.
    unsafe { addr_of_mut!(RECORD).cast::<u32>().add(i).read_volatile() }
}

fn set_word(i: usize, v: u32) {
    // SAFETY: as in `word`; only the panic/fault handlers (interrupts off,
    // guarded by PANICKING) and `take` (in init, before interrupts) write.
    unsafe { addr_of_mut!(RECORD).cast::<u32>().add(i).write_volatile(v) }
}

fn checksum(words: &[u32; WORDS]) -> u32 {
    words[..WORDS - 1]
        .iter()
        .fold(0x1234_5678u32, |h, &w| h.rotate_left(5) ^ w)
}

/// What a panic or fault left behind.
pub struct PanicRecord {
    words: [u32; WORDS],
}

impl PanicRecord {
    fn bytes(&self, first_word: usize, len: usize) -> [u8; MESSAGE_BYTES] {
        let mut out = [0u8; MESSAGE_BYTES];
        for (k, b) in out.iter_mut().enumerate().take(len.min(MESSAGE_BYTES)) {
            *b = (self.words[first_word + k / 4] >> (8 * (k % 4))) as u8;
        }
        out
    }

    /// Panic or hard fault.
    pub fn kind(&self) -> Kind {
        if self.words[1] == 2 {
            Kind::HardFault
        } else {
            Kind::Panic
        }
    }

    /// The line (panic) or the faulting PC (hard fault).
    pub fn line(&self) -> u32 {
        self.words[2]
    }

    /// Calls `f` with the file name and the message kept.
    pub fn with_text(&self, f: impl FnOnce(&str, &str)) {
        let file_len = (self.words[3] as usize).min(FILE_BYTES);
        let message_len = (self.words[4] as usize).min(MESSAGE_BYTES);
        let file = self.bytes(5, file_len);
        let message = self.bytes(5 + FILE_BYTES / 4, message_len);
        f(
            core::str::from_utf8(&file[..file_len]).unwrap_or("(file)"),
            core::str::from_utf8(&message[..message_len]).unwrap_or("(message)"),
        );
    }
}

/// The longest tail of `s` that fits `n` bytes and starts on a character.
fn tail(s: &str, n: usize) -> &str {
    let mut start = s.len().saturating_sub(n);
    while !s.is_char_boundary(start) {
        start += 1;
    }
    &s[start..]
}

/// The longest head of `s` that fits `n` bytes.
fn head(s: &str, n: usize) -> &str {
    let mut end = s.len().min(n);
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    &s[..end]
}

/// Enters the panic or fault path: true the first time; a second entry (a
/// panic while recording) should reset at once.
pub fn begin() -> bool {
    cortex_m::interrupt::disable();
    !PANICKING.swap(true, Ordering::Relaxed)
}

/// Writes a record.
pub fn write(kind: Kind, file: &str, line: u32, message: &str) {
    let mut w = [0u32; WORDS];
    w[0] = MAGIC;
    w[1] = match kind {
        Kind::Panic => 1,
        Kind::HardFault => 2,
    };
    w[2] = line;
    let f = tail(file, FILE_BYTES).as_bytes();
    let m = head(message, MESSAGE_BYTES).as_bytes();
    w[3] = f.len() as u32;
    w[4] = m.len() as u32;
    for (k, &b) in f.iter().enumerate() {
        w[5 + k / 4] |= u32::from(b) << (8 * (k % 4));
    }
    for (k, &b) in m.iter().enumerate() {
        w[5 + FILE_BYTES / 4 + k / 4] |= u32::from(b) << (8 * (k % 4));
    }
    w[WORDS - 1] = checksum(&w);
    for (i, &v) in w.iter().enumerate() {
        set_word(i, v);
    }
}

/// Writes the record of a panic.
pub fn write_panic(info: &core::panic::PanicInfo) {
    let (file, line) = info
        .location()
        .map_or(("(unknown)", 0), |l| (l.file(), l.line()));
    let message = info.message().as_str().unwrap_or("(formatted message)");
    write(Kind::Panic, file, line, message);
}

/// The previous boot's record, if it left one; clears it. Call once, in
/// `init`, before interrupts run.
pub fn take() -> Option<PanicRecord> {
    let mut words = [0u32; WORDS];
    for (i, w) in words.iter_mut().enumerate() {
        *w = word(i);
    }
    set_word(0, 0);
    (words[0] == MAGIC && words[WORDS - 1] == checksum(&words)).then_some(PanicRecord { words })
}
