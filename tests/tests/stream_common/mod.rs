//! Shared rig of the streaming tests: a short simulated run-down of the
//! bundled paper machine, a stream configuration for it, the firmware's
//! device compiled for the host behind a pseudo-terminal (with an optional
//! seeded fault-injecting proxy on the byte stream), and the host-only
//! reference (the same device fed the same sample blocks in memory).
#![allow(dead_code)]

use plinth::sim::inject::EffectSet;
use plinth::sim::machine::Machine;
use plinth::sim::signals::{synthesise_to, RunDown, SignalOptions};
use plinth::stream::config::{BearingTables, StreamConfig};
use plinth::stream::port::{pseudo_terminal, TTYPort};
use plinth::stream::replay::{ReplayPlan, SignalSetReplay};
use plinth_firmware::device::Device;
use plinth_firmware::link::ByteLink;
use plinth_firmware::replay::ReplaySource as FirmwareReplay;
use plinth_shared::protocol::{
    DeviceMessage, Hello, HostMessage, Receiver, Transmitter, MAX_FRAME_SIZE, PROTOCOL_VERSION,
};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::collections::VecDeque;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// ADC step of the simulated box [V] (the replay sends volts, so it only
/// matters for the capabilities the box reports).
pub const VOLTS_PER_CODE: f32 = 10.0 / 32768.0;

/// The bundled paper machine with pedestal damping.
pub const PAPER_MACHINE_DAMPED: &str = include_str!("../../../examples/feng-hahn-1997-damped.toml");

/// A simulated run-down on disk with its stream configuration.
pub struct Scenario {
    /// Holds every file.
    pub dir: tempfile::TempDir,
    /// The signal set (`plinth signals` output).
    pub signals: PathBuf,
    /// The stream configuration file.
    pub config_path: PathBuf,
    /// The configuration, loaded.
    pub config: StreamConfig,
    /// Its bearing tables.
    pub tables: BearingTables,
}

impl Scenario {
    /// The damped paper machine run down from `start_hz` to `end_hz` at
    /// `rate` [Hz/s], sampled at the box's 51.2 kHz, accelerometers on the
    /// pedestals, 1 mV noise.
    pub fn paper_rundown(start_hz: f64, end_hz: f64, rate: f64) -> Scenario {
        let dir = tempfile::tempdir().expect("temporary directory");
        let machine = Machine::from_toml_str(PAPER_MACHINE_DAMPED, "feng-hahn-1997-damped.toml")
            .expect("bundled paper machine");
        let opts = SignalOptions {
            rundown: RunDown {
                start_hz,
                end_hz,
                rate_hz_per_s: rate,
            },
            sample_rate_hz: plinth_firmware::device::SAMPLE_RATE_HZ as f64,
            grid_step_hz: 0.25,
            seed: 7,
            ..SignalOptions::default()
        };
        let signals = dir.path().join("signals");
        let set = synthesise_to(&machine, &EffectSet::none(), &opts, &signals)
            .expect("synthesising the run-down");
        // The box holds 48 rows per bearing: keep the truth grid's rows over
        // the run (plus one on each side), thinned to at most 40.
        let truth = plinth::rundir::RunDir::read(signals.join("truth")).expect("truth run");
        let (lo, hi) = (start_hz.min(end_hz), start_hz.max(end_hz));
        let mut rows = Vec::new();
        for name in machine.bearing_names() {
            let mine: Vec<_> = truth
                .bearings
                .iter()
                .filter(|r| r.bearing == name)
                .collect();
            let first = mine.iter().rposition(|r| r.speed_hz <= lo).unwrap_or(0);
            let last = mine
                .iter()
                .position(|r| r.speed_hz >= hi)
                .unwrap_or(mine.len() - 1);
            let step = (last - first).div_ceil(39).max(1);
            let mut i = first;
            while i < last {
                rows.push(mine[i].clone());
                i += step;
            }
            rows.push(mine[last].clone());
        }
        let tables_dir = dir.path().join("tables");
        plinth::rundir::RunDir {
            measurements: Vec::new(),
            bearings: rows,
            truth: None,
        }
        .write(&tables_dir)
        .expect("writing bearings.csv");
        let config_path = dir.path().join("stream.toml");
        std::fs::write(
            &config_path,
            plinth::demo::config_text(&set, "tables/bearings.csv", 4),
        )
        .expect("writing the stream configuration");
        let config = StreamConfig::load(&config_path).expect("stream configuration");
        let tables = config.load_bearing_tables().expect("bearing tables");
        Scenario {
            dir,
            signals,
            config_path,
            config,
            tables,
        }
    }

    /// The replay as the host sends it.
    pub fn replay(&self) -> SignalSetReplay {
        SignalSetReplay::load(&self.signals, &self.config).expect("replay signals")
    }

