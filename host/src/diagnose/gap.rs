//! The disagreement between what a model predicts and what was measured.
//!
//! **The gap** (defined here, once, for the whole workflow): over every
//! channel c and speed j of the level in question,
//!
//! ```text
//! gap = sqrt( Σ_{c,j} |X_pred − X_meas|²  /  Σ_{c,j} |X_meas|² )
//! ```
//!
//! a relative RMS of complex 1X phasors (dimensionless; 0 = perfect).
//! At the pedestal level the channels are the pedestal responses (y, z of every
//! bearing) and X_pred is the response the model predicts from the measured
//! forces, X̂ = M⁻¹·(F − g) (for the paper's model X̂ = F/(k − Ω²m + iΩc) per
//! direction), with any modelled sensor delay applied so that it is comparable
//! with the reading. At the machine level (`--machine`) the channels are every
//! measured channel of the re-simulated machine.
//!
//! **Its noise floor**: the gap measurement noise alone would produce with a
//! perfect model. X̂ − X_meas is linear in the measured numbers, so its
//! expected square is Σ (∂/∂number)²·σ² over the rel numbers (through the
//! force) and the pedestal numbers; floor = sqrt(Σ E|δ|² / Σ |X_meas|²).

use super::data::Prepared;
use super::model::{predict, Model, Params};
use num_complex::Complex;

/// A model's pedestal-level prediction of every pedestal channel.
#[derive(Clone, Debug)]
pub struct Prediction {
    /// `ped[b][j]`: predicted pedestal reading (y, z) [m] of bearing `b` at
    /// speed index `j`; `None` where not measured or the model is singular.
    pub ped: Vec<Vec<Option<[Complex<f64>; 2]>>>,
    /// Expected |X_pred − X_meas|² [m²] from measurement noise alone, (y, z).
    pub noise_var: Vec<Vec<Option<[f64; 2]>>>,
    /// Number of measured speeds where the model could not predict (singular).
    pub singular: usize,
}

/// The gap and its noise floor.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Gap {
    /// Relative RMS disagreement (module docs) [-].
    pub gap: f64,
    /// The gap measurement noise alone would give [-].
    pub floor: f64,
}

/// A model's agreement with the measurements at the pedestal level on both
/// yardsticks: the gap (amplitude-weighted relative RMS, what the report
/// prints) and the noise-whitened χ² ([`Prediction::chi2`], the statistic
/// the fits weigh residuals by: each reading against its own noise).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Agreement {
    /// The gap and its noise floor [-].
    pub gap: Gap,
    /// Noise-whitened χ² of the prediction [-].
    pub chi2: f64,
    /// Real numbers the χ² sums (its degrees of freedom before the fitted
    /// parameters are counted) [-].
    pub n: usize,
}

impl Agreement {
    /// χ² per real number summed [-] (≈ 1 for a model that explains the
    /// data to their noise; +∞ when nothing is summed).
    pub fn chi2_per_number(&self) -> f64 {
        if self.n == 0 {
            f64::INFINITY
        } else {
            self.chi2 / self.n as f64
        }
    }
}

impl Prediction {
    /// Both yardsticks of this prediction over every pedestal reading of
    /// `prep` ([`Agreement`]).
    pub fn agreement(&self, prep: &Prepared) -> Agreement {
        let (chi2, n) = self.chi2(prep);
        Agreement {
            gap: self.gap(prep, None),
            chi2,
            n,
        }
    }

    /// Predicts every pedestal channel with `model` at `params`.
    pub fn new(prep: &Prepared, model: &Model, params: &Params) -> Self {
        let nb = prep.bearings.len();
        let ns = prep.speeds_hz.len();
        let mut ped = vec![vec![None; ns]; nb];
        let mut noise_var = vec![vec![None; ns]; nb];
        let mut singular = 0;
        for group in model.groups(nb) {
            for j in 0..ns {
                let measured = group
                    .iter()
                    .filter(|&&b| prep.points[b][j].is_some())
                    .count();
                if measured == 0 {
                    continue;
                }
                let assembled = model.assemble(prep, &group, j, &params.nl, Some(&params.beta));
                let Some(a) = assembled else {
                    // A coupled neighbour was not measured at this speed.
                    singular += measured;
                    continue;
                };
                let (Some(x), Some(m_inv)) =
                    (predict(&a), a.matrix.clone().and_then(|m| m.try_inverse()))
                else {
                    singular += measured;
                    continue;
                };
                for (pb, &b) in group.iter().enumerate() {
                    let Some(point) = prep.points[b][j].as_ref() else {
                        continue;
                    };
                    ped[b][j] = Some([x[2 * pb], x[2 * pb + 1]]);
                    let mut var = [0.0; 2];
                    for (d, v) in var.iter_mut().enumerate() {
                        let e = 2 * pb + d;
                        // Through the forces of every bearing in the group.
                        for (qb, &q) in group.iter().enumerate() {
                            let Some(pq) = prep.points[q][j].as_ref() else {
                                continue;
                            };
                            for dc in 0..2 {
                                let mut a_ec = Complex::new(0.0, 0.0);
                                for r in 0..2 {
                                    a_ec += m_inv[(e, 2 * qb + r)] * a.kstar[qb][r][dc];
                                }
                                a_ec = a_ec * a.rel_phase[2 * qb + dc] / a.ped_phase[e];
                                *v += a_ec.norm_sqr() * (pq.var[2 * dc] + pq.var[2 * dc + 1]);
                            }
                        }
                        *v += point.var[4 + 2 * d] + point.var[5 + 2 * d];
                    }
                    noise_var[b][j] = Some(var);
                }
            }
        }
        Self {
            ped,
            noise_var,
            singular,
        }
    }

