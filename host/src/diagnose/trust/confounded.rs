//! A shared base that a kept probe runout may have taken for itself: the
//! pedestal ± counting it as an unknown, or no trust.
//!
//! Above a base's modes the base moves as its mass under the bearing
//! forces: x_B ≈ −ΣF/(M·Ω²) per direction, F ∝ Ω² (unbalance), so a nearly
//! constant phasor; a probe runout r is a constant phasor in `rel`, i.e. a
//! force offset K*·r that changes as slowly as the bearing coefficients.
//! Over a band well above the base's modes the two are nearly collinear:
//! the runout takes what the base would, the rigid k, c, m absorb the
//! rest (a smooth k/(Ω²M) term of ~1 %), and the fit ends at the digits'
//! floor with pedestal ± that hold the base known to be absent
//! (unseen-four `base-runout-d3`, 3 digits, grid 225-346 Hz, frame modes
//! 34/40 Hz: runout named at B2, the 350 kg frame under B1 and B2 never,
//! final pedestals 3.3-7.5 ± off in 14 of 16 seeds, trusted;
//! docs/unseen.md "Session 43 (baserunout17)"). The nonlinear base fit
//! cannot tell this: refitted on the runout-corrected data it ends at
//! rigid ground, where the base's directions are "not detected" and its
//! profile does not move (docs/unseen.md, Session 44 (reliab17)).
//!
//! So the base is judged as a linear nuisance at rigid ground (Baarda's
//! external reliability): per direction d one compliance μ_d = 1/M_d, its
//! column in bearing b's force equation (k + iΩc)_b,d·ΣT_d/Ω² (the
//! reported pedestal's spring and damper, which the base moves at their far end, ΣT_d = Σ(k + iΩc)·ped what the
//! pedestals on the base put on it), beside every pedestal's k, c, m and the kept
//! runouts' four real numbers, each equation whitened by its own noise.
//! The design's inflation factor of a parameter, ρ = √(C_marg/C_cond) (its
//! variance with μ free over its variance with μ = 0), is what counting
//! the base as unknown does to its ±, whatever the noise's level. One rule:
//! the base is **excluded** when ρ ≤ [`EXCLUDED_WITHIN`] for the k_y, k_z
//! and m of every pedestal on it (the base's share of the variance at most the
//! pedestal's own: a base at its one-σ bound moves the value by at most one
//! σ). Where it is not, every such pedestal keeps its value and takes the
//! interval about it that holds the joint fit: √((ρ·σ)² + Δ²), Δ what
//! freeing μ changes in the value (one Gauss–Newton step from the reported
//! values with μ free less the same step with μ held at 0; the linearised
//! change overshot B2 on 1603/1604, so it widens, it does not move; every
//! parameter), and the verdict says so; where the design is
//! singular with μ free (the data bound neither), the diagnosis is
//! untrusted.

use super::Conclusion;
use crate::diagnose::data::Prepared;
use crate::diagnose::report::Pedestal;
use crate::estimate::Observation;
use nalgebra::DMatrix;
use num_complex::Complex;
use plinth_shared::regression::Parameter;

/// The inflation factor ρ above which the base is not excluded at a
/// pedestal [-]: √2, the base's share of the variance equal to the
/// pedestal's own.
pub const EXCLUDED_WITHIN: f64 = std::f64::consts::SQRT_2;

/// The values a pedestal is judged by (its k and m).
const JUDGED: [Parameter; 3] = [Parameter::Ky, Parameter::Kz, Parameter::M];

/// The largest number of bearings whose candidate bases are enumerated
/// (2^n subsets).
const MAX_ENUMERATED: usize = 12;

