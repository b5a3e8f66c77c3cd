//! The machine file: a rotor-bearing-pedestal machine in TOML, and its
//! validation into a [`Machine`].
//!
//! # Format (SI units everywhere: m, kg, s, N, Pa, Pa·s; angles in degrees)
//!
//! ```toml
//! name = "example"                 # optional
//! gravity = 9.80665                # optional [m/s²], used by load = "weight"
//!
//! [shaft]
//! start = 0.0                      # optional: axial position of node 0 [m]
//! # Default material of every section (a section may give its own `material`).
//! # Give young_modulus [Pa], density [kg/m³] and one of shear_modulus [Pa]
//! # or poisson_ratio [-] (G = E / (2(1+ν))).
//! material = { young_modulus = 2.11e11, poisson_ratio = 0.3, density = 7810.0 }
//!
//! [[shaft.sections]]               # left to right along the rotor axis x
//! length = 0.2                     # [m]
//! outer_diameter = 0.05            # [m]
//! inner_diameter = 0.0             # optional [m], default 0 (solid)
//! elements = 2                     # optional: Timoshenko elements, default 1
//!
//! [[disks]]                        # rigid disks
//! node = 3                         # shaft node, or `position = 0.45` [m] (must be a node)
//! mass = 20.0                      # [kg] and inertias [kg·m²] ...
//! polar_inertia = 0.3
//! diametral_inertia = 0.15
//! # ... or geometry instead: width, outer_diameter, inner_diameter [m], density [kg/m³]
//! unbalance = 1.0e-4               # optional m·e [kg·m]
//! unbalance_angle = 0.0            # optional [deg], from +y towards +z at the keyphasor
//!
//! [[bearings]]
//! name = "left"                    # used as `bearing` in run directories
//! node = 0                         # or position [m]
//! # Either a speed table of the 8 coefficients (K [N/m], C [N·s/m]; one row =
//! # constant; several rows = linear interpolation, no extrapolation) ...
//! coefficients = [ { speed_hz = 0.0, kyy = 1e8, kzz = 1e8, cyy = 1e3, czz = 1e3 } ]
//! # ... or a plain cylindrical oil-film bearing (short-bearing theory):
//! # oil_film = { diameter = 0.1, length = 0.0254, clearance = 1e-4,
//! #              viscosity = 0.0069, load = "weight" }   # or load = 1500.0 [N]
//! pedestal = { m = 200.0, k_y = 1e7, k_z = 8e6, c_y = 0.0, c_z = 0.0 }
//! # Omit `pedestal` for a bearing on rigid ground.
//! base = "skid"                    # optional: the pedestal stands on this base
//! # ... or on its own flexible sub-base (not measured; a two-DOF pedestal):
//! # sub_base = { m = 150.0, k_y = 2e7, k_z = 1.6e7, c_y = 2e3, c_z = 2e3 }
//! #   (m or m_y and m_z [kg], k to ground [N/m], optional c [N·s/m], eta [-])
//!
//! [[base]]                         # optional rigid bases (skid, baseplate, frame)
//! name = "skid"
//! m = 400.0                        # [kg], or m_y and m_z per direction
//! k_y = 5e7                        # stiffness to ground [N/m]
//! k_z = 4e7
//! c_y = 2e3                        # optional viscous damping to ground [N·s/m]
//! c_z = 2e3
//! eta = 0.0                        # optional hysteretic loss factor [-]
//!
//! [[unbalance]]                    # optional extra unbalances at shaft nodes
//! node = 5                         # or position [m]
//! magnitude = 5.0e-5               # m·e [kg·m]
//! angle = 90.0                     # [deg]
//! ```
//!
//! Coefficient keys missing from a table row are zero. `load = "weight"`
//! gives each oil-film bearing its share of the weight of the rotor (shaft
//! and disks, not the pedestals) from statics: the shaft on rigid supports at
//! the bearing nodes (the lever rule for two bearings).
//!
//! Node numbering: node 0 at `shaft.start`, one node per element end, left to
//! right. Every problem is reported with the key it concerns, e.g.
//! `shaft.sections[3].outer_diameter: must be > inner_diameter (got 0.05 <= 0.06)`.
//!
//! This module holds the validated machine; reading the file (its TOML schema
//! and checks) is [`super::machine_file`], the rotor's weight on the bearings
//! [`super::static_load`].

