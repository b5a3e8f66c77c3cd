//! The one-mass fits of a run linearised in one speed offset Δ shared by
//! every bearing ([`super`]'s module docs): per bearing its whitened
//! Jacobian in θ, the column of Δ and the residual ([`terms`]), then Δ̂ and
//! its ± from all bearings at once, each parameter's shift per Hz of Δ and
//! its ± with Δ held at zero ([`joint`]).

use crate::estimate::gauss_helmert::{self as gh, Equations};
use crate::estimate::lack_of_fit::delay_unknown::information_std_errs;
use crate::estimate::ml::{Rigid, Weighting};
use crate::estimate::{complex_stiffness, Observation};
use crate::rundir::BearingSchedule;
use nalgebra::{DMatrix, DVector};
use plinth_shared::phasor::omega_from_hz;
use plinth_shared::regression::{Parameter, PARAMETERS};

/// Half the central difference's step in speed [Hz] for the column of Δ:
/// well inside a bearing table's row spacing (its interpolation is linear
/// between rows, so within a segment the difference is the segment's slope
/// exactly), and the equations are quadratic in Ω (Ω²m, iΩc, iΩC_b), which
/// a central difference differentiates exactly.
pub const STEP_HZ: f64 = 0.01;

/// One bearing's fit linearised in Δ ([`terms`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Terms {
    /// Whitened Jacobian of the equations in the estimated parameters (4
    /// rows per speed: y re, y im, z re, z im) [whitened units per unit of
    /// each parameter].
    pub jac: DMatrix<f64>,
    /// Whitened derivative of the equations in Δ, the speed column minus
    /// the speed of the revolutions the vectors are made of [per Hz].
    pub column: DVector<f64>,
    /// Whitened residual at the fit [-].
    pub resid: DVector<f64>,
    /// Per estimated parameter, then Δ last: rᵀ·L⁻¹·∂B·V·Bᵀ·L⁻ᵀ·r summed
    /// over the speeds, the share of the weights' own change in the
    /// gradient of the fit's cost Σ eᵀ(B·V·Bᵀ)⁻¹e (B = ∂e/∂measured
    /// numbers, V their variances) [-]: the equations' derivative in the
    /// speed is made of the measured phasors, so its product with the
    /// residual has the mean tr(L⁻¹·∂B·V·Bᵀ·L⁻ᵀ) under the noise, and
    /// this term (whose mean is the same) takes it back.
    pub weight_terms: Vec<f64>,
    /// Σ over the speeds of tr(L⁻¹·∂B_Δ·V·∂B_Δᵀ·L⁻ᵀ): the noise's own
    /// share of the Δ column's squared norm [-], taken off its
    /// information.
    pub column_noise: f64,
    /// The speed column's value at each speed, in the rows' order (4 rows
    /// per speed) [Hz].
    pub speeds: Vec<f64>,
    /// `weight_terms` speed by speed (one row per speed, the columns as
    /// in `weight_terms`) [-]: what each speed adds.
    pub weight_by_speed: DMatrix<f64>,
    /// `column_noise` speed by speed [-].
    pub column_noise_by_speed: Vec<f64>,
}

/// `obs` (one bearing's observations, speeds as stamped) with every speed
/// moved by `shift` [Hz] and the bearing's complex stiffness read from
/// `schedule` there; an observation whose moved speed lies outside the
/// table stays where it is (`None` in its place).
pub fn moved(
    obs: &[Observation],
    schedule: &BearingSchedule,
    shift: f64,
) -> Vec<Option<Observation>> {
    obs.iter()
        .map(|o| {
            let f = o.speed_hz + shift;
            let c = schedule.at(f).ok()?;
            Some(Observation {
                speed_hz: f,
                kstar: complex_stiffness(&c, omega_from_hz(f)),
                ..*o
            })
        })
        .collect()
}

