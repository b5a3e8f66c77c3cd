//! Reading a machine file: the TOML schema (`Raw*`, exactly the keys the
//! file may hold) and its validation into a [`Machine`], every problem named
//! by file and key. The format is documented in [`super::machine`].

use super::base::Base;
use super::disk::{inertia_from_geometry, Disk};
use super::machine::{Bearing, BearingModel, Machine, MachineError, Unbalance, STANDARD_GRAVITY};
use super::oil_film::OilFilmBearing;
use super::timoshenko::ShaftElement;
use crate::estimate::Pedestal;
use plinth_shared::bearing::BearingCoefficients;
use serde::Deserialize;
use std::path::Path;

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
    #[serde(default)]
    base: Vec<RawBody>,
}

/// A base body's name, mass, springs and dampers to ground: a `[[base]]`
/// (named) or a bearing's `sub_base` (named after its bearing).
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawBody {
    name: Option<String>,
    m: Option<f64>,
    m_y: Option<f64>,
    m_z: Option<f64>,
    k_y: f64,
    k_z: f64,
    #[serde(default)]
    c_y: f64,
    #[serde(default)]
    c_z: f64,
    #[serde(default)]
    eta: f64,
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
    base: Option<String>,
    sub_base: Option<RawBody>,
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

/// The `[[base]]` tables, checked (names unique and CSV-safe).
fn read_bases(ctx: &Ctx, raw: &[RawBody]) -> Result<Vec<Base>, MachineError> {
    let mut bases: Vec<Base> = Vec::new();
    for (i, rb) in raw.iter().enumerate() {
        let key = format!("base[{i}]");
        let name = rb
            .name
            .as_deref()
            .ok_or_else(|| ctx.err(format!("{key}.name"), "missing: a base needs a name"))?;
        crate::names::check("base", name).map_err(|m| ctx.err(format!("{key}.name"), m))?;
        if let Some(other) = bases.iter().position(|b| b.name == name) {
            return Err(ctx.err(
                format!("{key}.name"),
                format!("{:?} is already the name of base[{other}]", name),
            ));
        }
        bases.push(read_body(ctx, &key, name, rb)?);
    }
    Ok(bases)
}

/// A base body (`[[base]]` or `sub_base`) at TOML key `key`, checked.
fn read_body(ctx: &Ctx, key: &str, name: &str, rb: &RawBody) -> Result<Base, MachineError> {
    let m = match (rb.m, rb.m_y, rb.m_z) {
        (Some(m), None, None) => {
            let m = ctx.positive(&format!("{key}.m"), m)?;
            [m, m]
        }
        (None, Some(my), Some(mz)) => [
            ctx.positive(&format!("{key}.m_y"), my)?,
            ctx.positive(&format!("{key}.m_z"), mz)?,
        ],
        _ => {
            return Err(ctx.err(
                key,
                "give the mass as either m [kg] or both m_y and m_z [kg]",
            ))
        }
    };
    Ok(Base {
        name: name.to_string(),
        m,
        k: [
            ctx.positive(&format!("{key}.k_y"), rb.k_y)?,
            ctx.positive(&format!("{key}.k_z"), rb.k_z)?,
        ],
        c: [
            ctx.non_negative(&format!("{key}.c_y"), rb.c_y)?,
            ctx.non_negative(&format!("{key}.c_z"), rb.c_z)?,
        ],
        eta: ctx.non_negative(&format!("{key}.eta"), rb.eta)?,
    })
}

/// Index of the base `name` that bearing `key` stands on (it needs a pedestal).
fn base_of(
    ctx: &Ctx,
    key: &str,
    name: &str,
    has_pedestal: bool,
    bases: &[Base],
) -> Result<usize, MachineError> {
    if !has_pedestal {
        return Err(ctx.err(
            format!("{key}.base"),
            "a bearing on a base needs a `pedestal` between bearing and base",
        ));
    }
    bases.iter().position(|b| b.name == name).ok_or_else(|| {
        let known: Vec<&str> = bases.iter().map(|b| b.name.as_str()).collect();
        ctx.err(
            format!("{key}.base"),
            format!(
                "no [[base]] named {name:?} (bases: {})",
                if known.is_empty() {
                    "none".to_string()
                } else {
                    known.join(", ")
                }
            ),
        )
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

/// Refuses, before the shaft is built, a mesh whose model would not fit in
/// the memory this machine has (`super::budget::machine_bytes`): the number
/// of elements is limited by memory, not by a constant.
fn element_budget(ctx: &Ctx, raw: &RawMachine) -> Result<(), MachineError> {
    let mut total: u64 = 0;
    let mut largest = (0usize, 0u64);
    for (s, sec) in raw.shaft.sections.iter().enumerate() {
        let n = u64::try_from(sec.elements.unwrap_or(1)).unwrap_or(0);
        total = total.saturating_add(n);
        if n > largest.1 {
            largest = (s, n);
        }
    }
    let needed = super::budget::machine_bytes(total, raw.bearings.len() as u64);
    super::budget::check(
        &format!("a shaft of {total} elements"),
        needed,
        super::budget::available_bytes(),
    )
    .map_err(|m| ctx.err(format!("shaft.sections[{}].elements", largest.0), m))
}

impl Machine {
    /// Reads and validates a machine file.
    pub fn from_toml_path(path: impl AsRef<Path>) -> Result<Machine, MachineError> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let text = crate::input_file::read_to_string(path).map_err(|source| MachineError::Io {
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
            message: crate::input_file::toml_error(text, &e),
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
        element_budget(&ctx, &raw)?;
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
            if n < 1 {
                return Err(ctx.err(
                    format!("{key}.elements"),
                    format!("must be at least 1 (got {n})"),
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
        let bases = read_bases(&ctx, &raw.base)?;
        let mut bearings = Vec::new();
        let mut weight_share: Vec<usize> = Vec::new();
        for (b, rb) in raw.bearings.iter().enumerate() {
            let key = format!("bearings[{b}]");
            crate::names::check("bearing", &rb.name)
                .map_err(|m| ctx.err(format!("{key}.name"), m))?;
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
                    Some(Pedestal {
                        m: ctx.positive(&format!("{pk}.m"), p.m)?,
                        k_y: ctx.positive(&format!("{pk}.k_y"), p.k_y)?,
                        k_z: ctx.positive(&format!("{pk}.k_z"), p.k_z)?,
                        c_y: ctx.non_negative(&format!("{pk}.c_y"), p.c_y)?,
                        c_z: ctx.non_negative(&format!("{pk}.c_z"), p.c_z)?,
                    })
                }
                None => None,
            };
            let base = match &rb.base {
                Some(name) => Some(base_of(&ctx, &key, name, pedestal.is_some(), &bases)?),
                None => None,
            };
            let sub_base = match &rb.sub_base {
                Some(body) => {
                    let sk = format!("{key}.sub_base");
                    if pedestal.is_none() {
                        return Err(ctx.err(
                            sk,
                            "a sub-base carries a pedestal: give the bearing a `pedestal`",
                        ));
                    }
                    if rb.base.is_some() {
                        return Err(ctx.err(
                            sk,
                            "a pedestal stands on either a `base` or a `sub_base`, not both",
                        ));
                    }
                    if body.name.is_some() {
                        return Err(ctx.err(
                            format!("{sk}.name"),
                            "a sub-base takes its bearing's name: remove `name`",
                        ));
                    }
                    Some(read_body(
                        &ctx,
                        &sk,
                        &format!("{}.sub_base", rb.name),
                        body,
                    )?)
                }
                None => None,
            };
            bearings.push(Bearing {
                name: rb.name.clone(),
                node,
                model,
                pedestal,
                base,
                sub_base,
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
            bases,
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
}