use super::base::Base;
use super::disk::Disk;
use super::oil_film::OilFilmBearing;
use super::timoshenko::ShaftElement;
use crate::estimate::Pedestal;
use plinth_shared::bearing::BearingCoefficients;

/// A problem with a machine file, naming the file and the key.
#[derive(Debug, thiserror::Error)]
pub enum MachineError {
    /// The file could not be read.
    #[error("{file}: {source}")]
    Io {
        /// File name.
        file: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// TOML syntax or type error (the message gives line and column).
    #[error("{file}: {message}")]
    Parse {
        /// File name.
        file: String,
        /// The parser's message.
        message: String,
    },
    /// A value that parses but makes no physical sense.
    #[error("{file}: {key}: {message}")]
    Invalid {
        /// File name.
        file: String,
        /// The offending key, e.g. `shaft.sections[3].outer_diameter`.
        key: String,
        /// What is wrong, with the value.
        message: String,
    },
    /// A request about a machine that it cannot answer (unknown bearing...).
    #[error("{0}")]
    Request(String),
}

// ---------------------------------------------------------------- validated

/// How a bearing's coefficients are obtained at a speed.
#[derive(Clone, Debug, PartialEq)]
pub enum BearingModel {
    /// A speed table: (speed [Hz], coefficients); one row = constant, several
    /// rows = linear interpolation in speed, no extrapolation.
    Table(Vec<(f64, BearingCoefficients<f64>)>),
    /// A plain cylindrical oil-film bearing (short-bearing theory), with its
    /// static load already resolved.
    OilFilm(OilFilmBearing),
}

/// One bearing: where it is, its oil film or table, and its pedestal.
#[derive(Clone, Debug, PartialEq)]
pub struct Bearing {
    /// Name used as `bearing` in run directories.
    pub name: String,
    /// Shaft node the journal is at.
    pub node: usize,
    /// Coefficient model.
    pub model: BearingModel,
    /// The pedestal under the bearing; `None` = bearing on rigid ground.
    pub pedestal: Option<Pedestal>,
    /// Index into [`Machine::bases`] of the base the pedestal stands on;
    /// `None` = the pedestal stands on rigid ground.
    pub base: Option<usize>,
    /// The pedestal's own flexible sub-base (effect `pedestal_sub_base`):
    /// the pedestal's k, c act between pedestal and sub-base, the sub-base
    /// stands on the ground; `None` = no sub-base. Not with [`Bearing::base`].
    pub sub_base: Option<Base>,
}

/// An unbalance m·e at a shaft node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unbalance {
    /// Shaft node.
    pub node: usize,
    /// m·e [kg·m].
    pub magnitude: f64,
    /// Angular position at the keyphasor instant (t = 0) [deg], measured from
    /// +y towards +z (the direction of rotation).
    pub angle_deg: f64,
}

/// A validated machine: shaft elements, disks, bearings with pedestals,
/// unbalance. Built from a machine file or programmatically (then check it
/// with [`Machine::validate`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Machine {
    /// Name from the file (or the file stem).
    pub name: String,
    /// Axial position of each shaft node [m].
    pub node_positions: Vec<f64>,
    /// Shaft elements, element e between nodes e and e + 1.
    pub elements: Vec<ShaftElement>,
    /// Rigid disks.
    pub disks: Vec<Disk>,
    /// Bearings (with pedestals), in file order.
    pub bearings: Vec<Bearing>,
    /// Unbalance distribution (disk unbalances included).
    pub unbalances: Vec<Unbalance>,
    /// Gravitational acceleration [m/s²].
    pub gravity: f64,
    /// Bases that pedestals stand on (file order; see [`super::base`]).
    pub bases: Vec<Base>,
}