/// The one-mass fit of `obs` (one bearing on rigid ground, its variances
/// as given) at `theta` (SI) over the estimated `columns`, linearised in Δ:
/// the equations at the vectors' own speed f − Δ (f the speed column)
/// differ from those at f by −Δ·∂e/∂f, ∂e/∂f by a central difference of
/// ±[`STEP_HZ`] through the table's interpolation and the Ω of the
/// pedestal's and the bearing's terms (one-sided at the table's ends).
/// The weights are frozen at the stamped speeds. `None` where a whitening
/// or a figure cannot be formed.
pub fn terms(
    obs: &[Observation],
    schedule: &BearingSchedule,
    theta: &[f64; PARAMETERS],
    columns: &[Parameter],
) -> Option<Terms> {
    let n = obs.len();
    let p = columns.len();
    if n == 0 || p == 0 {
        return None;
    }
    let up = moved(obs, schedule, STEP_HZ);
    let down = moved(obs, schedule, -STEP_HZ);
    let mut span = Vec::with_capacity(n);
    let (mut plus, mut minus) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for (o, (u, d)) in obs.iter().zip(up.into_iter().zip(down)) {
        let h = STEP_HZ * (u.is_some() as u8 + d.is_some() as u8) as f64;
        if h == 0.0 {
            return None;
        }
        span.push(h);
        plus.push(u.unwrap_or(*o));
        minus.push(d.unwrap_or(*o));
    }
    let weighting = Weighting::default();
    let eq = Rigid::new(obs, &weighting);
    let eq_plus = Rigid::new(&plus, &weighting);
    let eq_minus = Rigid::new(&minus, &weighting);
    let mut jac = DMatrix::<f64>::zeros(4 * n, p);
    let mut column = DVector::<f64>::zeros(4 * n);
    let mut resid = DVector::<f64>::zeros(4 * n);
    let mut weight_by_speed = DMatrix::<f64>::zeros(n, p + 1);
    let mut column_noise_by_speed = vec![0.0; n];
    for (s, h) in span.iter().enumerate() {
        let l = gh::whitening(&eq, s, theta)?;
        let (e0, b) = eq.residual(s, theta);
        let var = eq.variance(s);
        if e0.len() != 4 || b.ncols() != var.len() {
            return None;
        }
        let r = l.solve_lower_triangular(&e0)?;
        // w = Σ⁻¹e; the weights' term of column c is (∂Bᵀw)ᵀ·V·(Bᵀw).
        let w = l.transpose().solve_upper_triangular(&r)?;
        let bw = b.transpose() * &w;
        let weight = |db: &DMatrix<f64>| {
            (db.transpose() * &w)
                .iter()
                .zip(bw.iter())
                .zip(var)
                .map(|((a, c), v)| a * v * c)
                .sum::<f64>()
        };
        resid.rows_mut(4 * s, 4).copy_from(&r);
        for (k, &c) in columns.iter().enumerate() {
            // e and B are linear in θ: a unit step gives the columns exactly.
            let mut t = *theta;
            t[c as usize] += 1.0;
            let (e1, b1) = eq.residual(s, &t);
            let col = l.solve_lower_triangular(&(e1 - &e0))?;
            jac.view_mut((4 * s, k), (4, 1)).copy_from(&col);
            weight_by_speed[(s, k)] = weight(&(b1 - &b));
        }
        // ∂e/∂Δ = −∂e/∂f, and ∂B/∂Δ likewise.
        let (e_minus, b_minus) = eq_minus.residual(s, theta);
        let (e_plus, b_plus) = eq_plus.residual(s, theta);
        let de = (e_minus - e_plus) / *h;
        let db = (b_minus - b_plus) / *h;
        column
            .rows_mut(4 * s, 4)
            .copy_from(&l.solve_lower_triangular(&de)?);
        weight_by_speed[(s, p)] = weight(&db);
        let ldb = l.solve_lower_triangular(&db)?;
        column_noise_by_speed[s] = ldb
            .column_iter()
            .zip(var)
            .map(|(c, v)| c.norm_squared() * v)
            .sum::<f64>();
    }
    let weight_terms: Vec<f64> = weight_by_speed.row_sum().iter().copied().collect();
    let column_noise = column_noise_by_speed.iter().sum::<f64>();
    let finite = jac
        .iter()
        .chain(column.iter())
        .chain(resid.iter())
        .chain(weight_by_speed.iter())
        .all(|v| v.is_finite())
        && column_noise.is_finite();
    finite.then_some(Terms {
        jac,
        column,
        resid,
        weight_terms,
        column_noise,
        speeds: obs.iter().map(|o| o.speed_hz).collect(),
        weight_by_speed,
        column_noise_by_speed,
    })
}

/// What one bearing's fit says of Δ ([`joint`]).
#[derive(Clone, Debug, PartialEq)]
pub struct BearingShare {
    /// Per estimated parameter (the Jacobian's columns in order): b, the
    /// shift of its Δ-held estimate per Hz of Δ (the Δ-free fit has it at
    /// held + b·Δ; b = −X⁺t) [its unit per Hz].
    pub path: Vec<f64>,
    /// Per estimated parameter: its ± with Δ held at zero, from the
    /// information times the fit's excess √(χ²/dof) where above 1 [its
    /// unit].
    pub held: Vec<f64>,
}

