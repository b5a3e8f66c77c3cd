//! The board's acquisition path (`plinth_firmware::acquisition`, the logic
//! of the `plinth-box` image) on the host against simulated hardware: a
//! CONVST timer at the rate its settings really give, an SPI DMA filling a
//! double buffer one conversion at a time, a transfer-complete count, and a
//! 32-bit capture timer latching keyphasor edges; the consumer is slowed
//! down at random (late polls, copies preempted by the DMA).
//!
//! - Overruns: every lost half is counted, the counts add up to the samples
//!   not delivered, and no delivered buffer holds a sample from the wrong
//!   conversion (each sample vector is checked against the one converted at
//!   its time).
//! - A conversion the BUSY interrupt misses (a sequence fault) restarts
//!   acquisition: one counted gap, never samples one conversion out of
//!   place (each vector carries its conversion's number, each edge is
//!   checked against the conversions' own times).
//! - Keyphasor at a changing speed (60 → 25 Hz in 2.5 s), captures at
//!   84 MHz across the 32-bit wrap: every edge delivered once, within
//!   1e-3 sample of the true time (measured ≤ 3.0e-4, half a tick).
//! - Through the protocol: the box announces the rate its timer gives,
//!   its phasors match the exact ones and its speeds are within 1e-4; with
//!   a slow consumer, the status frame's `overruns` is the lost samples.

mod firmware_dma_board;
mod firmware_support;

use firmware_dma_board::{check_buffer, codes, source, Board, HALF, TIMER_HZ};
use firmware_support::{Client, Scenario, VOLTS_PER_CODE};
use num_complex::Complex;
use plinth_firmware::acquisition::dma_source::DmaSource;
use plinth_firmware::ad7606::Range;
use plinth_firmware::device::Device;
use plinth_firmware::link::ByteLink;
use plinth_firmware::source::{SampleBuffer, SampleSource, CHANNELS};
use plinth_shared::protocol::{DeviceMessage, HostMessage, StatusFrame};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::collections::VecDeque;

#[test]
fn a_slow_consumer_loses_whole_counted_halves_and_never_a_torn_one() {
    let scenario = Scenario::standard();
    let board = Board::new(scenario, 0x1234_5678);
    let mut source = source(&board);
    source.start().unwrap();
    let p = board.0.borrow().p;
    let half_ticks = p * HALF as u64;
    let mut rng = StdRng::seed_from_u64(12);
    let (mut next, mut delivered, mut reported_lost, mut halves) = (0u64, 0u64, 0u64, 0u64);
    let mut buf = SampleBuffer::default();
    let mut edges = 0usize;
    while board.0.borrow().converted < board.0.borrow().total {
        // Mostly on time; sometimes several halves late; copies sometimes
        // slowed to a crawl (up to 1.5 sample periods per vector).
        let wait = match rng.random_range(0..10) {
            0..=5 => rng.random_range(half_ticks / 4..half_ticks),
            6..=8 => rng.random_range(half_ticks..4 * half_ticks),
            _ => rng.random_range(0..half_ticks / 2),
        };
        board.0.borrow_mut().read_cost = if rng.random_bool(0.3) {
            rng.random_range(p / 4..3 * p / 2)
        } else {
            0
        };
        board.advance(wait);
        source.poll(&mut buf);
        if buf.is_empty() {
            continue;
        }
        let first = next + u64::from(buf.lost_before);
        for pos in check_buffer(&board, &buf, first) {
            let s = board.0.borrow();
            let rate = s.rate();
            assert!(
                s.pulses.iter().any(|t| (t * rate - pos).abs() < 1e-3),
                "edge at sample {pos} matches no keyphasor pulse"
            );
            edges += 1;
        }
        reported_lost += u64::from(buf.lost_before);
        delivered += buf.samples.len() as u64;
        halves += 1;
        next = first + buf.samples.len() as u64;
    }
    // A last, prompt poll reports any loss still pending.
    board.0.borrow_mut().read_cost = 0;
    board.advance(half_ticks);
    source.poll(&mut buf);
    if !buf.is_empty() {
        let first = next + u64::from(buf.lost_before);
        check_buffer(&board, &buf, first);
        reported_lost += u64::from(buf.lost_before);
        delivered += buf.samples.len() as u64;
        halves += 1;
        next = first + buf.samples.len() as u64;
    }
    let c = source.counters();
    eprintln!(
        "delivered {halves} halves ({delivered} vectors, {edges} edges), lost {} halves ({} torn)",
        c.overrun_halves, c.torn_halves
    );
    assert_eq!(delivered + reported_lost, next);
    assert_eq!(u64::from(c.overrun_halves) * HALF as u64, reported_lost);
    assert!(c.torn_halves >= 3, "the scenario tears copies: {c:?}");
    assert!(
        c.overrun_halves > c.torn_halves + 10,
        "and skips halves: {c:?}"
    );
    assert!(halves > 100, "and delivers most: {halves}");
}