    /// A fresh output directory inside the scenario.
    pub fn out_dir(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }
}

/// Faults a proxy injects into one direction of the byte stream, each with
/// its probability per byte.
#[derive(Clone, Copy, Debug, Default)]
pub struct Faults {
    /// One random bit of the byte flipped.
    pub flip: f64,
    /// The byte dropped.
    pub drop: f64,
    /// The byte sent twice.
    pub duplicate: f64,
}

/// How many faults a proxy injected.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FaultCounts {
    /// Bits flipped.
    pub flipped: u64,
    /// Bytes dropped.
    pub dropped: u64,
    /// Bytes duplicated.
    pub duplicated: u64,
}

impl FaultCounts {
    /// All faults.
    pub fn total(&self) -> u64 {
        self.flipped + self.dropped + self.duplicated
    }
}

/// A seeded byte mangler.
struct Mangler {
    faults: Faults,
    rng: StdRng,
    counts: FaultCounts,
}

impl Mangler {
    fn new(faults: Faults, seed: u64) -> Self {
        Self {
            faults,
            rng: StdRng::seed_from_u64(seed),
            counts: FaultCounts::default(),
        }
    }

    fn pass(&mut self, input: &[u8], out: &mut Vec<u8>) {
        for &b in input {
            let r: f64 = self.rng.random();
            if r < self.faults.drop {
                self.counts.dropped += 1;
                continue;
            }
            let mut byte = b;
            if self.rng.random::<f64>() < self.faults.flip {
                byte ^= 1 << self.rng.random_range(0..8);
                self.counts.flipped += 1;
            }
            out.push(byte);
            if self.rng.random::<f64>() < self.faults.duplicate {
                out.push(byte);
                self.counts.duplicated += 1;
            }
        }
    }
}

/// The device's end of the pseudo-terminal, with the fault proxy in both
/// directions, as the firmware's non-blocking byte link.
struct ProxiedPty {
    master: TTYPort,
    rx: VecDeque<u8>,
    tx: Vec<u8>,
    to_device: Mangler,
    to_host: Mangler,
    /// Everything the device sent, before any fault.
    sent: Arc<Mutex<Vec<u8>>>,
    scratch: Vec<u8>,
}

impl ProxiedPty {
    /// Reads what the host wrote (through the proxy).
    fn fill(&mut self) {
        let mut buf = [0u8; 4096];
        match self.master.read(&mut buf) {
            Ok(n) if n > 0 => {
                self.scratch.clear();
                self.to_device.pass(&buf[..n], &mut self.scratch);
                self.rx.extend(self.scratch.iter().copied());
            }
            // Timeouts, and EIO while no host has the slave open.
            _ => {}
        }
    }

    /// Writes what the device queued (through the proxy).
    fn flush(&mut self) {
        if self.tx.is_empty() {
            return;
        }
        if let Ok(mut s) = self.sent.lock() {
            s.extend_from_slice(&self.tx);
        }
        self.scratch.clear();
        self.to_host.pass(&self.tx, &mut self.scratch);
        self.tx.clear();
        let mut rest = &self.scratch[..];
        let deadline = Instant::now() + Duration::from_millis(500);
        while !rest.is_empty() && Instant::now() < deadline {
            match self.master.write(rest) {
                Ok(n) => rest = &rest[n..],
                Err(_) => std::thread::sleep(Duration::from_millis(1)),
            }
        }
    }
}

impl ByteLink for ProxiedPty {
    fn read_byte(&mut self) -> Option<u8> {
        self.rx.pop_front()
    }
    fn write_byte(&mut self, byte: u8) -> bool {
        self.tx.push(byte);
        true
    }
}

/// The firmware's device running on the host behind a pseudo-terminal.
pub struct DeviceThread {
    /// Path of the slave end for `plinth stream --port`.
    pub port: String,
    stop: Arc<AtomicBool>,
    sent: Arc<Mutex<Vec<u8>>>,
    thread: Option<JoinHandle<(FaultCounts, FaultCounts)>>,
}