/// Every shared base a kept runout can take for itself: each set of at
/// least two of the `n` bearings (indices) that holds a bearing in `acted`
/// (where a kept runout acts), all `n` on one frame among them; sorted
/// sets, smaller first. Independent of the base model's trial: which
/// grouping that trial favoured says nothing once the runout has taken the
/// base's part. Empty when nothing acts or `n` is above [`MAX_ENUMERATED`].
pub fn candidate_bases(n: usize, acted: &[usize]) -> Vec<Vec<usize>> {
    if acted.is_empty() || n > MAX_ENUMERATED {
        return Vec::new();
    }
    let mut out: Vec<Vec<usize>> = (1u32..(1 << n))
        .map(|mask| (0..n).filter(|b| mask & (1 << b) != 0).collect::<Vec<_>>())
        .filter(|set| set.len() >= 2 && set.iter().any(|b| acted.contains(b)))
        .collect();
    out.sort_by(|a, b| a.len().cmp(&b.len()).then_with(|| a.cmp(b)));
    out
}

/// Column of a pedestal parameter within a bearing's block: k_y, k_z, m,
/// c_y, c_z (the order of [`Parameter::ALL`]).
fn column_of(q: Parameter) -> usize {
    Parameter::ALL.iter().position(|p| *p == q).unwrap_or(0)
}

