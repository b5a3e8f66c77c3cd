//! One group's equations as a Gauss–Helmert system ([`GroupEquations`]):
//! the residual of the model's own equation per speed, linear in the
//! measured numbers ([`super`] module docs), and its whitened linearisation
//! at a set of values ([`linearised`]), what every inference of the final
//! refit ([`super::serial::inference`]) and of its nuisance rules is made
//! from.

use super::super::criterion::Inference;
use super::super::data::Prepared;
use super::super::model::{Model, Term};
use super::super::state::State;
use crate::estimate::base::put;
use crate::estimate::gauss_helmert::{self as gh, Equations};
use nalgebra::{DMatrix, DVector};
use num_complex::Complex;

/// Measured real numbers per bearing and speed (rel y, rel z, ped y, ped z;
/// real and imaginary parts, the order of [`crate::estimate::Observation::var`]).
const MEASURED: usize = 8;

/// The equations of one group of a [`Model`] as a Gauss–Helmert system:
/// p = (the group's linear terms, then its nonlinear scalars), the other
/// groups' values held (they do not enter).
pub(super) struct GroupEquations<'a> {
    prep: &'a Prepared,
    pub(super) model: &'a Model,
    pub(super) group: &'a [usize],
    /// The group's speeds (indices into [`Prepared::speeds_hz`], ascending).
    pub(super) speeds: Vec<usize>,
    pub(super) terms: Vec<usize>,
    pub(super) nonlinear: Vec<usize>,
    pub(super) beta: Vec<f64>,
    pub(super) nl: Vec<f64>,
    var: Vec<Vec<f64>>,
}

impl<'a> GroupEquations<'a> {
    pub(super) fn new(
        prep: &'a Prepared,
        model: &'a Model,
        group: &'a [usize],
        state: &State,
    ) -> Self {
        Self::from_values(prep, model, group, &state.params.beta, &state.params.nl)
    }

    /// The equations of `group` of `model` at the values (β, nl) of the
    /// whole model (β one entry per term of `model`).
    pub(super) fn from_values(
        prep: &'a Prepared,
        model: &'a Model,
        group: &'a [usize],
        beta: &[f64],
        nl: &[f64],
    ) -> Self {
        let speeds = Model::group_speeds(prep, group);
        let var = speeds
            .iter()
            .map(|&j| {
                group
                    .iter()
                    .flat_map(|&b| {
                        prep.points[b][j]
                            .as_ref()
                            .map_or([0.0; MEASURED], |o| o.var)
                    })
                    .collect()
            })
            .collect();
        Self {
            prep,
            model,
            group,
            speeds,
            terms: model.group_terms(group),
            nonlinear: model.group_nonlinear(group),
            beta: beta.to_vec(),
            nl: nl.to_vec(),
            var,
        }
    }

    /// The model's (β, nl) with the group's entries set from `p`.
    pub(super) fn unpack(&self, p: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let (mut beta, mut nl) = (self.beta.clone(), self.nl.clone());
        for (t, v) in self.terms.iter().zip(p) {
            beta[*t] = *v;
        }
        for (k, v) in self.nonlinear.iter().zip(&p[self.terms.len()..]) {
            nl[*k] = *v;
        }
        (beta, nl)
    }

    /// The values of `state` as p.
    pub(super) fn pack(&self, beta: &[f64], nl: &[f64]) -> Vec<f64> {
        self.terms
            .iter()
            .map(|&t| beta[t])
            .chain(self.nonlinear.iter().map(|&k| nl[k]))
            .collect()
    }

    /// The start p and per-parameter scales of these equations when they
    /// are those of `held_model` with held dampings appended
    /// ([`with_freed`]): the group's terms and scalars are scaled by the
    /// larger of their size and their ± in `held_fit` (the held model's
    /// group refit), each appended damping by `freed_scale(bearing, dir, k)`
    /// [N·s/m] (k: that bearing's stiffness in that direction in
    /// `held_beta` [N/m]). `None` where a start value or a scale is not a
    /// finite number, or `freed_scale` gives none.
    pub(super) fn freed_start(
        &self,
        held_model: &Model,
        held_beta: &[f64],
        held_fit: &Inference,
        mut freed_scale: impl FnMut(usize, usize, f64) -> Option<f64>,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let n_held = held_model.group_terms(self.group).len();
        let n_terms = self.terms.len();
        let n_new = n_terms - n_held;
        let start = self.pack(&self.beta, &self.nl);
        let stiffness = |bearing: usize, dir: usize| {
            let i = held_model
                .terms
                .iter()
                .position(|u| *u == Term::Stiffness { bearing, dir })?;
            held_beta.get(i).copied()
        };
        let mut scale = Vec::with_capacity(start.len());
        for (i, v) in start.iter().enumerate() {
            let s = if i < n_held {
                v.abs().max(held_fit.std_err(i))
            } else if i < n_terms {
                let Term::Damping { bearing, dir } = self.model.terms[self.terms[i]] else {
                    return None;
                };
                freed_scale(bearing, dir, stiffness(bearing, dir).unwrap_or(0.0))?
            } else {
                v.abs().max(held_fit.std_err(i - n_new))
            };
            if !s.is_finite() {
                return None;
            }
            scale.push(s.max(f64::MIN_POSITIVE));
        }
        start
            .iter()
            .all(|v| v.is_finite())
            .then_some((start, scale))
    }
}

