//! The firmware's device and pipeline on the host (simulated hardware): a
//! synthetic run-down replayed over an in-memory link through the real
//! protocol, checked against the exact phasors and pedestal, and the box's
//! recursive estimate against the host's batch least squares on the box's
//! own phasors.

mod firmware_support;

use firmware_support::{Client, Scenario, VOLTS_PER_CODE};
use num_complex::Complex;
use plinth::estimate::Observation;
use plinth::identify::{fit_pedestal, Options};
use plinth_firmware::device::Device;
use plinth_firmware::link::ByteLink;
use plinth_firmware::replay::ReplaySource;
use plinth_shared::protocol::{DeviceMessage, DeviceState, HostMessage, NackReason};
use std::collections::VecDeque;

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

/// A box on the host with its link and replay source.
struct Bench {
    device: Box<Device>,
    source: ReplaySource,
    link: VecLink,
    client: Client,
    now_ms: u32,
}

impl Bench {
    fn new() -> Self {
        Self {
            device: Box::new(Device::new(VOLTS_PER_CODE as f32)),
            source: ReplaySource::new(VOLTS_PER_CODE as f32),
            link: VecLink::default(),
            client: Client::new(),
            now_ms: 0,
        }
    }

    /// Runs the box until it has nothing left to do.
    fn settle(&mut self) {
        loop {
            let a = self
                .device
                .poll(&mut self.link, &mut self.source, self.now_ms);
            let bytes = std::mem::take(&mut self.link.tx);
            self.client.feed(&bytes);
            if a.received == 0 && a.sent == 0 && a.samples == 0 {
                break;
            }
        }
    }

    /// Sends wire bytes and lets the box answer; returns the new messages.
    fn send_bytes(&mut self, bytes: &[u8]) -> Vec<DeviceMessage> {
        let before = self.client.received.len();
        self.link.rx.extend(bytes);
        self.settle();
        self.client.received[before..].to_vec()
    }

    /// Sends a command; returns its sequence number and the box's messages.
    fn send(&mut self, m: &HostMessage) -> (u32, Vec<DeviceMessage>) {
        let (seq, bytes) = self.client.encode(m);
        (seq, self.send_bytes(&bytes))
    }

    /// Sends a command that must be acknowledged.
    fn command(&mut self, m: &HostMessage) -> Vec<DeviceMessage> {
        let (seq, got) = self.send(m);
        assert!(
            got.iter()
                .any(|r| matches!(r, DeviceMessage::Ack(a) if a.command_seq == seq)),
            "command {seq} not acknowledged: {got:?}"
        );
        got
    }

    fn open(&mut self) {
        let (_, bytes) = self.client.hello(7);
        let got = self.send_bytes(&bytes);
        match got.first() {
            Some(DeviceMessage::HelloAck(a)) => {
                assert_eq!(a.host_nonce, 7);
                assert_eq!(a.capabilities.max_channels, 8);
                assert_eq!(a.capabilities.sample_rate_hz, 51_200.0);
            }
            other => panic!("expected HelloAck, got {other:?}"),
        }
    }
}

fn nack_reason(got: &[DeviceMessage], seq: u32) -> Option<NackReason> {
    got.iter().find_map(|m| match m {
        DeviceMessage::Nack(n) if n.command_seq == seq => Some(n.reason),
        _ => None,
    })
}

#[test]
fn a_hello_sent_again_after_its_answer_was_lost_opens_the_session() {
    let mut b = Bench::new();
    // Hello 1 reaches the box; its HelloAck is lost on the way back.
    let (_, hello1) = b
        .client
        .encode(&HostMessage::Hello(plinth_shared::protocol::Hello {
            protocol_version: plinth_shared::protocol::PROTOCOL_VERSION,
            host_nonce: 1,
        }));
    b.link.rx.extend(&hello1);
    b.device.poll(&mut b.link, &mut b.source, 0);
    b.device.poll(&mut b.link, &mut b.source, 0);
    assert!(!b.link.tx.is_empty(), "the box answered");
    b.link.tx.clear();
    assert_eq!(b.device.state(), DeviceState::Idle);
    // The host sends Hello again, frame 0 again, with a fresh nonce: the box
    // must take it as a new session, not as a repeated frame 0.
    let (seq, hello2) = b.client.hello(2);
    assert_eq!(seq, 0);
    let got = b.send_bytes(&hello2);
    assert!(
        matches!(got.as_slice(), [DeviceMessage::HelloAck(a)] if a.host_nonce == 2),
        "{got:?}"
    );
    // The same frame repeated by the line is dropped (and counted).
    let got = b.send_bytes(&hello2);
    assert!(got.is_empty(), "{got:?}");
    assert_eq!(b.device.link_stats().duplicates, 1);
    // The session works.
    let scenario = Scenario::standard();
    for m in scenario.configuration() {
        b.command(&m);
    }
}

