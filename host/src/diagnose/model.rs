//! Augmented pedestal models: the paper's pedestal equation (eq. 3) with the
//! extra terms of the effect library, in one linear-in-parameters form.
//!
//! At one speed, for a group of pedestals fitted together (each group is a
//! single pedestal: the pedestals on a shared, unmeasured base are the
//! nonlinear model of `crate::estimate::base`, tried by `super::foundation`),
//! the model is
//!
//! ```text
//! Σ_k β_k·(M_k·X + g_k) = F,     X = corrected pedestal displacement,
//!                                F = K*·rel_corrected (force from the bearing)
//! ```
//!
//! with one complex equation per pedestal and direction (y, z). Each term k has
//! a matrix M_k (how β_k multiplies the pedestal motion) and an offset g_k (a
//! motion-independent force). The regressor of β_k is M_k·X + g_k, so the
//! least-squares rows (eq. 4, extended) and the prediction X = M⁻¹·(F − g),
//! M = Σβ_k·M_k, g = Σβ_k·g_k, come from the same definition.
//!
//! Two effects are not linear in their parameter and are handled as
//! *nonlinear scalars* profiled by a 1-D search (`fit`): the loss factor η
//! (K → K·(1 + iη), which multiplies the stiffness terms' M_k) and a sensor
//! delay τ (a delayed channel reads q·e^{−iΩτ}, so the model uses the
//! measured value times e^{iΩτ}).

use super::bearing_table::{TableCorrection, WrittenTable};
use super::data::{Complex2x2, Prepared};
use crate::estimate::Observation;
use nalgebra::{DMatrix, DVector};
use num_complex::Complex;
use serde::Serialize;

/// Direction index of y (vertical).
pub const Y: usize = 0;
/// Direction index of z (horizontal).
pub const Z: usize = 1;
/// Direction suffixes used in parameter names.
pub const DIR_NAMES: [&str; 2] = ["y", "z"];

/// One linear term of an augmented pedestal model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub enum Term {
    /// Direct stiffness k_y or k_z [N/m] of a pedestal.
    Stiffness {
        /// Bearing index.
        bearing: usize,
        /// Direction (0 = y, 1 = z).
        dir: usize,
    },
    /// Pedestal mass [kg]: one mass for both directions (`dir: None`, the
    /// paper's model) or the mass of one direction (mass anisotropy).
    Mass {
        /// Bearing index.
        bearing: usize,
        /// Direction, or `None` for the shared mass.
        dir: Option<usize>,
    },
    /// Viscous pedestal damping c_y or c_z [N·s/m].
    Damping {
        /// Bearing index.
        bearing: usize,
        /// Direction.
        dir: usize,
    },
    /// Symmetric off-diagonal pedestal stiffness k_yz = k_zy [N/m].
    CrossStiffness {
        /// Bearing index.
        bearing: usize,
    },
    /// One real component of a constant runout vector r [m] on a bearing's
    /// `rel` probes: the bearing force is K*·(rel − r).
    Runout {
        /// Bearing index.
        bearing: usize,
        /// Probe direction.
        dir: usize,
        /// Imaginary (true) or real (false) part.
        imag: bool,
    },
    /// The Ω⁴ coefficient q [N·s⁴/m] of one direction's pedestal dynamic
    /// stiffness, k − Ω²m − Ω⁴q + iΩc: a support whose second mode lies
    /// above the speed range (`pedestal_sub_base` above the range,
    /// `crate::estimate::lack_of_fit::support`).
    Quartic {
        /// Bearing index.
        bearing: usize,
        /// Direction.
        dir: usize,
    },
}

impl Term {
    /// The bearings the term acts on.
    pub fn bearings(&self) -> [Option<usize>; 2] {
        match *self {
            Term::Stiffness { bearing, .. }
            | Term::Mass { bearing, .. }
            | Term::Damping { bearing, .. }
            | Term::CrossStiffness { bearing }
            | Term::Runout { bearing, .. }
            | Term::Quartic { bearing, .. } => [Some(bearing), None],
        }
    }

    /// Whether the term is part of the pedestal's own parameters (k, m, c).
    pub fn is_pedestal(&self) -> bool {
        matches!(
            self,
            Term::Stiffness { .. } | Term::Mass { .. } | Term::Damping { .. }
        )
    }

    /// Parameter name (formats.md / `crate::effects` names).
    pub fn name(&self) -> String {
        match *self {
            Term::Stiffness { dir, .. } => format!("k_{}", DIR_NAMES[dir]),
            Term::Mass { dir: None, .. } => "m".to_string(),
            Term::Mass { dir: Some(d), .. } => format!("m_{}", DIR_NAMES[d]),
            Term::Damping { dir, .. } => format!("c_{}", DIR_NAMES[dir]),
            Term::CrossStiffness { .. } => "k_yz".to_string(),
            Term::Runout { dir, imag, .. } => {
                format!("r_{}_{}", DIR_NAMES[dir], if imag { "im" } else { "re" })
            }
            Term::Quartic { dir, .. } => format!("q_{}", DIR_NAMES[dir]),
        }
    }

