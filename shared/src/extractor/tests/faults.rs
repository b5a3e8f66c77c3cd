//! Keyphasor faults: a missing or an extra pulse is flagged and tracking
//! recovers with nothing garbled emitted; a keyphasor that stops is a
//! missing pulse while tracking and a timeout while acquiring.

use super::*;

/// The run-down the missing and extra pulses are put into: 40 Hz down at
/// 5 Hz/s.
const PULSE_RUN_DOWN: RunDown = RunDown {
    f0: 40.0,
    rate: 5.0,
    offset: 0.5,
};

#[test]
fn missing_pulse_is_flagged_and_tracking_recovers() {
    let channels = three_sensors();
    let shaft = PULSE_RUN_DOWN;
    let dropped = 60;
    let run = simulate(configured(&channels), shaft, &channels, 4.0, 1000, |e| {
        e.remove(dropped);
    });
    assert_eq!(run.faults(), [FaultKind::MissingPulse]);
    // Nothing garbled came out, and outputs resume after the gap.
    check(&run, &channels, 1e-4);
    let after = run
        .phasors()
        .filter(|p| p.revolution as usize > dropped + 1)
        .count();
    assert!(after > 50, "{after} outputs after the missing pulse");
    // The revolution spanning the gap (ids dropped and dropped+1) was not emitted.
    assert!(run.phasors().all(|p| p.revolution as usize != dropped + 1));
}

#[test]
fn extra_pulse_is_flagged_and_tracking_recovers() {
    let channels = three_sensors();
    let shaft = PULSE_RUN_DOWN;
    // A glitch in mid-revolution, and one just before the true edge (which
    // passes the period check and is only caught by the next revolution).
    for position in [0.4, 0.985] {
        let run = simulate(configured(&channels), shaft, &channels, 4.0, 1000, |e| {
            let p = e[70] + position * (e[71] - e[70]);
            e.insert(71, p);
        });
        let faults = run.faults();
        assert_eq!(
            faults.first(),
            Some(&FaultKind::ExtraPulse),
            "{position}: {faults:?}"
        );
        check(&run, &channels, 1e-4);
        let after = run.phasors().filter(|p| p.revolution > 75).count();
        assert!(
            after > 35,
            "{position}: {after} outputs after the extra pulse"
        );
        // Neither revolution touching the glitch (closed by edge counts 72,
        // the glitch, and 73) was emitted.
        assert!(
            run.phasors().all(|p| !(72..=73).contains(&p.revolution)),
            "{position}"
        );
    }
}

#[test]
fn timeout_when_the_keyphasor_stops() {
    let channels = [Channel::new(Sensor::displacement(1.0), (1.0, 0.0))];
    let shaft = RunDown {
        f0: 20.0,
        rate: 0.0,
        offset: 0.1,
    };
    let run = simulate(configured(&channels), shaft, &channels, 3.0, 512, |e| {
        e.truncate(20);
    });
    // While tracking, the first missing edge is flagged once; the extractor
    // then waits for a new edge without further events.
    assert_eq!(run.faults(), [FaultKind::MissingPulse]);
    check(&run, &channels, 1e-4);
    assert!(run.phasors().all(|p| p.revolution <= 20));
    // While acquiring (two edges seen), silence beyond 1/min_speed_hz is a timeout.
    let run = simulate(configured(&channels), shaft, &channels, 3.0, 512, |e| {
        e.truncate(2);
    });
    assert_eq!(run.faults(), [FaultKind::Timeout]);
    assert_eq!(run.phasors().count(), 0);
}
