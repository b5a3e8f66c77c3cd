//! Simulated hardware on the host: the firmware's AD7606 driver and ADC
//! source read a simulated converter (embedded-hal 1.0 SPI device, CONVST
//! and BUSY pins) and capture timer that serve the simulator's run-down
//! (its i16 codes, sample by sample, and its keyphasor times), and the
//! pipeline's phasors and recursive estimates are checked against the
//! simulator's truth (its steady-state response at each revolution's
//! speed, solved afresh, not the spline the signals were made from) and the
//! host's batch least squares.
//!
//! Two run-downs, 51.2 kHz, no added noise (ADC quantisation only):
//! - a field coast-down of `tests/machines/field-coast-down.toml`, 70 → 30 Hz
//!   at 1 Hz/s through its rotor-on-pedestal modes (20-55 µm), with a front
//!   end that scales each channel to use the converter: every phasor within
//!   1e-4 of the channel's peak truth (measured ≤ 3.6e-5; 2 Hz/s gives
//!   ≤ 8e-5, 0.5 Hz/s ≤ 4e-5: the floor is quantisation);
//! - the paper's machine (pedestals at ζ = 3 %) straight into the converter
//!   at 4 Hz/s: probe signals of 3-5 codes, where quantisation is all there
//!   is to see: every phasor within one ADC step of the truth (measured
//!   ≤ 0.51 step).
//!
//! Both: the box's recursive estimates within 1 % of the batch fit of the
//! same phasors (measured ≤ 1.2e-5).
//!
//! The simulated converter and timer are `simulated_ad7606`; this file
//! makes the run-downs, drives the firmware through them and compares.

mod simulated_ad7606;

use num_complex::Complex;
use plinth::estimate::Observation;
use plinth::identify::{fit_pedestal, Options};
use plinth::sim::signals::{synthesise, Channel, RunDown, SensorKind, SignalOptions, SignalSet};
use plinth::sim::{EffectSet, Machine};
use plinth_firmware::ad7606::{Ad7606, Range};
use plinth_firmware::adc_source::AdcSource;
use plinth_firmware::config::{Configuration, TABLE_ROWS};
use plinth_firmware::pipeline::Pipeline;
use plinth_firmware::source::{SampleBuffer, SampleSource};
use plinth_shared::bearing::BearingTable;
use plinth_shared::protocol::{
    BearingTableChunk, BearingTableRow, ChannelConfig, ChannelSet, DeviceMessage, PhasorFrame,
    WirePhasor,
};
use simulated_ad7606::{Hardware, SimBusy, SimConvst, SimSpi, SimTimer, TICKS_PER_SAMPLE};
use std::f64::consts::TAU;

/// The bundled Feng & Hahn machine with field-like pedestals:
/// pedestal damping for ζ = 3 % of each pedestal's own √(k/m) (the scan's
/// 70-100 N·s/m are ζ ≈ 0.2 %: resonances 0.2 Hz wide that a run-down
/// crosses in a few revolutions, where no steady-state response exists to
/// compare with).
fn paper_machine_field_damped() -> Machine {
    let mut text = plinth::paper::DAMPED_MACHINE.to_string();
    // (m, k_y, k_z, scan c_y, scan c_z) of the left and right pedestals.
    for (m, ky, kz, cy, cz) in [
        (80.0f64, 10.0e6f64, 8.0e6f64, "100.0", "90.0"),
        (60.0, 6.0e6, 8.0e6, "70.0", "80.0"),
    ] {
        let zeta = 0.03;
        let old = format!("c_y = {cy}, c_z = {cz}");
        let new = format!(
            "c_y = {:.1}, c_z = {:.1}",
            2.0 * zeta * (ky * m).sqrt(),
            2.0 * zeta * (kz * m).sqrt()
        );
        assert!(text.contains(&old), "{old} not in the machine");
        text = text.replace(&old, &new);
    }
    Machine::from_toml_str(&text, "feng-hahn-1997-field.toml").unwrap()
}

