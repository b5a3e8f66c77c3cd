//! The fault matrix: interrupt latency 0-25 µs at every phase of the
//! sample period, interrupts masked 1-100 µs, stop/restart at every point
//! of the period (converting, mid-read, between halves), the 16 MHz RC
//! clock, SPI overruns (the DMA held off the bus), DMA transfer errors,
//! BUSY stuck high or low, a keyphasor missing, bouncing or too fast; each
//! scenario with its own AD7606 conversion time (3.45-4.15 µs).

use crate::check::Outcome;
use crate::scenario::{run, ClockSetup, Fault, Scenario};
use crate::uart::{UartOutcome, UartScenario};
use plinth_firmware::acquisition::adc_dma::RestartPath;
use plinth_firmware::revert::Revert;

/// A small deterministic generator (SplitMix64) for conversion times.
fn mix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// Every scenario of the matrix, on the given restart path.
pub fn scenarios(path: RestartPath) -> Vec<Scenario> {
    let base = Scenario {
        path,
        ..Scenario::clean("clean")
    };
    let p = base.ticks_per_sample();
    let us = |x: f64| (x * 84.0) as u64;
    let half = p * base.vectors_per_half as u64;
    // The faults land in the third half, at conversion `at` + phase.
    let at = |phase: u64| 2 * half + 5 * p + phase;
    let mut v = vec![base];
    // Latency 0-25 µs (0.5 µs steps) at 64 phases of the period.
    for d in 0..=50u64 {
        for k in 0..64 {
            v.push(Scenario {
                name: "interrupt latency",
                fault: Fault::Masked {
                    at: at(k * p / 64),
                    ticks: us(d as f64 * 0.5),
                },
                ..base
            });
        }
    }
    // Masked 1-100 µs at 40 phases.
    for d in 1..=100u64 {
        for k in 0..40 {
            v.push(Scenario {
                name: "interrupts masked",
                fault: Fault::Masked {
                    at: at(k * p / 40 + 7),
                    ticks: us(d as f64),
                },
                ..base
            });
        }
    }
    // Stop/restart every 8 ticks of a period (converting, mid-read,
    // idle), in the middle of a half and across the half boundary, with
    // and without a pause.
    for offset in [5 * p, half - p, half] {
        for phase in (0..p).step_by(8) {
            for pause in [0, 3 * p] {
                v.push(Scenario {
                    name: "stop/restart",
                    fault: Fault::Restart {
                        at: 2 * half + offset + phase,
                        pause,
                    },
                    ..base
                });
            }
        }
    }
    // Stop/restart while the DMA is held off the bus (1-6 µs) at every
    // 16th tick of a period: the word it did not take must not start the
    // next run.
    for phase in (0..p).step_by(16) {
        for stall in [us(1.0), us(3.0), us(6.0), us(60.0)] {
            v.push(Scenario {
                name: "stop/restart in a DMA stall",
                fault: Fault::RestartInDmaStall {
                    at: 2 * half + 5 * p + phase,
                    stall,
                },
                ..base
            });
        }
    }
    // The 16 MHz RC clock: the box refuses (checked as refused).
    v.push(Scenario {
        name: "16 MHz clock",
        clocks: ClockSetup::HSI,
        ..base
    });
    // SPI overrun: the DMA held off for 0.5-40 µs at 16 phases.
    for d in 1..=80u64 {
        for k in 0..16 {
            v.push(Scenario {
                name: "SPI overrun",
                fault: Fault::DmaStall {
                    at: at(k * p / 16),
                    ticks: us(d as f64 * 0.5),
                },
                ..base
            });
        }
    }
    // DMA transfer error at every 4th tick of a period.
    for phase in (0..p).step_by(4) {
        v.push(Scenario {
            name: "DMA transfer error",
            fault: Fault::TransferError { at: at(phase) },
            ..base
        });
    }
    // BUSY stuck high or low at 64 phases: the box must end in a
    // watchdog reset.
    for high in [false, true] {
        for k in 0..64 {
            v.push(Scenario {
                name: if high {
                    "BUSY stuck high"
                } else {
                    "BUSY stuck low"
                },
                fault: Fault::BusyStuck {
                    at: at(k * p / 64),
                    high,
                },
                // Long enough for the watchdog to bite (scenario.rs:
                // NO_PROGRESS_US + WATCHDOG_US after the last restart).
                halves: 14,
                ..base
            });
        }
    }
    // Keyphasor: missing 1-40 revolutions, bouncing 1-20 times, too fast.
    for r in 1..=40 {
        v.push(Scenario {
            name: "keyphasor missing",
            fault: Fault::KeyphasorMissing { revolutions: r },
            ..base
        });
    }
    for b in 1..=20 {
        for hz in [50.0, 390.0, 1000.0] {
            v.push(Scenario {
                name: "keyphasor bouncing",
                keyphasor_hz: hz,
                fault: Fault::KeyphasorBouncing { bounces: b },
                ..base
            });
        }
    }
    for k in 0..40 {
        v.push(Scenario {
            name: "keyphasor too fast",
            fault: Fault::KeyphasorFast {
                hz: 16_000.0 + 500.0 * f64::from(k),
            },
            ..base
        });
    }
    for (i, s) in v.iter_mut().enumerate() {
        s.index = i;
        s.conversion_ns = 3_450 + (mix(i as u64) % 701) as u32;
    }
    v
}

