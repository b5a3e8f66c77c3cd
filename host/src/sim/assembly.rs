//! Global finite-element model of a machine: DOF numbering, the
//! speed-independent band matrices, and the dynamic stiffness at a speed.
//!
//! DOFs: 4 per shaft node `[y, z, θ_y, θ_z]` (see `timoshenko`), and for
//! each bearing with a pedestal 2 pedestal DOFs `[y, z]` numbered right after
//! the bearing's shaft node, so the matrix stays banded (half-bandwidth ≤ 9).
//! The bearing couples shaft node and pedestal: the force on the pedestal is
//! (K_b + iΩC_b)·(x_shaft − x_ped), the reaction on the shaft the opposite;
//! the pedestal stands on the ground through its own M, K, C (and η).
//! Bases (`super::base`) carry pedestals that may be far apart, sub-bases
//! one pedestal each (the machine's bases first, then the sub-bases in
//! bearing order): their DOFs come after all others, outside the band, and the bordered system is
//! solved by a Schur complement (one extra banded solve per base DOF).
//!
//! Dynamic stiffness at spin Ω [rad/s] (synchronous, excitation at Ω):
//! A(Ω) = K + iΩ(C + Ω·G) − Ω²M + bearings(Ω), with A·X = F and
//! q(t) = Re{X e^{iΩt}}.

use super::banded::{BandError, BandMatrix, BandShape, C64};
use super::base::{BaseBorder, BaseLink};
use super::machine::Machine;
use super::pedestal::PedestalDynamics;
use super::timoshenko::StiffnessForm;
use plinth_shared::bearing::BearingCoefficients;

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
    /// [K, M, G] of every band element (the `kl + ku + 1` band rows of each
    /// column, without LAPACK's fill-in rows), column by column.
    kmg: ColumnTable,
    /// The few nonzero (storage index, imaginary K = η·K, C) of the
    /// pedestals: structural damping and viscous damping live only there.
    damping: Vec<(usize, f64, f64)>,
    /// Storage index of the (shaft, shaft), (shaft, ped), (ped, shaft),
    /// (ped, ped) 2×2 blocks of each bearing (`usize::MAX` when absent).
    bearing_idx: Vec<[[[usize; 2]; 2]; 4]>,
    /// Base DOFs (after the banded part) and their links to pedestals.
    pub bases: BaseBorder,
    /// The distinct shaft-element stiffnesses in deformation form, and which
    /// one each element (between nodes e and e + 1) is: the residual's K.
    stiffness_forms: Vec<StiffnessForm>,
    element_form: Vec<u32>,
}

/// Index into the fill-free band arrays (`kl + ku + 1` rows per column) of
/// LAPACK band storage index `i` (a band row, not a fill-in row).
fn compact(shape: &BandShape, i: usize) -> usize {
    let ldab = shape.ldab();
    (i / ldab) * (ldab - shape.kl) + i % ldab - shape.kl
}

/// One step of the assembly's walk over the model.
enum Visit {
    /// Add a value of a kind at (row, column).
    Add(usize, usize, Kind, f64),
    /// Every column before this one is complete.
    Complete(usize),
}

/// The speed-independent [K, M, G] band columns, each distinct column
/// stored once (identical elements give identical columns), so memory and
/// the bytes read per speed do not grow with a uniform mesh's fineness.
#[derive(Clone, Debug)]
struct ColumnTable {
    width: usize,
    /// Distinct columns, `width` entries each.
    distinct: Vec<[f64; 3]>,
    /// Which distinct column each matrix column is.
    of_column: Vec<u32>,
    /// Distinct column by its bit pattern.
    seen: std::collections::HashMap<Vec<u64>, u32>,
}

impl ColumnTable {
    fn new(width: usize, n: usize) -> Self {
        Self {
            width,
            distinct: Vec::new(),
            of_column: Vec::with_capacity(n),
            seen: Default::default(),
        }
    }

    /// Appends the next matrix column.
    fn push(&mut self, column: &[[f64; 3]]) {
        let key: Vec<u64> = column.iter().flatten().map(|v| v.to_bits()).collect();
        let next = (self.distinct.len() / self.width.max(1)) as u32;
        let id = *self.seen.entry(key).or_insert_with(|| {
            self.distinct.extend_from_slice(column);
            next
        });
        self.of_column.push(id);
    }

