//! Keyphasor flips (issue 17 item 2, "bad speeds are found and named") on
//! the fourth unseen machine's stored clean run
//! (tests/data/ross-unseen-4/clean-n1: ROSS 2.3.0's phasors with the
//! machine's noise, scripts/ross_unseen.py `--machine unseen-flex`, seed 1),
//! every channel of B1 (rel and ped, y and z) negated at chosen speeds here:
//! the flip is the only thing the test adds, the response and its noise are
//! ROSS's and the script's. A run of two bearings gives no cross-bearing
//! test (`robust::cross_bearing_flips` needs three): only the test in speed
//! (`robust::keyphasor_flips`) judges, and what it cannot confirm the other
//! bearing judges (`robust::confirmed_across`). The rates over several seeds:
//! `BENCH_JOBS=1 python3 scripts/bench_unseen.py --machine unseen-flex
//! PLINTH DIR 5 flips` (docs/trust-flips.md, "Keyphasor flips on the fourth
//! unseen machine").

use plinth::identify::Identification;
use plinth::rundir::RunDir;
use plinth_tests::rundown::identify;
use plinth_tests::unseen;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-4");

/// The stored clean run with every channel of `bearing` negated at the
/// speeds `flipped` [Hz] (each must be a measured speed of the run).
fn flipped_run(bearing: &str, flipped: &[f64]) -> RunDir {
    let mut r = unseen::stored(DATA, "clean-n1");
    let mut hit = 0;
    for row in &mut r.measurements {
        if row.bearing == bearing && flipped.contains(&row.speed_hz) {
            for z in row.rel.iter_mut().chain(row.ped.iter_mut()) {
                *z = -*z;
            }
            hit += 1;
        }
    }
    assert_eq!(hit, flipped.len(), "every flipped speed is a measured one");
    r
}

/// What `id` lists per bearing: (B1, B2) [Hz].
fn lists(id: &Identification) -> (Vec<f64>, Vec<f64>) {
    (unseen::listed(id, "B1"), unseen::listed(id, "B2"))
}

#[test]
fn flips_away_from_the_resonances_are_listed_exactly() {
    // 31.7 Hz between the first two bending modes, 71.0 Hz on the rising
    // flank of the 82 Hz peak, 106.3 Hz past it.
    let flipped = [31.701, 70.971, 106.309];
    let id = identify(&flipped_run("B1", &flipped));
    assert_eq!(lists(&id), (flipped.to_vec(), vec![]));
}

#[test]
fn flips_next_to_a_resonance_and_two_speeds_apart_are_listed_exactly() {
    // 13.2 Hz just below the 15.5 Hz mode (its right-hand neighbour swings
    // with the mode: the local model is confirmed on the left only); 51.2
    // and 53.5 Hz two speeds apart before the recorder's gap (each flip
    // spoils the prediction of the speed between them). Both were missed
    // before `robust::ONE_SIDED_RATIO` (main at 22df24b: nothing listed).
    let flipped = [13.245, 51.152, 53.486];
    let id = identify(&flipped_run("B1", &flipped));
    assert_eq!(lists(&id), (flipped.to_vec(), vec![]));
}

#[test]
fn flips_at_a_peak_and_on_a_flank_are_confirmed_by_the_other_bearing() {
    // 81.988 Hz at the top of the 82 Hz peak and 14.65 Hz on the 15.5 Hz
    // mode's flank: there the local model in speed misses a reading by more
    // than the noise, negated too, and the test in speed alone names
    // nothing (main at 2f157a4: nothing listed). B2 at the same speeds
    // tells a flip (B1 alone negated) from the machine's true phase swing
    // (every bearing turns together) (`robust::confirmed_across`). Either
    // bearing flipped is named at that bearing; both flipped together is a
    // common sign, which the other bearing cannot see: nothing listed.
    let flipped = [14.65, 81.988];
    let id = identify(&flipped_run("B1", &flipped));
    assert_eq!(lists(&id), (flipped.to_vec(), vec![]));
    let warned = id
        .pedestals
        .iter()
        .find(|p| p.bearing == "B1")
        .is_some_and(|p| {
            p.warnings.iter().any(|w| {
                w.message
                    .contains("at a resonance's peak or flank at 14.65, 81.988 Hz")
            })
        });
    assert!(warned, "{:?}", id.pedestals[0].warnings);
    let id = identify(&flipped_run("B2", &flipped));
    assert_eq!(lists(&id), (vec![], flipped.to_vec()));
    let mut both = flipped_run("B1", &flipped);
    for row in &mut both.measurements {
        if row.bearing == "B2" && flipped.contains(&row.speed_hz) {
            for z in row.rel.iter_mut().chain(row.ped.iter_mut()) {
                *z = -*z;
            }
        }
    }
    assert_eq!(lists(&identify(&both)), (vec![], vec![]));
}