/// The inflation factor ρ of every parameter (k_y, k_z, m, c_y, c_z, in
/// the order of [`Parameter::ALL`]), and its change in one Gauss–Newton
/// step of the joint fit from the reported values, of each of `bearings` (indices of
/// `prep`, whose reported pedestals `theta` give Ẑ) when a base under them
/// (one compliance per direction) is added to the rigid model with the
/// runouts of `runouts` (module docs); on the speeds where every one of
/// `bearings` has a reading. `None` when fewer than two bearings, no such
/// speed, or the design without the base is singular; a ρ of infinity
/// where the design with it is.
pub fn inflation(
    prep: &Prepared,
    bearings: &[usize],
    theta: &[[f64; 5]],
    runouts: &[(usize, [Complex<f64>; 2])],
) -> Option<Vec<Joint>> {
    if bearings.len() < 2 || theta.len() != bearings.len() {
        return None;
    }
    let with_runout: Vec<(usize, [Complex<f64>; 2])> = bearings
        .iter()
        .filter_map(|b| runouts.iter().find(|(r, _)| r == b).copied())
        .collect();
    let n_ped = 5 * bearings.len();
    let n_run = 4 * with_runout.len();
    let cols = n_ped + n_run + 2;
    let mut rows: Vec<Vec<f64>> = Vec::new();
    let mut rhs: Vec<f64> = Vec::new();
    for j in 0..prep.speeds_hz.len() {
        let at: Option<Vec<&Observation>> = bearings
            .iter()
            .map(|&b| prep.points.get(b)?.get(j)?.as_ref())
            .collect();
        let Some(at) = at else { continue };
        let omega = at[0].omega();
        let w2 = omega * omega;
        let force = |o: &Observation, d: usize| o.kstar[d][0] * o.rel[0] + o.kstar[d][1] * o.rel[1];
        for d in 0..2 {
            // What the pedestals' springs and dampers put on the base
            // (the bearing force less the pedestal's inertia).
            let spring = |i: usize| {
                let t = &theta[i];
                Complex::new(t[column_of(k_of(d))], omega * t[column_of(c_of(d))])
            };
            let total: Complex<f64> = at
                .iter()
                .enumerate()
                .map(|(i, o)| spring(i) * o.ped[d])
                .sum();
            for (i, o) in at.iter().enumerate() {
                let t = &theta[i];
                let (k, c) = (t[column_of(k_of(d))], t[column_of(c_of(d))]);
                let m = t[column_of(Parameter::M)];
                let z = Complex::new(k - w2 * m, omega * c);
                // The equation's noise: the pedestal's through Ẑ, the
                // probes' through K* (each real number's variance, the
                // mean of its two parts).
                let var_ped = 0.5 * (o.var[4 + 2 * d] + o.var[5 + 2 * d]);
                let var_rel: f64 = (0..2)
                    .map(|e| o.kstar[d][e].norm_sqr() * 0.5 * (o.var[2 * e] + o.var[2 * e + 1]))
                    .sum();
                let sd = (z.norm_sqr() * var_ped + var_rel).sqrt();
                if !(sd.is_finite() && sd > 0.0) {
                    continue;
                }
                let mut col = vec![Complex::new(0.0, 0.0); cols];
                let p = o.ped[d];
                col[5 * i + column_of(k_of(d))] = p;
                col[5 * i + column_of(Parameter::M)] = -w2 * p;
                col[5 * i + column_of(c_of(d))] = Complex::new(0.0, omega) * p;
                let mut e_now = z * p - force(o, d);
                if let Some(r) = with_runout.iter().position(|(b, _)| *b == bearings[i]) {
                    for e in 0..2 {
                        e_now += o.kstar[d][e] * with_runout[r].1[e];
                        col[n_ped + 4 * r + 2 * e] = o.kstar[d][e];
                        col[n_ped + 4 * r + 2 * e + 1] = Complex::new(0.0, 1.0) * o.kstar[d][e];
                    }
                }
                // The base moves the springs' far end: (k + iΩc)·x_B.
                col[n_ped + n_run + d] = Complex::new(k, omega * c) * total / w2;
                rows.push(col.iter().map(|v| v.re / sd).collect());
                rows.push(col.iter().map(|v| v.im / sd).collect());
                rhs.push(-e_now.re / sd);
                rhs.push(-e_now.im / sd);
            }
        }
    }
    if rows.len() <= cols {
        return None;
    }
    let j = DMatrix::from_fn(rows.len(), cols, |r, c| rows[r][c]);
    // Columns scaled to unit norm: the ratio of variances does not depend
    // on the scaling, the conditioning does.
    let norms: Vec<f64> = (0..cols).map(|c| j.column(c).norm()).collect();
    if norms.iter().any(|n| !(n.is_finite() && *n > 0.0)) {
        return None;
    }
    let js = DMatrix::from_fn(j.nrows(), cols, |r, c| j[(r, c)] / norms[c]);
    let info = js.transpose() * &js;
    let cond = info.view((0, 0), (cols - 2, cols - 2)).into_owned();
    let c_cond = cond.cholesky()?.inverse();
    let c_marg = info.clone().cholesky().map(|ch| ch.inverse());
    // What freeing μ changes in the values: one Gauss–Newton step from the
    // reported values with μ free less the same step with μ held at 0
    // (the part of the step that is this design's own re-weighting of the
    // rigid fit is not the base's).
    let b = nalgebra::DVector::from_vec(rhs);
    let jtb = js.transpose() * &b;
    let step: Vec<f64> = match &c_marg {
        Some(m) => {
            let full = m * &jtb;
            let held = &c_cond * jtb.rows(0, cols - 2);
            (0..cols)
                .map(|c| {
                    let held = if c < cols - 2 { held[c] } else { 0.0 };
                    (full[c] - held) / norms[c]
                })
                .collect()
        }
        None => vec![0.0; cols],
    };
    Some(
        (0..bearings.len())
            .map(|i| {
                let rho = std::array::from_fn(|q| {
                    let a = 5 * i + q;
                    match &c_marg {
                        Some(m) if m[(a, a)] > 0.0 && c_cond[(a, a)] > 0.0 => {
                            (m[(a, a)] / c_cond[(a, a)]).sqrt().max(1.0)
                        }
                        _ => f64::INFINITY,
                    }
                });
                (rho, std::array::from_fn(|q| step[5 * i + q]))
            })
            .collect(),
    )
}

/// A pedestal with the base free: the inflation factor ρ of each
/// parameter's ± and the change of its value [SI] (k_y, k_z, m, c_y, c_z).
pub type Joint = ([f64; 5], [f64; 5]);