#[test]
fn keyphasor_edges_at_a_changing_speed_within_a_thousandth_of_a_sample() {
    let scenario = Scenario::standard(); // 60 → 25 Hz in 2.5 s
                                         // The capture count wraps ≈ 1.2 s into the run.
    let board = Board::new(scenario, u32::MAX - 100_000_000);
    let mut source = source(&board);
    source.start().unwrap();
    let p = board.0.borrow().p;
    let mut rng = StdRng::seed_from_u64(3);
    let mut positions = Vec::new();
    let mut next = 0u64;
    let mut buf = SampleBuffer::default();
    loop {
        board.advance(rng.random_range(p * 10..p * HALF as u64));
        source.poll(&mut buf);
        if !buf.is_empty() {
            assert_eq!(buf.lost_before, 0);
            positions.extend(check_buffer(&board, &buf, next));
            next += buf.samples.len() as u64;
        }
        let s = board.0.borrow();
        if s.converted == s.total && s.completions.count() as u64 * HALF as u64 == next {
            break;
        }
    }
    let s = board.0.borrow();
    let rate = s.rate();
    // Every pulse inside the delivered samples, once, in order.
    let want: Vec<f64> = s
        .pulses
        .iter()
        .map(|t| t * rate)
        .filter(|&x| x < (next - 1) as f64)
        .collect();
    assert_eq!(positions.len(), want.len());
    let worst = positions
        .iter()
        .zip(&want)
        .map(|(g, w)| (g - w).abs())
        .fold(0.0, f64::max);
    eprintln!("{} edges, worst error {worst:.2e} sample", want.len());
    assert!(worst < 1e-3, "worst edge error {worst:e} sample");
    assert_eq!(source.counters().dropped_edges, 0);
    assert!(want.len() > 100);
}

#[test]
fn a_missed_conversion_restarts_acquisition_instead_of_shifting_the_samples() {
    // BUSY's interrupt misses conversion 50 000 (≈ 1 s in): without a
    // restart every later sample would sit one conversion early and every
    // keyphasor edge one sample late.
    let scenario = Scenario::standard();
    let board = Board::new(scenario, 0xFFFF_0000);
    board.0.borrow_mut().skip = Some(50_000);
    let mut source = source(&board);
    source.start().unwrap();
    let p = board.0.borrow().p;
    let mut rng = StdRng::seed_from_u64(5);
    let mut buf = SampleBuffer::default();
    let (mut edges, mut gaps) = (0usize, 0usize);
    let mut previous_last: Option<u64> = None;
    while board.0.borrow().converted < board.0.borrow().total {
        board.advance(rng.random_range(p * 10..p * HALF as u64));
        source.poll(&mut buf);
        if buf.is_empty() {
            continue;
        }
        let s = board.0.borrow();
        let step = Range::PlusMinus10V.volts_per_code();
        // Which conversion each vector holds (its channels 4 and 5), and
        // that it is that conversion, whole.
        let k_of = |v: &[f32; CHANNELS]| {
            let lo = (v[4] / step).round() as u64;
            let hi = (v[5] / step).round() as u64;
            hi * 30_000 + lo
        };
        let k_first = k_of(&buf.samples[0]);
        for (i, v) in buf.samples.iter().enumerate() {
            let k = k_first + i as u64;
            assert_eq!(
                k_of(v),
                k,
                "vectors of one buffer are consecutive conversions"
            );
            let want = codes(&s.scenario, k, s.ticks[k as usize]).map(|c| f32::from(c) * step);
            assert_eq!(*v, want);
        }
        if buf.lost_before > 0 {
            gaps += 1;
        } else if let Some(last) = previous_last {
            assert_eq!(k_first, last + 1, "no gap without lost_before");
        }
        previous_last = Some(k_first + buf.samples.len() as u64 - 1);
        // Each edge where the pulse really was, by the conversions' own
        // times.
        for e in &buf.edges {
            let before = s.ticks[(k_first + e.index as u64 - 1) as usize];
            let tick = before as f64 + f64::from(e.fraction) * p as f64;
            let nearest = s
                .pulses
                .iter()
                .map(|t| (t * f64::from(TIMER_HZ) - tick).abs())
                .fold(f64::INFINITY, f64::min);
            assert!(
                nearest < 1e-3 * p as f64,
                "edge {e:?} of the buffer from conversion {k_first} is {:.3} samples off",
                nearest / p as f64
            );
            edges += 1;
        }
    }
    let c = source.counters();
    eprintln!("{edges} edges, {} resync, {gaps} gaps", c.resyncs);
    assert_eq!(c.resyncs, 1);
    assert_eq!(gaps, 1);
    assert!(edges > 90, "{edges} edges");
}

