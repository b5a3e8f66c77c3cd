//! The fault matrix on the board model (`bash scripts/bench-board-faults.sh`).
//!
//! `board-faults [--stride N] [--legacy-restart | --revert FIX] [--only I]
//! [--budget]`: runs every N-th scenario (default 1: all), on the box's
//! code or with one fix switched off (`--revert slip-detector`,
//! `spi-error-irq`, `stop-drain`, `stop-wait-busy`, `stop-wait-spi-idle`, `watchdog-feeding`,
//! `prescaler-refusal`), prints each failing scenario by name, a table per
//! fault class, the unreported faults and unrecovered scenarios, and last
//! `scenarios N, silent corruptions C, uncounted losses U`. Exit status 1
//! if any scenario failed.

use plinth_board_model::matrix::{run_all, scenarios, scenarios_reverted, Summary};
use plinth_firmware::acquisition::adc_dma::RestartPath;
use plinth_firmware::revert::Revert;
use std::collections::BTreeMap;
use std::process::ExitCode;

/// Per-handler figures of a clean run with the box's 96-vector halves:
/// `MODEL <handler> priority P calls N accesses_per_call A cycles_per_call C
/// conversions K` (cycles: entry, exit and register accesses at the
/// model's costs; scripts/bench-firmware.sh adds the compiled handlers'
/// other instructions).
fn budget() {
    let s = plinth_board_model::scenario::Scenario {
        vectors_per_half: 96,
        halves: 10,
        ..plinth_board_model::scenario::Scenario::clean("budget")
    };
    let conversions = 96 * 10;
    for h in plinth_board_model::scenario::handler_stats(&s) {
        let per = |x: u64| {
            if h.calls == 0 {
                0.0
            } else {
                x as f64 / h.calls as f64
            }
        };
        println!(
            "MODEL {} priority {} calls {} accesses_per_call {:.2} cycles_per_call {:.1} conversions {}",
            h.name,
            h.priority,
            h.calls,
            per(h.accesses),
            per(h.cycles),
            conversions
        );
    }
}

fn main() -> ExitCode {
    let mut stride = 1usize;
    let mut path = RestartPath::Clean;
    let mut only: Option<usize> = None;
    let mut revert = Revert::None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--stride" => match args.next().and_then(|v| v.parse().ok()) {
                Some(n) if n > 0 => stride = n,
                _ => {
                    eprintln!("error: --stride takes a whole number ≥ 1");
                    return ExitCode::from(2);
                }
            },
            "--legacy-restart" => path = RestartPath::Legacy,
            "--revert" => match args.next().as_deref().and_then(Revert::from_name) {
                Some(r) => revert = r,
                None => {
                    let names: Vec<&str> = Revert::ALL.iter().map(|r| r.name()).collect();
                    eprintln!("error: --revert takes one of {}", names.join(", "));
                    return ExitCode::from(2);
                }
            },
            "--budget" => {
                budget();
                return ExitCode::SUCCESS;
            }
            "--only" => match args.next().and_then(|v| v.parse().ok()) {
                Some(n) => only = Some(n),
                None => {
                    eprintln!("error: --only takes a scenario index");
                    return ExitCode::from(2);
                }
            },
            other => {
                eprintln!(
                    "error: unknown option {other:?} (--stride N, --legacy-restart, --revert FIX, --only I, --budget)"
                );
                return ExitCode::from(2);
            }
        }
    }
    let all = if revert == Revert::None {
        scenarios(path)
    } else {
        scenarios_reverted(revert)
    };
    if let Some(i) = only {
        let Some(s) = all.get(i) else {
            eprintln!("error: --only {i}: the matrix has {} scenarios", all.len());
            return ExitCode::from(2);
        };
        let o = plinth_board_model::scenario::run(s);
        println!("{s:?}\n{o:?}");
        for h in plinth_board_model::scenario::handler_stats(s) {
            println!("{h:?}");
        }
        return ExitCode::SUCCESS;
    }
    let start = std::time::Instant::now();
    let mut sum: Summary = run_all(&all, stride);
    let mut classes: BTreeMap<&str, usize> = BTreeMap::new();
    for s in all.iter().step_by(stride) {
        *classes.entry(s.name).or_default() += 1;
    }
    // The host link (USART2 and its receive DMA), on the box's code.
    let uart = plinth_board_model::uart::scenarios();
    plinth_board_model::matrix::run_uart(&mut sum, &uart, stride);
    for s in uart.iter().step_by(stride) {
        *classes.entry(s.name).or_default() += 1;
    }
    let mut failed: BTreeMap<&str, usize> = BTreeMap::new();
    for (index, name, fault, problem) in &sum.failures {
        *failed.entry(name).or_default() += 1;
        if failed[name] <= 3 {
            println!("FAIL scenario {index} ({name}, {fault}): {problem}");
        }
    }
    println!("{:<28} {:>9} {:>7}", "fault class", "scenarios", "failed");
    for (name, n) in &classes {
        println!(
            "{name:<28} {n:>9} {:>7}",
            failed.get(name).copied().unwrap_or(0)
        );
    }
    println!(
        "{} samples checked in {:.1} s",
        sum.delivered,
        start.elapsed().as_secs_f64()
    );
    println!("{}", sum.recovery_line());
    println!("{}", sum.line());
    if !sum.passed() {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    }
}