#[test]
fn commands_before_hello_and_in_the_wrong_state_are_refused() {
    let mut b = Bench::new();
    let (seq, got) = b.send(&HostMessage::Start);
    assert_eq!(nack_reason(&got, seq), Some(NackReason::NoSession));
    // The Hello continues the numbering (a seq-0 Hello right after the
    // seq-0 Start would be dropped as a duplicate by the receiver).
    let hello = HostMessage::Hello(plinth_shared::protocol::Hello {
        protocol_version: plinth_shared::protocol::PROTOCOL_VERSION,
        host_nonce: 9,
    });
    b.client.rx.reset(); // the HelloAck is the box's frame 0 again
    let (_, got) = b.send(&hello);
    assert!(matches!(got.first(), Some(DeviceMessage::HelloAck(a)) if a.host_nonce == 9));
    assert_eq!(b.device.state(), DeviceState::Idle);
    // No configuration yet: Start is refused.
    let (seq, got) = b.send(&HostMessage::Start);
    assert_eq!(nack_reason(&got, seq), Some(NackReason::WrongState));
    let scenario = Scenario::standard();
    let config = scenario.configuration();
    // Channels without the bearing table: still not ready.
    b.command(&config[0]);
    let (seq, got) = b.send(&HostMessage::Start);
    assert_eq!(nack_reason(&got, seq), Some(NackReason::WrongState));
    for m in &config[1..] {
        b.command(m);
    }
    b.command(&HostMessage::Start);
    assert_eq!(b.device.state(), DeviceState::Running);
    // Reconfiguring while running is refused.
    let (seq, got) = b.send(&config[0]);
    assert_eq!(nack_reason(&got, seq), Some(NackReason::WrongState));
    // A block whose channel count differs from the channel set.
    let mut block = scenario.blocks().remove(0);
    block.channels = 3;
    let (seq, got) = b.send(&HostMessage::Samples(block));
    assert_eq!(nack_reason(&got, seq), Some(NackReason::BadBlock));
    let got = b.command(&HostMessage::Stop);
    assert!(got.iter().any(|m| matches!(m, DeviceMessage::Status(_))));
    assert_eq!(b.device.state(), DeviceState::Idle);
    // Counted since the Hello: the four refusals above.
    assert_eq!(b.device.counters().commands_rejected, 4);
}

#[test]
fn bad_configuration_values_are_refused_with_their_reason() {
    let mut b = Bench::new();
    b.open();
    let scenario = Scenario::standard();
    let HostMessage::ConfigureChannels(good) = scenario.configuration().remove(0) else {
        unreachable!()
    };
    type Mutation = Box<dyn Fn(&mut plinth_shared::protocol::ChannelSet)>;
    let cases: Vec<(Mutation, NackReason)> = vec![
        (
            Box::new(|s| s.channels[1].channel = 8),
            NackReason::BadChannel,
        ),
        (
            Box::new(|s| s.channels[1].channel = 0),
            NackReason::BadChannel,
        ),
        (
            Box::new(|s| s.channels[2].bearing = 4),
            NackReason::BadBearing,
        ),
        (
            Box::new(|s| s.channels[0].sensitivity = 0.0),
            NackReason::BadValue,
        ),
        (
            Box::new(|s| s.channels[0].sensitivity = f32::NAN),
            NackReason::BadValue,
        ),
    ];
    for (break_it, reason) in cases {
        let mut set = good.clone();
        break_it(&mut set);
        let (seq, got) = b.send(&HostMessage::ConfigureChannels(set));
        assert_eq!(nack_reason(&got, seq), Some(reason));
    }
    let (seq, got) = b.send(&HostMessage::ConfigureAveraging(
        plinth_shared::protocol::Averaging {
            revolutions_per_phasor: 0,
        },
    ));
    assert_eq!(nack_reason(&got, seq), Some(NackReason::BadValue));
    // A table chunk that does not start at row 0.
    let HostMessage::BearingTable(mut chunk) = scenario.configuration().remove(2) else {
        unreachable!()
    };
    chunk.first_row = 1;
    chunk.total_rows = 4;
    let (seq, got) = b.send(&HostMessage::BearingTable(chunk.clone()));
    assert_eq!(nack_reason(&got, seq), Some(NackReason::TableOutOfOrder));
    // Decreasing speeds.
    chunk.first_row = 0;
    chunk.total_rows = chunk.rows.len() as u16;
    chunk.rows[1].speed_hz = 0.5;
    let (seq, got) = b.send(&HostMessage::BearingTable(chunk));
    assert_eq!(nack_reason(&got, seq), Some(NackReason::TableNotIncreasing));
}