    /// Column `c`'s `width` band entries.
    fn column(&self, c: usize) -> &[[f64; 3]] {
        let id = self.of_column[c] as usize;
        &self.distinct[id * self.width..(id + 1) * self.width]
    }
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
    /// bearing, `None` for rigid ground; `None` must match the machine).
    pub fn new(
        machine: &Machine,
        pedestals: &[Option<PedestalDynamics>],
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
        // Every structural entry, visited twice (band pattern, then values)
        // node by node, in the order the entries were always summed:
        // element i − 1, then node i − 1's disks, pedestals and bearings;
        // after that, every column before node i is complete
        // (`Visit::Complete`). Nothing per element is stored.
        let visit = |on: &mut dyn FnMut(Visit)| {
            for node in 1..=nn {
                let e = node - 1;
                if let Some(el) = machine.elements.get(e).filter(|_| node < nn) {
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
                            on(Visit::Add(dof(i), dof(j), Kind::M, me[i][j]));
                            on(Visit::Add(dof(i), dof(j), Kind::KRe, ke[i][j]));
                            on(Visit::Add(dof(i), dof(j), Kind::G, ge[i][j]));
                        }
                    }
                }
                for d in machine.disks.iter().filter(|d| d.node == e) {
                    let (md, gd) = (d.mass_matrix(), d.gyroscopic_matrix());
                    let base = node_dof[d.node];
                    for i in 0..4 {
                        for j in 0..4 {
                            on(Visit::Add(base + i, base + j, Kind::M, md[i][j]));
                            on(Visit::Add(base + i, base + j, Kind::G, gd[i][j]));
                        }
                    }
                }
                for (b, brg) in machine.bearings.iter().enumerate() {
                    if brg.node != e {
                        continue;
                    }
                    if let (Some(p), Some(pd)) = (&pedestals[b], pedestal_dof[b]) {
                        for i in 0..2 {
                            on(Visit::Add(pd + i, pd + i, Kind::M, p.m[i]));
                            for j in 0..2 {
                                on(Visit::Add(pd + i, pd + j, Kind::KRe, p.k[i][j]));
                                on(Visit::Add(pd + i, pd + j, Kind::KIm, p.eta * p.k[i][j]));
                                on(Visit::Add(pd + i, pd + j, Kind::C, p.c[i][j]));
                            }
                        }
                    }
                }
                // Bearing blocks take part in the band pattern.
                for (b, brg) in machine.bearings.iter().enumerate() {
                    if brg.node != e {
                        continue;
                    }
                    let s = node_dof[brg.node];
                    let mut pair = |r: usize, c: usize| on(Visit::Add(r, c, Kind::KRe, 0.0));
                    pair(s, s + 1);
                    pair(s + 1, s);
                    if let Some(p) = pedestal_dof[b] {
                        pair(s, p + 1);
                        pair(p + 1, s);
                        pair(s + 1, p + 1);
                        pair(p + 1, s + 1);
                    }
                }
                on(Visit::Complete(
                    node_dof.get(node).copied().unwrap_or(n_dof),
                ));
            }
        };
        let (mut kl, mut ku) = (0usize, 0usize);
        visit(&mut |v| {
            if let Visit::Add(r, c, _, _) = v {
                kl = kl.max(r.saturating_sub(c));
                ku = ku.max(c.saturating_sub(r));
            }
        });
        let shape = BandShape { n: n_dof, kl, ku };
        let width = kl + ku + 1;
        // Columns are summed while open (from `first_open` on), then kept
        // once in the table: a shaft section's identical elements give
        // identical columns, so the table stays small however fine the mesh.
        let mut columns = ColumnTable::new(width, n_dof);
        let mut open: std::collections::VecDeque<Vec<[f64; 3]>> = Default::default();
        let mut first_open = 0usize;
        let mut damping_at = std::collections::BTreeMap::<usize, (f64, f64)>::new();
        visit(&mut |v| match v {
            Visit::Add(r, c, kind, v) => {
                if v == 0.0 {
                    return;
                }
                let Some(i) = shape.index(r, c) else { return };
                let slot = match kind {
                    Kind::KRe => 0,
                    Kind::M => 1,
                    Kind::G => 2,
                    Kind::KIm => {
                        damping_at.entry(i).or_default().0 += v;
                        return;
                    }
                    Kind::C => {
                        damping_at.entry(i).or_default().1 += v;
                        return;
                    }
                };
                // Entries only reach columns not yet complete.
                let Some(k) = c.checked_sub(first_open) else {
                    debug_assert!(false, "entry in completed column {c}");
                    return;
                };
                while open.len() <= k {
                    open.push_back(vec![[0.0; 3]; width]);
                }
                open[k][compact(&shape, i) - c * width][slot] += v;
            }
            Visit::Complete(before) => {
                while first_open < before {
                    let column = open.pop_front().unwrap_or_else(|| vec![[0.0; 3]; width]);
                    columns.push(&column);
                    first_open += 1;
                }
            }
        });
        let damping = damping_at
            .into_iter()
            .map(|(i, (k, c))| (i, k, c))
            .collect();
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
        // The machine's bases, then each sub-base (a base carrying one pedestal).
        let mut all_bases = machine.bases.clone();
        let mut links = Vec::new();
        for (b, brg) in machine.bearings.iter().enumerate() {
            let (Some(p), Some(pd)) = (pedestals[b], pedestal_dof[b]) else {
                continue;
            };
            let base = match (brg.base, &brg.sub_base) {
                (Some(i), _) => i,
                (None, Some(sb)) => {
                    all_bases.push(sb.clone());
                    all_bases.len() - 1
                }
                (None, None) => continue,
            };
            links.push(BaseLink {
                pedestal_dof: pd,
                base,
                pedestal: p,
            });
        }
        let bases = BaseBorder {
            bases: all_bases,
            links,
            first_dof: n_dof,
        };
        let mut stiffness_forms = Vec::new();
        let mut element_form = Vec::with_capacity(nn.saturating_sub(1));
        let mut seen = std::collections::HashMap::<[u64; 3], u32>::new();
        for el in machine.elements.iter().take(nn.saturating_sub(1)) {
            let f = el.stiffness_form();
            let key = [f.length.to_bits(), f.shear.to_bits(), f.bending.to_bits()];
            let id = *seen.entry(key).or_insert_with(|| {
                stiffness_forms.push(f);
                (stiffness_forms.len() - 1) as u32
            });
            element_form.push(id);
        }
        Ok(Assembly {
            n_dof: n_dof + bases.n_dof(),
            node_dof,
            pedestal_dof,
            bearing_node: machine.bearings.iter().map(|b| b.node).collect(),
            shape,
            kmg: columns,
            damping,
            bearing_idx,
            bases,
            stiffness_forms,
            element_form,
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
        let ldab = self.shape.ldab();
        let extras = self.extras(omega, bearings);
        let mut next = 0;
        for (c, storage) in a.data_mut().chunks_exact_mut(ldab).enumerate() {
            next = self.write_column(c, storage, omega, &extras, next);
        }
    }

    /// Fills `a` with the banded part of A(Ω) (as [`Assembly::fill`]) and
    /// factors it, each column written as the elimination reaches it.
    pub fn fill_and_factor(
        &self,
        a: &mut BandMatrix,
        omega: f64,
        bearings: &[BearingCoefficients<f64>],
    ) -> Result<(), BandError> {
        let extras = self.extras(omega, bearings);
        let mut next = 0;
        a.factor_with(|c, storage| next = self.write_column(c, storage, omega, &extras, next))
    }

    /// The few entries of A(Ω) beyond K − Ω²M + iΩ²G: the pedestals'
    /// damping and the bearings, as (storage index, value) sorted by index
    /// (so by column).
    fn extras(&self, omega: f64, bearings: &[BearingCoefficients<f64>]) -> Vec<(usize, C64)> {
        let mut extras: Vec<(usize, C64)> = self
            .damping
            .iter()
            .map(|&(i, k_im, c)| (i, C64::new(0.0, k_im + omega * c)))
            .collect();
        for (blocks, coef) in self.bearing_idx.iter().zip(bearings) {
            for i in 0..2 {
                for j in 0..2 {
                    let z = C64::new(coef.k[i][j], omega * coef.c[i][j]);
                    for (blk, sign) in blocks.iter().zip([1.0, -1.0, -1.0, 1.0]) {
                        let idx = blk[i][j];
                        if idx != usize::MAX {
                            extras.push((idx, z * sign));
                        }
                    }
                }
            }
        }
        extras.sort_by_key(|e| e.0);
        extras
    }

    /// Writes column `c`'s band storage at spin Ω [rad/s]: fill-in rows
    /// zero, K − Ω²M + iΩ²G, plus the `extras` of this column, which start at
    /// `extras[next]` (columns are written in increasing order); returns
    /// the first extra of a later column.
    fn write_column(
        &self,
        c: usize,
        storage: &mut [C64],
        omega: f64,
        extras: &[(usize, C64)],
        mut next: usize,
    ) -> usize {
        let (kl, ldab) = (self.shape.kl, self.shape.ldab());
        let w2 = omega * omega;
        let (fill, band) = storage.split_at_mut(kl);
        fill.fill(C64::new(0.0, 0.0));
        for (d, &[k, m, g]) in band.iter_mut().zip(self.kmg.column(c)) {
            *d = C64::new(k - w2 * m, w2 * g);
        }
        let end = (c + 1) * ldab;
        while let Some(&(i, v)) = extras.get(next) {
            if i >= end {
                break;
            }
            if i >= c * ldab {
                storage[i - c * ldab] += v;
            }
            next += 1;
        }
        next
    }

    /// Dense real stiffness (structure, pedestals, bases and the bearing
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
                    let [ki, mi, _] = self.kmg.column(c)
                        [compact(&self.shape, i) - c * (self.shape.kl + self.shape.ku + 1)];
                    k[(r, c)] = ki;
                    m[(r, c)] = mi;
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
        (k, m)
    }

    /// Solves A(Ω)·x = f at spin Ω [rad/s] with bearing coefficients
    /// `bearings` (the speed `a` was filled and factored at): the factored
    /// banded part `a`, each banded solve refined (`super::refine`) with
    /// residuals free of cancellation ([`Assembly::residual`]), and the
    /// bases;
    /// `f` (length `n_dof`) is overwritten by x.
    pub fn solve(
        &self,
        a: &BandMatrix,
        omega: f64,
        bearings: &[BearingCoefficients<f64>],
        f: &mut [C64],
    ) -> Result<(), BandError> {
        if f.len() != self.n_dof {
            return Err(BandError::Dimension {
                expected: self.n_dof,
                got: f.len(),
            });
        }
        let extras = self.extras(omega, bearings);
        self.bases.solve(
            omega,
            f,
            |r| {
                super::refine::solve_refined(a, r, |x, b, res| {
                    self.residual(omega, &extras, x, b, res)
                })
                .map(|_| ())
            },
            |column| BandError::Singular { column },
        )
    }

    /// r = b − A0(Ω)·x for the banded part A0 at spin Ω [rad/s] with its
    /// `extras` ([`Assembly::extras`]), without cancellation: the shaft's
    /// stiffness from each element's deformations
    /// ([`StiffnessForm::forces`]: on a fine mesh the matrix entries κGA/h
    /// are huge and cancel, the deformation forces do not), −Ω²M, iΩ²G,
    /// the pedestals' stiffness and the extras from their entries.
    fn residual(&self, omega: f64, extras: &[(usize, C64)], x: &[C64], b: &[C64], r: &mut [C64]) {
        let (n, kl, ku, ldab) = (
            self.shape.n,
            self.shape.kl,
            self.shape.ku,
            self.shape.ldab(),
        );
        let w2 = omega * omega;
        r.copy_from_slice(b);
        // Band entry d of column c is row c + d − ku: rows c − ku ..= c + kl
        // inside the matrix. −(−Ω²m + iΩ²g)·x_c = m·y − i·g·y, y = Ω²x_c.
        for (c, &xc) in x.iter().enumerate().take(n) {
            if xc.re == 0.0 && xc.im == 0.0 {
                continue;
            }
            let y = xc * w2;
            let (top, end) = (c.saturating_sub(ku), (c + kl + 1).min(n));
            let column = &self.kmg.column(c)[top + ku - c..end + ku - c];
            for (ri, &[_, m, g]) in r[top..end].iter_mut().zip(column) {
                ri.re += m * y.re + g * y.im;
                ri.im += m * y.im - g * y.re;
            }
        }
        // K in the table is the shaft's (rebuilt below) and the pedestals'.
        let row = |c: usize, d: usize| (c + d).checked_sub(ku).filter(|&r| r < n);
        for &p in self.pedestal_dof.iter().flatten() {
            for (c, &xc) in x.iter().enumerate().skip(p).take(2) {
                for (d, &[k, _, _]) in self.kmg.column(c).iter().enumerate() {
                    if let (Some(i), true) = (row(c, d), k != 0.0) {
                        r[i] -= xc * k;
                    }
                }
            }
        }
        for (e, &form) in self.element_form.iter().enumerate() {
            let (d0, d1) = (self.node_dof[e], self.node_dof[e + 1]);
            let q = std::array::from_fn(|i| if i < 4 { x[d0 + i] } else { x[d1 + i - 4] });
            let f = self.stiffness_forms[form as usize].forces(&q);
            for i in 0..4 {
                r[d0 + i] -= f[i];
                r[d1 + i] -= f[i + 4];
            }
        }
        for &(i, v) in extras {
            let c = i / ldab;
            r[(i % ldab + c) - (kl + ku)] -= v * x[c];
        }
    }
}