/// Standard gravity [m/s²].
pub const STANDARD_GRAVITY: f64 = 9.80665;

impl Machine {
    /// Names of the bearings in file order (the `bearing` column of run directories).
    pub fn bearing_names(&self) -> Vec<String> {
        self.bearings.iter().map(|b| b.name.clone()).collect()
    }

    /// Index of the bearing called `name`.
    pub fn bearing_index(&self, name: &str) -> Result<usize, MachineError> {
        self.bearings
            .iter()
            .position(|b| b.name == name)
            .ok_or_else(|| {
                MachineError::Request(format!(
                    "no bearing named {name:?} (bearings: {})",
                    self.bearing_names().join(", ")
                ))
            })
    }

    /// The pedestal under bearing `name` (`None` for rigid ground).
    pub fn pedestal(&self, name: &str) -> Result<Option<Pedestal>, MachineError> {
        Ok(self.bearings[self.bearing_index(name)?].pedestal)
    }

    /// Replaces the pedestal under bearing `name` (e.g. with identified values
    /// for `plinth predict`); `None` puts the bearing on rigid ground.
    pub fn set_pedestal(
        &mut self,
        name: &str,
        pedestal: Option<Pedestal>,
    ) -> Result<(), MachineError> {
        let i = self.bearing_index(name)?;
        if let Some(p) = pedestal {
            let values = [
                ("m", p.m, false),
                ("k_y", p.k_y, true),
                ("k_z", p.k_z, true),
                ("c_y", p.c_y, true),
                ("c_z", p.c_z, true),
            ];
            for (key, v, zero_allowed) in values {
                if let Some(why) = not_a_quantity(v, zero_allowed) {
                    return Err(MachineError::Request(format!(
                        "pedestal for {name:?}: {key} {why}: m must be > 0 and k, c finite and >= 0 (got {p:?})"
                    )));
                }
            }
        }
        self.bearings[i].pedestal = pedestal;
        Ok(())
    }

    /// Coefficients of bearing `index` at `speed_hz` [Hz]: K [N/m], C [N·s/m].
    pub fn bearing_coefficients(
        &self,
        index: usize,
        speed_hz: f64,
    ) -> Result<BearingCoefficients<f64>, MachineError> {
        let b = self
            .bearings
            .get(index)
            .ok_or_else(|| MachineError::Request(format!("bearing index {index} out of range")))?;
        b.model.coefficients_at(&b.name, speed_hz)
    }

    /// Total rotor mass (shaft and disks) [kg].
    pub fn rotor_mass(&self) -> f64 {
        self.elements.iter().map(ShaftElement::mass).sum::<f64>()
            + self.disks.iter().map(|d| d.mass).sum::<f64>()
    }

    /// Checks a machine built in code (files are checked when read).
    pub fn validate(&self) -> Result<(), MachineError> {
        let bad = |m: String| Err(MachineError::Request(m));
        if self.elements.is_empty() || self.node_positions.len() != self.elements.len() + 1 {
            return bad("machine needs shaft elements and one more node position".into());
        }
        let nn = self.node_positions.len();
        for (i, e) in self.elements.iter().enumerate() {
            let ok = e.length > 0.0
                && e.outer_diameter > e.inner_diameter
                && e.inner_diameter >= 0.0
                && e.young > 0.0
                && e.shear > 0.0
                && e.density > 0.0
                && [e.length, e.outer_diameter, e.young, e.shear, e.density]
                    .iter()
                    .all(|v| v.is_finite());
            if !ok {
                return bad(format!("shaft element {i} is not physical: {e:?}"));
            }
        }
        for d in &self.disks {
            if d.node >= nn || d.mass.is_nan() || d.mass <= 0.0 {
                return bad(format!("disk {d:?}: node out of range or mass not > 0"));
            }
        }
        if self.bearings.is_empty() {
            return bad("machine needs at least one bearing".into());
        }
        for b in &self.bearings {
            if b.node >= nn {
                return bad(format!(
                    "bearing {:?}: node {} out of range",
                    b.name, b.node
                ));
            }
        }
        for (i, base) in self.bases.iter().enumerate() {
            if let Err(m) = base.check() {
                return bad(format!("base {i} ({:?}): {m}", base.name));
            }
        }
        for b in &self.bearings {
            if let Some(i) = b.base {
                if i >= self.bases.len() || b.pedestal.is_none() {
                    return bad(format!(
                        "bearing {:?}: base {i} does not exist or the bearing has no pedestal",
                        b.name
                    ));
                }
            }
        }
        for b in &self.bearings {
            if let Some(sb) = &b.sub_base {
                if b.pedestal.is_none() || b.base.is_some() {
                    return bad(format!(
                        "bearing {:?}: a sub-base needs a pedestal on it and no base",
                        b.name
                    ));
                }
                if let Err(m) = sb.check() {
                    return bad(format!("bearing {:?}: sub-base: {m}", b.name));
                }
            }
        }
        for u in &self.unbalances {
            if u.node >= nn {
                return bad(format!("unbalance at node {} out of range", u.node));
            }
        }
        Ok(())
    }
}

