//! identify's sensor-delay test (session 45, helper idelay17;
//! host/src/estimate/lack_of_fit/delay.rs): a 150 µs delay on B2's `rel`
//! probes of the sixth unseen machine (tests/data/ross-unseen-6/
//! unseen-six.toml; B2's pedestal resonances, 22 and 52 Hz, inside the
//! run) turns the apparent pedestal into Z·(1 − iΩτ), its dampings
//! c − τ(k − Ω²m). The stored run is ROSS 2.3.0's
//! (`python3 scripts/ross_unseen.py --machine unseen-six
//! OUT delay 4301`, copied to tests/data/ross-unseen-6/delay-4301/). Rates
//! over seeds: docs/trust.md, Session 45 (idelay17).

use plinth_tests::rundown::identify;
use plinth_tests::unseen::{self, ok_but_wrong, untrusted};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ross-unseen-6");

/// Main (52c0f7c, dd006b2) printed B2 `ok` here with c_y 411 ± 57 against
/// 800 (z −6.8) and c_z 785 ± 53 against 330 (z +8.5), trusted. The delay
/// test untrusts B2 and only B2, says so with the delay's size (150 µs
/// within 3 of its σ), and every value still printed `ok` is right within
/// 3 ± (dampings included). Measured over seeds 4301-4320: B2 untrusted
/// 20/20 (main 12/20; main printed B2 `ok` beyond 3 ± in 7/20).
#[test]
fn a_delay_on_b2s_probes_untrusts_b2_and_says_so() {
    let run = unseen::stored(DATA, "delay-4301");
    let id = identify(&run);
    assert_eq!(untrusted(&id), ["B2"]);
    let wrong = ok_but_wrong(&run, &id, true);
    assert!(wrong.is_empty(), "{wrong:?}");
    let b2 = id.pedestals.iter().find(|p| p.bearing == "B2").expect("B2");
    assert!(
        b2.warnings
            .iter()
            .any(|w| w.message.contains("sensor delay of about")),
        "{:?}",
        b2.warnings
    );
    let t = id.noise["B2"]
        .lack_of_fit
        .and_then(|l| l.sensor_delay)
        .expect("the delay test is made with noise columns");
    assert!((t.delay_us - 150.0).abs() < 3.0 * t.delay_std_us, "{t:?}");
}
