//! The measurements as a diagnosis state corrects them: probe runout removed
//! from `rel`, sensor delays undone, a bearing table's clearance correction
//! added to the bearing coefficients K*, pedestal cross-coupling taken off
//! the bearing force, so that a base can be fitted to data the chosen
//! corrections explain.

use super::data::Prepared;
use super::foundation::FoundationFit;
use super::gap::Prediction;
use super::model::{Model, Nonlinear, Term};
use super::state::State;
use crate::estimate::base::BaseFitResult;
use crate::estimate::Observation;
use num_complex::Complex;

/// Whether every effect of `model` beyond the pedestal's own parameters is
/// a correction of the data (probe runout, sensor delay, a bearing table's
/// clearance): then a base can be fitted to the corrected data.
pub(super) fn corrections_only(model: &Model) -> bool {
    model.terms.iter().all(|t| {
        let split_mass = matches!(t, Term::Mass { dir: Some(_), .. });
        (t.is_pedestal() && !split_mass)
            || matches!(t, Term::Runout { .. } | Term::CrossStiffness { .. })
    }) && model
        .nonlinear
        .iter()
        .all(|p| !matches!(p, Nonlinear::LossFactor { .. }))
}

/// The measurements as `state` corrects them: runout removed from `rel`,
/// delays undone, a bearing table's clearance correction added to K*,
/// pedestal cross-coupling taken off the bearing force (on rigid ground).
pub fn corrected(prep: &Prepared, state: &State) -> Prepared {
    corrected_on(prep, state, None)
}

/// The measurements as `state` corrects them with the pedestals standing
/// on the bases of `base` (held): as [`corrected`], but the cross-coupling
/// of a pedestal on a base acts on its motion relative to the base
/// ([`cross_coupling_on_base`]).
pub fn corrected_on(prep: &Prepared, state: &State, base: Option<&FoundationFit>) -> Prepared {
    let mut out = prep.clone();
    let value = |t: Term| {
        state
            .model
            .terms
            .iter()
            .position(|u| *u == t)
            .map_or(0.0, |i| state.params.beta[i])
    };
    for (b, row) in out.points.iter_mut().enumerate() {
        let runout: [Complex<f64>; 2] = std::array::from_fn(|dir| {
            Complex::new(
                value(Term::Runout {
                    bearing: b,
                    dir,
                    imag: false,
                }),
                value(Term::Runout {
                    bearing: b,
                    dir,
                    imag: true,
                }),
            )
        });
        for p in row.iter_mut().flatten() {
            for (k, nl) in state.model.nonlinear.iter().enumerate() {
                let v = state.params.nl[k];
                match *nl {
                    Nonlinear::Delay { bearing, channels } if bearing == b => {
                        let f = Complex::from_polar(1.0, p.omega() * v);
                        for d in 0..2 {
                            if channels.ped[d] {
                                p.ped[d] *= f;
                            }
                            if channels.rel[d] {
                                p.rel[d] *= f;
                            }
                        }
                    }
                    Nonlinear::Clearance { bearing } | Nonlinear::StiffnessRatio { bearing }
                        if bearing == b =>
                    {
                        let corr = state
                            .model
                            .table_correction(nl)
                            .and_then(|t| t.correction(p.speed_hz, &p.kstar, v));
                        if let Some(corr) = corr {
                            for (k_row, c_row) in p.kstar.iter_mut().zip(corr) {
                                for (k, c) in k_row.iter_mut().zip(c_row) {
                                    *k += c;
                                }
                            }
                        }
                    }
                    _ => {}
                }
            }
            for (rel, r) in p.rel.iter_mut().zip(runout) {
                *rel -= r;
            }
        }
    }
    // Pedestal cross-coupling last: on a base it needs the base's motion,
    // i.e. the total force of the base's pedestals on the otherwise
    // corrected data (which the correction leaves unchanged).
    let k_yz: Vec<f64> = (0..out.points.len())
        .map(|b| value(Term::CrossStiffness { bearing: b }))
        .collect();
    if k_yz.iter().all(|&k| k == 0.0) {
        return out;
    }
    let on_base: Vec<Option<(Vec<usize>, usize, BaseFitResult)>> = (0..out.points.len())
        .map(|b| {
            let f = base?;
            f.grouping
                .groups
                .iter()
                .zip(&f.grouping.fits)
                .find_map(|(g, fit)| {
                    let i = g.iter().position(|&x| x == b)?;
                    Some((g.clone(), i, fit.clone()))
                })
        })
        .collect();
    for (b, &k) in k_yz.iter().enumerate() {
        if k == 0.0 {
            continue;
        }
        for j in 0..out.speeds_hz.len() {
            let moved = on_base[b]
                .as_ref()
                .and_then(|(g, i, fit)| cross_coupling_on_base(&out, j, g, *i, fit, k));
            let Some(p) = out.points[b][j].as_mut() else {
                continue;
            };
            match moved {
                Some((dped, df)) => {
                    for (x, dx) in p.ped.iter_mut().zip(dped) {
                        *x += dx;
                    }
                    add_force(p, df);
                }
                None => {
                    // Rigid ground: F' = F − k_yz·(X_z, X_y).
                    let df = [-p.ped[1] * k, -p.ped[0] * k];
                    add_force(p, df);
                }
            }
        }
    }
    out
}