    /// The pedestal-level residual whitened by its own noise, the one
    /// yardstick on which models of different kinds (library augmentations,
    /// bases) are compared: χ² = Σ 2·|X̂ − X_meas|²/E|X̂ − X_meas|² over every
    /// pedestal reading (y, z of every bearing and speed; a reading the
    /// model cannot predict counts whole, against the reading's own noise),
    /// and the number of real numbers it sums (2 per complex reading) [-].
    pub fn chi2(&self, prep: &Prepared) -> (f64, usize) {
        let (mut chi2, mut n) = (0.0, 0);
        for (b, row) in prep.points.iter().enumerate() {
            for (j, p) in row.iter().enumerate() {
                let Some(p) = p else { continue };
                for d in 0..2 {
                    n += 2;
                    let (miss, var) = match (self.ped[b][j], self.noise_var[b][j]) {
                        (Some(x), Some(v)) => ((x[d] - p.ped[d]).norm_sqr(), v[d]),
                        _ => (p.ped[d].norm_sqr(), p.var[4 + 2 * d] + p.var[5 + 2 * d]),
                    };
                    if var > 0.0 && var.is_finite() {
                        chi2 += 2.0 * miss / var;
                    } else if miss > 0.0 {
                        chi2 = f64::INFINITY;
                    }
                }
            }
        }
        (chi2, n)
    }

    /// The pedestal-level gap and its noise floor over all bearings, or over
    /// the bearings in `only` when given.
    pub fn gap(&self, prep: &Prepared, only: Option<&[usize]>) -> Gap {
        self.gap_over(prep, |b, _| only.is_none_or(|o| o.contains(&b)))
    }

    /// Whether the disagreement is more than `factor` times its noise floor
    /// anywhere: over the whole machine, or on any one pedestal channel
    /// (bearing, direction) against that channel's own floor. A model error
    /// at one pedestal (a sub-base under it) can hide in the pooled gap when
    /// another, noisier channel dominates the pool's floor.
    pub fn above_floor(&self, prep: &Prepared, factor: f64) -> bool {
        let over = |g: Gap| g.gap > factor * g.floor;
        over(self.gap(prep, None))
            || (0..prep.points.len())
                .any(|b| (0..2).any(|d| over(self.gap_over(prep, |q, e| q == b && e == d))))
    }

    /// The gap over the readings (bearing, direction) that `keep` selects.
    fn gap_over(&self, prep: &Prepared, keep: impl Fn(usize, usize) -> bool) -> Gap {
        let (mut num, mut den, mut noise) = (0.0, 0.0, 0.0);
        for (b, row) in prep.points.iter().enumerate() {
            for (j, p) in row.iter().enumerate() {
                let Some(p) = p else { continue };
                for d in 0..2 {
                    if !keep(b, d) {
                        continue;
                    }
                    den += p.ped[d].norm_sqr();
                    match (self.ped[b][j], self.noise_var[b][j]) {
                        (Some(x), Some(v)) => {
                            num += (x[d] - p.ped[d]).norm_sqr();
                            noise += v[d];
                        }
                        // No prediction: the whole reading is disagreement.
                        _ => num += p.ped[d].norm_sqr(),
                    }
                }
            }
        }
        if den == 0.0 {
            return Gap {
                gap: 0.0,
                floor: 0.0,
            };
        }
        Gap {
            gap: (num / den).sqrt(),
            floor: (noise / den).sqrt(),
        }
    }
}