/// Every scenario of the matrix with one fix switched off.
pub fn scenarios_reverted(revert: Revert) -> Vec<Scenario> {
    let mut v = scenarios(RestartPath::Clean);
    for s in &mut v {
        s.revert = revert;
    }
    v
}

/// The matrix's totals.
#[derive(Clone, Debug, Default)]
pub struct Summary {
    /// Scenarios run.
    pub scenarios: usize,
    /// Silent corruptions, over all scenarios.
    pub corruptions: u64,
    /// Uncounted losses, over all scenarios.
    pub uncounted: u64,
    /// Samples checked.
    pub delivered: u64,
    /// Hardware faults no counter shows, over all scenarios.
    pub unreported: u64,
    /// Scenarios the box did not recover from as it should.
    pub unrecovered: u64,
    /// Sequence faults caused by commanded stop/restarts.
    pub unclean: u64,
    /// Scenarios with a problem: (index, name, fault, first problem).
    pub failures: Vec<(usize, &'static str, String, String)>,
}

impl Summary {
    /// Adds one scenario's outcome.
    pub fn add(&mut self, s: &Scenario, o: &Outcome) {
        self.scenarios += 1;
        self.corruptions += o.corruptions;
        self.uncounted += o.uncounted;
        self.delivered += o.delivered;
        self.unreported += o.unreported;
        self.unrecovered += o.unrecovered;
        self.unclean += o.unclean;
        if o.failed() {
            self.failures.push((
                s.index,
                s.name,
                format!("{:?}", s.fault),
                o.first_problem.clone().unwrap_or_default(),
            ));
        }
    }

    /// Adds one host-link scenario's outcome.
    pub fn add_uart(&mut self, s: &UartScenario, o: &UartOutcome) {
        self.scenarios += 1;
        self.corruptions += o.corruptions;
        self.uncounted += o.uncounted;
        if o.corruptions + o.uncounted > 0 {
            self.failures.push((
                s.index,
                s.name,
                format!("{:?}", s.fault),
                o.first_problem.clone().unwrap_or_default(),
            ));
        }
    }

    /// Whether every scenario passed.
    pub fn passed(&self) -> bool {
        self.failures.is_empty()
    }

    /// The line before the last: the faults beyond corruption and loss.
    pub fn recovery_line(&self) -> String {
        format!(
            "unreported hardware faults {}, unrecovered scenarios {}, unclean restarts {}",
            self.unreported, self.unrecovered, self.unclean
        )
    }

    /// The bench script's last line.
    pub fn line(&self) -> String {
        format!(
            "scenarios {}, silent corruptions {}, uncounted losses {}",
            self.scenarios, self.corruptions, self.uncounted
        )
    }
}

/// Runs every `stride`-th host-link scenario and adds it to `sum`.
pub fn run_uart(sum: &mut Summary, scenarios: &[UartScenario], stride: usize) {
    for s in scenarios.iter().step_by(stride.max(1)) {
        let o = crate::uart::run(s);
        sum.add_uart(s, &o);
    }
}

/// Runs every `stride`-th scenario of fault class `name` and sums them up.
pub fn run_class(scenarios: &[Scenario], name: &str, stride: usize) -> Summary {
    let class: Vec<Scenario> = scenarios
        .iter()
        .filter(|s| s.name == name)
        .copied()
        .collect();
    run_all(&class, stride)
}

/// Runs `scenarios` (every `stride`-th one) and sums them up.
pub fn run_all(scenarios: &[Scenario], stride: usize) -> Summary {
    let mut sum = Summary::default();
    for s in scenarios.iter().step_by(stride.max(1)) {
        let o = run(s);
        sum.add(s, &o);
    }
    sum
}
