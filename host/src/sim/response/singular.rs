//! Why a speed could not be solved, said in the machine file's words: a zero
//! pivot (nothing holds a DOF at that speed) or a pivot beyond double
//! precision's range (a value far too large), each named by the DOF's place
//! (a pedestal, a shaft node, the bases) and the keys that set it.

use super::{SimError, UnbalanceSolver};
use crate::sim::banded::BandError;
use crate::sim::machine::BearingModel;

/// Names of the DOF directions of a node (pedestals use the first two).
const DIRS: [&str; 4] = ["y", "z", "θ_y", "θ_z"];

/// The largest term magnitude the solver can square (it compares pivots by
/// |a|²): √f64::MAX ≈ 1.34e154.
const SQUARE_LIMIT: f64 = 1.3407807929942596e154;

/// Where a DOF of the assembled model is.
enum Place {
    /// Bearing `b`'s pedestal, direction `d` (0 = y, 1 = z).
    Pedestal { b: usize, d: usize },
    /// Shaft node `node`, direction `d` (0..4: y, z, θ_y, θ_z).
    Shaft { node: usize, d: usize },
    /// A base DOF (the bordered part).
    Base,
}

impl UnbalanceSolver {
    /// The [`SimError`] of a factorisation or solve that failed at
    /// `speed_hz` [Hz]: [`SimError::Overflow`] for a pivot beyond double
    /// precision, else [`SimError::Singular`].
    pub(super) fn solver_failure(&self, e: &BandError, speed_hz: f64) -> SimError {
        match *e {
            BandError::Overflow { column } => SimError::Overflow {
                speed_hz,
                detail: self.where_overflow(column, speed_hz),
            },
            _ => SimError::Singular {
                speed_hz,
                detail: self.where_singular(e, speed_hz),
            },
        }
    }

    /// The place of DOF `column`.
    fn place(&self, column: usize) -> Place {
        if column >= self.assembly.bases.first_dof {
            return Place::Base;
        }
        for (b, p) in self.assembly.pedestal_dof.iter().enumerate() {
            if let Some(p) = *p {
                if (p..p + 2).contains(&column) {
                    return Place::Pedestal { b, d: column - p };
                }
            }
        }
        let node = self
            .assembly
            .node_dof
            .iter()
            .rposition(|&d| d <= column)
            .unwrap_or(0);
        let d = (column - self.assembly.node_dof[node]).min(3);
        Place::Shaft { node, d }
    }

    /// Axial position [m] of shaft node `node`.
    fn node_x(&self, node: usize) -> f64 {
        self.machine
            .node_positions
            .get(node)
            .copied()
            .unwrap_or(0.0)
    }

    /// Names the machine-file keys behind a zero pivot at `speed_hz` [Hz].
    pub(super) fn where_singular(&self, e: &BandError, speed_hz: f64) -> String {
        let BandError::Singular { column } = *e else {
            return e.to_string();
        };
        match self.place(column) {
            Place::Base => "the bases with their pedestals are singular at this speed: check the [[base]] and the bearings' sub_base m, k_y, k_z".into(),
            Place::Pedestal { b, d } => {
                let name = &self.machine.bearings[b].name;
                let d = DIRS[d];
                format!(
                    "the pedestal of bearings[{b}] (name = {name:?}) has no dynamic stiffness against {d} motion at this speed (k_{d} − ω²·m + iω·c_{d} with its bearing's vanishes): check its `pedestal = {{ m, k_{d}, c_{d} }}`"
                )
            }
            Place::Shaft { node, d } => {
                let x = self.node_x(node);
                let near = self.coefficient_sources(speed_hz);
                format!(
                    "nothing holds shaft node {node} (x = {x} m) in {} at {speed_hz} Hz: check the bearing coefficients (kyy, kzz) in force at this speed: {near}",
                    DIRS[d]
                )
            }
        }
    }

