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

use super::disk::{inertia_from_geometry, Disk};
use super::oil_film::OilFilmBearing;
use super::pedestal::PedestalParams;
use super::timoshenko::ShaftElement;
use nalgebra::{DMatrix, DVector};
use plinth_shared::bearing::BearingCoefficients;
use serde::Deserialize;
use std::path::Path;

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

// ---------------------------------------------------------------- raw TOML

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawMachine {
    name: Option<String>,
    gravity: Option<f64>,
    shaft: RawShaft,
    #[serde(default)]
    disks: Vec<RawDisk>,
    #[serde(default)]
    bearings: Vec<RawBearing>,
    #[serde(default)]
    unbalance: Vec<RawUnbalance>,
}

#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    young_modulus: f64,
    shear_modulus: Option<f64>,
    poisson_ratio: Option<f64>,
    density: f64,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawShaft {
    start: Option<f64>,
    material: Option<RawMaterial>,
    #[serde(default)]
    sections: Vec<RawSection>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawSection {
    length: f64,
    outer_diameter: f64,
    inner_diameter: Option<f64>,
    elements: Option<i64>,
    material: Option<RawMaterial>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawDisk {
    name: Option<String>,
    node: Option<i64>,
    position: Option<f64>,
    mass: Option<f64>,
    polar_inertia: Option<f64>,
    diametral_inertia: Option<f64>,
    width: Option<f64>,
    outer_diameter: Option<f64>,
    inner_diameter: Option<f64>,
    density: Option<f64>,
    unbalance: Option<f64>,
    unbalance_angle: Option<f64>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawCoefficientRow {
    speed_hz: f64,
    #[serde(default)]
    kyy: f64,
    #[serde(default)]
    kyz: f64,
    #[serde(default)]
    kzy: f64,
    #[serde(default)]
    kzz: f64,
    #[serde(default)]
    cyy: f64,
    #[serde(default)]
    cyz: f64,
    #[serde(default)]
    czy: f64,
    #[serde(default)]
    czz: f64,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(untagged)]
enum RawLoad {
    Newton(f64),
    Keyword(String),
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawOilFilm {
    diameter: f64,
    length: f64,
    clearance: f64,
    viscosity: f64,
    load: RawLoad,
}

#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(deny_unknown_fields)]
struct RawPedestal {
    m: f64,
    k_y: f64,
    k_z: f64,
    #[serde(default)]
    c_y: f64,
    #[serde(default)]
    c_z: f64,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawBearing {
    name: String,
    node: Option<i64>,
    position: Option<f64>,
    coefficients: Option<Vec<RawCoefficientRow>>,
    oil_film: Option<RawOilFilm>,
    pedestal: Option<RawPedestal>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawUnbalance {
    node: Option<i64>,
    position: Option<f64>,
    magnitude: f64,
    #[serde(default)]
    angle: f64,
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
    pub pedestal: Option<PedestalParams>,
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
}

/// Standard gravity [m/s²].
pub const STANDARD_GRAVITY: f64 = 9.80665;

struct Ctx<'a> {
    file: &'a str,
}

impl Ctx<'_> {
    fn err(&self, key: impl Into<String>, message: impl Into<String>) -> MachineError {
        MachineError::Invalid {
            file: self.file.to_string(),
            key: key.into(),
            message: message.into(),
        }
    }
    fn positive(&self, key: &str, v: f64) -> Result<f64, MachineError> {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(self.err(key, format!("must be a finite number > 0 (got {v})")))
        }
    }
    fn non_negative(&self, key: &str, v: f64) -> Result<f64, MachineError> {
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(self.err(key, format!("must be a finite number >= 0 (got {v})")))
        }
    }
    fn finite(&self, key: &str, v: f64) -> Result<f64, MachineError> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err(key, format!("must be finite (got {v})")))
        }
    }
}

struct Material {
    young: f64,
    shear: f64,
    density: f64,
}

