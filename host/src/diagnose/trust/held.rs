//! A diagnosis whose final model holds a pedestal damping at zero against
//! the data is not trusted.
//!
//! The hold is a passive pedestal's bound, taken where the free damping
//! came out impossible. Where the group's ML refit with the effect in the
//! model and the damping free still finds it impossible
//! ([`crate::diagnose::ml_final::held_free`], `plinth identify`'s
//! family-wise rule for negative dampings confirmed by the likelihood
//! ratio), the model with the effect still needs an active pedestal there:
//! it lacks something, and every value fitted beside the hold absorbs it
//! with a ± conditional on the hold (unseen-four `runout-d3` seed 1201:
//! B3 k_y 6.8 % = 9.7 ± off, trusted). A hold within the noise (a truly
//! undamped pedestal, a damping that trades with a delay) leaves the
//! verdict as it was.
//!
//! A delay on a bearing's `rel` probes or (τ̂ < 0) its `ped` pick-ups that
//! the data do not exclude ([`crate::diagnose::ml_final::delay_unknown`])
//! leaves the verdict as it was too (the values are within their widened
//! ±) but the verdict says it, naming the channels the sign implies: the
//! pedestal ± at that bearing count the delay as unknown.

use super::Conclusion;
use crate::diagnose::ml_final::delay_unknown::DelayUnknown;
use crate::diagnose::ml_final::GroupRefit;

/// Untrusts `conclusion` for every damping of `refits` held at zero
/// against the data ([`GroupRefit::held_against_data`]), one reason per
/// bearing (`bearings`: the run's bearing names, by index).
pub fn judge_held(conclusion: &mut Conclusion, bearings: &[String], refits: &[GroupRefit]) {
    for r in refits {
        for &b in &r.group {
            let at: Vec<_> = r
                .held_against_data
                .iter()
                .filter(|h| h.bearing == b)
                .collect();
            let (Some(first), Some(name)) = (at.first(), bearings.get(b)) else {
                continue;
            };
            let values = at
                .iter()
                .map(|h| {
                    format!(
                        "{} = {:.3e} ± {:.2e} N·s/m ({:.1} standard errors below zero)",
                        h.name(),
                        h.value,
                        h.std_err,
                        -h.value / h.std_err
                    )
                })
                .collect::<Vec<_>>()
                .join(", ");
            let why = format!(
                "bearing {name}: its pedestal dampings are held at 0 (a passive pedestal's bound), but the final fit with them free still finds them impossible: {values}, beyond the {:.2} standard errors of `plinth identify`'s rule for the run's {} damping(s) (1 % family-wise), and freeing them lowers the fit's χ² by {:.1}; the model with its effects still lacks something there, and the k, m fitted beside the hold absorb it with a ± that counts the hold as exact",
                first.sigmas, first.family, first.likelihood_ratio
            );
            conclusion.verdict += &format!(
                " But at bearing {name} the dampings are held at zero against the data (reasons below): the identified parameters are not to be trusted."
            );
            conclusion.reasons.push(why);
            conclusion.trusted = false;
        }
    }
    for d in refits.iter().flat_map(|r| &r.delay_unknown) {
        let Some(name) = bearings.get(d.bearing) else {
            continue;
        };
        // The dampings always, any other value whose ± moved by 10 % or more.
        let widened = d
            .widened
            .iter()
            .filter(|w| w.damping || w.ratio() >= 1.1)
            .map(|w| {
                let at = bearings.get(w.bearing).map_or("?", String::as_str);
                format!("{at} {} ±×{:.3}", w.name, w.ratio())
            })
            .collect::<Vec<_>>()
            .join(", ");
        conclusion.verdict += &format!(
            " At bearing {name} the data do not exclude a sensor delay on {}, linearised at τ = 0), which reads as a pedestal damping c − τ·(k − Ω²m): the pedestal ± count it as unknown ({widened}).",
            delay_text(d)
        );
    }
}

