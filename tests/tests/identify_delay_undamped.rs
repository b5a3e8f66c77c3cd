//! Session 47 (undamp17): identify's unexcluded-delay rule
//! (`estimate::lack_of_fit::delay_unknown`, one rule with diagnose) widens
//! a pedestal's ± only where the data favour a delay with the pedestal's
//! dampings held passive (c ≥ 0), not where a truly undamped pedestal's
//! damping comes out below zero by chance. Until session 47 the gate
//! opened on that sign alone: main 48c03f6 widened unseen-four's undamped
//! B4 in 24 of 30 fresh clean ROSS runs and the paper machine's pedestals
//! in 40 of 40 simulated 5-60 Hz runs (docs/trust-lack-of-fit.md,
//! "Session 47 (undamp17)").

use plinth::identify::{Identification, WarningKind};
use plinth_tests::rundown::{identify, pedestal};
use plinth_tests::unseen::{ok_but_wrong, stored};

const FOUR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen");
const PAPER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/undamp17");

fn widened(id: &Identification, bearing: &str) -> bool {
    pedestal(id, bearing).has_warning(WarningKind::DelayNotExcluded)
}

/// unseen-four's stored clean run with noise columns (ROSS; B4's pedestal
/// truly undamped, its dampings 13 and −19 N·s/m against ± 48-57, τ̂
/// 2.3 ± 2.3 µs): main widened B4 (c_z ± × 2.1) on the sign of c_z alone.
/// No bearing's ± is widened, and every value printed `ok` is within 3 of
/// its ± of the truth.
#[test]
fn an_undamped_pedestal_of_a_ross_machine_is_not_widened_by_chance() {
    let run = stored(FOUR, "clean-w1c");
    let id = identify(&run);
    for p in &id.pedestals {
        assert!(!widened(&id, &p.bearing), "{}: {:?}", p.bearing, p.warnings);
    }
    let wrong = ok_but_wrong(&run, &id, true);
    assert!(wrong.is_empty(), "{wrong:?}");
}

/// The paper machine (pedestal damping truly zero) on a 12-speed 5-60 Hz
/// run at 1 % noise, seed 7100 (tests/data/undamp17/README.md): main
/// widened both pedestals with τ 55 ± 1709 and 79 ± 1779 µs, a delay the
/// data cannot estimate, the gate opened by a damping below zero. Neither
/// is widened, and every value printed `ok` is within 3 of its ± of the
/// truth.
#[test]
fn the_undamped_paper_machine_is_not_widened_by_chance() {
    let run = stored(PAPER, "paper-5-60-7100");
    let id = identify(&run);
    for b in ["left", "right"] {
        assert!(!widened(&id, b), "{b}: {:?}", pedestal(&id, b).warnings);
    }
    let wrong = ok_but_wrong(&run, &id, true);
    assert!(wrong.is_empty(), "{wrong:?}");
}
