//! A panic leaves a record in RAM that no start-up code touches (the
//! `.uninit` section of cortex-m-rt), then resets the MCU; the next boot
//! reports the record over defmt and clears it.

use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;

/// Marks a valid record.
const MAGIC: u32 = 0x504C_4E54; // "PLNT"
/// Bytes kept of the file name (its end) and of the message.
const FILE_BYTES: usize = 48;
const MESSAGE_BYTES: usize = 64;

/// What a panic left behind.
#[repr(C)]
pub struct PanicRecord {
    magic: u32,
    line: u32,
    file_len: u32,
    message_len: u32,
    file: [u8; FILE_BYTES],
    message: [u8; MESSAGE_BYTES],
    check: u32,
}

#[link_section = ".uninit.plinth_panic_record"]
static mut RECORD: MaybeUninit<PanicRecord> = MaybeUninit::uninit();

impl PanicRecord {
    /// A check word over the fields, so that power-up garbage is not
    /// taken for a record.
    fn checksum(&self) -> u32 {
        let mut h = self.line ^ self.file_len.rotate_left(8) ^ self.message_len.rotate_left(16);
        for &b in self.file.iter().chain(self.message.iter()) {
            h = h.rotate_left(5) ^ u32::from(b);
        }
        h
    }

    /// The file name kept.
    pub fn file(&self) -> &str {
        let n = (self.file_len as usize).min(FILE_BYTES);
        core::str::from_utf8(&self.file[..n]).unwrap_or("(file)")
    }

    /// The message kept.
    pub fn message(&self) -> &str {
        let n = (self.message_len as usize).min(MESSAGE_BYTES);
        core::str::from_utf8(&self.message[..n]).unwrap_or("(message)")
    }

    /// The line.
    pub fn line(&self) -> u32 {
        self.line
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

/// Writes the record of this panic (called once, from the panic handler).
pub fn write(info: &core::panic::PanicInfo) {
    let (file, line) = info
        .location()
        .map_or(("(unknown)", 0), |l| (l.file(), l.line()));
    let message = info.message().as_str().unwrap_or("(formatted message)");
    let mut r = PanicRecord {
        magic: MAGIC,
        line,
        file_len: 0,
        message_len: 0,
        file: [0; FILE_BYTES],
        message: [0; MESSAGE_BYTES],
        check: 0,
    };
    let f = tail(file, FILE_BYTES).as_bytes();
    r.file[..f.len()].copy_from_slice(f);
    r.file_len = f.len() as u32;
    let m = head(message, MESSAGE_BYTES).as_bytes();
    r.message[..m.len()].copy_from_slice(m);
    r.message_len = m.len() as u32;
    r.check = r.checksum();
    // SAFETY: the panic handler runs once with interrupts disabled; nothing
    // else writes RECORD.
    unsafe { addr_of_mut!(RECORD).write(MaybeUninit::new(r)) };
}

/// The previous boot's panic record, if it left one; clears it.
pub fn take() -> Option<PanicRecord> {
    // SAFETY: called once from `init` before interrupts run. Every bit
    // pattern is a valid `PanicRecord` (integers and byte arrays), so
    // reading the uninitialised RAM is defined; the magic and the check
    // word tell a record from garbage.
    let r = unsafe { addr_of_mut!(RECORD).read().assume_init() };
    // SAFETY: as above.
    unsafe { addr_of_mut!(RECORD).cast::<u32>().write_volatile(0) };
    (r.magic == MAGIC && r.check == r.checksum()).then_some(r)
}