/// The channels and size of `d`'s delay as the verdict names them: only
/// the relative phase of force and motion enters, so the delay is
/// linearised on the `rel` probes and τ̂ < 0 there is the `ped` pick-ups
/// of the same directions read |τ̂| late (unseen-seven `ped-delay`).
fn delay_text(d: &DelayUnknown) -> String {
    let (tau, sd) = (d.tau * 1e6, d.tau_std_err * 1e6);
    // A τ̂ that rounds to zero is printed 0, never −0.
    let tau = if tau.abs() < 0.5 { 0.0 } else { tau };
    let rel = d.channels.label();
    if tau < 0.0 {
        format!(
            "`{}` (its pick-ups {:.0} ± {:.0} µs late: τ {tau:.0} µs on `{rel}`",
            rel.replace("rel", "ped"),
            -tau,
            sd
        )
    } else {
        format!("`{rel}` (τ {tau:.0} ± {sd:.0} µs")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::criterion::Inference;
    use crate::diagnose::ml_final::held_free::HeldAgainstData;
    use nalgebra::{DMatrix, DVector};

    fn refit(held: Vec<HeldAgainstData>) -> GroupRefit {
        let jac = DMatrix::from_row_slice(3, 1, &[1.0, 2.0, 1.5]);
        let resid = DVector::from_vec(vec![0.1, -0.2, 0.05]);
        let inference = Inference::new(&jac, &resid, &[0, 1, 2], DVector::from_vec(vec![1.0]))
            .expect("inference");
        GroupRefit {
            group: vec![1],
            terms: vec![0],
            nonlinear: Vec::new(),
            inference,
            held_delays: Vec::new(),
            held_against_data: held,
            freed: Vec::new(),
            held_unknown: None,
            delay_unknown: Vec::new(),
        }
    }

    fn trusted() -> Conclusion {
        Conclusion {
            verdict: "v.".to_string(),
            trusted: true,
            reasons: Vec::new(),
        }
    }

    /// A held damping the free fit finds impossible untrusts the
    /// diagnosis with its bearing, value and ± in the reason.
    #[test]
    fn a_damping_held_against_the_data_untrusts() {
        let h = HeldAgainstData {
            bearing: 1,
            dir: 1,
            value: -5.0e3,
            std_err: 1.0e3,
            sigmas: 2.81,
            family: 4,
            likelihood_ratio: 30.0,
        };
        let mut c = trusted();
        judge_held(&mut c, &["B1".into(), "B2".into()], &[refit(vec![h])]);
        assert!(!c.trusted);
        assert_eq!(c.reasons.len(), 1);
        assert!(c.reasons[0].starts_with("bearing B2:"), "{}", c.reasons[0]);
        assert!(c.reasons[0].contains("c_z = -5.000e3"), "{}", c.reasons[0]);
        assert!(
            c.reasons[0].contains("5.0 standard errors"),
            "{}",
            c.reasons[0]
        );
    }

    /// No damping held against the data: the verdict is untouched.
    #[test]
    fn no_damping_held_against_the_data_leaves_the_verdict() {
        let mut c = trusted();
        judge_held(&mut c, &["B1".into(), "B2".into()], &[refit(Vec::new())]);
        assert_eq!(c, trusted());
    }

    /// A delay read as τ̂ < 0 on the probes is named on the `ped`
    /// pick-ups, late by |τ̂|; τ̂ > 0 on the `rel` probes.
    #[test]
    fn the_verdict_names_the_channels_the_sign_implies() {
        use crate::diagnose::ml_final::delay_unknown::Widened;
        use crate::diagnose::model::DelayChannels;
        let delay = |tau: f64| {
            let mut r = refit(Vec::new());
            r.delay_unknown = vec![DelayUnknown {
                bearing: 1,
                channels: DelayChannels {
                    rel: [true, true],
                    ped: [false, false],
                },
                tau,
                tau_std_err: 38e-6,
                widened: vec![Widened {
                    bearing: 1,
                    name: "c_y".into(),
                    held: 1.0e3,
                    free: 2.0e3,
                    damping: true,
                    factor: 6.0,
                }],
            }];
            let mut c = trusted();
            judge_held(&mut c, &["B1".into(), "B2".into()], &[r]);
            assert!(c.trusted);
            c.verdict
        };
        let ped = delay(-203e-6);
        assert!(
            ped.contains("sensor delay on `ped` (its pick-ups 203 ± 38 µs late"),
            "{ped}"
        );
        let rel = delay(150e-6);
        assert!(
            rel.contains("sensor delay on `rel` (τ 150 ± 38 µs"),
            "{rel}"
        );
        assert!(!delay(-0.2e-6).contains("-0"), "{}", delay(-0.2e-6));
    }
}
