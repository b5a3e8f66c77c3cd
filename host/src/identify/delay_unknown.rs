//! A sensor delay on a bearing's `rel` probes or (τ̂ < 0) its `ped`
//! pick-ups that the data do not exclude, counted in its pedestal ± as
//! unknown: the one rule of
//! [`crate::estimate::lack_of_fit::delay_unknown`] (shared with
//! `plinth diagnose`'s final ±) on identify's one-mass fit.
//!
//! The one-mass fit takes a delay τ into its damping, c − τ(k − Ω²m); its
//! score test ([`super::trust`], `sensor_delay`) untrusts a bearing where
//! the delay shows beyond the fit, but where the pedestal's resonance lies
//! above the band τ and c are nearly collinear and the test cannot see it
//! (unseen-five `delay`, 3 of 10 runs: B1 printed `ok` with c_y 5.2-6.4 ±
//! off, docs/trust.md, Session 45 (idelay17)). Here, per bearing on rigid
//! ground, the fit linearised with τ free ([`DelayNuisance`], made with the
//! lack-of-fit evidence) is judged by the shared gate (the data favour a
//! delay with the reported dampings held passive: the likelihood ratio of
//! τ with c ≥ 0 in both fits beyond 4, which is |τ̂| > 2σ_τ, two-sided,
//! where the dampings are well above zero; a delay on the pick-ups reads
//! as τ̂ < 0 on the probes) and exclusion; where the delay is
//! counted as unknown every pedestal ± and the covariance are multiplied by
//! the shared widening (from ρ = σ(τ free)/σ(τ held) and τ̂/σ_τ,
//! [`crate::estimate::lack_of_fit::delay_unknown::widening`]; the modal
//! view's ζ ± with them), the
//! values and the trust verdict are left as they are, and an informative
//! warning names the delay, the channels its sign implies (τ̂ < 0: the
//! `ped` pick-ups) and the ρ; a τ the data do not estimate (its interval
//! spans more than 1 rad of phase at the top speed) is printed as such, not
//! as a number ([`delay_figure`]).

use super::{Identification, PedestalFit, Warning, WarningKind};
use crate::estimate::lack_of_fit::DelayNuisance;
use plinth_shared::regression::Parameter;

/// Widens the ± of every pedestal of `identification` on rigid ground
/// whose bearing's delay the data do not exclude (module docs), with a
/// [`WarningKind::DelayNotExcluded`] warning; its modal view is recomputed
/// from the widened covariance.
pub fn mark(identification: &mut Identification) {
    for p in &mut identification.pedestals {
        if p.base.is_some() {
            continue;
        }
        let Some(d) = identification
            .noise
            .get(&p.bearing)
            .and_then(|n| n.lack_of_fit)
            .and_then(|l| l.delay_unknown)
        else {
            continue;
        };
        let theta = p.pedestal.theta();
        if d.counted_unknown(&theta) {
            let evidence = d.evidence(&theta);
            widen(p, &d, evidence);
        }
    }
}

fn is_fixed(p: &PedestalFit, c: Parameter) -> bool {
    p.fixed.iter().any(|f| f == c.name())
}

/// Multiplies `p`'s ± and covariance by `d`'s widening (from ρ and τ̂/σ_τ,
/// [`DelayNuisance::widening`]) and says so; `evidence` is the data's
/// evidence for the delay with the pedestal passive
/// ([`DelayNuisance::evidence`]).
fn widen(p: &mut PedestalFit, d: &DelayNuisance, evidence: f64) {
    let w = d.widening();
    p.widen_by(w);
    // The dampings always, any other value whose ± moved by 10 % or more.
    let widened: Vec<String> = Parameter::ALL
        .iter()
        .filter(|&&c| !is_fixed(p, c))
        .filter(|&&c| matches!(c, Parameter::Cy | Parameter::Cz) || w[c as usize] >= 1.1)
        .map(|&c| {
            let i = c as usize;
            format!("{} ±×{:.3} (ρ {:.3})", c.name(), w[i], d.ratio[i])
        })
        .collect();
    p.warnings.push(Warning {
        kind: WarningKind::DelayNotExcluded,
        message: format!(
            "the data do not exclude a sensor delay on {} ({}, linearised at τ = 0; the data favour it: likelihood ratio {evidence:.1} > 4 with the dampings held passive, c ≥ 0), which reads as a pedestal damping c − τ·(k − Ω²m): its ± count the delay as unknown, multiplied by √(1 + (ρ² − 1)·(1 + (τ̂/σ_τ)²)), ρ = σ(τ free)/σ(τ held) ({}); the values are the fit's",
            delay_channels(d),
            delay_figure(d),
            widened.join(", ")
        ),
    });
}

