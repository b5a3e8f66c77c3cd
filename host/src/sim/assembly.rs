//! Global finite-element model of a machine: DOF numbering, the
//! speed-independent band matrices, and the dynamic stiffness at a speed.
//!
//! DOFs: 4 per shaft node `[y, z, θ_y, θ_z]` (see `timoshenko`), and for
//! each bearing with a pedestal 2 pedestal DOFs `[y, z]` numbered right after
//! the bearing's shaft node, so the matrix stays banded (half-bandwidth ≤ 9).
//! The bearing couples shaft node and pedestal: the force on the pedestal is
//! (K_b + iΩC_b)·(x_shaft − x_ped), the reaction on the shaft the opposite;
//! the pedestal stands on the ground through its own M, K, C (and η).
//! Springs between two pedestals (foundation coupling) would break the band:
//! they are kept apart as a low-rank term and solved by Woodbury's identity.
//! Bases (`super::base`) carry pedestals that may be far apart: their DOFs
//! come after all others, outside the band, and the bordered system is
//! solved by a Schur complement (one extra banded solve per base DOF).
//!
//! Dynamic stiffness at spin Ω [rad/s] (synchronous, excitation at Ω):
//! A(Ω) = K + iΩ(C + Ω·G) − Ω²M + bearings(Ω), with A·X = F and
//! q(t) = Re{X e^{iΩt}}.

use super::banded::{BandError, BandMatrix, BandShape, C64};
use super::base::{BaseBorder, BaseLink};
use super::machine::Machine;
use super::pedestal::PedestalDynamics;
use plinth_shared::bearing::BearingCoefficients;

/// A spring [N/m] between two DOFs, outside the band.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CouplingSpring {
    /// First DOF.
    pub a: usize,
    /// Second DOF.
    pub b: usize,
    /// Stiffness [N/m].
    pub k: f64,
}

/// The assembled model of a machine with given pedestal dynamics.
#[derive(Clone, Debug)]
pub struct Assembly {
    /// Number of DOFs.
    pub n_dof: usize,
    /// First DOF of each shaft node.
    pub node_dof: Vec<usize>,
    /// First pedestal DOF (y; z follows) of each bearing, `None` on rigid ground.
    pub pedestal_dof: Vec<Option<usize>>,
    /// Shaft node of each bearing.
    pub bearing_node: Vec<usize>,
    shape: BandShape,
    /// Band-storage arrays, same layout as `template`: K real and imaginary
    /// parts, M, C, G.
    k_re: Vec<f64>,
    k_im: Vec<f64>,
    m: Vec<f64>,
    c: Vec<f64>,
    g: Vec<f64>,
    /// Storage index of the (shaft, shaft), (shaft, ped), (ped, shaft),
    /// (ped, ped) 2×2 blocks of each bearing (`usize::MAX` when absent).
    bearing_idx: Vec<[[[usize; 2]; 2]; 4]>,
    /// Springs outside the band.
    pub couplings: Vec<CouplingSpring>,
    /// Base DOFs (after the banded part) and their links to pedestals.
    pub bases: BaseBorder,
}

#[derive(Clone, Copy)]
enum Kind {
    KRe,
    KIm,
    M,
    C,
    G,
}