fn material(ctx: &Ctx, key: &str, m: &RawMaterial) -> Result<Material, MachineError> {
    let young = ctx.positive(&format!("{key}.young_modulus"), m.young_modulus)?;
    let density = ctx.positive(&format!("{key}.density"), m.density)?;
    let shear = match (m.shear_modulus, m.poisson_ratio) {
        (Some(g), None) => ctx.positive(&format!("{key}.shear_modulus"), g)?,
        (None, Some(nu)) => {
            if !(nu.is_finite() && nu > -1.0 && nu < 0.5) {
                return Err(ctx.err(
                    format!("{key}.poisson_ratio"),
                    format!("must lie in (-1, 0.5) (got {nu})"),
                ));
            }
            young / (2.0 * (1.0 + nu))
        }
        (Some(_), Some(_)) => {
            return Err(ctx.err(key, "give either shear_modulus or poisson_ratio, not both"))
        }
        (None, None) => return Err(ctx.err(key, "needs shear_modulus or poisson_ratio")),
    };
    Ok(Material {
        young,
        shear,
        density,
    })
}

/// Node index from `node` or `position` (exactly one), checked.
fn locate(
    ctx: &Ctx,
    key: &str,
    node: Option<i64>,
    position: Option<f64>,
    positions: &[f64],
) -> Result<usize, MachineError> {
    let last = positions.len() - 1;
    match (node, position) {
        (Some(n), None) => {
            if n < 0 || n as usize > last {
                Err(ctx.err(
                    format!("{key}.node"),
                    format!("must be a shaft node 0..={last} (got {n})"),
                ))
            } else {
                Ok(n as usize)
            }
        }
        (None, Some(x)) => {
            let x = ctx.finite(&format!("{key}.position"), x)?;
            let span = positions[last] - positions[0];
            let (i, d) = positions
                .iter()
                .enumerate()
                .map(|(i, p)| (i, (p - x).abs()))
                .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
            if d <= 1e-9 * span.max(1e-3) {
                Ok(i)
            } else {
                Err(ctx.err(
                    format!("{key}.position"),
                    format!(
                        "{x} m is not at a shaft node (nearest: node {i} at {} m); split the shaft sections there",
                        positions[i]
                    ),
                ))
            }
        }
        (Some(_), Some(_)) => Err(ctx.err(key, "give either node or position, not both")),
        (None, None) => Err(ctx.err(key, "needs node or position")),
    }
}

fn bearing_name_ok(name: &str) -> bool {
    !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.')
}