/// The stiffness parameter of direction `d` (0 = y).
fn k_of(d: usize) -> Parameter {
    if d == 0 {
        Parameter::Ky
    } else {
        Parameter::Kz
    }
}

/// The damping parameter of direction `d` (0 = y).
fn c_of(d: usize) -> Parameter {
    if d == 0 {
        Parameter::Cy
    } else {
        Parameter::Cz
    }
}

/// What one candidate base does to the pedestals on it.
enum OnBase {
    /// The data exclude it at every pedestal on it (ρ ≤ [`EXCLUDED_WITHIN`]).
    Excluded,
    /// With its compliance free the design is singular at these bearings.
    Unbounded(Vec<usize>),
    /// Not excluded: each bearing's ± holding the joint fit [SI] (k_y,
    /// k_z, m, c_y, c_z) and its largest ρ over k_y, k_z, m.
    Widened(Vec<(usize, [f64; 5], f64)>),
}

/// The reported value and ± of a bearing's pedestal (k_y, k_z, m, c_y,
/// c_z) [SI]; `None` when not reported.
fn reported(prep: &Prepared, pedestals: &[Pedestal], b: usize) -> Option<([f64; 5], [f64; 5])> {
    let name = prep.bearings.get(b)?;
    let p = pedestals.iter().find(|p| &p.bearing == name)?;
    let mut t = [0.0; 5];
    let mut se = [0.0; 5];
    for (k, q) in Parameter::ALL.iter().enumerate() {
        t[k] = *p.values.get(q.name())?;
        se[k] = *p.std_err.get(q.name())?;
    }
    Some((t, se))
}

/// Judges one candidate base under `set` (module docs); `None` when the
/// design cannot be built (a pedestal not reported, no common speed).
fn judge_one(
    prep: &Prepared,
    pedestals: &[Pedestal],
    set: &[usize],
    runouts: &[(usize, [Complex<f64>; 2])],
) -> Option<OnBase> {
    let at: Vec<([f64; 5], [f64; 5])> = set
        .iter()
        .map(|&b| reported(prep, pedestals, b))
        .collect::<Option<_>>()?;
    let theta: Vec<[f64; 5]> = at.iter().map(|(t, _)| *t).collect();
    let joint = inflation(prep, set, &theta, runouts)?;
    let judged = |r: &[f64; 5]| JUDGED.map(|q| r[column_of(q)]);
    // The base is one unknown: excluded only where it is at every pedestal
    // on it; otherwise every pedestal on it takes the joint fit.
    if joint
        .iter()
        .all(|(r, _)| judged(r).iter().all(|v| *v <= EXCLUDED_WITHIN))
    {
        return Some(OnBase::Excluded);
    }
    let unbounded: Vec<usize> = set
        .iter()
        .zip(&joint)
        .filter(|(_, (r, _))| judged(r).iter().any(|v| !v.is_finite()))
        .map(|(b, _)| *b)
        .collect();
    if !unbounded.is_empty() {
        return Some(OnBase::Unbounded(unbounded));
    }
    Some(OnBase::Widened(
        set.iter()
            .zip(&joint)
            .zip(&at)
            .map(|((&b, (r, shift)), (_, se))| {
                let wide = std::array::from_fn(|q| (se[q] * r[q]).hypot(shift[q]));
                (b, wide, judged(r).iter().copied().fold(1.0, f64::max))
            })
            .collect(),
    ))
}

/// The names of bearings `set` (indices of `prep`) joined by `sep`.
fn names_of(prep: &Prepared, set: &[usize], sep: &str) -> String {
    set.iter()
        .filter_map(|&b| prep.bearings.get(b).map(String::as_str))
        .collect::<Vec<_>>()
        .join(sep)
}

