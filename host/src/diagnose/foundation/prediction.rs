//! A chosen base's pedestal-level prediction: the bases' motion
//! (`crate::estimate::base::predict`) where the pedestals stand on them, the
//! rigid model elsewhere, with or without the noise variance of each
//! prediction.

use super::{observations, FoundationFit, GroupingFit};
use crate::diagnose::data::Prepared;
use crate::diagnose::gap::Prediction;
use crate::estimate::base::{predict, BaseGroup};
use crate::estimate::Observation;
use anyhow::{anyhow, Result};
use num_complex::Complex;

/// The pedestal-level prediction with the bases of `grouping`: the rigid
/// prediction for bearings on no base, `estimate::base::predict` for the
/// others, with the noise variance of each prediction from its (linear)
/// dependence on every rel reading of the base's pedestals.
pub(super) fn prediction(
    prep: &Prepared,
    obs: &[Vec<Observation>],
    rigid: &Prediction,
    grouping: &GroupingFit,
) -> Result<Prediction> {
    predicted(prep, obs, rigid.clone(), grouping, true)
}

/// [`prediction`] from `out` (the rigid prediction, or blank where every
/// bearing stands on a base), with each prediction's noise variance when
/// `with_noise` (else `noise_var` is `None` on the bases' bearings).
fn predicted(
    prep: &Prepared,
    obs: &[Vec<Observation>],
    mut out: Prediction,
    grouping: &GroupingFit,
    with_noise: bool,
) -> Result<Prediction> {
    for (group, fit) in grouping.groups.iter().zip(&grouping.fits) {
        let g = BaseGroup {
            bearings: group.clone(),
        };
        let base_pred = predict(obs, &g, &fit.pedestals, &fit.base)
            .map_err(|e| anyhow!("predicting with the base: {e}"))?;
        if !with_noise {
            for pr in &base_pred {
                let Some(j) = speed_index(prep, pr.speed_hz) else {
                    continue;
                };
                for (i, &b) in group.iter().enumerate() {
                    if prep.points[b][j].is_some() {
                        out.ped[b][j] = Some(pr.ped[i]);
                        out.noise_var[b][j] = None;
                    }
                }
            }
            continue;
        }
        // Sensitivity to each rel channel: the prediction is linear in the
        // forces, so a unit change of one rel phasor shows it exactly.
        let mut sens = Vec::new();
        for (qi, &q) in group.iter().enumerate() {
            for c in 0..2 {
                let mut o2 = obs.to_vec();
                for o in &mut o2[q] {
                    o.rel[c] += Complex::new(1.0, 0.0);
                }
                let p2 = predict(&o2, &g, &fit.pedestals, &fit.base)
                    .map_err(|e| anyhow!("predicting with the base: {e}"))?;
                sens.push((qi, q, c, p2));
            }
        }
        for (s, pr) in base_pred.iter().enumerate() {
            let (speed, x) = (&pr.speed_hz, &pr.ped);
            let Some(j) = speed_index(prep, *speed) else {
                continue;
            };
            for (i, &b) in group.iter().enumerate() {
                let Some(point) = prep.points[b][j].as_ref() else {
                    continue;
                };
                out.ped[b][j] = Some(x[i]);
                let mut var = [0.0; 2];
                for (d, v) in var.iter_mut().enumerate() {
                    for (_, q, c, p2) in &sens {
                        let Some(pq) = prep.points[*q][j].as_ref() else {
                            continue;
                        };
                        let a = p2[s].ped[i][d] - x[i][d];
                        *v += a.norm_sqr() * (pq.var[2 * c] + pq.var[2 * c + 1]);
                    }
                    *v += point.var[4 + 2 * d] + point.var[5 + 2 * d];
                }
                out.noise_var[b][j] = Some(var);
            }
        }
    }
    Ok(out)
}

/// Index of `speed` [Hz] in `prep`'s speeds: it comes back through
/// Ω = 2πf, so it is matched to a relative 1e-9, not exactly.
fn speed_index(prep: &Prepared, speed: f64) -> Option<usize> {
    prep.speeds_hz
        .iter()
        .position(|v| (v - speed).abs() <= 1e-9 * v.abs().max(speed.abs()))
}

impl FoundationFit {
    /// This fit's bases, their values held, predicting the pedestal motion
    /// alone on other data `prep` (`noise_var` `None` on the bases'
    /// bearings): for a caller that carries the noise itself
    /// (`correct::residual_noise`, which needs only the motion, at
    /// 4·bearings + 1 predictions per χ²). `rigid` (the rigid-ground
    /// prediction) is called only when a measured bearing stands on no
    /// base. The motion is that of [`FoundationFit::predict_on`].
    pub fn motion_on(
        &self,
        prep: &Prepared,
        rigid: &dyn Fn(&Prepared) -> Prediction,
    ) -> Option<Prediction> {
        // The rigid prediction is needed where the bases predict nothing: a
        // bearing on no base, or a speed not every member of its base has.
        let on_base = |b: usize| self.grouping.groups.iter().any(|g| g.contains(&b));
        let covered = (0..prep.points.len())
            .all(|b| on_base(b) || prep.points[b].iter().all(Option::is_none))
            && self.grouping.groups.iter().all(|g| {
                (0..prep.speeds_hz.len()).all(|j| {
                    let measured = |b: &usize| prep.points[*b][j].is_some();
                    g.iter().all(measured) || !g.iter().any(measured)
                })
            });
        let out = if covered {
            let blank = vec![vec![None; prep.speeds_hz.len()]; prep.points.len()];
            Prediction {
                ped: blank.clone(),
                noise_var: blank.iter().map(|r| vec![None; r.len()]).collect(),
                singular: 0,
            }
        } else {
            rigid(prep)
        };
        let obs = observations(prep);
        predicted(prep, &obs, out, &self.grouping, false).ok()
    }

    /// This fit's bases, their values held, predicting the pedestals on
    /// other data `prep` (the data a correction changes), with `rigid` the
    /// rigid-ground prediction of bearings on no base; `None` when the
    /// prediction fails.
    pub fn predict_on(&self, prep: &Prepared, rigid: &Prediction) -> Option<Prediction> {
        let obs = observations(prep);
        prediction(prep, &obs, rigid, &self.grouping).ok()
    }
}
