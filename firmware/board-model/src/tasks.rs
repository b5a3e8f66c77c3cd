//! The box's two software tasks on the model board: `extract` (priority 2,
//! pended by every completed DMA half) running the library's extraction
//! body ([`Extraction::run`], what `plinth-box`'s `extract` calls), and
//! `process` (priority 1) running the protocol pass ([`Session::poll`])
//! with the host link flooded, so that every pass is as long as its byte
//! budget allows. What the two share is locked as RTIC locks it: the
//! running priority raised to the ceiling (2) for the closure
//! ([`Board::with_ceiling`]); a `RefCell` holds each shared part, so a
//! section the ceiling failed to protect would panic the model.
//!
//! The protocol code runs natively; its time is modelled per byte: a
//! received byte costs [`RX_CYCLES_PER_BYTE`] (QEMU-measured), an encoded
//! one [`ENCODE_CYCLES_PER_BYTE`], a byte handed to the link
//! [`TX_CYCLES_PER_BYTE`], a section on the extraction state
//! [`SECTION_CYCLES`] (its register accesses, `AdcDma::stop`/`start`'s
//! waits included, cost what the model says). The extraction costs its
//! register and RAM accesses plus [`IDLE_CYCLES_PER_VECTOR`] per vector.
//!
//! [`Structure::WholePass`] is the box before the split: `process` held
//! the device for its whole pass.

use crate::check::{Checker, Outcome};
use crate::scenario::{rig, BoardSource, Rig, Scenario, IDLE_CYCLES_PER_VECTOR};
use crate::sim::{Board, Port};
use plinth_firmware::device::{capabilities_at, Extraction, Lock, Outbox, Session, Shared};
use plinth_firmware::link::ByteLink;
use plinth_shared::protocol::{DeviceMessage, HostMessage, Receiver, Transmitter, MAX_FRAME_SIZE};
use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;

/// IRQ of `process`'s dispatcher on the box (USART1, unused as a UART).
pub const IRQ_PROCESS: u32 = 37;
/// IRQ of `extract`'s dispatcher on the box (USART3, unused as a UART).
pub const IRQ_EXTRACT: u32 = 39;
/// The ceiling of what `process` and `extract` share (extract's priority).
pub const CEILING: u8 = 2;
/// Cycles per received byte: the receiver's QEMU-measured cost
/// (`bash scripts/bench-firmware.sh`: 17 822 instructions for a 208-byte
/// frame, 86 per byte).
pub const RX_CYCLES_PER_BYTE: u64 = 86;
/// Cycles per encoded byte of a queued frame (taken equal to receiving:
/// the same CRC and COBS work; an estimate).
pub const ENCODE_CYCLES_PER_BYTE: u64 = 86;
/// Cycles per byte moved from the outbox to the link's ring (an estimate).
pub const TX_CYCLES_PER_BYTE: u64 = 12;
/// Cycles of a section on the extraction state besides its register
/// accesses (a configuration command, a status snapshot; an estimate).
pub const SECTION_CYCLES: u64 = 400;
/// Longest `extract` may wait from pending to entry [CPU cycles]: 20 000
/// cycles = 119 µs at 168 MHz, 6 % of a 96-vector half (1.875 ms), which
/// a half's extraction (≈ 23 000 cycles) and the interrupts above it fit
/// beside many times over before the DMA comes back to the half.
pub const EXTRACT_WAIT_BUDGET_CYCLES: u64 = 20_000;

/// How `process` holds what it shares with `extract`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Structure {
    /// The box: one short section per command, snapshot, frame or chunk.
    Split,
    /// Before the split: the whole protocol pass under the lock.
    WholePass,
}

/// What a run of the two tasks showed.
#[derive(Clone, Debug)]
pub struct TaskOutcome {
    /// Every delivered sample against the truth, as the fault matrix checks it.
    pub acquisition: Outcome,
    /// Halves the extraction came too late for (counted overruns).
    pub overrun_halves: u32,
    /// `extract` calls and its longest wait from pending to entry [cycles].
    pub extract_calls: u64,
    /// Longest wait of `extract` [CPU cycles].
    pub extract_max_wait_cycles: u64,
    /// Longest critical section of either task [CPU cycles].
    pub longest_section_cycles: u64,
    /// `process` passes and host bytes they took.
    pub process_calls: u64,
    /// Bytes the host sent.
    pub host_bytes: u64,
    /// Frames the host received (acks, phasors, …) and of them acks.
    pub frames_received: u64,
    /// Acks received.
    pub acks: u64,
    /// Frames the host could not decode (sequence gaps, bad CRC).
    pub link_errors: u64,
    /// Sample vectors that went through the pipeline.
    pub extracted: u64,
}

