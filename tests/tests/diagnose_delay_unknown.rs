//! Session 45: a sensor delay on a bearing's `rel` probes that the search
//! rejects at its level, while the data do not exclude it. The delay reads
//! as a pedestal damping c − τ·(k − Ω²m); where the pedestal's resonance
//! lies above the band, τ and c trade nearly one for one, and the final ±
//! of c conditional on τ = 0 were far too narrow: unseen-five `delay`
//! printed B1 c_y below zero, 3-5 ± off, trusted (docs/unseen.md "Session 44
//! (sweep17b)", finding 1). The final ± now count such a delay as unknown
//! (`diagnose::ml_final::delay_unknown`).

use plinth_tests::unseen::{diagnosis_with_machine_check, stored, truth_of};

const FIVE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-5");

/// unseen-five `delay` seed 3405 (ROSS; 150 µs on B1's rel probes; B1 k_y
/// 40 MN/m, c_y 2000 N·s/m, resonance 71 Hz above the 9.6-56 Hz band; 3 %
/// noise; made by `scripts/ross_unseen.py --machine unseen-five DIR delay
/// 3405`). Main 52c0f7c named nothing and printed the run trusted with B1
/// c_y −1.91e3 ± 8.0e2 N·s/m (4.9 ± off the truth). A trusted verdict's
/// final pedestal values, dampings included, must be within 3 of their ±
/// of the truth, and the verdict must say that B1's ± count the delay.
#[test]
fn an_unexcluded_delay_is_counted_unknown_in_the_dampings_error() {
    let run = stored(FIVE, "delay-3405");
    let d = diagnosis_with_machine_check(FIVE, "unseen-five.toml", &run);
    if !d.trusted {
        return;
    }
    for after in &d.pedestals_after {
        let t = truth_of(&run, &after.bearing);
        for (key, truth) in [
            ("k_y", t.k_y),
            ("k_z", t.k_z),
            ("m", t.m),
            ("c_y", t.c_y),
            ("c_z", t.c_z),
        ] {
            let (Some(v), Some(se)) = (after.values.get(key), after.std_err.get(key)) else {
                continue;
            };
            assert!(
                ((v - truth) / se).abs() < 3.0,
                "{} {key}: {v:.4e} ± {se:.2e}, truth {truth:.4e} ({:.1} ±), trusted\n{}",
                after.bearing,
                (v - truth) / se,
                d.to_text()
            );
        }
    }
    let named = d.effects_added.iter().any(|e| e == "sensor_delay");
    assert!(
        named
            || d.verdict
                .contains("At bearing B1 the data do not exclude a sensor delay on `rel`"),
        "{}",
        d.verdict
    );
}
