//! The unmeasured-base equations of a group, X_B eliminated (module docs of
//! [`crate::estimate::base`]): each speed's errors and their Jacobian for
//! the errors-in-variables fit, and the speeds every member shares.

use crate::estimate::base::{put, spring, BaseFitError, BaseGroup, C};
use crate::estimate::gauss_helmert::Equations;
use crate::estimate::Observation;
use nalgebra::{DMatrix, DVector};

/// One speed of a group: the observation of each group member.
pub(super) struct Speed {
    /// Rotor speed [rad/s].
    pub(super) omega: f64,
    /// Each member's observation (group order).
    pub(super) obs: Vec<Observation>,
    /// Each member's bearing force F = K*·rel [N].
    force: Vec<[C; 2]>,
    var: Vec<f64>,
}

impl Speed {
    /// The base in direction `d` at parameters `p`: its receptance
    /// G = κ/(1 − Ω²μ + iΩγ) [m/N] and T = Σ_j (F_j + Ω²m_j·X_j) [N], the
    /// force the group's pedestals put into it.
    fn base_terms(&self, p: &[f64], d: usize) -> (C, C) {
        let n = self.obs.len();
        let w = self.omega;
        let w2 = w * w;
        let q = &p[base_at(n, d)..base_at(n, d) + 3];
        let g = C::new(q[0], 0.0) / C::new(1.0 - w2 * q[1], w * q[2]);
        let t: C = self
            .obs
            .iter()
            .enumerate()
            .map(|(j, o)| self.force[j][d] + w2 * p[5 * j + 2] * o.ped[d])
            .sum();
        (g, t)
    }

    /// The errors of every member's equations at `p` [N] (4 per member:
    /// y re, y im, z re, z im), calling `each(i, d, d_i, h_i, G)` for member
    /// i's equation in direction d on the way (the Jacobian's rows).
    fn errors(&self, p: &[f64], mut each: impl FnMut(usize, usize, C, C, C)) -> DVector<f64> {
        let n = self.obs.len();
        let mut e = DVector::zeros(4 * n);
        for d in 0..2 {
            let (g, t) = self.base_terms(p, d);
            for i in 0..n {
                let (di, h, r) = self.member_error(p, i, d, (g, t));
                e[4 * i + 2 * d] = r.re;
                e[4 * i + 2 * d + 1] = r.im;
                each(i, d, di, h, g);
            }
        }
        e
    }

    /// Member `i`'s equation in direction `d` given the base's (G, T) of
    /// [`Speed::base_terms`]: its spring d_i [N/m], h_i = d_i − Ω²m_i [N/m]
    /// and the error h_i·X_i − F_i − d_i·G·T [N].
    fn member_error(&self, p: &[f64], i: usize, d: usize, (g, t): (C, C)) -> (C, C, C) {
        let w = self.omega;
        let th = &p[5 * i..5 * i + 5];
        let di = spring(th, d, w);
        let h = di - w * w * th[2];
        (
            di,
            h,
            h * self.obs[i].ped[d] - self.force[i][d] - di * g * t,
        )
    }
}

/// The unmeasured-base equations of a group (module docs); parameters
/// p = (θ of each member, then (κ, μ, γ) for y, then for z).
pub(super) struct Unmeasured {
    /// The speeds every member has, in increasing speed.
    pub(super) speeds: Vec<Speed>,
}

/// Offset of the base parameters of direction `d` in p for `n` pedestals.
pub(super) fn base_at(n: usize, d: usize) -> usize {
    5 * n + 3 * d
}

impl Equations for Unmeasured {
    fn speeds(&self) -> usize {
        self.speeds.len()
    }

    fn variance(&self, s: usize) -> &[f64] {
        &self.speeds[s].var
    }

    fn error(&self, s: usize, p: &[f64]) -> DVector<f64> {
        self.speeds[s].errors(p, |_, _, _, _, _| {})
    }

    fn residual(&self, s: usize, p: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
        let sp = &self.speeds[s];
        let n = sp.obs.len();
        let w = sp.omega;
        let w2 = w * w;
        let mut b = DMatrix::zeros(4 * n, 8 * n);
        let e = sp.errors(p, |i, d, di, h, g| {
            for (j, oj) in sp.obs.iter().enumerate() {
                let coupling = -di * g;
                // ∂e_i/∂X_j and ∂e_i/∂rel_j (through F_j = K*_j·rel_j).
                let dx = coupling * (w2 * p[5 * j + 2]) + if i == j { h } else { C::new(0.0, 0.0) };
                put(&mut b, 4 * i + 2 * d, 8 * j + 4 + 2 * d, dx);
                let df = coupling - if i == j { 1.0 } else { 0.0 };
                for c in 0..2 {
                    put(&mut b, 4 * i + 2 * d, 8 * j + 2 * c, df * oj.kstar[d][c]);
                }
            }
        });
        (e, b)
    }
}

/// The speeds every member of `group` has, with their observations.
pub(super) fn common_speeds(
    obs: &[Vec<Observation>],
    group: &BaseGroup,
) -> Result<Vec<Speed>, BaseFitError> {
    let mut seen = Vec::new();
    for &i in &group.bearings {
        if i >= obs.len() {
            return Err(BaseFitError::NoSuchBearing {
                index: i,
                available: obs.len(),
            });
        }
        if seen.contains(&i) {
            return Err(BaseFitError::BadGroup(group.bearings.clone()));
        }
        seen.push(i);
    }
    let Some(&first) = group.bearings.first() else {
        return Err(BaseFitError::BadGroup(Vec::new()));
    };
    let mut speeds: Vec<Speed> = Vec::new();
    for o in obs[first].iter().filter(|o| o.is_finite()) {
        let members: Option<Vec<Observation>> = group
            .bearings
            .iter()
            .map(|&i| {
                obs[i]
                    .iter()
                    .find(|x| x.speed_hz == o.speed_hz && x.is_finite())
                    .copied()
            })
            .collect();
        if let Some(members) = members {
            let var = members.iter().flat_map(|m| m.var).collect();
            speeds.push(Speed {
                omega: o.omega(),
                force: members.iter().map(Observation::force).collect(),
                obs: members,
                var,
            });
        }
    }
    speeds.sort_by(|a, b| a.omega.total_cmp(&b.omega));
    speeds.dedup_by(|a, b| a.omega == b.omega);
    Ok(speeds)
}
