//! Speeds the base model's robust fit down-weights (`plinth identify`'s
//! `outlier_speeds_hz`) in the search for missing effects.
//!
//! An outlier speed is a reading the robust fit of the BASE model
//! down-weights: one speed whose residual the rest of the data do not
//! share. A missing effect could explain it (a sub-base's resonance is
//! sharp too), so it is not dropped for good, but no effect may rest on
//! it: the search runs on the data without the listed speeds (an effect
//! must be significant without them), and each left-out reading is then
//! tested under the model the search chose ([`explained`]). A reading the
//! chosen effects explain (its whitened residual within the noise) is put
//! back and the search run again with it; one that stays an outlier under
//! the chosen model is left out and listed (`Diagnosis::outlier_speeds_hz`).
//! With no effect chosen the model is the base model under which the robust
//! fit listed them, and they stay out.

use super::bases::rigid_prediction;
use super::correct::corrected_on;
use super::criterion::chi2_sf;
use super::data::Prepared;
use super::gap::Prediction;
use super::workflow::{Options, Outcome};

/// Real numbers of one bearing's pedestal reading at one speed (y and z,
/// real and imaginary parts): the degrees of freedom of its χ² [-].
const DOF: usize = 4;

/// The whitened χ² (`DOF` degrees of freedom) of every listed reading
/// (`listed[b]`: speeds [Hz] of bearing `b` of `all`) under the final model
/// of `out`, predicted on `all` (the data with those readings); `None` for a
/// reading the model cannot predict there.
pub fn chi2_of_listed(
    all: &Prepared,
    out: &Outcome,
    opts: &Options,
    listed: &[Vec<f64>],
) -> Vec<Vec<(f64, Option<f64>)>> {
    let state = out.states.last();
    let predicted: Option<(Prediction, Prepared)> = match (&out.foundation, state) {
        (_, None) => None,
        (Some(f), Some(s)) => {
            let cprep = corrected_on(all, s, Some(f));
            let rigid = rigid_prediction(&cprep, s, &opts.base);
            f.predict_on(&cprep, &rigid).map(|p| (p, cprep))
        }
        (None, Some(s)) => Some((Prediction::new(all, &s.model, &s.params), all.clone())),
    };
    listed
        .iter()
        .enumerate()
        .map(|(b, speeds)| {
            speeds
                .iter()
                .map(|&hz| {
                    let chi2 = predicted.as_ref().and_then(|(pred, data)| {
                        let j = data.speeds_hz.iter().position(|&s| s == hz)?;
                        let point = data.points.get(b)?.get(j)?.as_ref()?;
                        let x = pred.ped.get(b)?.get(j).copied().flatten()?;
                        let v = pred.noise_var.get(b)?.get(j).copied().flatten()?;
                        let chi2: f64 = (0..2)
                            .map(|d| 2.0 * (x[d] - point.ped[d]).norm_sqr() / v[d])
                            .sum();
                        chi2.is_finite().then_some(chi2)
                    });
                    (hz, chi2)
                })
                .collect()
        })
        .collect()
}

/// Per bearing of `all`, the listed speeds [Hz] the final model of `out`
/// explains: the reading's whitened residual (χ², [`DOF`] degrees of
/// freedom) not significant at `opts.alpha`, Bonferroni over the readings
/// listed. Empty when the search chose no effect (its model is the base
/// model the speeds were listed under) or the bearings of `all` and of the
/// search's data differ.
pub fn explained(
    all: &Prepared,
    out: &Outcome,
    opts: &Options,
    listed: &[Vec<f64>],
) -> Vec<Vec<f64>> {
    let none = vec![Vec::new(); listed.len()];
    if out.diagnosis.effects_added.is_empty() || out.prep.bearings != all.bearings {
        return none;
    }
    let n: usize = listed.iter().map(Vec::len).sum();
    let level = opts.alpha / n.max(1) as f64;
    chi2_of_listed(all, out, opts, listed)
        .into_iter()
        .map(|row| {
            row.into_iter()
                .filter(|(_, chi2)| chi2.is_some_and(|c| chi2_sf(c, DOF) >= level))
                .map(|(hz, _)| hz)
                .collect()
        })
        .collect()
}

/// `listed` without `explained`, bearing by bearing.
pub fn still_out(listed: &[Vec<f64>], explained: &[Vec<f64>]) -> Vec<Vec<f64>> {
    listed
        .iter()
        .enumerate()
        .map(|(b, speeds)| {
            speeds
                .iter()
                .copied()
                .filter(|s| explained.get(b).is_none_or(|e| !e.contains(s)))
                .collect()
        })
        .collect()
}