/// An unbounded in-memory link.
#[derive(Default)]
struct VecLink {
    rx: VecDeque<u8>,
    tx: Vec<u8>,
}

impl ByteLink for VecLink {
    fn read_byte(&mut self) -> Option<u8> {
        self.rx.pop_front()
    }
    fn write_byte(&mut self, byte: u8) -> bool {
        self.tx.push(byte);
        true
    }
}

/// The box with the simulated board, through the protocol: returns the
/// phasor frames, the status frame after `Stop` and the source's counters.
fn session(
    lateness: impl FnMut(&mut StdRng, u64) -> u64,
) -> (
    Vec<plinth_shared::protocol::PhasorFrame>,
    StatusFrame,
    plinth_firmware::acquisition::dma_source::DmaSourceCounters,
    f32,
) {
    let mut lateness = lateness;
    let scenario = Scenario::standard();
    let board = Board::new(scenario, 77);
    let rate = board.0.borrow().rate() as f32;
    let mut device = Box::new(Device::with_sample_rate(VOLTS_PER_CODE as f32, rate));
    let mut source = source(&board);
    let mut link = VecLink::default();
    let mut client = Client::new();
    let send = |m: Option<&HostMessage>,
                device: &mut Device,
                source: &mut DmaSource<Board>,
                link: &mut VecLink,
                client: &mut Client| {
        if let Some(m) = m {
            let bytes = if matches!(m, HostMessage::Hello(_)) {
                client.hello(5).1
            } else {
                client.encode(m).1
            };
            link.rx.extend(bytes);
        }
        for _ in 0..4 {
            device.poll(link, source, 0);
            let bytes = std::mem::take(&mut link.tx);
            client.feed(&bytes);
        }
    };
    let hello = HostMessage::Hello(plinth_shared::protocol::Hello {
        protocol_version: 0,
        host_nonce: 0,
    });
    send(
        Some(&hello),
        &mut device,
        &mut source,
        &mut link,
        &mut client,
    );
    match client.received.first() {
        Some(DeviceMessage::HelloAck(a)) => assert_eq!(a.capabilities.sample_rate_hz, rate),
        other => panic!("expected HelloAck, got {other:?}"),
    }
    for m in scenario.configuration() {
        send(Some(&m), &mut device, &mut source, &mut link, &mut client);
    }
    send(
        Some(&HostMessage::Start),
        &mut device,
        &mut source,
        &mut link,
        &mut client,
    );
    let p = board.0.borrow().p;
    let mut rng = StdRng::seed_from_u64(9);
    while board.0.borrow().converted < board.0.borrow().total {
        board.advance(lateness(&mut rng, p * HALF as u64));
        send(None, &mut device, &mut source, &mut link, &mut client);
    }
    board.advance(p * HALF as u64);
    send(None, &mut device, &mut source, &mut link, &mut client);
    send(
        Some(&HostMessage::Stop),
        &mut device,
        &mut source,
        &mut link,
        &mut client,
    );
    let frames = client
        .received
        .iter()
        .filter_map(|m| match m {
            DeviceMessage::Phasors(p) => Some(p.clone()),
            _ => None,
        })
        .collect();
    let status = client
        .received
        .iter()
        .rev()
        .find_map(|m| match m {
            DeviceMessage::Status(s) => Some(s.clone()),
            _ => None,
        })
        .expect("a status frame after Stop");
    (frames, status, source.counters(), rate)
}

