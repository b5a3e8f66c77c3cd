//! Issue 17, "a ± must mean what it says": where `plinth diagnose`'s final
//! pedestal values are the base model's maximum-likelihood fit (nothing
//! named), their ± are the ML engine's, the ± `plinth identify` prints for
//! the same values, not the floor of the search's weighted least squares.
//! The search's weights give each real equation its own variance and leave
//! out the correlation a film's cross terms put between a pedestal's y and
//! z equations; at such a bearing that floor was 1.36-2.04 times the ML
//! bound (docs/unseen-six.md, "Session 46 (lowsnr17)", "4. Seen on the
//! way"; docs/diagnose-verdict.md, Session 46 (mlse17)).
//!
//! The run: `tests/data/ross-unseen-6/clean-s1c` (ROSS unseen-six, clean,
//! noise columns; `scripts/ross_unseen.py --machine unseen-six`). B2 sits
//! on a film with cross terms. Main (57b3cb7) printed B2's final ± at
//! 1.47 (k_y), 2.04 (k_z), 1.45 (m), 1.36 (c_y), 1.83 (c_z) times
//! identify's.

use plinth::diagnose::{diagnose, Options};
use plinth::rundir::RunDir;
use plinth_shared::regression::Parameter;
use std::path::Path;

/// Largest relative difference allowed between diagnose's ± and
/// identify's where both are the ML bound [-].
const TOLERANCE: f64 = 0.02;

/// B2's ± of the base model and of the final model (nothing named) equal
/// identify's for the same values within 2 %.
#[test]
fn diagnose_std_errs_are_identifys_where_its_values_are_identifys() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/ross-unseen-6/clean-s1c");
    let run = RunDir::read(&dir).expect("stored run");
    let out = diagnose(&run, &Options::default()).expect("diagnose");
    let d = &out.diagnosis;
    assert!(
        d.effects_added.is_empty(),
        "a clean run: nothing should be named, got {:?}",
        d.effects_added
    );
    let b = out
        .prep
        .bearings
        .iter()
        .position(|n| n == "B2")
        .expect("bearing B2");
    let identify = &out.prep.base_fits[b];
    let values = identify.pedestal.theta();
    let std_errs = identify.std_err.theta();
    for (list, pedestals) in [
        ("pedestals_before", &d.pedestals_before),
        ("pedestals_after", &d.pedestals_after),
    ] {
        let p = pedestals
            .iter()
            .find(|p| p.bearing == "B2")
            .unwrap_or_else(|| panic!("{list} has no B2"));
        for (k, q) in Parameter::ALL.iter().enumerate() {
            let name = q.name();
            let (value, want) = (values[k], std_errs[k]);
            let got = p.std_err[name];
            assert_eq!(
                p.values[name], value,
                "{list} B2 {name}: not identify's value"
            );
            let ratio = got / want;
            assert!(
                (ratio - 1.0).abs() <= TOLERANCE,
                "{list} B2 {name}: ± {got:.4e} is {ratio:.3} times identify's {want:.4e}"
            );
        }
    }
}