#[test]
fn replayed_run_down_gives_true_phasors_and_the_batch_estimate() {
    let scenario = Scenario::standard();
    let mut b = Bench::new();
    b.open();
    for m in scenario.configuration() {
        b.command(&m);
    }
    b.command(&HostMessage::Start);
    let mut frames = Vec::new();
    for block in scenario.blocks() {
        let got = b.command(&HostMessage::Samples(block));
        frames.extend(got.into_iter().filter_map(|m| match m {
            DeviceMessage::Phasors(p) => Some(p),
            _ => None,
        }));
    }
    let got = b.command(&HostMessage::Stop);
    let estimate = got
        .iter()
        .find_map(|m| match m {
            DeviceMessage::Estimates(e) => e.pedestals.first().copied(),
            _ => None,
        })
        .expect("a final estimate after Stop");
    let status = got
        .iter()
        .find_map(|m| match m {
            DeviceMessage::Status(s) => Some(s.clone()),
            _ => None,
        })
        .expect("a status frame after Stop");

    // 60 → 25 Hz over 2.5 s is ≈ 106 revolutions; the extractor needs
    // three edges to lock and holds two back.
    assert!(frames.len() >= 95, "{} phasor frames", frames.len());
    assert_eq!(status.counters.keyphasor_missing, 0);
    assert_eq!(status.counters.keyphasor_extra, 0);
    assert_eq!(status.counters.queue_full_drops, 0);
    assert_eq!(status.counters.overruns, 0);

    // Phasors against the response at each revolution's speed (the run-down
    // crosses the pedestal resonances at 14 Hz/s, 0.3 Hz per revolution):
    // what is left is ADC quantisation (~1e-3 of the smallest phasors) and
    // the run-down correction's remainder.
    let mut worst = 0.0f64;
    let mut points = Vec::new();
    for f in &frames {
        assert_eq!(f.bearings.len(), 1);
        assert_eq!(f.revolutions, 1);
        let (want, speed_want) = scenario
            .revolution_phasors(f.revolution as usize)
            .expect("a revolution inside the run");
        let speed = f64::from(f.speed_hz);
        assert!(
            (speed - speed_want).abs() < 1e-4 * speed_want,
            "revolution {}: speed {speed} vs {speed_want}",
            f.revolution
        );
        let c =
            |w: plinth_shared::protocol::WirePhasor| Complex::new(f64::from(w.re), f64::from(w.im));
        let bp = &f.bearings[0];
        let got = [c(bp.rel[0]), c(bp.rel[1]), c(bp.ped[0]), c(bp.ped[1])];
        for (g, w) in got.iter().zip(&want) {
            worst = worst.max((g - w).norm() / w.norm());
        }
        points.push(Observation::without_noise(
            speed,
            [got[0], got[1]],
            [got[2], got[3]],
            &scenario.bearing,
        ));
    }
    assert!(worst < 1e-3, "worst relative phasor error {worst:e}");

    // The box's recursive estimate equals the batch least squares on the
    // same phasors (f32 on the box vs f64 SVD on the host).
    let batch = fit_pedestal("0", &points, &Options::default()).expect("batch fit");
    let batch = batch.pedestal.theta();
    for (i, (&got, &want)) in estimate.theta.iter().zip(batch.iter()).enumerate() {
        let rel = (f64::from(got) - want).abs() / want.abs();
        assert!(rel < 2e-3, "parameter {i}: box {got} vs batch {want}");
    }
    eprintln!("box estimate {:?} ± {:?}", estimate.theta, estimate.std_err);
    eprintln!("batch        {batch:?}");
    eprintln!(
        "worst phasor error {worst:.2e} over {} revolutions",
        frames.len()
    );
    // And both are close to the pedestal the data came from.
    for i in 0..5 {
        let truth = scenario.pedestal[i];
        let rel = (f64::from(estimate.theta[i]) - truth).abs() / truth;
        let tol = if i < 3 { 1e-2 } else { 5e-2 };
        assert!(
            rel < tol,
            "parameter {i}: box {} vs truth {truth}",
            estimate.theta[i]
        );
        assert!(estimate.std_err[i].is_finite() && estimate.std_err[i] > 0.0);
    }
}