/// What the box's analogue front end makes of the sensors.
#[derive(Clone, Copy)]
struct FrontEnd {
    /// Probe channel sensitivity [V/m] (7870 for a 7.87 V/mm probe).
    probe_v_per_m: f64,
    /// DC the probe signal rides on [V] (the probe's gap voltage; 0 when
    /// AC-coupled).
    probe_gap_v: f64,
    /// Pedestal pick-up kind and channel sensitivity [V per SI unit].
    seismic: SensorKind,
    seismic_sensitivity: f64,
}

impl FrontEnd {
    /// Straight in: DC-coupled 7.87 V/mm probes with their −9 V gap, and
    /// the kind's default field sensitivity (100 mV/g, 20 mV/(mm/s)).
    fn direct(seismic: SensorKind) -> Self {
        Self {
            probe_v_per_m: 7870.0,
            probe_gap_v: -9.0,
            seismic,
            seismic_sensitivity: plinth::sim::signals::default_seismic_sensitivity(seismic),
        }
    }
}

/// The machine's run-down from `start` to `end` [Hz] at `rate` [Hz/s]
/// through `front`, 51.2 kHz, no added noise: ADC quantisation only.
fn signals(
    machine: &Machine,
    (start, end, rate): (f64, f64, f64),
    front: FrontEnd,
) -> (SignalSet, plinth::rundir::RunDir) {
    let opts = SignalOptions {
        rundown: RunDown {
            start_hz: start,
            end_hz: end,
            rate_hz_per_s: rate,
        },
        probe_sensitivity: front.probe_v_per_m,
        probe_gap_v: front.probe_gap_v,
        probe_noise_v: 0.0,
        seismic_kind: front.seismic,
        seismic_sensitivity: front.seismic_sensitivity,
        seismic_noise_v: 0.0,
        ..SignalOptions::default()
    };
    synthesise(machine, &EffectSet::none(), &opts).unwrap()
}

/// At most TABLE_ROWS rows of `bearing`'s truth table, evenly picked, with
/// both ends.
fn table_rows(truth: &plinth::rundir::RunDir, bearing: &str) -> Vec<BearingTableRow> {
    let rows: Vec<_> = truth
        .bearings
        .iter()
        .filter(|r| r.bearing == bearing)
        .collect();
    assert!(rows.len() >= 2, "bearing {bearing}: {} rows", rows.len());
    let picks = rows.len().min(TABLE_ROWS);
    (0..picks)
        .map(|i| rows[i * (rows.len() - 1) / (picks - 1)])
        .map(|r| BearingTableRow {
            speed_hz: r.speed_hz as f32,
            coefficients: r.coefficients.cast::<f32>(),
        })
        .collect()
}

/// One ADC step in metres on channel `ch` at `speed_hz` (a code over the
/// sensitivity, over Ω or Ω² for velocity and acceleration pick-ups).
fn lsb_m(set: &SignalSet, ch: &Channel, speed_hz: f64) -> f64 {
    let omega = TAU * speed_hz;
    set.header.adc.volts_per_code / ch.sensitivity
        * match ch.kind {
            SensorKind::Displacement => 1.0,
            SensorKind::Velocity => 1.0 / omega,
            SensorKind::Acceleration => 1.0 / (omega * omega),
        }
}

/// How one run through the simulated board came out.
struct Outcome {
    /// Bearing names in channel-map order.
    bearings: Vec<String>,
    /// Per bearing and quantity (rel y, rel z, ped y, ped z): peak truth
    /// amplitude over the run [m].
    peaks: Vec<[f64; 4]>,
    /// Per bearing and quantity: worst |box − truth at the revolution's
    /// speed| / peak.
    worst: Vec<[f64; 4]>,
    /// Per bearing and quantity: worst |box − truth| in ADC steps at the
    /// revolution's speed.
    worst_steps: Vec<[f64; 4]>,
    /// Per bearing: worst relative difference box RLS vs batch fit.
    rls_vs_batch: Vec<f64>,
}