/// Δ from every bearing's [`Terms`] at once ([`joint`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// Δ̂, one Gauss–Newton step from Δ = 0 [Hz].
    pub offset_hz: f64,
    /// Its ± [Hz].
    pub offset_std_hz: f64,
    /// Per bearing, in the order given.
    pub bearings: Vec<BearingShare>,
    /// Every bearing's speeds, what each pulls on Δ and its information
    /// (each bearing's scaled by its excess s²): Δ̂ is their pulls' sum
    /// over their informations' sum ([`super::spread`]).
    pub by_speed: Vec<super::spread::SpeedShare>,
}

/// One bearing's share of the joint step: its Δ column with the θ columns
/// projected out (t̃), its residual likewise (r̃), b = −X⁺t and the ± of
/// θ from the information (not yet scaled).
struct Projected {
    column: DVector<f64>,
    resid: DVector<f64>,
    /// The efficient score of Δ at Δ = 0 (half the cost's gradient, θ's
    /// share projected out) [-].
    score: f64,
    /// Δ's information with θ free, the noise's share taken off [-].
    info: f64,
    path: Vec<f64>,
    info_std: Vec<f64>,
    dof: f64,
    /// `score`, `info` and the score's variance |t̃ₛ|² speed by speed, in
    /// the order of `Terms::speeds` (the first two sum to `score` and
    /// `info`) [-].
    by_speed: Vec<(f64, f64, f64)>,
}

fn project(t: &Terms) -> Option<Projected> {
    let (rows, p) = t.jac.shape();
    let dof = rows.checked_sub(p + 1).filter(|&d| d > 0)? as f64;
    // Columns scaled to unit norm (their units differ by many orders).
    let norms: Vec<f64> = t.jac.column_iter().map(|c| c.norm()).collect();
    if !norms.iter().all(|v| v.is_finite() && *v > 0.0) {
        return None;
    }
    let mut scaled = t.jac.clone();
    for (mut c, s) in scaled.column_iter_mut().zip(&norms) {
        c /= *s;
    }
    let svd = scaled.clone().svd(true, true);
    let x_t = svd.solve(&t.column, 1e-14).ok()?;
    let x_r = svd.solve(&t.resid, 1e-14).ok()?;
    let column = &t.column - &scaled * &x_t;
    let resid = &t.resid - &scaled * &x_r;
    let path: Vec<f64> = x_t.iter().zip(&norms).map(|(v, s)| -v / s).collect();
    let info_std = information_std_errs(&t.jac)?;
    // Half the gradient of the cost in each θ and in Δ (the weights moving
    // with them); the efficient score g_Δ − t_ΔᵀX(XᵀX)⁻¹g_θ = g_Δ + bᵀg_θ.
    let p_theta = t.jac.ncols();
    let g = |col: DVector<f64>, k: usize| col.dot(&t.resid) - t.weight_terms[k];
    let g_delta = g(t.column.clone(), p_theta);
    let score = g_delta
        + (0..p_theta)
            .map(|k| path[k] * g(t.jac.column(k).into_owned(), k))
            .sum::<f64>();
    let info = column.norm_squared() - t.column_noise;
    // Speed by speed: t̃ₛ·rₛ less the weights' share along the same
    // projection (t̃ = t + X·b), and |t̃ₛ|² less the noise's share.
    let by_speed = (0..t.speeds.len())
        .map(|s| {
            let rows = 4 * s..4 * s + 4;
            let tt = column.rows(rows.start, 4);
            let w = t.weight_by_speed[(s, p_theta)]
                + (0..p_theta)
                    .map(|k| path[k] * t.weight_by_speed[(s, k)])
                    .sum::<f64>();
            (
                tt.dot(&t.resid.rows(rows.start, 4)) - w,
                tt.norm_squared() - t.column_noise_by_speed[s],
                tt.norm_squared(),
            )
        })
        .collect();
    Some(Projected {
        column,
        resid,
        score,
        info,
        path,
        info_std,
        dof,
        by_speed,
    })
}