impl Assembly {
    /// Assembles `machine` with the pedestal dynamics `pedestals` (one per
    /// bearing, `None` for rigid ground; `None` must match the machine) and
    /// the inter-pedestal springs `couplings` given as (bearing a, bearing b,
    /// k_y [N/m], k_z [N/m]).
    pub fn new(
        machine: &Machine,
        pedestals: &[Option<PedestalDynamics>],
        couplings: &[(usize, usize, f64, f64)],
    ) -> Result<Assembly, String> {
        machine.validate().map_err(|e| e.to_string())?;
        if pedestals.len() != machine.bearings.len() {
            return Err("one pedestal entry per bearing expected".into());
        }
        let nn = machine.node_positions.len();
        let mut node_dof = vec![0; nn];
        let mut pedestal_dof = vec![None; machine.bearings.len()];
        let mut next = 0;
        for (node, slot) in node_dof.iter_mut().enumerate() {
            *slot = next;
            next += 4;
            for (b, brg) in machine.bearings.iter().enumerate() {
                if brg.node == node && pedestals[b].is_some() {
                    pedestal_dof[b] = Some(next);
                    next += 2;
                }
            }
        }
        let n_dof = next;
        // Every structural entry, visited twice (band pattern, then values):
        // nothing per element is stored, so memory stays linear and small.
        let visit = |add: &mut dyn FnMut(usize, usize, Kind, f64)| {
            for (e, el) in machine.elements.iter().enumerate() {
                let dof = |i: usize| {
                    if i < 4 {
                        node_dof[e] + i
                    } else {
                        node_dof[e + 1] + i - 4
                    }
                };
                let (me, ke, ge) = (
                    el.mass_matrix(),
                    el.stiffness_matrix(),
                    el.gyroscopic_matrix(),
                );
                for i in 0..8 {
                    for j in 0..8 {
                        add(dof(i), dof(j), Kind::M, me[i][j]);
                        add(dof(i), dof(j), Kind::KRe, ke[i][j]);
                        add(dof(i), dof(j), Kind::G, ge[i][j]);
                    }
                }
            }
            for d in &machine.disks {
                let (md, gd) = (d.mass_matrix(), d.gyroscopic_matrix());
                let base = node_dof[d.node];
                for i in 0..4 {
                    for j in 0..4 {
                        add(base + i, base + j, Kind::M, md[i][j]);
                        add(base + i, base + j, Kind::G, gd[i][j]);
                    }
                }
            }
            for (b, p) in pedestals.iter().enumerate() {
                if let (Some(p), Some(pd)) = (p, pedestal_dof[b]) {
                    for i in 0..2 {
                        add(pd + i, pd + i, Kind::M, p.m[i]);
                        for j in 0..2 {
                            add(pd + i, pd + j, Kind::KRe, p.k[i][j]);
                            add(pd + i, pd + j, Kind::KIm, p.eta * p.k[i][j]);
                            add(pd + i, pd + j, Kind::C, p.c[i][j]);
                        }
                    }
                }
            }
            // Bearing blocks take part in the band pattern.
            for (b, brg) in machine.bearings.iter().enumerate() {
                let s = node_dof[brg.node];
                let mut pair = |r: usize, c: usize| add(r, c, Kind::KRe, 0.0);
                pair(s, s + 1);
                pair(s + 1, s);
                if let Some(p) = pedestal_dof[b] {
                    pair(s, p + 1);
                    pair(p + 1, s);
                    pair(s + 1, p + 1);
                    pair(p + 1, s + 1);
                }
            }
        };
        let (mut kl, mut ku) = (0usize, 0usize);
        visit(&mut |r, c, _, _| {
            kl = kl.max(r.saturating_sub(c));
            ku = ku.max(c.saturating_sub(r));
        });
        let shape = BandShape { n: n_dof, kl, ku };
        let len = shape.len();
        let mut arrays = [
            vec![0.0; len],
            vec![0.0; len],
            vec![0.0; len],
            vec![0.0; len],
            vec![0.0; len],
        ];
        visit(&mut |r, c, kind, v| {
            if v != 0.0 {
                if let Some(idx) = shape.index(r, c) {
                    arrays[kind as usize][idx] += v;
                }
            }
        });
        let idx = |r: usize, c: usize| shape.index(r, c).unwrap_or(usize::MAX);
        let mut bearing_idx = Vec::new();
        for (b, brg) in machine.bearings.iter().enumerate() {
            let s = node_dof[brg.node];
            let block = |r0: usize, c0: usize| {
                [
                    [idx(r0, c0), idx(r0, c0 + 1)],
                    [idx(r0 + 1, c0), idx(r0 + 1, c0 + 1)],
                ]
            };
            let absent = [[usize::MAX; 2]; 2];
            let blocks = match pedestal_dof[b] {
                Some(p) => [block(s, s), block(s, p), block(p, s), block(p, p)],
                None => [block(s, s), absent, absent, absent],
            };
            bearing_idx.push(blocks);
        }
        let mut springs = Vec::new();
        for &(a, b, ky, kz) in couplings {
            let (pa, pb) = match (pedestal_dof.get(a).copied().flatten(), pedestal_dof.get(b).copied().flatten()) {
                (Some(pa), Some(pb)) if a != b => (pa, pb),
                _ => return Err(format!("foundation coupling needs two different bearings with pedestals (got {a}, {b})")),
            };
            for (d, k) in [(0, ky), (1, kz)] {
                if !(k.is_finite() && k >= 0.0) {
                    return Err(format!(
                        "foundation coupling stiffness must be finite and >= 0 (got {k})"
                    ));
                }
                if k > 0.0 {
                    springs.push(CouplingSpring {
                        a: pa + d,
                        b: pb + d,
                        k,
                    });
                }
            }
        }
        let [k_re, k_im, m, c, g] = arrays;
        let mut links = Vec::new();
        for (b, brg) in machine.bearings.iter().enumerate() {
            if let (Some(base), Some(p), Some(pd)) = (brg.base, pedestals[b], pedestal_dof[b]) {
                links.push(BaseLink {
                    pedestal_dof: pd,
                    base,
                    pedestal: p,
                });
            }
        }
        let bases = BaseBorder {
            bases: machine.bases.clone(),
            links,
            first_dof: n_dof,
        };
        Ok(Assembly {
            n_dof: n_dof + bases.n_dof(),
            node_dof,
            pedestal_dof,
            bearing_node: machine.bearings.iter().map(|b| b.node).collect(),
            shape,
            k_re,
            k_im,
            m,
            c,
            g,
            bearing_idx,
            couplings: springs,
            bases,
        })
    }

    /// (sub, super) half-bandwidths of the banded part.
    pub fn bandwidths(&self) -> (usize, usize) {
        (self.shape.kl, self.shape.ku)
    }

    /// A zero band matrix with this model's pattern (reuse it across speeds).
    pub fn new_matrix(&self) -> BandMatrix {
        BandMatrix::zeros(self.shape.n, self.shape.kl, self.shape.ku)
    }

