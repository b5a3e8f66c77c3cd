//! The host link's receive path on the model board: USART2, its receive
//! DMA (stream 5, circular over a ring) and the firmware's own
//! `uart_dma::DmaSerial` and `host_rx_half`, fed with the host's encoded
//! commands at 115 200 baud while the line adds noise or the receiver
//! falls behind (a DMA held off the bus: USART overrun; an idle loop busy
//! elsewhere: the ring laps its reader).
//!
//! Checked: every byte the host sent is delivered unchanged or lost in a
//! stretch during which a receive-error counter moved (line errors, ring
//! overruns, the frame receiver's CRC/COBS failures); every command the
//! frame receiver delivers is the one the host sent with that sequence
//! number (no silent corruption of a command).

use crate::hw::{Hw, RAM_BASE};
use crate::sim::{Board, Port};
use plinth_firmware::acquisition::rm0090::nvic;
use plinth_firmware::link::ByteLink;
use plinth_firmware::uart_dma::{self, DmaSerial};
use plinth_shared::protocol::{encode, Averaging, HostMessage, Receiver, MAX_FRAME_SIZE};
use std::sync::atomic::AtomicU32;

/// Link speed [bit/s] (the box's).
pub const BAUD: u32 = 115_200;
/// Receive ring of the model [bytes] (the box's is 512; smaller here so
/// that a short absence laps it).
pub const RING_BYTES: usize = 64;
/// Where the ring and the transmit buffer live in model RAM.
const RING: usize = RAM_BASE + 0x8000;
const TX: usize = RAM_BASE + 0x9000;

/// What goes wrong on the host link.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UartFault {
    /// Nothing.
    None,
    /// Every `every`-th byte arrives with bit `bit` flipped; `flagged`:
    /// the USART sees it (noise/framing error), else only the frame CRC can.
    Noise {
        every: usize,
        bit: u8,
        flagged: bool,
    },
    /// DMA requests not served for `us` µs from byte `at` (USART overrun).
    DmaStall { at: usize, us: u64 },
    /// The idle loop does not read for `us` µs from byte `at` (the ring
    /// laps its reader).
    ReaderAway { at: usize, us: u64 },
}

/// One host-link scenario.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UartScenario {
    /// Fault class (in failure messages).
    pub name: &'static str,
    /// Index in its list.
    pub index: usize,
    /// Commands the host sends.
    pub commands: usize,
    /// The fault.
    pub fault: UartFault,
}

/// What a host-link scenario showed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UartOutcome {
    /// Bytes the host sent.
    pub sent: u64,
    /// Bytes delivered to the reader.
    pub delivered: u64,
    /// Commands the frame receiver delivered.
    pub commands: u64,
    /// Delivered commands that differ from what the host sent (silent
    /// corruption), plus delivered bytes that are neither the host's nor
    /// counted.
    pub corruptions: u64,
    /// Stretches of lost or altered bytes during which no counter moved.
    pub uncounted: u64,
    /// `receive_errors` at the end (line errors + ring overruns).
    pub receive_errors: u32,
    /// The first problem found.
    pub first_problem: Option<String>,
}

impl UartOutcome {
    fn problem(&mut self, text: impl FnOnce() -> String) {
        if self.first_problem.is_none() {
            self.first_problem = Some(text());
        }
    }
}

/// The host's commands: configuration frames of varied content.
fn commands(n: usize) -> Vec<HostMessage> {
    (0..n)
        .map(|k| match k % 3 {
            0 => HostMessage::Ping,
            _ => HostMessage::ConfigureAveraging(Averaging {
                revolutions_per_phasor: 1 + (k as u16 * 37) % 200,
            }),
        })
        .collect()
}

