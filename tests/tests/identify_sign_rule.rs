//! The sign rule (`identify/physical.rs`): a mass or stiffness below zero
//! within its noise is not "physically impossible" but not determined (the
//! pedestal untrusted, no exit 2), while a sign mistake in the data still
//! exits 2. The run: `tests/data/ross-recording-flex-sign` (ROSS,
//! unseen-flex, clean, 60 → 20 Hz at 2 Hz/s, extracted by `plinth extract`;
//! its README gives the commands), where B1's mass comes out
//! −347 ± 4710 kg; main at 296e18c exited 2 on it.

use plinth::identify::physical::NotPhysical;
use plinth::identify::WarningKind;
use plinth_tests::rundown::{identify_dir, pedestal};
use std::path::{Path, PathBuf};

fn stored() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data/ross-recording-flex-sign")
}

/// A copy of the stored run with every rel phasor negated in the CSV text
/// (the probes wired with the opposite sign: F = K*(rel) changes sign, and
/// so do the pedestal's mass, stiffnesses and dampings; made independently
/// of Plinth's own corrections).
fn rel_negated_copy() -> tempfile::TempDir {
    let dst = tempfile::tempdir().expect("temporary directory");
    for f in ["bearings.csv", "transducers.csv"] {
        std::fs::copy(stored().join(f), dst.path().join(f)).expect("copy");
    }
    let text = std::fs::read_to_string(stored().join("measurements.csv")).expect("read");
    let mut lines = text.lines();
    let header = lines.next().expect("header");
    let negated: Vec<usize> = header
        .split(',')
        .enumerate()
        .filter(|(_, n)| n.starts_with("rel_") && !n.ends_with("_sd"))
        .map(|(i, _)| i)
        .collect();
    assert_eq!(negated.len(), 4, "{header}");
    let mut out = vec![header.to_string()];
    for line in lines {
        let fields: Vec<String> = line
            .split(',')
            .enumerate()
            .map(|(i, f)| match (negated.contains(&i), f.strip_prefix('-')) {
                (false, _) => f.to_string(),
                (true, Some(s)) => s.to_string(),
                (true, None) => format!("-{f}"),
            })
            .collect();
        out.push(fields.join(","));
    }
    std::fs::write(dst.path().join("measurements.csv"), out.join("\n") + "\n").expect("write");
    dst
}

#[test]
fn a_mass_negative_within_its_noise_is_undetermined_not_impossible() {
    let id = identify_dir(&stored());
    let b1 = pedestal(&id, "B1");
    assert!(
        b1.pedestal.m < 0.0 && b1.pedestal.m > -b1.std_err.m,
        "the stored run no longer gives B1 a mass negative within its ± (m = {} ± {}): it tests nothing here",
        b1.pedestal.m,
        b1.std_err.m
    );
    for p in &id.pedestals {
        assert!(
            !p.has_warning(WarningKind::PhysicallyImpossible),
            "{}: {:#?}",
            p.bearing,
            p.warnings
        );
        // Never `ok` with a negative mass or stiffness.
        let negative = p.pedestal.m < 0.0 || p.pedestal.k_y < 0.0 || p.pedestal.k_z < 0.0;
        assert!(!(negative && p.trusted), "{}: {p:?}", p.bearing);
    }
    assert!(!b1.trusted);
    assert!(
        b1.has_warning(WarningKind::Undetermined),
        "{:#?}",
        b1.warnings
    );
    // No exit 2 (what `plinth identify` returns after printing).
    assert!(NotPhysical::of(&id).is_none(), "{:?}", NotPhysical::of(&id));
}

#[test]
fn probes_of_the_wrong_sign_are_still_impossible_where_the_forces_are_measured() {
    let dir = rel_negated_copy();
    let id = identify_dir(dir.path());
    // B2 resonates in the band: its forces are well above the noise, and its
    // pedestal comes out negative by many standard errors.
    let b2 = pedestal(&id, "B2");
    assert!(
        b2.pedestal.m < 0.0 && b2.pedestal.k_y < 0.0 && b2.pedestal.k_z < 0.0,
        "{b2:?}"
    );
    let impossible: Vec<&str> = b2
        .warnings
        .iter()
        .filter(|w| w.kind == WarningKind::PhysicallyImpossible)
        .map(|w| w.message.as_str())
        .collect();
    for name in ["m = ", "k_y = ", "k_z = "] {
        assert!(
            impossible.iter().any(|m| m.starts_with(name)),
            "{name}: {impossible:?}"
        );
    }
    assert!(!b2.trusted);
    let lines = NotPhysical::of(&id).expect("exit 2");
    assert!(lines.0.iter().any(|l| l.contains("`B2`")), "{lines:?}");
}