const NAMES: [&str; 4] = ["rel y", "rel z", "ped y", "ped z"];

/// Run the simulated board through `machine`'s run-down at `rate` [Hz/s]
/// and compare with the simulator's truth and the batch fit.
fn run(machine: &Machine, rundown: (f64, f64, f64), front: FrontEnd) -> Outcome {
    let rate = rundown.2;
    let (set, truth) = signals(machine, rundown, front);
    let h = set.header.clone();
    assert_eq!(set.channels(), 8);
    assert_eq!(h.sample_rate_hz, 51_200.0);
    assert_eq!(
        h.adc.volts_per_code,
        f64::from(Range::PlusMinus10V.volts_per_code())
    );
    let bearings: Vec<String> = {
        let mut b: Vec<_> = h
            .channels
            .iter()
            .map(|c| (c.bearing_index, c.bearing.clone()))
            .collect();
        b.sort();
        b.dedup();
        b.into_iter().map(|(_, n)| n).collect()
    };

    // The host's configuration, as the protocol would carry it.
    let mut config = Configuration::new();
    let mut set_cfg = ChannelSet {
        channels: Default::default(),
    };
    for (n, ch) in h.channels.iter().enumerate() {
        set_cfg
            .channels
            .push(ChannelConfig {
                channel: n as u8,
                kind: ch.kind,
                sensitivity: ch.sensitivity as f32,
                bearing: ch.bearing_index as u8,
                quantity: ch.quantity.to_protocol(),
            })
            .unwrap();
    }
    config.set_channels(&set_cfg).unwrap();
    let mut tables_f64: Vec<BearingTable<TABLE_ROWS, f64>> = Vec::new();
    for (b, name) in bearings.iter().enumerate() {
        let rows = table_rows(&truth, name);
        for chunk in BearingTableChunk::split(b as u8, &rows).unwrap() {
            config.add_table_chunk(&chunk).unwrap();
        }
        // The same rows in f64 for the host's batch fit.
        let mut t = BearingTable::new();
        for r in &rows {
            t.push(f64::from(r.speed_hz), r.coefficients.cast::<f64>())
                .unwrap();
        }
        tables_f64.push(t);
    }
    assert!(config.ready());

    // The simulated board.
    let hw = Hardware::serving(set);
    let adc = Ad7606::new(
        SimSpi(hw.clone()),
        SimConvst(hw.clone()),
        SimBusy(hw.clone()),
        Range::PlusMinus10V,
        100,
    )
    .unwrap();
    let mut source = AdcSource::new(adc, SimTimer(hw.clone()), TICKS_PER_SAMPLE);
    let mut pipeline = Pipeline::new(&config, h.sample_rate_hz as f32).unwrap();
    source.start().unwrap();
    let mut frames: Vec<PhasorFrame> = Vec::new();
    let mut buf = SampleBuffer::default();
    loop {
        buf.clear();
        source.poll(&mut buf);
        if buf.is_empty() {
            break;
        }
        pipeline.process(&buf, &config.tables, &mut |m| {
            if let DeviceMessage::Phasors(p) = m {
                frames.push(p);
            }
        });
    }
    let estimates = pipeline.estimates();
    let hwb = hw.borrow();
    assert_eq!(
        hwb.conversions,
        hwb.set.len(),
        "every sample converted once"
    );
    let last_sample = (hwb.set.len() - 1) as f64;
    assert_eq!(
        hwb.next_pulse,
        hwb.set
            .keyphasor
            .iter()
            .filter(|&&p| p <= last_sample)
            .count(),
        "every pulse up to the last sample captured"
    );
    assert_eq!(source.counters, Default::default());
    assert_eq!(pipeline.counters, Default::default());

    // Every revolution between pulses is reported but four: revolutions 0
    // and 1 (the extractor needs three edges to predict the angle before
    // it integrates) and the last two (held back until the next edge
    // confirms them and their successors, which never comes).
    let pulses = hwb.next_pulse;
    assert_eq!(frames[0].revolution, 2, "first revolution after lock-on");
    assert_eq!(frames.len(), pulses - 1 - 4, "{pulses} pulses");
    for (i, f) in frames.iter().enumerate() {
        assert_eq!(f.revolutions, 1);
        assert_eq!(f.revolution, frames[0].revolution + i as u32, "no gaps");
    }

    // The simulator's truth, solved afresh at every frame's speed.
    let speeds: Vec<f64> = frames.iter().map(|f| f64::from(f.speed_hz)).collect();
    let response = plinth::sim::unbalance_response(machine, &speeds, &EffectSet::none())
        .unwrap()
        .measurements();
    let c = |w: WirePhasor| Complex::new(f64::from(w.re), f64::from(w.im));
    let quantities = plinth::sim::signals::ChannelQuantity::ALL;
    let mut peaks = vec![[0.0f64; 4]; bearings.len()];
    let mut errors = vec![[0.0f64; 4]; bearings.len()];
    let mut worst_steps = vec![[0.0f64; 4]; bearings.len()];
    let mut points: Vec<Vec<Observation>> = vec![Vec::new(); bearings.len()];
    for m in &response {
        let b = bearings.iter().position(|n| *n == m.bearing).unwrap();
        for (q, quantity) in quantities.iter().enumerate() {
            peaks[b][q] = peaks[b][q].max(quantity.of(m).norm());
        }
    }
    for (i, f) in frames.iter().enumerate() {
        let speed = f64::from(f.speed_hz);
        // The frame's speed is the revolution's mean: pulse spacing.
        let j = f.revolution as usize;
        let s = &hwb.set;
        let want_speed = h.sample_rate_hz / (s.keyphasor[j + 1] - s.keyphasor[j]);
        assert!(
            (speed - want_speed).abs() < 1e-5 * want_speed,
            "revolution {j}: speed {speed} vs {want_speed}"
        );
        for bp in &f.bearings {
            let b = bp.bearing as usize;
            let m = &response[i * bearings.len() + b];
            assert_eq!(m.bearing, bearings[b]);
            let got = [c(bp.rel[0]), c(bp.rel[1]), c(bp.ped[0]), c(bp.ped[1])];
            for (q, quantity) in quantities.iter().enumerate() {
                let ch = h
                    .channels
                    .iter()
                    .find(|ch| ch.bearing_index == b && ch.quantity == *quantity)
                    .unwrap();
                let error = (got[q] - quantity.of(m)).norm();
                errors[b][q] = errors[b][q].max(error / peaks[b][q]);
                worst_steps[b][q] = worst_steps[b][q].max(error / lsb_m(s, ch, speed));
            }
            let coefficients = tables_f64[b].at(speed).unwrap();
            points[b].push(Observation::without_noise(
                speed,
                [got[0], got[1]],
                [got[2], got[3]],
                &coefficients,
            ));
        }
    }
    for ch in &h.channels {
        eprintln!(
            "{rate} Hz/s, {}: signal spline vs solver ≤ {:.1e} of the peak",
            ch.name, ch.interpolation_error_rel
        );
    }
    for (b, name) in bearings.iter().enumerate() {
        for q in 0..4 {
            eprintln!(
                "{rate} Hz/s, {name} {}: peak {:.3e} m; worst |box − truth| {:.2e} of the peak, {:.2} ADC steps",
                NAMES[q], peaks[b][q], errors[b][q], worst_steps[b][q]
            );
        }
    }

    // The box's recursive estimate against the batch fit on its phasors.
    let mut rls_vs_batch = Vec::new();
    for (b, name) in bearings.iter().enumerate() {
        let est = estimates
            .pedestals
            .iter()
            .find(|e| e.bearing as usize == b)
            .expect("an estimate for every pedestal");
        let fit = fit_pedestal(name, &points[b], &Options::default()).expect("batch fit");
        let (batch, batch_se) = (fit.pedestal.theta(), fit.std_err.theta());
        // The box weighs each phasor by its own noise and the batch (OLS) fit
        // does not: they agree to 1 % on clean data, and within 3 combined
        // standard errors where quantisation noise dominates.
        let mut worst_p = 0.0f64;
        for (i, (&got, &want)) in est.theta.iter().zip(batch.iter()).enumerate() {
            let rel = (f64::from(got) - want).abs() / want.abs();
            let z = (f64::from(got) - want).abs() / f64::from(est.std_err[i]).hypot(batch_se[i]);
            worst_p = worst_p.max(rel.min(1e-2 * z / 3.0));
            eprintln!(
                "bearing {name} θ{i}: box {got} ± {} batch {want} ± {} rel {rel:.2e}, {z:.2} σ",
                est.std_err[i], batch_se[i]
            );
        }
        eprintln!("bearing {name}: worst RLS vs batch {worst_p:.2e}");
        rls_vs_batch.push(worst_p);
    }
    Outcome {
        bearings,
        peaks,
        worst: errors,
        worst_steps,
        rls_vs_batch,
    }
}