impl BearingModel {
    /// Coefficients at `speed_hz` [Hz]: K [N/m], C [N·s/m]; errors name
    /// the bearing `name`.
    pub fn coefficients_at(
        &self,
        name: &str,
        speed_hz: f64,
    ) -> Result<BearingCoefficients<f64>, MachineError> {
        match self {
            BearingModel::Table(rows) => table_at(rows, speed_hz).ok_or_else(|| {
                let lo = rows.first().map_or(0.0, |r| r.0);
                let hi = rows.last().map_or(0.0, |r| r.0);
                MachineError::Request(format!(
                    "bearing {name:?}: speed {speed_hz} Hz is outside its coefficient table ({lo}..{hi} Hz; no extrapolation)"
                ))
            }),
            BearingModel::OilFilm(of) => of
                .coefficients(speed_hz)
                .map_err(|e| MachineError::Request(format!("bearing {name:?}: {e}"))),
        }
    }
}

/// Why `v` cannot be a physical quantity of a machine (a mass [kg], a
/// stiffness [N/m], a damping [N·s/m], a length [m]...), or `None` when it
/// can: not a number, infinite, negative, zero unless `zero_allowed`, or
/// subnormal (nonzero but below 2.2e-308, `f64::MIN_POSITIVE`, where a
/// double has lost digits and a ratio such as k/m overflows: 1e-310 kg is no
/// mass, and a unit slip rather than a machine). The reason is a phrase
/// starting "got", to follow "must be ...".
pub fn not_a_quantity(v: f64, zero_allowed: bool) -> Option<String> {
    if !v.is_finite() || v < 0.0 || (v == 0.0 && !zero_allowed) {
        Some(format!("got {v}"))
    } else if v != 0.0 && !v.is_normal() {
        Some(format!(
            "got {v:e}, a subnormal number below 2.2e-308 (`f64::MIN_POSITIVE`): no physical value; check the units{}",
            if zero_allowed { ", or write 0" } else { "" }
        ))
    } else {
        None
    }
}

