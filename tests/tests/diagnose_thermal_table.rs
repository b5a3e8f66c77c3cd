//! A bearing table off by a factor that drifts over the run (session 47,
//! helper thermal17): the seventh unseen machine's `table-thermal` case,
//! the oil's viscosity following the speed on all three journals (+29 % at
//! 5 Hz, 0 at the 50 Hz top speed; the table and the machine file at the
//! top speed's viscosity). No library effect describes it. Data from ROSS
//! 2.3.0 (scripts/ross_unseen.py, seed 5402; tests/data/thermal17/README.md),
//! an independent path; docs/diagnose-bearing-table.md, "Session 47
//! (thermal17)".
//!
//! On main at 48c03f6 the search on this run added and removed
//! `pedestal_sub_base` at B1 and B2 in turn until its step limit (steps 2-8 of 8:
//! a cycle of the forward selection and the backward check), and the
//! "unexplained" report was empty although the verdict untrusted B1 for a
//! model error there (a sub-base above the range).

use plinth::diagnose::diagnose;
use plinth::diagnose::locate::UnexplainedBecause;
use plinth::diagnose::report::Diagnosis;
use plinth_tests::unseen;
use std::collections::BTreeSet;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data");

/// `plinth diagnose RUN --machine unseen-seven.toml`'s search (the file's
/// oil-film geometry; the machine-level check is not needed here).
fn diagnosis() -> Diagnosis {
    let (_, options) =
        unseen::machine_and_options(&format!("{DATA}/ross-unseen-7"), "unseen-seven.toml");
    let run = unseen::stored(&format!("{DATA}/thermal17"), "table-thermal-5402");
    diagnose(&run, &options).expect("diagnose").diagnosis
}

/// The model after each step: the steps up to it not yet removed again
/// (a removal says "after step N").
fn models(d: &Diagnosis) -> Vec<BTreeSet<(String, String)>> {
    let removed_after = |s: &plinth::diagnose::report::Step| -> Option<usize> {
        let r = s.dropped.as_deref()?;
        let tail = r.split("after step ").nth(1)?;
        tail.split(|c: char| !c.is_ascii_digit())
            .next()?
            .parse()
            .ok()
    };
    (1..=d.steps.len())
        .map(|n| {
            d.steps[..n]
                .iter()
                .filter(|s| s.dropped.is_none() || removed_after(s).is_some_and(|k| k > n))
                .map(|s| (s.effect.clone(), s.bearing.clone()))
                .collect()
        })
        .collect()
}

#[test]
fn the_search_does_not_cycle_and_the_unexplained_report_points_at_the_untrusted_bearings() {
    let d = diagnosis();
    println!("{}", d.to_text());
    // The cycle: no model is visited twice, except the one the search
    // stopped at, which the statement names (a repeated model is where a
    // deterministic search would go round again).
    let m = models(&d);
    assert!(!m.is_empty(), "nothing named");
    let last = m.last().cloned().unwrap_or_default();
    let before_stop = &m[..m.len() - 1];
    for (i, a) in before_stop.iter().enumerate() {
        for b in &before_stop[i + 1..] {
            assert_ne!(a, b, "a model visited twice before the stop: {m:?}");
        }
    }
    let repeats_at_stop = before_stop.contains(&last);
    assert_eq!(
        repeats_at_stop,
        d.search_cycle.is_some(),
        "{m:?} {:?}",
        d.search_cycle
    );
    assert!(d.steps.len() < 8, "{} steps: {m:?}", d.steps.len());
    if let Some(why) = &d.search_cycle {
        assert!(why.contains("the search cycled"), "{why}");
        assert!(d.trust_reasons.contains(why));
    }
    // Never confidently wrong: untrusted.
    assert!(!d.trusted);
    // The unexplained report: every bearing the verdict untrusts for a
    // model error there ("bearing NAME: ...") is in it, with both its
    // channels.
    let flagged: BTreeSet<&str> = d
        .trust_reasons
        .iter()
        .filter_map(|r| r.strip_prefix("bearing ")?.split(':').next())
        .collect();
    assert!(flagged.contains("B1"), "{:?}", d.trust_reasons);
    for b in &flagged {
        for dir in ["y", "z"] {
            assert!(
                d.unexplained
                    .iter()
                    .any(|u| u.bearing == *b && u.direction == dir),
                "{b} {dir}: {:?}",
                d.unexplained
            );
        }
    }
    assert!(d
        .unexplained
        .iter()
        .filter(|u| u.because == UnexplainedBecause::ModelErrorAtBearing)
        .all(|u| flagged.contains(u.bearing.as_str())));
    assert!(d
        .to_text()
        .contains("The unexplained disagreement lies at:"));
    let json = serde_json::to_value(&d).expect("json");
    assert!(json["unexplained"]
        .as_array()
        .is_some_and(|a| a.iter().any(|u| u["because"] == "model_error_at_bearing")));
}