#[test]
fn diagnose_leaves_out_the_flips_the_other_bearing_confirms() {
    // The same flips through `plinth diagnose`'s own call of the tests
    // (`identify::flips::flipped_speeds`, before it fits anything).
    let flipped = [14.65, 81.988];
    let run = flipped_run("B1", &flipped);
    let d = plinth::diagnose::diagnose(&run, &plinth::diagnose::Options::default())
        .expect("diagnose")
        .diagnosis;
    assert_eq!(d.flipped_speeds_hz.len(), 1, "{:?}", d.flipped_speeds_hz);
    assert_eq!(d.flipped_speeds_hz["B1"], flipped);
}

/// The three-bearing machine's run (tests/data/three-bearing/noise-1:
/// `plinth simulate tests/machines/three-bearing-tabulated.toml --speeds
/// 5:200:2.5 --digits 12`, then `scripts/trust_data.py --noise 0.01 --seed
/// 1`, as `scripts/bench_flips.py` makes its every-bearing case, seed 1)
/// with every channel of every bearing negated at `flipped` [Hz].
fn three_bearings_flipped(flipped: &[f64]) -> RunDir {
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/data/three-bearing");
    let mut r = unseen::stored(data, "noise-1");
    for row in &mut r.measurements {
        if flipped.contains(&row.speed_hz) {
            for z in row.rel.iter_mut().chain(row.ped.iter_mut()) {
                *z = -*z;
            }
        }
    }
    r
}

#[test]
fn every_bearing_flipped_where_one_bearing_names_it_is_listed_at_every_bearing() {
    // The machine's keyphasor half a revolution off at 45, 67.5 and
    // 105 Hz: every bearing flipped at once. 45 Hz sits past the modes at
    // 35-47 Hz the 2.5 Hz steps do not resolve: `drive`'s test in speed
    // names it, `mid`'s and `outboard`'s do not (nor hold it as a block
    // they could not confirm), and across bearings a common sign is
    // invisible. With `drive` negated back there, the other two are
    // negated against it (`robust::followed_flips`). Main at afc02cc:
    // `mid` and `outboard` list 67.5 and 105 Hz only.
    let flipped = [45.0, 67.5, 105.0];
    let run = three_bearings_flipped(&flipped);
    let id = identify(&run);
    for b in ["drive", "mid", "outboard"] {
        assert_eq!(unseen::listed(&id, b), flipped, "{b}");
    }
    let d = plinth::diagnose::diagnose(&run, &plinth::diagnose::Options::default())
        .expect("diagnose")
        .diagnosis;
    for b in ["drive", "mid", "outboard"] {
        assert_eq!(d.flipped_speeds_hz[b], flipped, "{b}");
    }
}

#[test]
fn one_bearing_flipped_at_the_last_two_speeds_is_listed_exactly() {
    // The stored three-bearing run (1 % noise, seed 1) with one bearing's
    // channels negated at 197.5 or 200 Hz, the run's last two speeds: the
    // test in speed does not judge them, so the test across bearings is
    // the only one. There the window's subspace is an extrapolation:
    // r/s's tail is χ²(2)'s (robust::cross, EDGE_DOF), and a second
    // bearing's negation may pass too, the flipped one's likelihood ahead
    // by far more than the margin 2 ln(n/α) (docs/trust-bad-speeds.md "Session 38").
    // Main at eacba08 lists nothing for drive at 197.5 and 200 Hz, mid at
    // 200 and outboard at 200.
    let mut missed = Vec::new();
    for bearing in ["drive", "mid", "outboard"] {
        for speed in [197.5, 200.0] {
            let mut run = three_bearings_flipped(&[]);
            let mut hit = 0;
            for row in &mut run.measurements {
                if row.bearing == bearing && row.speed_hz == speed {
                    for z in row.rel.iter_mut().chain(row.ped.iter_mut()) {
                        *z = -*z;
                    }
                    hit += 1;
                }
            }
            assert_eq!(hit, 1, "{speed} Hz is a measured speed of {bearing}");
            let id = identify(&run);
            for b in ["drive", "mid", "outboard"] {
                let want: &[f64] = if b == bearing { &[speed] } else { &[] };
                if unseen::listed(&id, b) != want {
                    missed.push(format!(
                        "{bearing} at {speed} Hz: {b} lists {:?}",
                        unseen::listed(&id, b)
                    ));
                }
            }
        }
    }
    assert!(missed.is_empty(), "{missed:?}");
}