/// `model` with the held dampings `freed` appended to its terms, and its
/// values β with a zero for each: the group's terms keep their order, the
/// freed ones follow them in p, then the scalars (what
/// [`held_delay`] and [`held_free`] refit).
pub(super) fn with_freed(model: &Model, beta: &[f64], freed: &[Term]) -> (Model, Vec<f64>) {
    let mut extended = model.clone();
    extended.terms.extend(freed.iter().copied());
    let mut ext_beta = beta.to_vec();
    ext_beta.resize(extended.terms.len(), 0.0);
    (extended, ext_beta)
}

impl Equations for GroupEquations<'_> {
    fn speeds(&self) -> usize {
        self.speeds.len()
    }

    fn variance(&self, s: usize) -> &[f64] {
        &self.var[s]
    }

    fn residual(&self, s: usize, p: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
        let n = 2 * self.group.len();
        let (beta, nl) = self.unpack(p);
        let assembled =
            self.model
                .assemble(self.prep, self.group, self.speeds[s], &nl, Some(&beta));
        let Some((a, m)) = assembled.and_then(|a| a.matrix.clone().map(|m| (a, m))) else {
            // Not finite: J cannot be evaluated here.
            return (
                DVector::from_element(2 * n, f64::NAN),
                DMatrix::zeros(2 * n, MEASURED * self.group.len()),
            );
        };
        let mut e = DVector::zeros(2 * n);
        let mut b = DMatrix::zeros(2 * n, MEASURED * self.group.len());
        for (pb, _) in self.group.iter().enumerate() {
            for d in 0..2 {
                let row = 2 * pb + d;
                let mut v = -a.force[row];
                for (k, col) in &a.columns {
                    v += beta[*k] * col[row];
                }
                e[2 * row] = v.re;
                e[2 * row + 1] = v.im;
                for (qc, _) in self.group.iter().enumerate() {
                    for dc in 0..2 {
                        let c = 2 * qc + dc;
                        put(
                            &mut b,
                            2 * row,
                            MEASURED * qc + 4 + 2 * dc,
                            m[(row, c)] * a.ped_phase[c],
                        );
                    }
                }
                for dc in 0..2 {
                    let coef: Complex<f64> = -a.kstar[pb][d][dc] * a.rel_phase[2 * pb + dc];
                    put(&mut b, 2 * row, MEASURED * pb + 2 * dc, coef);
                }
            }
        }
        (e, b)
    }
}

/// The whitened Jacobian L_s⁻¹·∂e_s/∂p at fixed Σ(p̂) (central differences,
/// steps 1e-6·`scale`), the whitened residuals L_s⁻¹e_s and the speed of
/// every row, stacked over speeds: what [`Inference::new`] takes.
pub(super) fn linearised(
    eq: &GroupEquations<'_>,
    p: &[f64],
    scale: &[f64],
) -> Option<(DMatrix<f64>, DVector<f64>, Vec<usize>)> {
    let (mut rows, mut resid, mut speed) = (Vec::new(), Vec::new(), Vec::new());
    for s in 0..eq.speeds() {
        let l = gh::whitening(eq, s, p)?;
        let e = eq.error(s, p);
        let mut a = DMatrix::zeros(e.len(), p.len());
        for (k, sc) in scale.iter().enumerate() {
            let h = 1e-6 * sc;
            let (mut up, mut dn) = (p.to_vec(), p.to_vec());
            up[k] += h;
            dn[k] -= h;
            a.set_column(k, &((eq.error(s, &up) - eq.error(s, &dn)) / (2.0 * h)));
        }
        let wa = l.solve_lower_triangular(&a)?;
        let we = l.solve_lower_triangular(&e)?;
        for r in 0..wa.nrows() {
            rows.push(wa.row(r).clone_owned());
            resid.push(we[r]);
            speed.push(eq.speeds[s]);
        }
    }
    let jac = DMatrix::from_rows(&rows);
    let ok = jac.iter().chain(&resid).all(|v| v.is_finite());
    ok.then(|| (jac, DVector::from_vec(resid), speed))
}