/// Δ shared by every bearing of `terms` (each bearing's θ its own): the
/// Gauss–Newton step from Δ = 0 of the stacked equations, Δ̂ = Σ t̃ᵀ(−r̃)/s²
/// over Σ t̃ᵀt̃/s² and σ_Δ = (Σ t̃ᵀt̃/s²)^(−1/2), t̃ and r̃ each bearing's Δ
/// column and residual with its own θ columns projected out (the Schur
/// complement: θ free per bearing), s² each bearing's excess
/// max(1, χ²/dof) from its residual after the step (as the delay's ±,
/// [`crate::estimate::lack_of_fit::delay_unknown::linearise`]: the residual
/// at Δ = 0 carries Δ's own signature where there is one; s² at Δ = 0
/// first, then once more after the step). `None` with no bearing or
/// where a figure is not finite.
pub fn joint(terms: &[Terms]) -> Option<Joint> {
    let projected: Vec<Projected> = terms.iter().map(project).collect::<Option<_>>()?;
    if projected.is_empty() {
        return None;
    }
    let step = |scale: &[f64]| {
        let (mut info, mut score) = (0.0, 0.0);
        for (q, s2) in projected.iter().zip(scale) {
            info += q.info / s2;
            score -= q.score / s2;
        }
        (score / info, info)
    };
    let mut scale: Vec<f64> = projected
        .iter()
        .map(|q| (q.resid.norm_squared() / q.dof).max(1.0))
        .collect();
    let (first, _) = step(&scale);
    scale = projected
        .iter()
        .map(|q| ((&q.resid + &q.column * first).norm_squared() / q.dof).max(1.0))
        .collect();
    let (offset_hz, info) = step(&scale);
    let offset_std_hz = info.sqrt().recip();
    let bearings = projected
        .iter()
        .zip(&scale)
        .map(|(q, s2)| BearingShare {
            path: q.path.clone(),
            held: q.info_std.iter().map(|v| v * s2.sqrt()).collect(),
        })
        .collect();
    let by_speed = projected
        .iter()
        .zip(&scale)
        .zip(terms)
        .flat_map(|((q, s2), t)| {
            q.by_speed
                .iter()
                .zip(&t.speeds)
                .map(
                    move |(&(score, info, var), &speed_hz)| super::spread::SpeedShare {
                        speed_hz,
                        pull: -score / s2,
                        info: info / s2,
                        var: var / s2,
                    },
                )
        })
        .collect();
    let finite = info > 0.0 && offset_hz.is_finite() && offset_std_hz.is_finite();
    finite.then_some(Joint {
        offset_hz,
        offset_std_hz,
        bearings,
        by_speed,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two "bearings", each a straight line a + b·x in its own (a, b) plus
    /// a shared offset Δ entering as c·Δ: the joint step recovers Δ and
    /// its information sums the bearings' projected columns.
    #[test]
    fn a_shared_offset_from_two_bearings() {
        let make = |x: &[f64], c: &[f64], delta: f64, a: f64| {
            let n = x.len();
            let jac = DMatrix::from_fn(n, 2, |r, k| if k == 0 { 1.0 } else { x[r] });
            let column = DVector::from_column_slice(c);
            // Data a + Δ·c (b = 0): at the fit (a, 0) with Δ held the
            // residual is −Δ·c projected off the line.
            let y = DVector::from_fn(n, |r, _| a + delta * c[r]);
            let fit = jac.clone().svd(true, true).solve(&y, 1e-14).expect("fit");
            let resid = &jac * fit - y;
            Terms {
                jac,
                column,
                resid,
                weight_terms: vec![0.0; 3],
                column_noise: 0.0,
                speeds: Vec::new(),
                weight_by_speed: DMatrix::zeros(0, 3),
                column_noise_by_speed: Vec::new(),
            }
        };
        let x = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let c1: Vec<f64> = x.iter().map(|v| v * v).collect();
        let c2: Vec<f64> = x.iter().map(|v| (v * 0.7).sin()).collect();
        let j = joint(&[make(&x, &c1, 0.3, 1.0), make(&x, &c2, 0.3, 2.0)]).expect("joint");
        assert!((j.offset_hz - 0.3).abs() < 1e-9, "{}", j.offset_hz);
        // Exact data: s² = 1, σ_Δ from the projected columns alone.
        let proj = |c: &[f64]| {
            let t = make(&x, c, 0.0, 0.0);
            project(&t).expect("p").column.norm_squared()
        };
        let want = (proj(&c1) + proj(&c2)).sqrt().recip();
        assert!((j.offset_std_hz - want).abs() < 1e-12 * want);
        // b = −X⁺t: the line fitted to x² over 0..6 has slope 6.
        assert!(
            (j.bearings[0].path[1] + 6.0).abs() < 1e-9,
            "{:?}",
            j.bearings[0].path
        );
    }
}
