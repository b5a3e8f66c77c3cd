//! Session 41 (docs/trust-lack-of-fit.md, Session 41 (d3trust17)): `plinth diagnose` reads
//! written digits as truncated (the larger of the two noises), so the
//! lack-of-fit findings it took from its base fits were judged against a
//! level 4 times `plinth identify`'s (in variance) and never fired where
//! identify's did. A bearing identify untrusts for lack of fit is now
//! untrusted by diagnose too (where no kept step acts) when the fit fails
//! with the digits read as rounded both as written and moved half a last
//! digit away from zero; truncated clean data do not fire it.

use plinth::diagnose::diagnose;
use plinth::identify::WarningKind;
use plinth_tests::rundown::identify;
use plinth_tests::unseen::{self, untrusted};

const FOUR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen");
const OVERHUNG: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-2");

/// unseen-four `sub-base-d3` seed 1201 (ROSS, 3 digits rounded, no noise,
/// 170-290 Hz, above every pedestal's resonance): identify untrusts B3
/// for lack of fit; main's diagnose printed it trusted with B3 23.8 % off
/// at z 25.
#[test]
fn a_lack_of_fit_identify_sees_at_three_digits_untrusts_the_diagnosis() {
    let run = unseen::stored(FOUR, "sub-base-d3-1201");
    let id = identify(&run);
    assert_eq!(untrusted(&id), vec!["B3".to_string()]);
    assert!(id
        .pedestal("B3")
        .expect("B3")
        .has_warning(WarningKind::LackOfFit));
    let (_, options) = unseen::machine_and_options(FOUR, "unseen-four.toml");
    let d = diagnose(&run, &options).expect("diagnose").diagnosis;
    assert!(!d.trusted, "{}", d.to_text());
    assert!(
        d.trust_reasons
            .iter()
            .any(|r| r.starts_with("bearing B3:") && r.contains("lack-of-fit rule")),
        "{:?}",
        d.trust_reasons
    );
}

/// unseen-overhung `clean-d12` seed 1202 cut (not rounded) to 3 digits
/// (scripts/truncate_digits.py): read as rounded its bias is a lack of
/// fit, read as what it is it fits; nothing is flagged.
#[test]
fn truncated_clean_digits_are_not_a_lack_of_fit() {
    let run = unseen::stored(OVERHUNG, "truncated-d3-1202");
    let d = diagnose(&run, &plinth::diagnose::Options::default())
        .expect("diagnose")
        .diagnosis;
    assert!(
        !d.trust_reasons
            .iter()
            .any(|r| r.contains("lack-of-fit rule")),
        "{:?}",
        d.trust_reasons
    );
}