/// Worst |box − exact| / |exact| over the frames' phasors, the exact ones
/// at the frame's own speed.
fn worst_phasor_error(frames: &[plinth_shared::protocol::PhasorFrame]) -> f64 {
    let scenario = Scenario::standard();
    let c = |w: plinth_shared::protocol::WirePhasor| Complex::new(f64::from(w.re), f64::from(w.im));
    let mut worst = 0.0f64;
    for f in frames {
        let speed = f64::from(f.speed_hz);
        let (rel, ped) = (scenario.rel(speed), scenario.ped(speed));
        let b = &f.bearings[0];
        for (g, w) in [c(b.rel[0]), c(b.rel[1]), c(b.ped[0]), c(b.ped[1])]
            .iter()
            .zip([rel[0], rel[1], ped[0], ped[1]])
        {
            worst = worst.max((g - w).norm() / w.norm());
        }
    }
    worst
}

#[test]
fn through_the_protocol_phasors_are_exact_and_overruns_reach_the_status_frame() {
    // A prompt consumer: nothing lost, every revolution's phasor.
    let (frames, status, counters, rate) = session(|rng, half| rng.random_range(half / 8..half));
    assert_eq!(counters.overrun_halves, 0);
    assert_eq!(status.counters.overruns, 0);
    assert_eq!(status.counters.keyphasor_missing, 0);
    assert_eq!(status.counters.keyphasor_extra, 0);
    assert!(frames.len() >= 95, "{} phasor frames", frames.len());
    check_speeds(&frames, rate);
    let worst = worst_phasor_error(&frames);
    eprintln!(
        "prompt: {} frames, worst phasor error {worst:.2e}",
        frames.len()
    );
    assert!(worst < 2e-3, "worst relative phasor error {worst:e}");

    let scenario = Scenario::standard();
    // A consumer that now and then (1 % of its passes) falls three halves
    // behind.
    let (frames, status, counters, _) = session(|rng, half| {
        if rng.random_bool(0.01) {
            3 * half
        } else {
            rng.random_range(half / 8..half)
        }
    });
    assert!(counters.overrun_halves > 0);
    assert_eq!(
        u64::from(status.counters.overruns),
        u64::from(counters.overrun_halves) * HALF as u64,
        "status overruns count the lost samples"
    );
    // The extractor restarts after each gap: fewer phasors, each at the true
    // speed of one of the run's revolutions (the pipeline's revolution
    // numbers after a gap can be one off: it cannot count the revolutions
    // in lost samples). The first phasor after a restart has no earlier
    // revolution for the run-down correction (the extractor's design):
    // measured 2.1e-3 near the 31.8 Hz resonance.
    assert!(frames.len() >= 20, "{} phasor frames", frames.len());
    for f in &frames {
        let got = f64::from(f.speed_hz);
        assert!(
            (0..)
                .map_while(|r| scenario.revolution_phasors(r))
                .any(|(_, speed)| (got - speed).abs() < 1e-4 * speed),
            "{got} Hz is no revolution's speed"
        );
    }
    let worst = worst_phasor_error(&frames);
    eprintln!(
        "late: {} frames, {} halves lost, worst phasor error {worst:.2e}",
        frames.len(),
        counters.overrun_halves
    );
    assert!(worst < 5e-3, "worst relative phasor error {worst:e}");
}

/// Each frame's speed is its revolution's true mean speed within 1e-4 (the
/// box divides by the rate its timer really gives, `rate` [Hz]).
fn check_speeds(frames: &[plinth_shared::protocol::PhasorFrame], rate: f32) {
    let scenario = Scenario::standard();
    for f in frames {
        let (_, speed) = scenario.revolution_phasors(f.revolution as usize).unwrap();
        let got = f64::from(f.speed_hz);
        assert!(
            (got - speed).abs() < 1e-4 * speed,
            "revolution {}: {got} Hz vs {speed} Hz at {rate} samples/s",
            f.revolution
        );
    }
}