/// The host's end of the link.
#[derive(Default)]
struct Wire {
    to_box: VecDeque<u8>,
    from_box: Vec<u8>,
}

/// The box's end of the link, costing each byte's handling.
struct ModelLink {
    board: Rc<Board>,
    wire: Rc<RefCell<Wire>>,
}

impl ByteLink for ModelLink {
    fn read_byte(&mut self) -> Option<u8> {
        let b = self.wire.borrow_mut().to_box.pop_front()?;
        self.board.spend(RX_CYCLES_PER_BYTE);
        Some(b)
    }
    fn write_byte(&mut self, byte: u8) -> bool {
        self.wire.borrow_mut().from_box.push(byte);
        self.board.spend(TX_CYCLES_PER_BYTE);
        true
    }
}

/// The outbox under the ceiling, its encoding costed.
struct OutboxLock {
    board: Rc<Board>,
    outbox: Rc<RefCell<Outbox>>,
}

impl Lock for OutboxLock {
    type Target = Outbox;
    fn lock<R>(&mut self, f: impl FnOnce(&mut Outbox) -> R) -> R {
        let (board, outbox) = (self.board.clone(), self.outbox.clone());
        self.board.with_ceiling(CEILING, || {
            let mut o = outbox.borrow_mut();
            let before = o.len();
            let r = f(&mut o);
            let pushed = o.len().saturating_sub(before) as u64;
            drop(o);
            board.spend(pushed * ENCODE_CYCLES_PER_BYTE);
            r
        })
    }
}

/// What `process` shares, each access one section at the ceiling.
struct ModelShared {
    board: Rc<Board>,
    extraction: Rc<RefCell<Extraction>>,
    source: Rc<RefCell<BoardSource>>,
    outbox: OutboxLock,
    /// Hardware runs seen and the truth checker (a start moves it to the
    /// new run).
    runs: Rc<RefCell<(u32, Option<Checker>)>>,
}

impl Shared for ModelShared {
    type Source = BoardSource;
    fn acquisition<R>(&mut self, f: impl FnOnce(&mut Extraction, &mut BoardSource) -> R) -> R {
        let board = self.board.clone();
        let r = self.board.with_ceiling(CEILING, || {
            board.spend(SECTION_CYCLES);
            let mut e = self.extraction.borrow_mut();
            let mut s = self.source.borrow_mut();
            f(&mut e, &mut s)
        });
        let runs = self.board.hw.borrow().runs;
        let mut seen = self.runs.borrow_mut();
        if runs != seen.0 {
            seen.0 = runs;
            if let Some(c) = seen.1.as_mut() {
                c.started(runs);
            }
        }
        r
    }
    fn outbox<R>(&mut self, f: impl FnOnce(&mut Outbox) -> R) -> R {
        self.outbox.lock(f)
    }
    fn extract_inline(&mut self) -> usize {
        0
    }
}

/// Encodes host messages as the host does.
fn encode(tx: &mut Transmitter, m: &HostMessage, out: &mut VecDeque<u8>) {
    let mut buf = [0u8; MAX_FRAME_SIZE];
    if let Ok((_, bytes)) = tx.encode(m, &mut buf) {
        out.extend(bytes.iter().copied());
    }
}