/// Runs a host-link scenario and checks it.
pub fn run(s: &UartScenario) -> UartOutcome {
    let timer_hz = 84_000_000u32;
    let us = |x: u64| x * u64::from(timer_hz) / 1_000_000;
    let byte_ticks = u64::from(timer_hz) * 10 / u64::from(BAUD);
    let hw = Hw::new(timer_hz, 42_000_000, 4_000);
    let board = Board::new(hw, 2);
    let halves: &'static AtomicU32 = Box::leak(Box::new(AtomicU32::new(0)));
    board.attach(
        nvic::IRQ_DMA1_STREAM5,
        2,
        "host_rx_half",
        Box::new(move |r| uart_dma::host_rx_half(r, halves)),
    );
    let mut serial = DmaSerial::new(
        Port(board.clone()),
        halves,
        42_000_000,
        BAUD,
        RING as u32,
        RING_BYTES,
        TX as u32,
    );
    // The host's bytes on the line (with the fault's flips) after 100 µs.
    let sent_msgs = commands(s.commands);
    let mut host: Vec<u8> = Vec::new();
    let mut buf = [0u8; MAX_FRAME_SIZE];
    for (seq, m) in sent_msgs.iter().enumerate() {
        if let Ok(bytes) = encode(seq as u32, m, &mut buf) {
            host.extend_from_slice(bytes);
        }
    }
    let t0 = board.now() + us(100);
    let mut line = Vec::with_capacity(host.len());
    let mut flagged = Vec::with_capacity(host.len());
    let mut away: Option<(u64, u64)> = None;
    {
        let mut hw = board.hw.borrow_mut();
        for (i, &b) in host.iter().enumerate() {
            let t = t0 + i as u64 * byte_ticks;
            let (v, flag) = match s.fault {
                UartFault::Noise {
                    every,
                    bit,
                    flagged,
                } if i % every.max(1) == every / 2 => (b ^ (1 << (bit % 8)), flagged),
                _ => (b, false),
            };
            line.push(v);
            flagged.push(flag);
            hw.rx_bytes.push((t, v, flag));
        }
        match s.fault {
            UartFault::DmaStall { at, us: d } => {
                let a = t0 + at as u64 * byte_ticks;
                hw.faults.dma_stall = Some((a, a + us(d)));
            }
            UartFault::ReaderAway { at, us: d } => {
                let a = t0 + at as u64 * byte_ticks;
                away = Some((a, a + us(d)));
            }
            _ => {}
        }
    }
    // (Until the reader is back and has looked twice.)
    let back = away.map_or(0, |(_, b)| b + us(1_000));
    let end = (t0 + (host.len() as u64 + 20) * byte_ticks).max(back);
    // The idle loop: every 300 µs it reads what came and feeds the frame
    // receiver; per pass, (bytes delivered so far, the UART's counters
    // after it (line errors + ring overruns), the frame receiver's
    // failures after it).
    let mut receiver: Receiver<HostMessage> = Receiver::new();
    let mut got: Vec<u8> = Vec::new();
    let mut passes: Vec<(usize, [u64; 2])> = Vec::new();
    let mut pass_ticks: Vec<u64> = Vec::new();
    let mut decoded: Vec<(u32, HostMessage)> = Vec::new();
    let counted = |serial: &DmaSerial<Port>, rx: &Receiver<HostMessage>| {
        [
            u64::from(serial.receive_errors()),
            u64::from(rx.stats().failures()),
        ]
    };
    while board.now() < end {
        board.spend(2 * us(300));
        if matches!(away, Some((a, b)) if board.now() >= a && board.now() < b) {
            continue;
        }
        while let Some(b) = serial.read_byte() {
            got.push(b);
            if let Some(Ok(r)) = receiver.push_byte(b) {
                decoded.push((r.seq, r.message));
            }
        }
        passes.push((got.len(), counted(&serial, &receiver)));
        pass_ticks.push(board.now());
    }
    let mut out = UartOutcome {
        sent: host.len() as u64,
        delivered: got.len() as u64,
        commands: decoded.len() as u64,
        receive_errors: serial.receive_errors(),
        ..UartOutcome::default()
    };
    // Commands: each delivered one is the host's with that number.
    for (seq, m) in &decoded {
        if sent_msgs.get(*seq as usize) != Some(m) {
            out.corruptions += 1;
            out.problem(|| format!("command seq {seq} delivered as {m:?}, not as sent"));
        }
    }
    // Bytes: align what came with what was on the line (deletions only);
    // a stretch of host bytes lost or altered before delivered byte j must
    // see a counter move between the last pass before its first byte
    // arrived and the pass after the one that delivered the frame end
    // following it: the UART's own
    // counters when the UART could see it (a byte lost, or flagged noisy),
    // else (a bit flip the UART cannot see) the frame receiver's.
    let pass_of = |j: usize| {
        passes
            .iter()
            .position(|p| p.0 > j)
            .unwrap_or(passes.len() - 1)
    };
    let counter_after = |q: usize, k: usize| passes.get(q).map_or(0, |p| p.1[k]);
    let final_count = |k: usize| passes.last().map_or(0, |p| p.1[k]);
    // The last pass that ended before host byte `i` arrived.
    let last_pass_before = |i: usize| {
        let arrival = t0 + i as u64 * byte_ticks;
        pass_ticks.iter().rposition(|&t| t < arrival)
    };
    let (mut i, mut j) = (0usize, 0usize);
    let mut bad_since: Option<usize> = None;
    // Whether the UART could see the stretch (0: its counters, 1: frames').
    let mut which = 1usize;
    // Bytes the USART dropped (overrun) are known to the model: taken out
    // of the alignment as lost, so that equal byte values cannot shift it.
    let usart_lost: std::collections::BTreeSet<usize> =
        board.hw.borrow().rx_lost.iter().copied().collect();
    while i < line.len() {
        let altered = line[i] != host[i];
        if usart_lost.contains(&i) {
            which = 0;
            bad_since.get_or_insert(i);
        } else if j < got.len() && got[j] == line[i] && !altered {
            if let Some(first) = bad_since.take() {
                let k = which;
                which = 1;
                let before = last_pass_before(first).map_or(0, |q| counter_after(q, k));
                // (The frame receiver counts a broken frame at its
                // delimiter: the window runs to the next one delivered.)
                let delim = got[j..]
                    .iter()
                    .position(|&b| b == 0)
                    .map_or(got.len() - 1, |k| j + k);
                let after =
                    counter_after(pass_of(delim) + 1, k).max(counter_after(pass_of(delim), k));
                if after <= before {
                    out.uncounted += 1;
                    out.problem(|| {
                        format!(
                            "host bytes {first}..{i} lost or altered, no {} counter moved",
                            ["UART", "frame"][k]
                        )
                    });
                }
            }
            j += 1;
        } else {
            if j < got.len() && got[j] == line[i] {
                j += 1; // delivered, altered on the line
                if flagged[i] {
                    which = 0;
                }
            } else {
                which = 0; // lost: the USART or the ring must count it
            }
            bad_since.get_or_insert(i);
        }
        i += 1;
    }
    if let Some(first) = bad_since {
        let before = last_pass_before(first).map_or(0, |q| counter_after(q, which));
        if final_count(which) <= before {
            out.uncounted += 1;
            out.problem(|| {
                format!("host bytes {first}.. lost or altered at the end, no counter moved")
            });
        }
    }
    if j < got.len() {
        let extra = got.len() - j;
        out.corruptions += extra as u64;
        out.problem(|| format!("{extra} delivered bytes the host never sent"));
    }
    out
}

