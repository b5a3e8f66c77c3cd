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

use super::Conclusion;
use crate::diagnose::data::Prepared;
use crate::diagnose::ml_final::GroupRefit;

/// Untrusts `conclusion` for every damping of `refits` held at zero
/// against the data ([`GroupRefit::held_against_data`]), one reason per
/// bearing.
pub fn judge_held(conclusion: &mut Conclusion, prep: &Prepared, refits: &[GroupRefit]) {
    for r in refits {
        for &b in &r.group {
            let at: Vec<_> = r
                .held_against_data
                .iter()
                .filter(|h| h.bearing == b)
                .collect();
            let (Some(first), Some(name)) = (at.first(), prep.bearings.get(b)) else {
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
}
