//! A clean recording of a stiff pedestal over a narrow band names no
//! convention mistake, and the same run with its phasors conjugated by
//! hand still names the mistake where the band can see it
//! (docs/field-data.md "Session 41 (recflex17)"). The run: `tests/data/ross-recording-flex-narrow`
//! (ROSS, unseen-flex, 60 → 20 Hz at 2 Hz/s, extracted by `plinth
//! extract`; its README gives the commands). main at 4e8447f named
//! `conjugated` at B1 on it and exited 2.

use plinth::identify::convention::Convention;
use plinth::identify::{identify_run, Identification, Options, WarningKind};
use plinth::rundir::RunDir;
use std::path::{Path, PathBuf};

fn stored() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data/ross-recording-flex-narrow")
}

fn identify(dir: &Path) -> Identification {
    let run = RunDir::read(dir).expect("reading the run directory");
    identify_run(&run, &Options::default()).expect("identification")
}

/// A copy of the stored run with the imaginary part of every column in
/// `columns` negated in the CSV text (a conjugation made independently of
/// Plinth's own corrections).
fn conjugated_copy(columns: &[&str]) -> tempfile::TempDir {
    let dst = tempfile::tempdir().expect("temporary directory");
    for f in ["bearings.csv", "transducers.csv"] {
        std::fs::copy(stored().join(f), dst.path().join(f)).expect("copy");
    }
    let text = std::fs::read_to_string(stored().join("measurements.csv")).expect("read");
    let mut lines = text.lines();
    let header = lines.next().expect("header");
    let names: Vec<&str> = header.split(',').collect();
    let negated: Vec<usize> = columns
        .iter()
        .map(|c| names.iter().position(|n| n == c).expect("column"))
        .collect();
    let mut out = vec![header.to_string()];
    for line in lines {
        let fields: Vec<String> = line
            .split(',')
            .enumerate()
            .map(|(i, f)| {
                if !negated.contains(&i) {
                    f.to_string()
                } else if let Some(s) = f.strip_prefix('-') {
                    s.to_string()
                } else {
                    format!("-{f}")
                }
            })
            .collect();
        out.push(fields.join(","));
    }
    std::fs::write(dst.path().join("measurements.csv"), out.join("\n") + "\n").expect("write");
    dst
}

fn named(id: &Identification, bearing: &str) -> Option<Convention> {
    id.pedestals
        .iter()
        .find(|p| p.bearing == bearing)
        .expect("pedestal")
        .suspected_convention_error
}

#[test]
fn a_stiff_pedestal_over_a_narrow_band_names_no_convention() {
    let id = identify(&stored());
    for p in &id.pedestals {
        assert!(
            p.suspected_convention_error.is_none()
                && !p.has_warning(WarningKind::SuspectedConventionError),
            "{} names {:?}: {:#?}",
            p.bearing,
            p.suspected_convention_error,
            p.warnings
        );
    }
}

#[test]
fn the_same_run_conjugated_by_hand_is_named_where_the_band_can_see_it() {
    let all = conjugated_copy(&["rel_y_im", "rel_z_im", "ped_y_im", "ped_z_im"]);
    let id = identify(all.path());
    assert_eq!(named(&id, "B2"), Some(Convention::Conjugated));
    // B1's forces are mostly noise over this band: it may say nothing, but
    // no mistake other than the one made.
    let b1 = named(&id, "B1");
    assert!(b1.is_none_or(|c| c == Convention::Conjugated), "B1 {b1:?}");
    let ped = conjugated_copy(&["ped_y_im", "ped_z_im"]);
    let id = identify(ped.path());
    assert_eq!(named(&id, "B2"), Some(Convention::PedConjugated));
    let b1 = named(&id, "B1");
    assert!(
        b1.is_none_or(|c| c == Convention::PedConjugated),
        "B1 {b1:?}"
    );
}
