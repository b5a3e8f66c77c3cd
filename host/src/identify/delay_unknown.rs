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
//! lack-of-fit evidence) is judged by the shared gate (a damping of the
//! reported fit below zero, or |τ̂| > 2σ_τ, two-sided: a delay on the
//! pick-ups reads as τ̂ < 0 on the probes) and exclusion; where the delay is
//! counted as unknown every pedestal ± and the covariance are multiplied by
//! the shared widening (from ρ = σ(τ free)/σ(τ held) and τ̂/σ_τ,
//! [`crate::estimate::lack_of_fit::delay_unknown::widening`]; the modal
//! view's ζ ± with them), the
//! values and the trust verdict are left as they are, and an informative
//! warning names the delay and the ρ.

use super::{Identification, PedestalFit, Warning, WarningKind};
use crate::estimate::lack_of_fit::DelayNuisance;
use crate::estimate::Pedestal;
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
        let negative = [Parameter::Cy, Parameter::Cz]
            .iter()
            .any(|&c| !is_fixed(p, c) && theta[c as usize] < 0.0);
        if d.counted_unknown(negative) {
            widen(p, &d, negative);
        }
    }
}

fn is_fixed(p: &PedestalFit, c: Parameter) -> bool {
    p.fixed.iter().any(|f| f == c.name())
}

/// Multiplies `p`'s ± and covariance by `d`'s widening (from ρ and τ̂/σ_τ,
/// [`DelayNuisance::widening`]) and says so.
fn widen(p: &mut PedestalFit, d: &DelayNuisance, negative: bool) {
    let w = d.widening();
    let se = p.std_err.theta();
    p.std_err = Pedestal::from_theta(std::array::from_fn(|i| se[i] * w[i]));
    if let Some(cov) = &mut p.covariance {
        for (i, row) in cov.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v *= w[i] * w[j];
            }
        }
    }
    p.modal = Some(crate::present::modal::pedestal(
        &p.pedestal.theta(),
        p.covariance.as_ref(),
    ));
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
    let why = if negative {
        "a damping comes out below zero, which a delay on the rel probes makes of a passive pedestal's"
    } else {
        "the data favour a delay (|τ̂| beyond 2 of its ±, two-sided)"
    };
    p.warnings.push(Warning {
        kind: WarningKind::DelayNotExcluded,
        message: format!(
            "the data do not exclude a sensor delay on its rel probes or (τ̂ < 0) its ped pick-ups (τ {:.0} ± {:.0} µs, linearised at τ = 0; {why}), which reads as a pedestal damping c − τ·(k − Ω²m): its ± count the delay as unknown, multiplied by √(1 + (ρ² − 1)·(1 + (τ̂/σ_τ)²)), ρ = σ(τ free)/σ(τ held) ({}); the values are the fit's",
            d.delay_us,
            d.delay_std_us,
            widened.join(", ")
        ),
    });
}

/// Under the table: one line per pedestal whose ± count a delay as unknown
/// (its [`WarningKind::DelayNotExcluded`] warning); empty when none.
pub fn describe(identification: &Identification) -> String {
    let mut out = String::new();
    for p in &identification.pedestals {
        for w in p
            .warnings
            .iter()
            .filter(|w| w.kind == WarningKind::DelayNotExcluded)
        {
            out.push_str(&format!("\n{}: {}\n", p.bearing, w.message));
        }
    }
    out
}