    /// Names the machine-file key behind a pivot (or a solution) beyond
    /// double precision's range at `speed_hz` [Hz] at DOF `column`.
    pub(super) fn where_overflow(&self, column: usize, speed_hz: f64) -> String {
        let why = format!(
            "the solver squares each pivot, which overflows double precision above about {SQUARE_LIMIT:.1e}"
        );
        match self.place(column) {
            Place::Base => format!(
                "the bases with their pedestals hold a number beyond double precision's range at this speed ({why}): check the [[base]] and the bearings' sub_base m, k_y, k_z for a value far too large (a unit mistake?)"
            ),
            Place::Pedestal { b, d } => self.pedestal_overflow(b, d, speed_hz, &why),
            Place::Shaft { node, d } => {
                let x = self.node_x(node);
                let near = self.coefficient_sources(speed_hz);
                let largest = self.largest_bearing_term(node, speed_hz);
                format!(
                    "shaft node {node} (x = {x} m) in {} holds a number beyond double precision's range ({why}){largest}: check for a value far too large (a unit mistake?) in the shaft's sections (E, density, diameters) near x = {x} m and in the bearing coefficients in force at this speed: {near}",
                    DIRS[d]
                )
            }
        }
    }

    /// [`UnbalanceSolver::where_overflow`] at pedestal `b`, direction `d`:
    /// the largest of its stiffness, ω²·mass and ω·damping, by its key.
    fn pedestal_overflow(&self, b: usize, d: usize, speed_hz: f64, why: &str) -> String {
        let name = &self.machine.bearings[b].name;
        let dir = DIRS[d];
        let Some(p) = self.pedestals.get(b).copied().flatten() else {
            return format!(
                "the pedestal of bearings[{b}] (name = {name:?}) holds a number beyond double precision's range in {dir} ({why})"
            );
        };
        let omega = std::f64::consts::TAU * speed_hz;
        let k = p.k[d][d];
        let terms = [
            (format!("k_{dir} = {k:e} N/m"), k.abs(), "stiff"),
            (
                format!(
                    "m = {:e} kg (ω²·m = {:.2e} N/m at this speed)",
                    p.m[d],
                    omega * omega * p.m[d]
                ),
                (omega * omega * p.m[d]).abs(),
                "heavy",
            ),
            (
                format!(
                    "c_{dir} = {:e} N·s/m (ω·c_{dir} = {:.2e} N/m at this speed)",
                    p.c[d][d],
                    omega * p.c[d][d]
                ),
                (omega * p.c[d][d]).abs(),
                "damped",
            ),
        ];
        let (what, size, adjective) = terms
            .iter()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(w, s, a)| (w.as_str(), *s, *a))
            .unwrap_or(("", 0.0, "stiff"));
        if size < SQUARE_LIMIT / 1e6 {
            // None of its own terms is near the limit: a product of the
            // elimination overflowed (the bearing's coefficients, the shaft).
            return format!(
                "the pedestal of bearings[{b}] (name = {name:?}) in {dir}: a number of the elimination there went beyond double precision's range ({why}), its own largest term is only {what}{}: check the bearing coefficients at this speed ({}) for a value far too large (a unit mistake?)",
                self.largest_bearing_term(self.machine.bearings[b].node, speed_hz),
                self.coefficient_sources(speed_hz)
            );
        }
        format!(
            "the pedestal of bearings[{b}] (name = {name:?}) in {dir}: its {what} is too large to compute with ({why}); a pedestal that {adjective} does not move (any value far above its bearing's stiffness gives the same shaft response): give a value whose term stays below about 1e150, or check the units"
        )
    }

    /// ", its largest term: bearings[i] kyy = ... N/m" for a bearing at
    /// `node` whose coefficient term (k, or ω·c) at `speed_hz` [Hz] is near
    /// the squaring limit; empty otherwise.
    fn largest_bearing_term(&self, node: usize, speed_hz: f64) -> String {
        const NAMES: [[&str; 2]; 2] = [["yy", "yz"], ["zy", "zz"]];
        let omega = std::f64::consts::TAU * speed_hz;
        let mut best: Option<(f64, String)> = None;
        for (i, bearing) in self.machine.bearings.iter().enumerate() {
            if bearing.node != node {
                continue;
            }
            let Ok(c) = self.machine.bearing_coefficients(i, speed_hz) else {
                continue;
            };
            for (r, row) in NAMES.iter().enumerate() {
                for (s, n) in row.iter().enumerate() {
                    for (size, text) in [
                        (c.k[r][s].abs(), format!("k{n} = {:e} N/m", c.k[r][s])),
                        (
                            (omega * c.c[r][s]).abs(),
                            format!(
                                "c{n} = {:e} N·s/m (ω·c{n} = {:.2e} N/m)",
                                c.c[r][s],
                                omega * c.c[r][s]
                            ),
                        ),
                    ] {
                        if best.as_ref().is_none_or(|b| size > b.0) {
                            best = Some((
                                size,
                                format!("bearings[{i}] (name = {:?}) {text}", bearing.name),
                            ));
                        }
                    }
                }
            }
        }
        match best {
            Some((size, text)) if size >= SQUARE_LIMIT / 1e6 => {
                format!("; its bearing's largest term: {text}")
            }
            _ => String::new(),
        }
    }

    /// Every bearing's coefficient source at `speed_hz` [Hz], as
    /// `bearings[i] (name = "...", node n): KEY; ...`.
    fn coefficient_sources(&self, speed_hz: f64) -> String {
        self.machine
            .bearings
            .iter()
            .enumerate()
            .map(|(i, b)| {
                format!(
                    "bearings[{i}] (name = {:?}, node {}): {}",
                    b.name,
                    b.node,
                    coefficient_source(i, &b.model, speed_hz)
                )
            })
            .collect::<Vec<_>>()
            .join("; ")
    }
}