fn assert_rls_matches_batch(out: &Outcome) {
    for (name, worst) in out.bearings.iter().zip(&out.rls_vs_batch) {
        assert!(
            *worst < 1e-2,
            "bearing {name}: RLS vs batch beyond both 1 % and 3 combined standard errors ({worst:e})"
        );
    }
}

#[test]
fn field_coast_down_gives_truth_phasors_within_1e4_and_the_batch_estimate() {
    // tests/machines/field-coast-down.toml coasting down 70 → 30 Hz at 1 Hz/s
    // through its rotor-on-pedestal modes (38 and 41.5 Hz): 20-45 µm at the
    // probes, 15-35 µm at the pedestals. The front end scales every channel
    // to use the converter: probes AC-coupled (gap voltage removed) at
    // gain 8 (63 V/mm), accelerometers 1 V/g at gain 10.
    let machine = Machine::from_toml_str(
        include_str!("../machines/field-coast-down.toml"),
        "tests/machines/field-coast-down.toml",
    )
    .unwrap();
    let front = FrontEnd {
        probe_v_per_m: 8.0 * 7870.0,
        probe_gap_v: 0.0,
        seismic: SensorKind::Acceleration,
        seismic_sensitivity: 10.0 / plinth::sim::machine::STANDARD_GRAVITY,
    };
    let out = run(&machine, (70.0, 30.0, 1.0), front);
    for (b, name) in out.bearings.iter().enumerate() {
        for (q, quantity) in NAMES.iter().enumerate() {
            let w = out.worst[b][q];
            assert!(
                w < 1e-4,
                "bearing {name} {quantity}: |box − truth| {w:.2e} of the peak {:.3e} m",
                out.peaks[b][q]
            );
        }
    }
    assert_rls_matches_batch(&out);
}

#[test]
fn fast_run_down_at_small_signals_is_within_one_adc_step_of_the_truth() {
    // The paper's machine (with ζ = 3 % pedestals) straight into the
    // converter at 4 Hz/s: probe signals of 3-5 codes, so quantisation is
    // all there is to see; the box stays within one step of the truth.
    let out = run(
        &paper_machine_field_damped(),
        (70.0, 40.0, 4.0),
        FrontEnd::direct(SensorKind::Acceleration),
    );
    for (b, name) in out.bearings.iter().enumerate() {
        for (q, quantity) in NAMES.iter().enumerate() {
            let w = out.worst_steps[b][q];
            assert!(
                w < 1.0,
                "bearing {name} {quantity}: |box − truth| {w:.2} ADC steps"
            );
        }
    }
    assert_rls_matches_batch(&out);
}
