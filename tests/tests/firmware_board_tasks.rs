//! The box's extraction and protocol tasks on the tick-level board model
//! (firmware/board-model, `tasks`): `extract` (priority 2) runs the
//! library's extraction body, `Extraction::run`, on every completed DMA
//! half; `process` (priority 1) runs the protocol pass, `Session::poll`,
//! with the host link kept full so that every pass takes its whole byte
//! budget. What they share is locked at the ceiling as RTIC locks it.
//! Checked: `extract` never waits longer than its budget, no half is lost,
//! every delivered sample is the right conversion and channel; and the
//! structure before the split (the whole pass under the lock) breaks the
//! budget on the same model and loses halves (counted).

mod firmware_support;

use plinth_board_model::scenario::Scenario;
use plinth_board_model::tasks::{run_tasks, Structure, EXTRACT_WAIT_BUDGET_CYCLES};

/// The reference board's clean run, long enough for many passes.
fn scenario() -> Scenario {
    Scenario {
        halves: 24,
        keyphasor_hz: 400.0,
        ..Scenario::clean("tasks")
    }
}

fn configuration() -> Vec<plinth_shared::protocol::HostMessage> {
    firmware_support::Scenario::standard().configuration()
}

#[test]
fn extract_waits_at_most_one_short_section_and_loses_no_half() {
    let s = scenario();
    let o = run_tasks(&s, Structure::Split, &configuration()).expect("the PLL samples");
    eprintln!("split: {o:?}");
    // The session started, every half went through the pipeline.
    assert!(o.extract_calls >= s.halves, "{o:?}");
    let vectors = (s.halves as usize * s.vectors_per_half) as u64;
    assert!(
        o.extracted + 2 * s.vectors_per_half as u64 >= vectors,
        "{o:?}"
    );
    assert_eq!(o.overrun_halves, 0, "{o:?}");
    assert_eq!(o.acquisition.reported_lost, 0, "{o:?}");
    assert!(!o.acquisition.failed(), "{:?}", o.acquisition.first_problem);
    assert_eq!(o.acquisition.corruptions, 0);
    // The protocol task really ran long passes all along (flooded link).
    assert!(o.process_calls > 10 && o.acks > 100, "{o:?}");
    assert_eq!(o.link_errors, 0, "{o:?}");
    assert!(
        o.extract_max_wait_cycles <= EXTRACT_WAIT_BUDGET_CYCLES,
        "extract waited {} cycles (budget {EXTRACT_WAIT_BUDGET_CYCLES})",
        o.extract_max_wait_cycles
    );
    assert!(
        o.longest_section_cycles <= EXTRACT_WAIT_BUDGET_CYCLES,
        "{o:?}"
    );
}

#[test]
fn the_whole_pass_under_the_lock_breaks_the_budget() {
    let s = scenario();
    let old = run_tasks(&s, Structure::WholePass, &configuration()).expect("the PLL samples");
    eprintln!("whole pass: {old:?}");
    assert!(old.process_calls > 10, "{old:?}");
    assert!(
        old.extract_max_wait_cycles > 2 * EXTRACT_WAIT_BUDGET_CYCLES,
        "{old:?}"
    );
    assert!(old.longest_section_cycles > 2 * EXTRACT_WAIT_BUDGET_CYCLES);
    // The model's halves are 32 vectors (625 µs): a pass of ~1 ms under
    // the lock makes the extraction miss halves (counted, never silent).
    assert!(old.overrun_halves > 0, "{old:?}");
    assert!(old.acquisition.reported_lost > 0);
    assert!(
        !old.acquisition.failed(),
        "{:?}",
        old.acquisition.first_problem
    );
}