impl Machine {
    /// Reads and validates a machine file.
    pub fn from_toml_path(path: impl AsRef<Path>) -> Result<Machine, MachineError> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| MachineError::Io {
            file: file.clone(),
            source,
        })?;
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "machine".into());
        let mut m = Self::from_toml_str(&text, &file)?;
        if m.name.is_empty() {
            m.name = stem;
        }
        Ok(m)
    }

    /// Parses and validates machine-file text; `file` names it in errors.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Machine, MachineError> {
        let raw: RawMachine = toml::from_str(text).map_err(|e| MachineError::Parse {
            file: file.to_string(),
            message: e.to_string(),
        })?;
        Self::from_raw(raw, file)
    }

    fn from_raw(raw: RawMachine, file: &str) -> Result<Machine, MachineError> {
        let ctx = Ctx { file };
        let gravity = match raw.gravity {
            Some(g) => ctx.non_negative("gravity", g)?,
            None => STANDARD_GRAVITY,
        };
        // Shaft.
        if raw.shaft.sections.is_empty() {
            return Err(ctx.err("shaft.sections", "needs at least one section"));
        }
        let default_material = match &raw.shaft.material {
            Some(m) => Some(material(&ctx, "shaft.material", m)?),
            None => None,
        };
        let start = ctx.finite("shaft.start", raw.shaft.start.unwrap_or(0.0))?;
        let mut node_positions = vec![start];
        let mut elements = Vec::new();
        for (s, sec) in raw.shaft.sections.iter().enumerate() {
            let key = format!("shaft.sections[{s}]");
            let length = ctx.positive(&format!("{key}.length"), sec.length)?;
            let od = ctx.positive(&format!("{key}.outer_diameter"), sec.outer_diameter)?;
            let id = ctx.non_negative(
                &format!("{key}.inner_diameter"),
                sec.inner_diameter.unwrap_or(0.0),
            )?;
            if od <= id {
                return Err(ctx.err(
                    format!("{key}.outer_diameter"),
                    format!("must be > inner_diameter (got {od} <= {id})"),
                ));
            }
            let n = sec.elements.unwrap_or(1);
            if !(1..=10_000).contains(&n) {
                return Err(ctx.err(
                    format!("{key}.elements"),
                    format!("must be between 1 and 10000 (got {n})"),
                ));
            }
            let own;
            let mat = match &sec.material {
                Some(m) => {
                    own = material(&ctx, &format!("{key}.material"), m)?;
                    &own
                }
                None => default_material.as_ref().ok_or_else(|| {
                    ctx.err(
                        format!("{key}.material"),
                        "no material here and no shaft.material default",
                    )
                })?,
            };
            let le = length / n as f64;
            for _ in 0..n {
                elements.push(ShaftElement {
                    length: le,
                    outer_diameter: od,
                    inner_diameter: id,
                    young: mat.young,
                    shear: mat.shear,
                    density: mat.density,
                });
                let last = *node_positions.last().unwrap_or(&start);
                node_positions.push(last + le);
            }
        }
        // Disks.
        let mut disks = Vec::new();
        let mut unbalances = Vec::new();
        for (d, raw_disk) in raw.disks.iter().enumerate() {
            let key = format!("disks[{d}]");
            let _ = &raw_disk.name;
            let node = locate(
                &ctx,
                &key,
                raw_disk.node,
                raw_disk.position,
                &node_positions,
            )?;
            let given = [
                raw_disk.mass,
                raw_disk.polar_inertia,
                raw_disk.diametral_inertia,
            ];
            let geometry = [raw_disk.width, raw_disk.outer_diameter, raw_disk.density];
            let (mass, ip, id) = if given.iter().all(Option::is_some)
                && geometry.iter().all(Option::is_none)
                && raw_disk.inner_diameter.is_none()
            {
                (
                    ctx.positive(&format!("{key}.mass"), raw_disk.mass.unwrap_or(0.0))?,
                    ctx.non_negative(
                        &format!("{key}.polar_inertia"),
                        raw_disk.polar_inertia.unwrap_or(0.0),
                    )?,
                    ctx.non_negative(
                        &format!("{key}.diametral_inertia"),
                        raw_disk.diametral_inertia.unwrap_or(0.0),
                    )?,
                )
            } else if geometry.iter().all(Option::is_some) && given.iter().all(Option::is_none) {
                let w = ctx.positive(&format!("{key}.width"), raw_disk.width.unwrap_or(0.0))?;
                let od = ctx.positive(
                    &format!("{key}.outer_diameter"),
                    raw_disk.outer_diameter.unwrap_or(0.0),
                )?;
                let id = ctx.non_negative(
                    &format!("{key}.inner_diameter"),
                    raw_disk.inner_diameter.unwrap_or(0.0),
                )?;
                if od <= id {
                    return Err(ctx.err(
                        format!("{key}.outer_diameter"),
                        format!("must be > inner_diameter (got {od} <= {id})"),
                    ));
                }
                let rho =
                    ctx.positive(&format!("{key}.density"), raw_disk.density.unwrap_or(0.0))?;
                inertia_from_geometry(w, od, id, rho)
            } else {
                return Err(ctx.err(
                    key,
                    "give either mass, polar_inertia and diametral_inertia, or width, outer_diameter, (inner_diameter,) density",
                ));
            };
            disks.push(Disk {
                node,
                mass,
                polar_inertia: ip,
                diametral_inertia: id,
            });
            match (raw_disk.unbalance, raw_disk.unbalance_angle) {
                (Some(u), angle) => {
                    let u = ctx.non_negative(&format!("{key}.unbalance"), u)?;
                    let a = ctx.finite(&format!("{key}.unbalance_angle"), angle.unwrap_or(0.0))?;
                    unbalances.push(Unbalance {
                        node,
                        magnitude: u,
                        angle_deg: a,
                    });
                }
                (None, Some(_)) => {
                    return Err(ctx.err(format!("{key}.unbalance_angle"), "given without unbalance"))
                }
                (None, None) => {}
            }
        }
        for (u, raw_u) in raw.unbalance.iter().enumerate() {
            let key = format!("unbalance[{u}]");
            let node = locate(&ctx, &key, raw_u.node, raw_u.position, &node_positions)?;
            unbalances.push(Unbalance {
                node,
                magnitude: ctx.non_negative(&format!("{key}.magnitude"), raw_u.magnitude)?,
                angle_deg: ctx.finite(&format!("{key}.angle"), raw_u.angle)?,
            });
        }
        // Bearings.
        if raw.bearings.is_empty() {
            return Err(ctx.err("bearings", "needs at least one bearing"));
        }
        let mut bearings = Vec::new();
        let mut weight_share: Vec<usize> = Vec::new();
        for (b, rb) in raw.bearings.iter().enumerate() {
            let key = format!("bearings[{b}]");
            if !bearing_name_ok(&rb.name) {
                return Err(ctx.err(
                    format!("{key}.name"),
                    format!(
                        "{:?}: use letters, digits, '_', '-', '.' only (it becomes a CSV field)",
                        rb.name
                    ),
                ));
            }
            if let Some(other) = bearings.iter().position(|x: &Bearing| x.name == rb.name) {
                return Err(ctx.err(
                    format!("{key}.name"),
                    format!("{:?} is already the name of bearings[{other}]", rb.name),
                ));
            }
            let node = locate(&ctx, &key, rb.node, rb.position, &node_positions)?;
            if let Some(other) = bearings.iter().position(|x: &Bearing| x.node == node) {
                return Err(ctx.err(
                    key,
                    format!("node {node} already carries bearings[{other}]"),
                ));
            }
            let model = match (&rb.coefficients, &rb.oil_film) {
                (Some(rows), None) => {
                    if rows.is_empty() {
                        return Err(ctx.err(format!("{key}.coefficients"), "is empty"));
                    }
                    let mut table = Vec::new();
                    for (r, row) in rows.iter().enumerate() {
                        let rk = format!("{key}.coefficients[{r}]");
                        let s = ctx.non_negative(&format!("{rk}.speed_hz"), row.speed_hz)?;
                        if let Some(&(prev, _)) = table.last() {
                            if s <= prev {
                                return Err(ctx.err(
                                    format!("{rk}.speed_hz"),
                                    format!("speeds must increase (got {s} after {prev})"),
                                ));
                            }
                        }
                        let vals = [
                            ("kyy", row.kyy),
                            ("kyz", row.kyz),
                            ("kzy", row.kzy),
                            ("kzz", row.kzz),
                            ("cyy", row.cyy),
                            ("cyz", row.cyz),
                            ("czy", row.czy),
                            ("czz", row.czz),
                        ];
                        for (n, v) in vals {
                            ctx.finite(&format!("{rk}.{n}"), v)?;
                        }
                        table.push((
                            s,
                            BearingCoefficients {
                                k: [[row.kyy, row.kyz], [row.kzy, row.kzz]],
                                c: [[row.cyy, row.cyz], [row.czy, row.czz]],
                            },
                        ));
                    }
                    BearingModel::Table(table)
                }
                (None, Some(of)) => {
                    let ok = format!("{key}.oil_film");
                    let load = match &of.load {
                        RawLoad::Newton(w) => ctx.positive(&format!("{ok}.load"), *w)?,
                        RawLoad::Keyword(k) if k == "weight" => {
                            weight_share.push(b);
                            f64::NAN
                        }
                        RawLoad::Keyword(k) => {
                            return Err(ctx.err(
                                format!("{ok}.load"),
                                format!("must be a load in N or \"weight\" (got {k:?})"),
                            ))
                        }
                    };
                    let diameter = ctx.positive(&format!("{ok}.diameter"), of.diameter)?;
                    let clearance = ctx.positive(&format!("{ok}.clearance"), of.clearance)?;
                    if clearance >= 0.05 * diameter {
                        return Err(ctx.err(
                            format!("{ok}.clearance"),
                            format!("{clearance} m is not small against the diameter {diameter} m (radial clearance, not diametral, in m)"),
                        ));
                    }
                    BearingModel::OilFilm(OilFilmBearing {
                        diameter,
                        length: ctx.positive(&format!("{ok}.length"), of.length)?,
                        clearance,
                        viscosity: ctx.positive(&format!("{ok}.viscosity"), of.viscosity)?,
                        load,
                    })
                }
                (Some(_), Some(_)) => {
                    return Err(ctx.err(key, "give either coefficients or oil_film, not both"))
                }
                (None, None) => {
                    return Err(ctx.err(key, "needs coefficients (a speed table) or oil_film"))
                }
            };
            let pedestal = match rb.pedestal {
                Some(p) => {
                    let pk = format!("{key}.pedestal");
                    Some(PedestalParams {
                        m: ctx.positive(&format!("{pk}.m"), p.m)?,
                        k_y: ctx.positive(&format!("{pk}.k_y"), p.k_y)?,
                        k_z: ctx.positive(&format!("{pk}.k_z"), p.k_z)?,
                        c_y: ctx.non_negative(&format!("{pk}.c_y"), p.c_y)?,
                        c_z: ctx.non_negative(&format!("{pk}.c_z"), p.c_z)?,
                    })
                }
                None => None,
            };
            bearings.push(Bearing {
                name: rb.name.clone(),
                node,
                model,
                pedestal,
            });
        }
        let mut machine = Machine {
            name: raw.name.unwrap_or_default(),
            node_positions,
            elements,
            disks,
            bearings,
            unbalances,
            gravity,
        };
        if !weight_share.is_empty() {
            let loads = machine.static_bearing_loads().map_err(|m| {
                ctx.err(
                    format!("bearings[{}].oil_film.load", weight_share[0]),
                    format!("\"weight\": {m}"),
                )
            })?;
            for b in weight_share {
                let w = loads[b];
                if w.is_nan() || w <= 0.0 {
                    return Err(ctx.err(
                        format!("bearings[{b}].oil_film.load"),
                        format!("\"weight\" gives {w:.6e} N: the film would be unloaded or pulled (overhung rotor?); give a load in N"),
                    ));
                }
                if let BearingModel::OilFilm(of) = &mut machine.bearings[b].model {
                    of.load = w;
                }
            }
        }
        Ok(machine)
    }

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
    pub fn pedestal(&self, name: &str) -> Result<Option<PedestalParams>, MachineError> {
        Ok(self.bearings[self.bearing_index(name)?].pedestal)
    }

    /// Replaces the pedestal under bearing `name` (e.g. with identified values
    /// for `plinth predict`); `None` puts the bearing on rigid ground.
    pub fn set_pedestal(
        &mut self,
        name: &str,
        pedestal: Option<PedestalParams>,
    ) -> Result<(), MachineError> {
        let i = self.bearing_index(name)?;
        if let Some(p) = pedestal {
            let ok = |v: f64| v.is_finite() && v >= 0.0;
            if !(p.m > 0.0 && ok(p.m) && ok(p.k_y) && ok(p.k_z) && ok(p.c_y) && ok(p.c_z)) {
                return Err(MachineError::Request(format!(
                    "pedestal for {name:?}: m must be > 0 and k, c finite and >= 0 (got {p:?})"
                )));
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
        match &b.model {
            BearingModel::Table(rows) => table_at(rows, speed_hz).ok_or_else(|| {
                let lo = rows.first().map_or(0.0, |r| r.0);
                let hi = rows.last().map_or(0.0, |r| r.0);
                MachineError::Request(format!(
                    "bearing {:?}: speed {speed_hz} Hz is outside its coefficient table ({lo}..{hi} Hz; no extrapolation)",
                    b.name
                ))
            }),
            BearingModel::OilFilm(of) => of
                .coefficients(speed_hz)
                .map_err(|e| MachineError::Request(format!("bearing {:?}: {e}", b.name))),
        }
    }

    /// Total rotor mass (shaft and disks) [kg].
    pub fn rotor_mass(&self) -> f64 {
        self.elements.iter().map(ShaftElement::mass).sum::<f64>()
            + self.disks.iter().map(|d| d.mass).sum::<f64>()
    }

    /// Vertical bearing reactions [N] (upwards on the rotor, per bearing) that
    /// carry the rotor's weight, from the static shaft on rigid supports at
    /// the bearing nodes (vertical plane, Timoshenko stiffness; statically
    /// determinate cases reduce to the lever rule).
    pub fn static_bearing_loads(&self) -> Result<Vec<f64>, String> {
        let nn = self.node_positions.len();
        let n = 2 * nn; // (y, θ_z) per node
        let mut k = DMatrix::<f64>::zeros(n, n);
        let mut f = DVector::<f64>::zeros(n);
        for (e, el) in self.elements.iter().enumerate() {
            let ke = el.stiffness_matrix();
            let map = [2 * e, 2 * e + 1, 2 * e + 2, 2 * e + 3];
            let local = [0usize, 3, 4, 7];
            for i in 0..4 {
                for j in 0..4 {
                    k[(map[i], map[j])] += ke[local[i]][local[j]];
                }
            }
            // Element weight, lumped half to each end (exact resultant and moment).
            let w = el.mass() * self.gravity;
            f[2 * e] -= 0.5 * w;
            f[2 * e + 2] -= 0.5 * w;
        }
        for d in &self.disks {
            f[2 * d.node] -= d.mass * self.gravity;
        }
        if self.bearings.len() < 2 {
            return Err("needs at least two bearings to carry the rotor's weight".into());
        }
        let fixed: Vec<usize> = self.bearings.iter().map(|b| 2 * b.node).collect();
        let free: Vec<usize> = (0..n).filter(|i| !fixed.contains(i)).collect();
        let kff = DMatrix::from_fn(free.len(), free.len(), |i, j| k[(free[i], free[j])]);
        let ff = DVector::from_fn(free.len(), |i, _| f[free[i]]);
        let u = kff
            .lu()
            .solve(&ff)
            .ok_or("the shaft on rigid supports at the bearings is singular")?;
        Ok(fixed
            .iter()
            .map(|&r| {
                // Reaction = K_rf·u_f − f_r (force the support exerts on the shaft).
                let ku: f64 = free
                    .iter()
                    .enumerate()
                    .map(|(j, &c)| k[(r, c)] * u[j])
                    .sum();
                ku - f[r]
            })
            .collect())
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
        for u in &self.unbalances {
            if u.node >= nn {
                return bad(format!("unbalance at node {} out of range", u.node));
            }
        }
        Ok(())
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

    #[test]
    fn table_interpolates_and_refuses_to_extrapolate() {
        let c = |k: f64| BearingCoefficients::<f64>::isotropic(k, 0.0);
        let rows = vec![(10.0, c(1.0)), (20.0, c(3.0))];
        assert_eq!(table_at(&rows, 15.0).unwrap().k[0][0], 2.0);
        assert!(table_at(&rows, 25.0).is_none());
        assert_eq!(table_at(&rows[..1], 99.0).unwrap().k[0][0], 1.0);
    }
}