/// A (y, z) pair of phasors.
type Pair = [Complex<f64>; 2];

/// Adds the force `df` [N] to the bearing force F = K*·rel of `p`,
/// carried into rel through K*⁻¹ (unchanged when K* is singular).
fn add_force(p: &mut Observation, df: [Complex<f64>; 2]) {
    let k = p.kstar;
    let det = k[0][0] * k[1][1] - k[0][1] * k[1][0];
    if det.norm() > 0.0 {
        p.rel[0] += (k[1][1] * df[0] - k[0][1] * df[1]) / det;
        p.rel[1] += (k[0][0] * df[1] - k[1][0] * df[0]) / det;
    }
}

/// The cross-coupling correction of pedestal `i` of base group `group`
/// (its fit `fit`, values held) at speed index `j`, with cross-stiffness
/// `k_yz` [N/m] acting, as the simulator's pedestal does, on the motion
/// relative to the base: −Ω²m·X + d·(X − X_B) + K_c·(X − X_B) = F,
/// K_c = [[0, k_yz], [k_yz, 0]], d = k + iΩc per direction. The base model
/// (`crate::estimate::base`) has no K_c, and the base moves with the total
/// force T = Σ (F_j + Ω²m_j·X_j) of its pedestals whatever their links, so
/// the correction must leave T unchanged: the pedestal motion moves by
/// δX = d⁻¹·K_c·(X − X_B) and the force by −Ω²m·δX. Then the corrected
/// data obey the base model exactly, and T and X_B = G·T are unchanged.
/// Returns (δX [m], δF [N]); `None` when a member of the group is not
/// measured at that speed or d is zero.
fn cross_coupling_on_base(
    prep: &Prepared,
    j: usize,
    group: &[usize],
    i: usize,
    fit: &BaseFitResult,
    k_yz: f64,
) -> Option<(Pair, Pair)> {
    let theta = fit.pedestals.get(i)?;
    let p = prep.points.get(group[i])?.get(j)?.as_ref()?;
    let w = p.omega();
    let w2 = w * w;
    let mut x_b = [Complex::new(0.0, 0.0); 2];
    for (q, &b) in group.iter().enumerate() {
        let o = prep.points.get(b)?.get(j)?.as_ref()?;
        let m = fit.pedestals.get(q)?[2];
        let f = o.force();
        for d in 0..2 {
            x_b[d] += f[d] + o.ped[d] * (w2 * m);
        }
    }
    for (d, x) in x_b.iter_mut().enumerate() {
        *x *= fit.base.receptance(d, w);
    }
    let mut dped = [Complex::new(0.0, 0.0); 2];
    for d in 0..2 {
        let spring = Complex::new(theta[d], w * theta[3 + d]);
        if spring.norm() == 0.0 {
            return None;
        }
        let other = 1 - d;
        dped[d] = (p.ped[other] - x_b[other]) * k_yz / spring;
    }
    let df = [dped[0] * (-w2 * theta[2]), dped[1] * (-w2 * theta[2])];
    Some((dped, df))
}

/// Whether the corrections of `state` mix the measured channels (a
/// pedestal cross-coupling: the corrected reading of one direction holds
/// the other direction's reading, the corrected force holds the pedestal
/// readings), so that the noise of the corrected data is no longer that of
/// the measured numbers ([`residual_noise`]). Runout (an offset), a delay
/// (a phase of unit modulus) and a table's clearance (K*) do not mix.
pub(super) fn mixes_channels(state: &State) -> bool {
    state
        .model
        .terms
        .iter()
        .zip(&state.params.beta)
        .any(|(t, &v)| matches!(t, Term::CrossStiffness { .. }) && v != 0.0)
}

/// Noise variance [m²] of each pedestal residual X̂ − X′ (y, z) per bearing
/// and speed index; `None` where there is no prediction.
pub(super) type ResidualNoise = Vec<Vec<Option<[f64; 2]>>>;