/// The machine-file key the coefficients of `bearings[index]` come from at
/// `speed_hz` [Hz]: the `coefficients` table row(s) in force there (one row
/// beyond the table's ends, two around a speed between rows) or the
/// `oil_film`.
fn coefficient_source(index: usize, model: &BearingModel, speed_hz: f64) -> String {
    match model {
        BearingModel::OilFilm(_) => format!("bearings[{index}].oil_film"),
        BearingModel::Table(rows) => {
            let after = rows.partition_point(|(s, _)| *s < speed_hz);
            let key = |r: usize| format!("bearings[{index}].coefficients[{r}]");
            let last = rows.len().saturating_sub(1);
            match after {
                0 => key(0),
                a if a > last => key(last),
                a if rows[a].0 == speed_hz => key(a),
                a => format!("{} and {}", key(a - 1), key(a)),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::inject::EffectSet;
    use crate::sim::machine::Machine;

    /// The paper machine with the left bearing as a two-row coefficient
    /// table (rows at 0 and 10 Hz) and the right one an oil film.
    fn machine() -> Machine {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../examples/feng-hahn-1997.toml"
        ))
        .unwrap();
        let table = "coefficients = [ \
            { speed_hz = 0.0, kyy = 1e8, kyz = 0.0, kzy = 0.0, kzz = 1e8, cyy = 1e3, cyz = 0.0, czy = 0.0, czz = 1e3 }, \
            { speed_hz = 10.0, kyy = 1e8, kyz = 0.0, kzy = 0.0, kzz = 1e8, cyy = 1e3, cyz = 0.0, czy = 0.0, czz = 1e3 } ]";
        let first_oil = text.find("oil_film").unwrap();
        let line_end = first_oil + text[first_oil..].find('\n').unwrap();
        let text = format!("{}{}{}", &text[..first_oil], table, &text[line_end..]);
        Machine::from_toml_str(&text, "m.toml").unwrap()
    }

    #[test]
    fn a_zero_pivot_is_named_by_its_machine_file_key() {
        let m = machine();
        let solver = UnbalanceSolver::new(&m, &EffectSet::none()).unwrap();
        let asm = solver.assembly();
        // A shaft DOF: every bearing's coefficient source at that speed.
        let shaft = asm.node_dof[5] + 1;
        let msg = solver.where_singular(&BandError::Singular { column: shaft }, 5.0);
        assert!(
            msg.contains("shaft node 5") && msg.contains(" in z "),
            "{msg}"
        );
        assert!(
            msg.contains("bearings[0].coefficients[0] and bearings[0].coefficients[1]")
                && msg.contains("bearings[1].oil_film"),
            "{msg}"
        );
        let msg = solver.where_singular(&BandError::Singular { column: shaft }, 10.0);
        assert!(msg.contains("bearings[0].coefficients[1]"), "{msg}");
        assert!(!msg.contains("coefficients[0]"), "{msg}");
        let msg = solver.where_singular(&BandError::Singular { column: shaft }, 50.0);
        assert!(msg.contains("bearings[0].coefficients[1]"), "{msg}");
        // A pedestal DOF: that pedestal's keys.
        let p = asm.pedestal_dof[1].unwrap();
        let msg = solver.where_singular(&BandError::Singular { column: p }, 5.0);
        assert!(
            msg.contains("bearings[1]") && msg.contains("\"right\"") && msg.contains("k_y"),
            "{msg}"
        );
        let err = SimError::Singular {
            speed_hz: 5.0,
            detail: msg,
        };
        assert!(err.to_string().contains("singular at 5 Hz"), "{err}");
    }

    /// The damped paper machine with `from` replaced by `to` in its text.
    fn edited(from: &str, to: &str) -> Machine {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../examples/feng-hahn-1997-damped.toml"
        ))
        .unwrap();
        assert!(text.contains(from), "{from}");
        Machine::from_toml_str(&text.replacen(from, to, 1), "m.toml").unwrap()
    }

    fn failure(m: &Machine) -> String {
        let solver = UnbalanceSolver::new(m, &EffectSet::none()).unwrap();
        solver.run(&[5.0, 50.0]).unwrap_err().to_string()
    }

    #[test]
    fn a_value_too_large_to_square_is_named_as_an_overflow_not_a_missing_stiffness() {
        let pedestal = "pedestal = { m = 80.0, k_y = 10.0e6,";
        let e = failure(&edited(pedestal, "pedestal = { m = 80.0, k_y = 1e300,"));
        assert!(
            e.contains("cannot be solved in double precision")
                && e.contains("bearings[0] (name = \"left\") in y")
                && e.contains("k_y = 1e300 N/m is too large")
                && !e.contains("singular")
                && !e.contains("no stiffness"),
            "{e}"
        );
        let e = failure(&edited(pedestal, "pedestal = { m = 1e300, k_y = 10.0e6,"));
        assert!(e.contains("m = 1e300 kg") && e.contains("heavy"), "{e}");
        // Just below the squaring limit the run is solved (a rigid pedestal).
        let m = edited(pedestal, "pedestal = { m = 80.0, k_y = 1e150,");
        let r = UnbalanceSolver::new(&m, &EffectSet::none())
            .unwrap()
            .run(&[5.0, 50.0])
            .unwrap();
        assert!(
            r.bearings[0][0].ped[0].norm() < 1e-140,
            "{:?}",
            r.bearings[0][0]
        );
        // A bearing coefficient far too large: its shaft node and key.
        let e = failure(&edited("oil_film", "coefficients = [ { speed_hz = 0.0, kyy = 1e300, kyz = 0.0, kzy = 0.0, kzz = 1e8, cyy = 1e3, cyz = 0.0, czy = 0.0, czz = 1e3 } ] # "));
        assert!(
            e.contains("cannot be solved in double precision") && e.contains("kyy = 1e300"),
            "{e}"
        );
    }
}