impl DeviceThread {
    /// Starts a device with `to_host` / `to_device` faults (seeded).
    pub fn start(to_host: Faults, to_device: Faults, seed: u64) -> DeviceThread {
        let (mut master, port) = pseudo_terminal().expect("pseudo-terminal");
        use serialport_trait::SerialPort;
        master
            .set_timeout(Duration::from_millis(1))
            .expect("pty timeout");
        let stop = Arc::new(AtomicBool::new(false));
        let sent = Arc::new(Mutex::new(Vec::new()));
        let mut link = ProxiedPty {
            master,
            rx: VecDeque::new(),
            tx: Vec::new(),
            to_device: Mangler::new(to_device, seed),
            to_host: Mangler::new(to_host, seed ^ 0x9e37_79b9_7f4a_7c15),
            sent: sent.clone(),
            scratch: Vec::new(),
        };
        let flag = stop.clone();
        let thread = std::thread::spawn(move || {
            let mut device = Box::new(Device::new(VOLTS_PER_CODE));
            let mut source = FirmwareReplay::new(VOLTS_PER_CODE);
            let t0 = Instant::now();
            while !flag.load(Ordering::Relaxed) {
                link.fill();
                let now_ms = t0.elapsed().as_millis() as u32;
                let mut busy = false;
                loop {
                    let a = device.poll(&mut link, &mut source, now_ms);
                    link.flush();
                    if a.received == 0 && a.sent == 0 && a.samples == 0 {
                        break;
                    }
                    busy = true;
                }
                if !busy && link.rx.is_empty() {
                    std::thread::sleep(Duration::from_micros(200));
                }
            }
            (link.to_host.counts, link.to_device.counts)
        });
        DeviceThread {
            port,
            stop,
            sent,
            thread: Some(thread),
        }
    }

    /// Everything the device has sent so far, before faults.
    pub fn sent(&self) -> Vec<u8> {
        self.sent.lock().map(|s| s.clone()).unwrap_or_default()
    }

    /// Stops the device; returns the faults injected (to host, to device).
    pub fn stop(mut self) -> (FaultCounts, FaultCounts) {
        self.stop.store(true, Ordering::Relaxed);
        self.thread
            .take()
            .map(|t| t.join().expect("device thread"))
            .unwrap_or_default()
    }
}

impl Drop for DeviceThread {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// `serialport::SerialPort` through the host crate (the tests do not depend
/// on serialport directly).
pub mod serialport_trait {
    pub use plinth::stream::port::SerialPort;
}

/// The host-only pipeline: the firmware's device fed the replay's sample
/// blocks in memory, in order, without a link; returns every byte it sent
/// (the raw log a perfect link would give).
pub fn reference_bytes(scenario: &Scenario) -> Vec<u8> {
    #[derive(Default)]
    struct Mem {
        rx: VecDeque<u8>,
        tx: Vec<u8>,
    }
    impl ByteLink for Mem {
        fn read_byte(&mut self) -> Option<u8> {
            self.rx.pop_front()
        }
        fn write_byte(&mut self, b: u8) -> bool {
            self.tx.push(b);
            true
        }
    }
    let replay = scenario.replay();
    let plan = ReplayPlan::new(&replay).expect("replay plan");
    let mut commands = vec![HostMessage::Hello(Hello {
        protocol_version: PROTOCOL_VERSION,
        host_nonce: 1,
    })];
    commands.push(HostMessage::Stop);
    commands.extend(
        scenario
            .config
            .device_commands(&scenario.tables)
            .expect("configuration commands"),
    );
    commands.push(HostMessage::Start);
    for i in 0..plan.len() {
        commands.push(HostMessage::Samples(plan.block(&replay, i, 0)));
    }
    commands.push(HostMessage::Stop);
    let mut device = Box::new(Device::new(VOLTS_PER_CODE));
    let mut source = FirmwareReplay::new(VOLTS_PER_CODE);
    let mut link = Mem::default();
    let mut tx = Transmitter::new();
    let mut wire = [0u8; MAX_FRAME_SIZE];
    let mut out = Vec::new();
    let mut rx = Receiver::<DeviceMessage>::new();
    for cmd in &commands {
        let (_, bytes) = tx.encode(cmd, &mut wire).expect("encode");
        link.rx.extend(bytes.iter().copied());
        loop {
            let a = device.poll(&mut link, &mut source, 0);
            if a.received == 0 && a.sent == 0 && a.samples == 0 {
                break;
            }
        }
        for f in rx.feed(&link.tx).flatten() {
            if let DeviceMessage::Nack(n) = f.message {
                panic!("reference device refused a command: {n:?}");
            }
        }
        out.append(&mut link.tx);
    }
    out
}

/// Every frame in `bytes`, in order, grouped by device session (a sequence
/// restart at 0 opens a new one): (seq, message).
pub fn frames_by_session(bytes: &[u8]) -> Vec<Vec<(u32, DeviceMessage)>> {
    let mut rx = Receiver::<DeviceMessage>::new();
    let mut sessions: Vec<Vec<(u32, DeviceMessage)>> = Vec::new();
    for f in rx.feed(bytes).flatten() {
        if f.seq == 0 || sessions.is_empty() {
            sessions.push(Vec::new());
        }
        if let Some(s) = sessions.last_mut() {
            s.push((f.seq, f.message));
        }
    }
    sessions
}

/// Reads a run directory's measurements.
pub fn measurements(dir: &Path) -> Vec<plinth::rundir::Measurement> {
    plinth::rundir::RunDir::read(dir)
        .expect("reading the run directory")
        .measurements
}