/// The noise variance of every pedestal residual X̂ − X′ of `predict` on
/// the data `state` corrects (with the bases of `base` held,
/// [`corrected_on`]), carried from every measured number it depends on.
/// The residual is linear in the measured phasors (each correction and
/// each prediction is), so moving one measured channel of one bearing by
/// its noise sd at every speed at once (speeds are independent) moves each
/// residual by its share: the variance is the sum of the squared moves over
/// the four channels (rel y, rel z, ped y, ped z) of every bearing. The
/// prediction's own variance ([`Prediction::noise_var`]) treats the
/// corrected numbers as measured ones; a cross-coupling correction mixes
/// the channels (δX = d⁻¹·K_c·(X − X_B), δF = −Ω²m·δX), and near a
/// pedestal's resonance the other direction's reading then dominates the
/// residual's noise. `None` when `predict` fails.
pub(super) fn residual_noise(
    prep: &Prepared,
    state: &State,
    base: Option<&FoundationFit>,
    predict: &dyn Fn(&Prepared) -> Option<Prediction>,
) -> Option<ResidualNoise> {
    type Residual = Vec<Vec<Option<[Complex<f64>; 2]>>>;
    let residual: &dyn Fn(&Prepared) -> Option<Residual> = &|data| {
        let c = corrected_on(data, state, base);
        let p = predict(&c)?;
        Some(
            c.points
                .iter()
                .zip(&p.ped)
                .map(|(row, pred)| {
                    row.iter()
                        .zip(pred)
                        .map(|(o, x)| {
                            let (o, x) = (o.as_ref()?, (*x)?);
                            Some([x[0] - o.ped[0], x[1] - o.ped[1]])
                        })
                        .collect()
                })
                .collect(),
        )
    };
    let r0 = residual(prep)?;
    let mut var: ResidualNoise = r0
        .iter()
        .map(|row| row.iter().map(|r| r.map(|_| [0.0; 2])).collect())
        .collect();
    for q in 0..prep.points.len() {
        for ch in 0..4 {
            let mut moved = prep.clone();
            for o in moved.points[q].iter_mut().flatten() {
                let sd = (o.var[2 * ch] + o.var[2 * ch + 1]).sqrt();
                if ch < 2 {
                    o.rel[ch] += sd;
                } else {
                    o.ped[ch - 2] += sd;
                }
            }
            let r1 = residual(&moved)?;
            for ((v_row, r0_row), r1_row) in var.iter_mut().zip(&r0).zip(&r1) {
                for ((v, a), b) in v_row.iter_mut().zip(r0_row).zip(r1_row) {
                    if let (Some(v), Some(a), Some(b)) = (v.as_mut(), a, b) {
                        for d in 0..2 {
                            v[d] += (b[d] - a[d]).norm_sqr();
                        }
                    }
                }
            }
        }
    }
    Some(var)
}

/// The corrected data `cprep` with each pedestal reading's noise variance
/// raised so that a fit weighting the corrected numbers as measured ones
/// sees each residual with the noise the corrections carry into it: the
/// residual's variance carried from the measured numbers (`carried`,
/// [`residual_noise`]) less the variance the prediction `own` takes from
/// the corrected numbers as if measured (its `noise_var`), where positive,
/// split evenly over the real and imaginary part (the corrected noise is
/// circular: each correction is complex-linear in the readings). The base's
/// own refit (`estimate::base`, errors in variables: each residual weighted
/// by the variance of the numbers in it) then weights the residual of every
/// pedestal reading by its carried noise at the prediction `own` was made
/// with. Not carried: the correlation the correction makes between the two
/// directions and between bearings (the fit's noise model has none).
pub(super) fn carrying_noise(
    cprep: &Prepared,
    own: &Prediction,
    carried: &ResidualNoise,
) -> Prepared {
    let mut out = cprep.clone();
    for (b, row) in out.points.iter_mut().enumerate() {
        for (j, p) in row.iter_mut().enumerate() {
            let (Some(p), Some(Some(v_own)), Some(Some(v))) = (
                p.as_mut(),
                own.noise_var.get(b).and_then(|r| r.get(j)),
                carried.get(b).and_then(|r| r.get(j)),
            ) else {
                continue;
            };
            for d in 0..2 {
                let extra = v[d] - v_own[d];
                if extra > 0.0 && extra.is_finite() {
                    p.var[4 + 2 * d] += 0.5 * extra;
                    p.var[5 + 2 * d] += 0.5 * extra;
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests;