    /// Fills `a` with the banded part of A(Ω) for spin Ω [rad/s] and bearing
    /// coefficients `bearings` (one per bearing).
    pub fn fill(&self, a: &mut BandMatrix, omega: f64, bearings: &[BearingCoefficients<f64>]) {
        let w2 = omega * omega;
        let data = a.data_mut();
        for (i, d) in data.iter_mut().enumerate() {
            *d = C64::new(
                self.k_re[i] - w2 * self.m[i],
                self.k_im[i] + omega * self.c[i] + w2 * self.g[i],
            );
        }
        for (blocks, coef) in self.bearing_idx.iter().zip(bearings) {
            for i in 0..2 {
                for j in 0..2 {
                    let z = C64::new(coef.k[i][j], omega * coef.c[i][j]);
                    for (blk, sign) in blocks.iter().zip([1.0, -1.0, -1.0, 1.0]) {
                        let idx = blk[i][j];
                        if idx != usize::MAX {
                            data[idx] += z * sign;
                        }
                    }
                }
            }
        }
    }

    /// Dense real stiffness (structure, pedestals, couplings and the bearing
    /// stiffness `bearings[b].k`) and mass matrices, for modal checks on
    /// small models (not the response path).
    pub fn dense_stiffness_and_mass(
        &self,
        bearings: &[BearingCoefficients<f64>],
    ) -> (nalgebra::DMatrix<f64>, nalgebra::DMatrix<f64>) {
        let n = self.n_dof;
        let mut k = nalgebra::DMatrix::<f64>::zeros(n, n);
        let mut m = nalgebra::DMatrix::<f64>::zeros(n, n);
        for r in 0..n {
            for c in 0..n {
                if let Some(i) = self.shape.index(r, c) {
                    k[(r, c)] = self.k_re[i];
                    m[(r, c)] = self.m[i];
                }
            }
        }
        for ((b, coef), &node) in bearings.iter().enumerate().zip(&self.bearing_node) {
            let s = self.node_dof[node];
            for i in 0..2 {
                for j in 0..2 {
                    let v = coef.k[i][j];
                    k[(s + i, s + j)] += v;
                    if let Some(p) = self.pedestal_dof[b] {
                        k[(s + i, p + j)] -= v;
                        k[(p + i, s + j)] -= v;
                        k[(p + i, p + j)] += v;
                    }
                }
            }
        }
        self.bases.add_dense(&mut k, &mut m);
        for sp in &self.couplings {
            k[(sp.a, sp.a)] += sp.k;
            k[(sp.b, sp.b)] += sp.k;
            k[(sp.a, sp.b)] -= sp.k;
            k[(sp.b, sp.a)] -= sp.k;
        }
        (k, m)
    }

    /// Solves A(Ω)·x = f at spin Ω [rad/s] (the speed `a` was filled at):
    /// the factored banded part `a`, the coupling springs and the bases;
    /// `f` (length `n_dof`) is overwritten by x.
    pub fn solve(&self, a: &BandMatrix, omega: f64, f: &mut [C64]) -> Result<(), BandError> {
        if f.len() != self.n_dof {
            return Err(BandError::Dimension {
                expected: self.n_dof,
                got: f.len(),
            });
        }
        self.bases.solve(
            omega,
            f,
            |r| self.solve_band(a, r),
            |column| BandError::Singular { column },
        )
    }

    /// Solves (banded part + coupling springs)·x = f on the DOFs before the
    /// bases (Woodbury identity, one extra solve per spring).
    fn solve_band(&self, a: &BandMatrix, f: &mut [C64]) -> Result<(), BandError> {
        a.solve_in_place(f)?;
        if self.couplings.is_empty() {
            return Ok(());
        }
        // A = A0 + U·D·Uᵀ, u_i = e_a − e_b, D = diag(k_i).
        let r = self.couplings.len();
        let mut w = Vec::with_capacity(r); // A0⁻¹ u_i
        for s in &self.couplings {
            let mut u = vec![C64::new(0.0, 0.0); self.bases.first_dof];
            u[s.a] = C64::new(1.0, 0.0);
            u[s.b] = C64::new(-1.0, 0.0);
            a.solve_in_place(&mut u)?;
            w.push(u);
        }
        // S = D⁻¹ + Uᵀ A0⁻¹ U (r×r), rhs = Uᵀ x0.
        let mut s_mat = nalgebra::DMatrix::<C64>::zeros(r, r);
        let mut rhs = nalgebra::DVector::<C64>::zeros(r);
        for (i, si) in self.couplings.iter().enumerate() {
            for (j, wj) in w.iter().enumerate() {
                s_mat[(i, j)] = wj[si.a] - wj[si.b];
            }
            s_mat[(i, i)] += C64::new(1.0 / si.k, 0.0);
            rhs[i] = f[si.a] - f[si.b];
        }
        let y = s_mat
            .lu()
            .solve(&rhs)
            .ok_or(BandError::Singular { column: usize::MAX })?;
        for (j, wj) in w.iter().enumerate() {
            for (fi, wi) in f.iter_mut().zip(wj) {
                *fi -= *wi * y[j];
            }
        }
        Ok(())
    }
}