/// Coefficients from a speed table: constant for one row (a machine file's
/// speed-independent bearing), else [`plinth_shared::bearing::interpolate`]
/// (linear between rows, `None` outside the listed speeds).
fn table_at(
    rows: &[(f64, BearingCoefficients<f64>)],
    speed_hz: f64,
) -> Option<BearingCoefficients<f64>> {
    match rows {
        [(_, c)] => Some(*c),
        _ => {
            let (speeds, coefficients): (Vec<f64>, Vec<BearingCoefficients<f64>>) =
                rows.iter().copied().unzip();
            plinth_shared::bearing::interpolate(&speeds, &coefficients, speed_hz)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = r#"
        [shaft]
        material = { young_modulus = 2.11e11, poisson_ratio = 0.3, density = 7810.0 }
        [[shaft.sections]]
        length = 0.5
        outer_diameter = 0.05
        elements = 2
        [[shaft.sections]]
        length = 0.5
        outer_diameter = 0.05
        elements = 2
        [[disks]]
        position = 0.5
        width = 0.05
        outer_diameter = 0.3
        density = 7810.0
        unbalance = 1e-4
        [[bearings]]
        name = "left"
        node = 0
        oil_film = { diameter = 0.05, length = 0.02, clearance = 5e-5, viscosity = 0.0069, load = "weight" }
        pedestal = { m = 100.0, k_y = 1e7, k_z = 8e6 }
        [[bearings]]
        name = "right"
        position = 1.0
        coefficients = [ { speed_hz = 0.0, kyy = 1e8, kzz = 1e8 } ]
    "#;

    #[test]
    fn weight_share_of_a_symmetric_rotor_is_half() {
        let m = Machine::from_toml_str(BASE, "t.toml").unwrap();
        assert_eq!(m.node_positions.len(), 5);
        assert_eq!(m.disks[0].node, 2);
        let loads = m.static_bearing_loads().unwrap();
        let w = m.rotor_mass() * STANDARD_GRAVITY;
        assert!((loads[0] - w / 2.0).abs() < 1e-9 * w);
        assert!((loads[1] - w / 2.0).abs() < 1e-9 * w);
        match &m.bearings[0].model {
            BearingModel::OilFilm(of) => assert!((of.load - w / 2.0).abs() < 1e-9 * w),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn errors_name_the_key() {
        let bad = BASE.replacen("outer_diameter = 0.05\n        elements = 2\n        [[disks]]", "outer_diameter = 0.05\n        inner_diameter = 0.06\n        elements = 2\n        [[disks]]", 1);
        let e = Machine::from_toml_str(&bad, "m.toml")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "m.toml: shaft.sections[1].outer_diameter: must be > inner_diameter (got 0.05 <= 0.06)"
        );
        let bad = BASE.replace("position = 0.5", "position = 0.51");
        let e = Machine::from_toml_str(&bad, "m.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("disks[0].position"), "{e}");
        let bad = BASE.replace("k_z = 8e6", "k_z = -8e6");
        let e = Machine::from_toml_str(&bad, "m.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("bearings[0].pedestal.k_z"), "{e}");
        let bad = BASE.replace("name = \"right\"", "name = \"left\"");
        let e = Machine::from_toml_str(&bad, "m.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("bearings[1].name"), "{e}");
        let bad = BASE.replace("elements = 2", "elemnts = 2");
        let e = Machine::from_toml_str(&bad, "m.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("elemnts") && e.contains("line"), "{e}");
    }

    /// A machine file's bearing names follow the one name rule
    /// (`crate::names`): a field name like `Brg. 2 (DE)` is accepted, a
    /// path or a CSV separator is refused at its key.
    #[test]
    fn bearing_names_follow_the_one_name_rule() {
        let ok = BASE.replace("name = \"right\"", "name = \"Brg. 2 (DE)\"");
        let m = Machine::from_toml_str(&ok, "m.toml").unwrap();
        assert_eq!(m.bearings[1].name, "Brg. 2 (DE)");
        for bad in ["../x", "DE/NDE", "a,b", "", ".."] {
            let text = BASE.replace("name = \"right\"", &format!("name = {bad:?}"));
            let e = Machine::from_toml_str(&text, "m.toml")
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with("m.toml: bearings[1].name: bearing `"),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn table_interpolates_and_refuses_to_extrapolate() {
        let c = |k: f64| BearingCoefficients::<f64>::isotropic(k, 0.0);
        let rows = vec![(10.0, c(1.0)), (20.0, c(3.0))];
        assert_eq!(table_at(&rows, 15.0).unwrap().k[0][0], 2.0);
        assert!(table_at(&rows, 25.0).is_none());
        assert_eq!(table_at(&rows[..1], 99.0).unwrap().k[0][0], 1.0);
    }
}
