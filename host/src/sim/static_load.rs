//! The rotor's weight on its bearings: the static shaft on rigid supports at
//! the bearing nodes, solved banded (linear in the number of elements).

use super::banded::{BandMatrix, C64};
use super::machine::Machine;

impl Machine {
    /// Vertical bearing reactions [N] (upwards on the rotor, per bearing) that
    /// carry the rotor's weight, from the static shaft on rigid supports at
    /// the bearing nodes (vertical plane, Timoshenko stiffness; statically
    /// determinate cases reduce to the lever rule).
    ///
    /// The vertical-plane DOFs (y, θ_z per node) numbered along the shaft give
    /// a stiffness matrix with 3 sub- and super-diagonals; with the supported
    /// DOFs removed it stays within that band, so one banded LU solves it in
    /// O(elements) time and memory.
    pub fn static_bearing_loads(&self) -> Result<Vec<f64>, String> {
        if self.bearings.len() < 2 {
            return Err("needs at least two bearings to carry the rotor's weight".into());
        }
        let nn = self.node_positions.len();
        let n = 2 * nn; // (y, θ_z) per node
                        // Nodal loads [N] and the element stiffness blocks (y1, θz1, y2, θz2).
        let mut f = vec![0.0f64; n];
        let local = [0usize, 3, 4, 7];
        let blocks: Vec<[[f64; 4]; 4]> = self
            .elements
            .iter()
            .map(|el| {
                let ke = el.stiffness_matrix();
                std::array::from_fn(|i| std::array::from_fn(|j| ke[local[i]][local[j]]))
            })
            .collect();
        for (e, el) in self.elements.iter().enumerate() {
            // Element weight, lumped half to each end (exact resultant and moment).
            let w = el.mass() * self.gravity;
            f[2 * e] -= 0.5 * w;
            f[2 * e + 2] -= 0.5 * w;
        }
        for d in &self.disks {
            f[2 * d.node] -= d.mass * self.gravity;
        }
        let mut fixed = vec![false; n];
        for b in &self.bearings {
            fixed[2 * b.node] = true;
        }
        // Free DOFs keep their order: index of each in the reduced system.
        let mut reduced = vec![usize::MAX; n];
        let mut m = 0usize;
        for (i, r) in reduced.iter_mut().enumerate() {
            if !fixed[i] {
                *r = m;
                m += 1;
            }
        }
        let mut k = BandMatrix::zeros(m, 3, 3);
        let mut rhs = vec![C64::new(0.0, 0.0); m];
        for (e, ke) in blocks.iter().enumerate() {
            for i in 0..4 {
                let ri = reduced[2 * e + i];
                if ri == usize::MAX {
                    continue;
                }
                for j in 0..4 {
                    let cj = reduced[2 * e + j];
                    if cj != usize::MAX && ke[i][j] != 0.0 {
                        k.add(ri, cj, C64::new(ke[i][j], 0.0));
                    }
                }
            }
        }
        for i in 0..n {
            if reduced[i] != usize::MAX {
                rhs[reduced[i]] = C64::new(f[i], 0.0);
            }
        }
        k.factor()
            .and_then(|()| k.solve_in_place(&mut rhs))
            .map_err(|e| {
                format!("the shaft on rigid supports at the bearings is singular ({e})")
            })?;
        let u = |i: usize| match reduced[i] {
            usize::MAX => 0.0,
            r => rhs[r].re,
        };
        // Reaction = (K·u)_r − f_r (force the support exerts on the shaft).
        let mut ku = vec![0.0f64; n];
        for (e, ke) in blocks.iter().enumerate() {
            for i in 0..4 {
                if fixed[2 * e + i] {
                    ku[2 * e + i] += (0..4).map(|j| ke[i][j] * u(2 * e + j)).sum::<f64>();
                }
            }
        }
        Ok(self
            .bearings
            .iter()
            .map(|b| ku[2 * b.node] - f[2 * b.node])
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::timoshenko::ShaftElement;

    /// The banded solve against the dense one it replaced, on a shaft with an
    /// overhang and three supports (statically indeterminate).
    #[test]
    fn banded_loads_match_a_dense_solve() {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../examples/feng-hahn-1997.toml"
        ))
        .unwrap();
        let mut machine = Machine::from_toml_str(&text, "feng-hahn-1997.toml").unwrap();
        let loads = machine.static_bearing_loads().unwrap();
        let dense = dense_loads(&machine);
        for (a, b) in loads.iter().zip(&dense) {
            assert!((a - b).abs() <= 1e-9 * b.abs(), "{loads:?} vs {dense:?}");
        }
        let total: f64 = machine.elements.iter().map(ShaftElement::mass).sum::<f64>()
            + machine.disks.iter().map(|d| d.mass).sum::<f64>();
        let sum: f64 = loads.iter().sum();
        assert!((sum - total * machine.gravity).abs() < 1e-9 * sum);
        // A third support in the middle: indeterminate, still the dense answer.
        let mut extra = machine.bearings[0].clone();
        extra.node = machine.node_positions.len() / 2;
        extra.name = "middle".into();
        machine.bearings.push(extra);
        let loads = machine.static_bearing_loads().unwrap();
        let dense = dense_loads(&machine);
        for (a, b) in loads.iter().zip(&dense) {
            assert!(
                (a - b).abs() <= 1e-8 * b.abs().max(1.0),
                "{loads:?} vs {dense:?}"
            );
        }
    }

    fn dense_loads(machine: &Machine) -> Vec<f64> {
        use nalgebra::{DMatrix, DVector};
        let n = 2 * machine.node_positions.len();
        let mut k = DMatrix::<f64>::zeros(n, n);
        let mut f = DVector::<f64>::zeros(n);
        for (e, el) in machine.elements.iter().enumerate() {
            let ke = el.stiffness_matrix();
            let map = [2 * e, 2 * e + 1, 2 * e + 2, 2 * e + 3];
            let local = [0usize, 3, 4, 7];
            for i in 0..4 {
                for j in 0..4 {
                    k[(map[i], map[j])] += ke[local[i]][local[j]];
                }
            }
            let w = el.mass() * machine.gravity;
            f[2 * e] -= 0.5 * w;
            f[2 * e + 2] -= 0.5 * w;
        }
        for d in &machine.disks {
            f[2 * d.node] -= d.mass * machine.gravity;
        }
        let fixed: Vec<usize> = machine.bearings.iter().map(|b| 2 * b.node).collect();
        let free: Vec<usize> = (0..n).filter(|i| !fixed.contains(i)).collect();
        let kff = DMatrix::from_fn(free.len(), free.len(), |i, j| k[(free[i], free[j])]);
        let ff = DVector::from_fn(free.len(), |i, _| f[free[i]]);
        let u = kff.lu().solve(&ff).unwrap();
        fixed
            .iter()
            .map(|&r| {
                free.iter()
                    .enumerate()
                    .map(|(j, &c)| k[(r, c)] * u[j])
                    .sum::<f64>()
                    - f[r]
            })
            .collect()
    }
}