/// The phasor frames among `got`.
fn phasor_frames(got: Vec<DeviceMessage>) -> Vec<plinth_shared::protocol::PhasorFrame> {
    got.into_iter()
        .filter_map(|m| match m {
            DeviceMessage::Phasors(p) => Some(p),
            _ => None,
        })
        .collect()
}

/// A box configured for `scenario` and started.
fn started(scenario: &Scenario) -> Bench {
    let mut b = Bench::new();
    b.open();
    for m in scenario.configuration() {
        b.command(&m);
    }
    b.command(&HostMessage::Start);
    b
}

#[test]
fn blocks_are_taken_in_order_repeats_acknowledged_and_gaps_refused() {
    let scenario = Scenario::standard();
    let blocks = scenario.blocks();

    // Reference: every block once, in order.
    let mut clean = started(&scenario);
    let mut want = Vec::new();
    let mut producing = Vec::new();
    for (i, block) in blocks.iter().enumerate() {
        let got = phasor_frames(clean.command(&HostMessage::Samples(block.clone())));
        if !got.is_empty() {
            producing.push(i);
        }
        want.extend(got);
    }
    // Two blocks that each complete a revolution, with blocks between them.
    let dup = producing[3];
    let skip_to = *producing.iter().find(|&&i| i > dup + 2).unwrap();

    let mut b = started(&scenario);
    let mut frames = Vec::new();
    let mut i = 0;
    let mut repeated = false;
    let mut skipped = false;
    while i < blocks.len() {
        // In order: processed and acknowledged.
        frames.extend(phasor_frames(
            b.command(&HostMessage::Samples(blocks[i].clone())),
        ));
        if i == dup && !repeated {
            // The same block again (its Ack was lost): acknowledged, and
            // nothing else; the frames it produced are not sent twice.
            repeated = true;
            let (seq, got) = b.send(&HostMessage::Samples(blocks[i].clone()));
            assert!(
                matches!(got.as_slice(), [DeviceMessage::Ack(a)] if a.command_seq == seq),
                "repeated block {i}: {got:?}"
            );
            // An older block too.
            let (seq, got) = b.send(&HostMessage::Samples(blocks[0].clone()));
            assert!(
                matches!(got.as_slice(), [DeviceMessage::Ack(a)] if a.command_seq == seq),
                "repeated block 0: {got:?}"
            );
        }
        if i + 1 == skip_to && !skipped {
            // Block i + 1 is lost on the way: the next ones are refused,
            // and what they would have produced is not sent.
            skipped = true;
            for later in [skip_to + 1, skip_to + 2] {
                let (seq, got) = b.send(&HostMessage::Samples(blocks[later].clone()));
                assert_eq!(got.len(), 1, "block {later} after a gap: {got:?}");
                assert_eq!(nack_reason(&got, seq), Some(NackReason::BadBlock));
            }
        }
        i += 1;
    }
    assert!(repeated && skipped);
    assert_eq!(b.source.counters().accepted as usize, blocks.len());
    assert_eq!(b.source.counters().duplicates, 2);
    assert_eq!(b.source.counters().out_of_order, 2);
    let counters = b.device.counters();
    assert_eq!(counters.commands_rejected, 2);
    assert_eq!(counters.overruns, 0);
    // The time base never broke: exactly the reference's frames.
    assert_eq!(frames.len(), want.len());
    assert!(frames == want, "phasor frames differ from the in-order run");
}