/// The host-link scenarios: line noise (flagged by the USART or not, at
/// every bit position, 1 in 7 to 1 in 97 bytes), USART overruns (the DMA
/// held off 0.1-2 ms at 20 points of the stream), the reader away 1-20 ms
/// (the 64-byte ring lapped).
pub fn scenarios() -> Vec<UartScenario> {
    let base = UartScenario {
        name: "host link clean",
        index: 0,
        commands: 40,
        fault: UartFault::None,
    };
    let mut v = vec![base];
    for every in [7, 13, 29, 53, 97] {
        for bit in 0..8 {
            for flagged in [true, false] {
                v.push(UartScenario {
                    name: "UART line noise",
                    fault: UartFault::Noise {
                        every,
                        bit,
                        flagged,
                    },
                    ..base
                });
            }
        }
    }
    for at in (5..205).step_by(10) {
        for us in [100, 300, 700, 2_000] {
            v.push(UartScenario {
                name: "UART overrun (DMA held off)",
                fault: UartFault::DmaStall { at, us },
                ..base
            });
        }
        for us in [1_000, 6_000, 20_000] {
            v.push(UartScenario {
                name: "UART ring lapped",
                fault: UartFault::ReaderAway { at, us },
                ..base
            });
        }
    }
    for (i, s) in v.iter_mut().enumerate() {
        s.index = i;
    }
    v
}
