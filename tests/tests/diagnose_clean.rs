//! `plinth diagnose` must name nothing on data the base model explains:
//! rounded to 2, 3 and 12 significant digits, and with 1 % noise, on two
//! different machines.

mod diagnose_common;

use diagnose_common::{generate, Effect, Machine, Writing};
use plinth::diagnose::{diagnose, Options};

fn assert_clean(machine: &Machine, writing: Writing) {
    let run = generate(machine, &Effect::None, writing);
    let out = diagnose(&run, &Options::default()).expect("diagnose failed");
    let d = &out.diagnosis;
    println!("{writing:?}\n{}", d.to_text());
    assert!(
        d.effects_added.is_empty(),
        "{writing:?}: named {:?}",
        d.effects_added
    );
    assert!(d.steps.is_empty());
    assert_eq!(d.gap_before, d.gap_after);
    // The base model explains the data to the noise floor.
    assert!(
        d.gap_before <= 3.0 * d.noise.gap_floor_before,
        "gap {} vs floor {}",
        d.gap_before,
        d.noise.gap_floor_before
    );
}

fn digits(d: usize) -> Writing {
    Writing {
        digits: Some(d),
        noise: 0.0,
        seed: 3,
    }
}

#[test]
fn two_digits_name_nothing() {
    assert_clean(&Machine::paper_like(), digits(2));
    assert_clean(&Machine::three_bearing(), digits(2));
}

#[test]
fn three_digits_name_nothing() {
    assert_clean(&Machine::paper_like(), digits(3));
    assert_clean(&Machine::three_bearing(), digits(3));
}

#[test]
fn twelve_digits_name_nothing() {
    assert_clean(&Machine::paper_like(), digits(12));
    assert_clean(&Machine::three_bearing(), digits(12));
}

#[test]
fn one_percent_noise_names_nothing() {
    for seed in [5, 6] {
        let w = Writing {
            digits: Some(12),
            noise: 0.01,
            seed,
        };
        assert_clean(&Machine::paper_like(), w);
        assert_clean(&Machine::three_bearing(), w);
    }
}