/// The channels a delay of `d`'s sign is on (only the relative phase of
/// force and motion enters: τ̂ > 0 the `rel` probes read late, τ̂ < 0 the
/// `ped` pick-ups); both where the data do not estimate τ.
fn delay_channels(d: &DelayNuisance) -> &'static str {
    if !d.estimable() {
        "its rel probes or its ped pick-ups"
    } else if d.delay_us < 0.0 {
        "its ped pick-ups"
    } else {
        "its rel probes"
    }
}

/// τ̂ ± σ_τ as text: of the channels [`delay_channels`] names (a delay of
/// |τ̂| on the pick-ups where τ̂ < 0); where the data do not estimate τ
/// ([`DelayNuisance::estimable`]) its ± as a phase at the top speed
/// instead of a number.
pub fn delay_figure(d: &DelayNuisance) -> String {
    if !d.estimable() {
        let phase = d.delay_std_us * 1e-6 * d.top_speed_rad_s;
        return format!(
            "τ not estimable from these data: its ± {:.0} µs is {:.2} rad of phase at the top speed {:.1} Hz, where the linearisation at τ = 0 fails",
            d.delay_std_us,
            phase,
            d.top_speed_rad_s / std::f64::consts::TAU
        );
    }
    // A τ̂ that rounds to zero is printed 0, never −0.
    let tau = if d.delay_us.abs() < 0.5 {
        0.0
    } else {
        d.delay_us
    };
    if tau < 0.0 {
        format!(
            "the pick-ups {:.0} ± {:.0} µs late: τ {:.0} µs on the rel probes",
            -tau, d.delay_std_us, tau
        )
    } else {
        format!("τ {:.0} ± {:.0} µs", tau, d.delay_std_us)
    }
}

/// Under the table: one line per pedestal whose ± count a delay as unknown
/// (its [`WarningKind::DelayNotExcluded`] warning); empty when none.
pub fn describe(identification: &Identification) -> String {
    identification
        .warnings_of(WarningKind::DelayNotExcluded)
        .map(|(bearing, w)| format!("\n{bearing}: {}\n", w.message))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn nuisance(delay_us: f64, delay_std_us: f64, top_hz: f64) -> DelayNuisance {
        DelayNuisance {
            delay_us,
            delay_std_us,
            ratio: [1.0; 5],
            held_std_err: [0.0; 5],
            path_per_us: [0.0; 5],
            top_speed_rad_s: std::f64::consts::TAU * top_hz,
        }
    }

    /// A τ the data do not estimate (the paper machine on 5-60 Hz: ± 1.8 ms,
    /// main printed "τ -0 ± 1815 µs") is printed as such; an estimable one
    /// as a number, never −0, on the channels its sign implies.
    #[test]
    fn an_unestimable_delay_is_printed_as_such() {
        let d = nuisance(-0.4, 1815.0, 60.0);
        let text = delay_figure(&d);
        assert!(
            text.starts_with("τ not estimable from these data"),
            "{text}"
        );
        assert!(
            text.contains("0.68 rad of phase at the top speed 60.0 Hz"),
            "{text}"
        );
        assert!(!text.contains("-0"), "{text}");
        assert_eq!(delay_channels(&d), "its rel probes or its ped pick-ups");
        let d = nuisance(-0.4, 39.0, 56.1);
        assert_eq!(delay_figure(&d), "τ 0 ± 39 µs");
        let d = nuisance(-203.0, 38.0, 50.0);
        assert_eq!(
            delay_figure(&d),
            "the pick-ups 203 ± 38 µs late: τ -203 µs on the rel probes"
        );
        assert_eq!(delay_channels(&d), "its ped pick-ups");
        assert_eq!(
            delay_channels(&nuisance(120.0, 39.0, 56.1)),
            "its rel probes"
        );
    }
}