    /// A typical size of the parameter for column scaling and finite
    /// differences is not needed: columns are normalised numerically.
    fn stiffness_like(&self) -> bool {
        matches!(self, Term::Stiffness { .. } | Term::CrossStiffness { .. })
    }
}

/// Which channels of a bearing a sensor delay acts on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct DelayChannels {
    /// Rotor-relative probes (y, z).
    pub rel: [bool; 2],
    /// Pedestal (seismic) sensors (y, z).
    pub ped: [bool; 2],
}

impl DelayChannels {
    /// Every variant the library considers: both pedestal channels (the
    /// `crate::effects` definition), one pedestal channel, both probes, one probe.
    pub const VARIANTS: [DelayChannels; 6] = [
        DelayChannels {
            rel: [false, false],
            ped: [true, true],
        },
        DelayChannels {
            rel: [false, false],
            ped: [true, false],
        },
        DelayChannels {
            rel: [false, false],
            ped: [false, true],
        },
        DelayChannels {
            rel: [true, true],
            ped: [false, false],
        },
        DelayChannels {
            rel: [true, false],
            ped: [false, false],
        },
        DelayChannels {
            rel: [false, true],
            ped: [false, false],
        },
    ];

    /// Short label: `ped`, `ped_y`, `ped_z`, `rel`, `rel_y`, `rel_z`.
    pub fn label(&self) -> String {
        let one = |kind: &str, f: [bool; 2]| match f {
            [true, true] => Some(kind.to_string()),
            [true, false] => Some(format!("{kind}_y")),
            [false, true] => Some(format!("{kind}_z")),
            [false, false] => None,
        };
        [one("rel", self.rel), one("ped", self.ped)]
            .into_iter()
            .flatten()
            .collect::<Vec<_>>()
            .join("+")
    }
}

/// A parameter of an augmented model that enters nonlinearly.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub enum Nonlinear {
    /// Loss factor η [-] of a pedestal: its stiffness terms become k·(1 + iη).
    LossFactor {
        /// Bearing index.
        bearing: usize,
    },
    /// Time delay τ [s] on some channels of a bearing.
    Delay {
        /// Bearing index.
        bearing: usize,
        /// Delayed channels.
        channels: DelayChannels,
    },
    /// Clearance correction δ = c_true/c_written − 1 [-] of an oil-film
    /// bearing table (`super::bearing_table`, geometry in [`Model::tables`]).
    Clearance {
        /// Bearing index.
        bearing: usize,
    },
    /// Stiffness ratio correction δ = k_scale − 1 [-] of a bearing table of
    /// any origin, its damping as written (`super::bearing_table::scale`).
    StiffnessRatio {
        /// Bearing index.
        bearing: usize,
    },
}

impl Nonlinear {
    /// The bearing the parameter belongs to.
    pub fn bearing(&self) -> usize {
        match *self {
            Nonlinear::LossFactor { bearing }
            | Nonlinear::Delay { bearing, .. }
            | Nonlinear::Clearance { bearing }
            | Nonlinear::StiffnessRatio { bearing } => bearing,
        }
    }

    /// Parameter name (`eta`, `tau`, as in `crate::effects`; the table
    /// scalars are δ, reported as `clearance_ratio` or `k_scale` = 1 + δ).
    pub fn name(&self) -> &'static str {
        match self {
            Nonlinear::LossFactor { .. } => "eta",
            Nonlinear::Delay { .. } => "tau",
            Nonlinear::Clearance { .. } => "clearance_ratio",
            Nonlinear::StiffnessRatio { .. } => "k_scale",
        }
    }
}

/// An augmented pedestal model of the whole machine.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Model {
    /// Linear terms, in parameter order.
    pub terms: Vec<Term>,
    /// Nonlinear scalars, in parameter order.
    pub nonlinear: Vec<Nonlinear>,
    /// Per bearing, the oil-film geometry its table was written for, when
    /// the machine file gives it (empty: none).
    pub tables: Vec<Option<WrittenTable>>,
}

/// Values of a model's parameters (SI units of each term).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Params {
    /// Linear parameters, one per [`Model::terms`].
    pub beta: Vec<f64>,
    /// Nonlinear scalars, one per [`Model::nonlinear`].
    pub nl: Vec<f64>,
}

