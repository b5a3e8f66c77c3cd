//! When a found scale is a unit mistake worth naming: its ± from the
//! machine-level fit, and the two conditions a named scale meets.
//!
//! The scale ŝ of a reading ([`super::Reading`]) is the least-squares fit of
//! one number, l = ln s, to the measured readings through the re-simulated
//! machine (the gap [`super::super::machine_gap`] is that sum of squares).
//! Linearised at l̂, with r(l) the re-simulated minus the measured readings
//! of hypothesis e^l (real numbers in [`super::super::gap::flat`]'s order)
//! and J = ∂r/∂l, l̂ − l = −Σ w_o·r_o with w = J / JᵀJ, so
//!
//! Var l̂ = Σ w_o²·σ_o² + Var(Σ w_o·X̂_o):
//!
//! the measurement noise of each real number (σ_o², the hypothesis's own
//! noise variances) and the identified parameters' own uncertainty carried
//! through the re-simulation ([`super::super::parameter_variance_of`],
//! the delta method the check's floor uses). Near a lightly damped
//! resonance the gap's valley in s is narrow, and the second term is what
//! keeps a pedestal moved by a fraction of its own ± from looking like a
//! precise scale (docs/robustness-hostile.md, "Session 41": unseen-train
//! clean-p2c 825, B3's `rel` × 1.007).
//!
//! A scale is named only when
//! 1. it is told from 1 by its ±: |l̂| > [`Z_EVIDENCE`]·sd(l̂), and
//! 2. it is one a field engineer can act on: farther from 1 than
//!    [`TOLERANCE`], the window within which [`super::nearest_common`] calls
//!    a factor a common unit factor. Within it a scale is a calibration
//!    matter (a vibration transducer's sensitivity is specified within
//!    about ±5 %, so a probe and a pick-up can disagree by up to 10 % with
//!    both in tolerance), not a unit mistake, and no common unit factor
//!    (the smallest is √2) lies within it.
//!
//! A scale not named leaves the diagnosis as the check found it (untrusted
//! with the machine-file reason when the final model fails): not naming
//! never trusts anything.

use super::super::{parameter_variance_of, resimulate, Readings};
use super::{hypothesis, Reading};
use crate::diagnose::data::Prepared;
use crate::diagnose::state::State;
use crate::sim::Machine;

/// How many of its ± a scale's ln must lie from 0 to be told from 1 [-]:
/// two-sided 0.27 % per reading under a normal ln ŝ; with at most 12
/// readings tried (every `rel`, every `ped`, each of five bearings' two)
/// at most 3.2 % per run whose final model already fails the check. The
/// same 3 ± the issue takes as "confidently wrong".
pub const Z_EVIDENCE: f64 = 3.0;

/// The window around 1 (and around each common unit factor, in
/// [`super::nearest_common`]) within which a factor counts as that value:
/// ×/÷ 1.1 [-].
pub const TOLERANCE: f64 = 1.1;

/// Step of ln s of the central difference of the residuals [-].
const H: f64 = 1.0e-3;

/// One hypothesis's misfit, real numbers in the order of
/// [`super::super::gap::flat`] (0 and 0 where a point is not measured).
struct Residuals {
    /// Re-simulated minus measured readings [m].
    r: Vec<f64>,
    /// The measured numbers' noise variances [m²].
    var: Vec<f64>,
    /// The hypothesis's re-simulated readings.
    readings: Readings,
    /// Its data.
    prep: Prepared,
    /// Its model.
    state: State,
}

/// [`Residuals`] of hypothesis `s` on `reading`.
fn residuals(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    reading: Reading,
    s: f64,
) -> Option<Residuals> {
    let (p, st) = hypothesis(prep, state, reading, s)?;
    let x: Readings = resimulate(machine, &p, &st, None).ok()?;
    let (mut r, mut var) = (Vec::new(), Vec::new());
    for (b, row) in x.iter().enumerate() {
        for (j, sim) in row.iter().enumerate() {
            let Some((rel, ped)) = sim else { continue };
            let obs = p.points.get(b).and_then(|r| r.get(j)).copied().flatten();
            let sims = rel.iter().chain(ped);
            match obs {
                Some(o) => {
                    let meas = o.rel.iter().chain(o.ped.iter());
                    for (z, m) in sims.zip(meas) {
                        r.push(z.re - m.re);
                        r.push(z.im - m.im);
                    }
                    var.extend_from_slice(&o.var);
                }
                None => {
                    r.extend([0.0; 8]);
                    var.extend([0.0; 8]);
                }
            }
        }
    }
    Some(Residuals {
        r,
        var,
        readings: x,
        prep: p,
        state: st,
    })
}

/// The standard deviation of ln ŝ [-] of the scale `s` found on
/// `reading` (module docs); infinite when the readings do not move with s
/// (the machine file cannot see the scale), `None` when a hypothesis
/// cannot be simulated.
pub fn log_sd(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    reading: Reading,
    s: f64,
) -> Option<f64> {
    let at = residuals(machine, prep, state, reading, s)?;
    let var = &at.var;
    let up = residuals(machine, prep, state, reading, s * H.exp())?.r;
    let down = residuals(machine, prep, state, reading, s * (-H).exp())?.r;
    if up.len() != var.len() || down.len() != var.len() {
        return None;
    }
    // Unmeasured points have zero residuals at every s: no weight.
    let j: Vec<f64> = up
        .iter()
        .zip(&down)
        .map(|(a, b)| (a - b) / (2.0 * H))
        .collect();
    let jtj: f64 = j.iter().map(|v| v * v).sum();
    if !(jtj.is_finite() && jtj > 0.0) {
        return Some(f64::INFINITY);
    }
    let w: Vec<f64> = j.iter().map(|v| v / jtj).collect();
    let noise: f64 = w.iter().zip(var).map(|(a, v)| a * a * v).sum();
    let params = parameter_variance_of(machine, &at.prep, &at.state, &at.readings, &w).ok()?;
    let sd = (noise + params).sqrt();
    Some(if sd.is_finite() { sd } else { f64::INFINITY })
}

/// Whether the scale `s` [-] with ln-standard-deviation `sd` [-] is named
/// (module docs: told from 1 by its ±, and beyond [`TOLERANCE`]).
pub fn named(s: f64, sd: f64) -> bool {
    let l = s.ln().abs();
    l > Z_EVIDENCE * sd && l > TOLERANCE.ln()
}

#[cfg(test)]
mod tests {
    use super::named;

    #[test]
    fn a_scale_is_named_only_when_told_from_one_and_beyond_the_tolerance() {
        assert!(named(2.0, 0.01));
        assert!(named(1.0 / 25.4, 0.05));
        assert!(!named(1.007, 0.0001), "within the 10 % tolerance");
        assert!(!named(1.3, 0.1), "ln 1.3 = 0.26 is within 3 sd");
        assert!(named(1.3, 0.05));
        assert!(!named(2.0, f64::INFINITY), "the file cannot see it");
    }
}