/// Runs scenario `s` with both tasks: the host opens a session, sends
/// `configuration` and `Start`, then keeps the link full of `Ping`s (every
/// `process` pass takes its whole byte budget). None when the box refuses
/// to sample at these clocks.
pub fn run_tasks(
    s: &Scenario,
    structure: Structure,
    configuration: &[HostMessage],
) -> Option<TaskOutcome> {
    let after_half: crate::sim::Handler = Box::new(|r: &mut Port| r.0.pend(IRQ_EXTRACT));
    let Rig {
        board,
        shared: adc,
        source,
        checker,
        p,
        end,
        timer_hz,
    } = rig(s, Some(after_half))?;
    let rate = timer_hz as f32 / p as f32;
    let extraction = Rc::new(RefCell::new(Extraction::new()));
    let source = Rc::new(RefCell::new(source));
    let outbox = Rc::new(RefCell::new(Outbox::new()));
    let runs = Rc::new(RefCell::new((board.hw.borrow().runs, Some(checker))));
    let wire = Rc::new(RefCell::new(Wire::default()));
    let extracted = Rc::new(RefCell::new(0u64));
    {
        let (board_, extraction, source, outbox, runs, extracted) = (
            board.clone(),
            extraction.clone(),
            source.clone(),
            outbox.clone(),
            runs.clone(),
            extracted.clone(),
        );
        board.attach(
            IRQ_EXTRACT,
            CEILING,
            "extract",
            Box::new(move |_| {
                let mut lock = OutboxLock {
                    board: board_.clone(),
                    outbox: outbox.clone(),
                };
                let mut e = extraction.borrow_mut();
                let mut src = source.borrow_mut();
                // The box's extract task body.
                let n = e.run(&mut *src, &mut lock);
                *extracted.borrow_mut() += n as u64;
                let c = src.counters();
                let mut runs = runs.borrow_mut();
                let Some(checker) = runs.1.as_mut() else {
                    return;
                };
                if e.buffer().is_empty() {
                    checker.counters(c);
                } else {
                    let hw = board_.hw.borrow();
                    checker.delivered(&hw, e.buffer(), src.delivered_first_sample(), c);
                    drop(hw);
                    drop((e, src, runs));
                    board_.spend(IDLE_CYCLES_PER_VECTOR * n as u64);
                }
            }),
        );
    }
    {
        let mut session = Session::new(capabilities_at(10.0 / 32768.0, rate));
        let mut link = ModelLink {
            board: board.clone(),
            wire: wire.clone(),
        };
        let mut shared = ModelShared {
            board: board.clone(),
            extraction: extraction.clone(),
            source: source.clone(),
            outbox: OutboxLock {
                board: board.clone(),
                outbox: outbox.clone(),
            },
            runs: runs.clone(),
        };
        let board_ = board.clone();
        board.attach(
            IRQ_PROCESS,
            1,
            "process",
            Box::new(move |_| {
                let now_ms = (board_.now() / u64::from(timer_hz / 1000)) as u32;
                match structure {
                    Structure::Split => {
                        session.poll(&mut link, &mut shared, now_ms);
                    }
                    Structure::WholePass => {
                        board_.with_ceiling(CEILING, || {
                            session.poll(&mut link, &mut shared, now_ms);
                        });
                    }
                }
            }),
        );
    }
    // The host: a session, the configuration, Start.
    let mut tx = Transmitter::new();
    let mut rx = Receiver::<DeviceMessage>::new();
    {
        let mut w = wire.borrow_mut();
        let hello = HostMessage::Hello(plinth_shared::protocol::Hello {
            protocol_version: plinth_shared::protocol::PROTOCOL_VERSION,
            host_nonce: 1,
        });
        encode(&mut tx, &hello, &mut w.to_box);
        for m in configuration {
            encode(&mut tx, m, &mut w.to_box);
        }
        encode(&mut tx, &HostMessage::Start, &mut w.to_box);
    }
    let mut host_bytes = wire.borrow().to_box.len() as u64;
    let (mut frames_received, mut acks, mut link_errors) = (0u64, 0u64, 0u64);
    let step = p / 2;
    let cycles_per_tick = u64::from(s.clocks.sysclk_hz / timer_hz);
    let mut started_at = None;
    loop {
        board.pend(IRQ_PROCESS);
        board.spend(step * cycles_per_tick);
        for event in rx.feed(&std::mem::take(&mut wire.borrow_mut().from_box)) {
            match event {
                Ok(frame) => {
                    frames_received += 1;
                    if matches!(frame.message, DeviceMessage::Ack(_)) {
                        acks += 1;
                    }
                }
                Err(_) => link_errors += 1,
            }
        }
        if started_at.is_none() && extraction.borrow().running() {
            started_at = Some(board.now());
        }
        if let Some(t0) = started_at {
            if board.now() >= t0 + end {
                break;
            }
            // Keep the link full: every pass takes its whole budget.
            let mut w = wire.borrow_mut();
            while w.to_box.len() < 2 * plinth_firmware::device::RX_BUDGET {
                let before = w.to_box.len();
                encode(&mut tx, &HostMessage::Ping, &mut w.to_box);
                host_bytes += (w.to_box.len() - before) as u64;
            }
        } else if board.now() > 40 * end {
            break; // never started: the outcome says so
        }
    }
    let stats = board.stats();
    let stat = |name: &str| stats.iter().find(|h| h.name == name).cloned();
    let extract = stat("extract");
    let process = stat("process");
    let src = source.borrow();
    let counters = src.counters();
    let checker = runs.borrow_mut().1.take()?;
    let vectors = *extracted.borrow();
    let hw = board.hw.borrow();
    let acquisition = checker.finish(
        &hw,
        counters,
        adc.faults(),
        p * (3 * s.vectors_per_half as u64 + 2),
        false,
    );
    Some(TaskOutcome {
        acquisition,
        overrun_halves: counters.overrun_halves,
        extract_calls: extract.as_ref().map_or(0, |h| h.calls),
        extract_max_wait_cycles: extract.as_ref().map_or(0, |h| h.max_wait_cycles),
        longest_section_cycles: board.longest_section_cycles(),
        process_calls: process.map_or(0, |h| h.calls),
        host_bytes,
        frames_received,
        acks,
        link_errors,
        extracted: vectors,
    })
}