/// One speed of one group of pedestals, assembled for a model.
#[derive(Clone, Debug)]
pub struct Assembled {
    /// Regressor (complex, one entry per group equation) of each group term,
    /// paired with the term's index in [`Model::terms`].
    pub columns: Vec<(usize, DVector<Complex<f64>>)>,
    /// The bearing force F = K*·rel (delay-corrected) per group equation [N].
    pub force: DVector<Complex<f64>>,
    /// Corrected pedestal displacement X per group equation [m].
    pub x: DVector<Complex<f64>>,
    /// The bearing stiffness K* [N/m] of each group member, corrected by a
    /// clearance scalar where the model has one.
    pub kstar: Vec<Complex2x2>,
    /// Factor e^{iΩτ} applied to each measured pedestal channel.
    pub ped_phase: Vec<Complex<f64>>,
    /// Factor e^{iΩτ} applied to each measured rel channel.
    pub rel_phase: Vec<Complex<f64>>,
    /// Total matrix M = Σβ_k·M_k (only when parameter values were given).
    pub matrix: Option<DMatrix<Complex<f64>>>,
    /// Total offset g = Σβ_k·g_k.
    pub offset: Option<DVector<Complex<f64>>>,
}

impl Model {
    /// The table correction a nonlinear scalar stands for, if it is one
    /// (a clearance needs its bearing's oil-film geometry in [`Model::tables`]).
    pub fn table_correction(&self, p: &Nonlinear) -> Option<TableCorrection> {
        match *p {
            Nonlinear::Clearance { bearing } => self
                .tables
                .get(bearing)
                .copied()
                .flatten()
                .map(TableCorrection::Film),
            Nonlinear::StiffnessRatio { .. } => Some(TableCorrection::StiffnessRatio),
            _ => None,
        }
    }

    /// The groups of pedestals that must be fitted together (connected by
    /// coupling terms), each sorted, in order of their first bearing.
    pub fn groups(&self, n_bearings: usize) -> Vec<Vec<usize>> {
        let mut parent: Vec<usize> = (0..n_bearings).collect();
        fn find(p: &mut [usize], i: usize) -> usize {
            let mut r = i;
            while p[r] != r {
                r = p[r];
            }
            p[i] = r;
            r
        }
        for t in &self.terms {
            if let [Some(a), Some(b)] = t.bearings() {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                if ra != rb {
                    parent[ra.max(rb)] = ra.min(rb);
                }
            }
        }
        let mut groups: Vec<Vec<usize>> = Vec::new();
        let mut root_of_group: Vec<usize> = Vec::new();
        for b in 0..n_bearings {
            let r = find(&mut parent, b);
            match root_of_group.iter().position(|&x| x == r) {
                Some(g) => groups[g].push(b),
                None => {
                    root_of_group.push(r);
                    groups.push(vec![b]);
                }
            }
        }
        groups
    }

    /// Indices of the terms acting within `group`.
    pub fn group_terms(&self, group: &[usize]) -> Vec<usize> {
        (0..self.terms.len())
            .filter(|&k| {
                self.terms[k]
                    .bearings()
                    .iter()
                    .flatten()
                    .all(|b| group.contains(b))
            })
            .collect()
    }

    /// Indices of the nonlinear scalars acting within `group`.
    pub fn group_nonlinear(&self, group: &[usize]) -> Vec<usize> {
        (0..self.nonlinear.len())
            .filter(|&k| group.contains(&self.nonlinear[k].bearing()))
            .collect()
    }

    /// Speed indices at which every bearing of `group` was measured.
    pub fn group_speeds(prep: &Prepared, group: &[usize]) -> Vec<usize> {
        (0..prep.speeds_hz.len())
            .filter(|&j| group.iter().all(|&b| prep.points[b][j].is_some()))
            .collect()
    }

