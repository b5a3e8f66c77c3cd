//! The fault matrix on the tick-level board model (firmware/board-model):
//! the box's own interrupt handlers and `AdcDma`/`DmaSource` on a model of
//! TIM3, TIM5, EXTI0, SPI2, DMA1 and the AD7606, with latency and
//! priorities. The full matrix (≥ 10 000 scenarios) is
//! `bash scripts/bench-board-faults.sh`; this test runs every 40th scenario
//! (every fault class), shows that the restart path before issue 18
//! corrupts samples on the same model, and that each fix switched off
//! alone (`plinth_firmware::revert::Revert`) fails its fault class.

use plinth_board_model::matrix::{run_all, run_class, scenarios, scenarios_reverted};
use plinth_board_model::scenario::{handler_stats, run, Fault, Scenario};
use plinth_firmware::acquisition::adc_dma::RestartPath;
use plinth_firmware::revert::Revert;

#[test]
fn the_matrix_finds_no_silent_corruption_and_no_uncounted_loss() {
    let all = scenarios(RestartPath::Clean);
    assert!(all.len() >= 10_000, "{} scenarios", all.len());
    let sum = run_all(&all, 40);
    eprintln!("{}", sum.line());
    for f in sum.failures.iter().take(5) {
        eprintln!("FAIL {f:?}");
    }
    assert!(sum.scenarios >= 250);
    assert!(sum.delivered > 50_000, "{} samples checked", sum.delivered);
    assert_eq!(
        (sum.corruptions, sum.uncounted),
        (0, 0),
        "{:?}",
        sum.failures.first()
    );
    assert!(sum.passed(), "{:?}", sum.failures.first());
}

/// A stop and an immediate start while the AD7606 converts, in the
/// middle of a half.
fn restart_while_converting(path: RestartPath) -> Scenario {
    let base = Scenario::clean("stop/restart while converting");
    let p = base.ticks_per_sample();
    let half = p * base.vectors_per_half as u64;
    Scenario {
        path,
        fault: Fault::Restart {
            at: 2 * half + 5 * p + 1_640,
            pause: 0,
        },
        ..base
    }
}

#[test]
fn the_old_restart_path_shifts_every_sample_by_one_conversion() {
    let old = run(&restart_while_converting(RestartPath::Legacy));
    eprintln!("legacy: {old:?}");
    assert!(old.corruptions > 100, "{old:?}");
    let problem = old.first_problem.unwrap_or_default();
    assert!(problem.contains("run 2 sample 0"), "{problem}");
    let new = run(&restart_while_converting(RestartPath::Clean));
    assert_eq!((new.corruptions, new.uncounted), (0, 0), "{new:?}");
    assert!(new.delivered > 150);
}

#[test]
fn masked_interrupts_become_counted_restarts_never_shifted_samples() {
    let base = Scenario::clean("masked 30 µs");
    let p = base.ticks_per_sample();
    let s = Scenario {
        fault: Fault::Masked {
            at: 2 * p * base.vectors_per_half as u64 + 7 * p,
            ticks: 30 * 84,
        },
        ..base
    };
    let o = run(&s);
    assert_eq!((o.corruptions, o.uncounted), (0, 0), "{o:?}");
    assert_eq!(o.resyncs, 1, "{o:?}");
    assert!(o.faults.slips + o.faults.late_reads >= 1, "{o:?}");
    assert!(o.reported_lost > 0);
}

#[test]
fn the_rc_clock_is_refused_and_a_clean_run_costs_what_the_readme_says() {
    let mut hsi = Scenario::clean("16 MHz");
    hsi.clocks = plinth_board_model::scenario::ClockSetup::HSI;
    assert!(run(&hsi).refused);
    let stats = handler_stats(&Scenario::clean("clean"));
    let busy = stats.iter().find(|h| h.name == "busy_fell").unwrap();
    // One BUSY interrupt per conversion: 13 register accesses.
    assert_eq!(busy.accesses, 13 * busy.calls);
    assert!(busy.calls >= 256);
}

/// Runs every `stride`-th scenario of fault class `class` with `revert`
/// applied: the box's code passes that slice, the reverted code fails it,
/// and the failures name the class.
fn reverted_fix_fails(revert: Revert, class: &str, stride: usize) {
    let fixed = run_class(&scenarios(RestartPath::Clean), class, stride);
    assert!(fixed.scenarios > 0, "no scenario of class {class}");
    assert!(
        fixed.passed(),
        "{class} fails with every fix: {:?}",
        fixed.failures.first()
    );
    let old = run_class(&scenarios_reverted(revert), class, stride);
    eprintln!("{}: {}; {}", revert.name(), old.recovery_line(), old.line());
    let Some((index, name, fault, problem)) = old.failures.first() else {
        panic!(
            "reverting {} is not caught by the {class} scenarios",
            revert.name()
        );
    };
    eprintln!("FAIL scenario {index} ({name}, {fault}): {problem}");
    assert_eq!(*name, class);
}

#[test]
fn without_the_slip_detector_masked_interrupts_shift_samples() {
    let old = run_class(
        &scenarios_reverted(Revert::SlipDetector),
        "interrupts masked",
        25,
    );
    assert!(old.corruptions > 0, "{}", old.line());
    reverted_fix_fails(Revert::SlipDetector, "interrupts masked", 25);
}

#[test]
fn without_the_spi_error_interrupt_overruns_go_unreported() {
    reverted_fix_fails(Revert::SpiErrorInterrupt, "SPI overrun", 7);
}

#[test]
fn without_the_stop_sequence_a_commanded_restart_is_not_clean() {
    reverted_fix_fails(Revert::StopDrain, "stop/restart", 12);
}

/// The stop's two waits, each reverted alone (the drain stays): a
/// conversion still in flight lets BUSY fall after `start` unmasked EXTI0;
/// a read still in flight leaves a word or an overrun for the next run.
#[test]
fn without_either_wait_of_the_stop_a_commanded_restart_is_not_clean() {
    reverted_fix_fails(Revert::StopWaitBusy, "stop/restart", 6);
    reverted_fix_fails(Revert::StopWaitSpiIdle, "stop/restart", 12);
}

#[test]
fn without_progress_feeding_a_stuck_busy_line_never_resets_the_box() {
    reverted_fix_fails(Revert::WatchdogFeeding, "BUSY stuck low", 8);
    reverted_fix_fails(Revert::WatchdogFeeding, "BUSY stuck high", 8);
}

#[test]
fn without_the_prescaler_refusal_the_rc_clock_restarts_forever() {
    reverted_fix_fails(Revert::PrescalerRefusal, "16 MHz clock", 1);
}

#[test]
fn the_host_link_delivers_every_command_or_counts_its_loss() {
    use plinth_board_model::matrix::{run_uart, Summary};
    use plinth_board_model::uart::{self, UartFault};
    let all = uart::scenarios();
    let clean = uart::run(&all[0]);
    assert_eq!(
        (clean.commands, clean.delivered),
        (40, clean.sent),
        "{clean:?}"
    );
    let mut sum = Summary::default();
    run_uart(&mut sum, &all, 5);
    assert!(sum.passed(), "{:?}", sum.failures.first());
    let lapped = all
        .iter()
        .find(|s| matches!(s.fault, UartFault::ReaderAway { us: 20_000, .. }))
        .unwrap();
    let o = uart::run(lapped);
    assert!(o.delivered < o.sent && o.receive_errors > 0, "{o:?}");
    assert!(o.commands < 40 && o.commands > 0, "{o:?}");
}