/// Judges the reported `pedestals` with every base of `candidates` (sets
/// of bearing indices of `prep`, [`candidate_bases`]) as an unknown
/// nuisance beside the kept runouts `runouts` (bearing, runout (y, z) [m])
/// (module docs). A pedestal on a base that is not excluded takes the
/// widest ± over those bases (the interval holds the joint fit whichever
/// of them stands under it), and the verdict names them; where one makes
/// the design singular the diagnosis is untrusted. Nothing when every
/// candidate is excluded or cannot be built.
pub fn judge_confounded(
    conclusion: &mut Conclusion,
    pedestals: &mut [Pedestal],
    prep: &Prepared,
    candidates: &[Vec<usize>],
    runouts: &[(usize, [Complex<f64>; 2])],
) {
    let mut open: Vec<String> = Vec::new();
    let mut unbounded: Vec<usize> = Vec::new();
    let mut widest: Vec<(usize, [f64; 5], f64)> = Vec::new();
    for set in candidates {
        match judge_one(prep, pedestals, set, runouts) {
            None | Some(OnBase::Excluded) => continue,
            Some(OnBase::Unbounded(at)) => unbounded.extend(at),
            Some(OnBase::Widened(at)) => {
                for (b, se, rho) in at {
                    match widest.iter_mut().find(|(w, _, _)| *w == b) {
                        Some((_, w, r)) => {
                            for (w, s) in w.iter_mut().zip(se) {
                                *w = w.max(s);
                            }
                            *r = r.max(rho);
                        }
                        None => widest.push((b, se, rho)),
                    }
                }
            }
        }
        open.push(names_of(prep, set, "+"));
    }
    if open.is_empty() {
        return;
    }
    let bases = open.join(", ");
    unbounded.sort_unstable();
    unbounded.dedup();
    if !unbounded.is_empty() {
        let at = names_of(prep, &unbounded, ", ");
        conclusion.verdict += &format!(
            " But a shared base (under {bases}) is neither found nor excluded by these data, and with it unknown beside the kept `probe_runout` the data do not bound the pedestals of {at} (reasons below): the identified parameters are not to be trusted."
        );
        conclusion.reasons.push(format!(
            "a shared base (under {bases}) is neither found nor excluded: a runout takes its part above its modes, and with its compliance free the pedestals of {at} are not determined"
        ));
        conclusion.trusted = false;
        return;
    }
    widest.sort_by_key(|(b, _, _)| *b);
    let mut widened = Vec::new();
    for (b, se, rho) in &widest {
        let Some(name) = prep.bearings.get(*b) else {
            continue;
        };
        let Some(p) = pedestals.iter_mut().find(|p| &p.bearing == name) else {
            continue;
        };
        for (q, w) in Parameter::ALL.iter().zip(se) {
            if let Some(s) = p.std_err.get_mut(q.name()) {
                *s = s.max(*w);
            }
        }
        widened.push(format!("{name} (ρ up to {rho:.1})"));
    }
    conclusion.verdict += &format!(
        " A shared base (under {bases}) is neither found nor excluded by these data (the kept `probe_runout` can take its part above its modes): the ± of {} hold the joint fit with it unknown.",
        widened.join(", ")
    );
}

#[cfg(test)]
mod tests {
    use super::candidate_bases;

    /// Four bearings, a runout at the second: every set of two or more
    /// holding it (three pairs, three triples, all four), whatever a base
    /// trial favoured; none without it.
    #[test]
    fn every_shared_base_under_the_runout_bearing_is_a_candidate() {
        let c = candidate_bases(4, &[1]);
        assert_eq!(
            c,
            vec![
                vec![0, 1],
                vec![1, 2],
                vec![1, 3],
                vec![0, 1, 2],
                vec![0, 1, 3],
                vec![1, 2, 3],
                vec![0, 1, 2, 3],
            ]
        );
        assert!(candidate_bases(4, &[]).is_empty());
        assert!(candidate_bases(1, &[0]).is_empty());
        // Two runouts: a set holding either.
        assert_eq!(candidate_bases(3, &[0, 2]).len(), 4);
    }
}