    /// Assembles speed `j` of `group` with nonlinear values `nl`; with `beta`
    /// also the total matrix and offset for prediction and noise propagation.
    pub fn assemble(
        &self,
        prep: &Prepared,
        group: &[usize],
        j: usize,
        nl: &[f64],
        beta: Option<&[f64]>,
    ) -> Option<Assembled> {
        let ng = group.len();
        let n = 2 * ng;
        let pos = |b: usize| group.iter().position(|&g| g == b);
        let points: Vec<&Observation> = group
            .iter()
            .map(|&b| prep.points[b][j].as_ref())
            .collect::<Option<Vec<_>>>()?;
        let omega = points[0].omega();
        let one = Complex::new(1.0, 0.0);
        let mut eta = vec![0.0; ng];
        let mut kstar: Vec<Complex2x2> = points.iter().map(|p| p.kstar).collect();
        let mut ped_phase = vec![one; n];
        let mut rel_phase = vec![one; n];
        for (k, p) in self.nonlinear.iter().enumerate() {
            let Some(pb) = pos(p.bearing()) else { continue };
            match p {
                Nonlinear::LossFactor { .. } => eta[pb] = nl[k],
                Nonlinear::Clearance { .. } | Nonlinear::StiffnessRatio { .. } => {
                    let table = self.table_correction(p)?;
                    let corr = table.correction(points[pb].speed_hz, &kstar[pb], nl[k])?;
                    for (row, c_row) in kstar[pb].iter_mut().zip(corr) {
                        for (v, c) in row.iter_mut().zip(c_row) {
                            *v += c;
                        }
                    }
                }
                Nonlinear::Delay { channels, .. } => {
                    let f = Complex::from_polar(1.0, omega * nl[k]);
                    for d in 0..2 {
                        if channels.ped[d] {
                            ped_phase[2 * pb + d] *= f;
                        }
                        if channels.rel[d] {
                            rel_phase[2 * pb + d] *= f;
                        }
                    }
                }
            }
        }
        let mut x = DVector::from_element(n, Complex::new(0.0, 0.0));
        let mut force = DVector::from_element(n, Complex::new(0.0, 0.0));
        for (pb, p) in points.iter().enumerate() {
            let rel_c = [
                p.rel[0] * rel_phase[2 * pb],
                p.rel[1] * rel_phase[2 * pb + 1],
            ];
            for d in 0..2 {
                x[2 * pb + d] = p.ped[d] * ped_phase[2 * pb + d];
                force[2 * pb + d] = kstar[pb][d][0] * rel_c[0] + kstar[pb][d][1] * rel_c[1];
            }
        }
        let mut columns = Vec::new();
        let mut matrix = beta.map(|_| DMatrix::from_element(n, n, Complex::new(0.0, 0.0)));
        let mut offset = beta.map(|_| DVector::from_element(n, Complex::new(0.0, 0.0)));
        for k in self.group_terms(group) {
            let term = self.terms[k];
            let mut col = DVector::from_element(n, Complex::new(0.0, 0.0));
            let mut entry =
                |r: usize, c: usize, v: Complex<f64>, col: &mut DVector<Complex<f64>>| {
                    col[r] += v * x[c];
                    if let (Some(m), Some(beta)) = (matrix.as_mut(), beta) {
                        m[(r, c)] += v * beta[k];
                    }
                };
            let loss = |b: usize| -> Complex<f64> {
                if term.stiffness_like() {
                    Complex::new(1.0, eta[b])
                } else {
                    one
                }
            };
            match term {
                Term::Stiffness { bearing, dir } => {
                    let p = pos(bearing)?;
                    entry(2 * p + dir, 2 * p + dir, loss(p), &mut col);
                }
                Term::Mass { bearing, dir } => {
                    let p = pos(bearing)?;
                    let v = Complex::new(-omega * omega, 0.0);
                    for d in 0..2 {
                        if dir.is_none() || dir == Some(d) {
                            entry(2 * p + d, 2 * p + d, v, &mut col);
                        }
                    }
                }
                Term::Damping { bearing, dir } => {
                    let p = pos(bearing)?;
                    entry(2 * p + dir, 2 * p + dir, Complex::new(0.0, omega), &mut col);
                }
                Term::Quartic { bearing, dir } => {
                    let p = pos(bearing)?;
                    let v = Complex::new(-omega.powi(4), 0.0);
                    entry(2 * p + dir, 2 * p + dir, v, &mut col);
                }
                Term::CrossStiffness { bearing } => {
                    let p = pos(bearing)?;
                    entry(2 * p, 2 * p + 1, loss(p), &mut col);
                    entry(2 * p + 1, 2 * p, loss(p), &mut col);
                }
                Term::Runout { bearing, dir, imag } => {
                    let p = pos(bearing)?;
                    let unit = if imag { Complex::new(0.0, 1.0) } else { one };
                    for r in 0..2 {
                        let v = kstar[p][r][dir] * unit;
                        col[2 * p + r] += v;
                        if let (Some(g), Some(beta)) = (offset.as_mut(), beta) {
                            g[2 * p + r] += v * beta[k];
                        }
                    }
                }
            }
            columns.push((k, col));
        }
        Some(Assembled {
            columns,
            force,
            x,
            kstar,
            ped_phase,
            rel_phase,
            matrix,
            offset,
        })
    }
}

/// The pedestal motion a model predicts from the measured forces at one
/// speed, as the pedestal sensors would read it (delays applied) [m], per
/// group equation; `None` when the model's dynamic stiffness is singular.
pub fn predict(a: &Assembled) -> Option<DVector<Complex<f64>>> {
    let m = a.matrix.clone()?;
    let g = a.offset.as_ref()?;
    let rhs = &a.force - g;
    let x = m.lu().solve(&rhs)?;
    if x.iter().any(|v| !v.re.is_finite() || !v.im.is_finite()) {
        return None;
    }
    Some(DVector::from_iterator(
        x.len(),
        x.iter().zip(&a.ped_phase).map(|(v, f)| v / f),
    ))
}
