//! Reading a machine file: the TOML schema (`Raw*`, exactly the keys the
//! file may hold) and its validation into a [`Machine`], every problem named
//! by file and key. The format is documented in [`super::machine`].

mod bearings;
mod shaft;

use super::disk::{inertia_from_geometry, Disk};
use super::machine::{BearingModel, Machine, MachineError, Unbalance, STANDARD_GRAVITY};
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
        match super::machine::not_a_quantity(v, false) {
            None => Ok(v),
            Some(why) => Err(self.err(key, format!("must be a finite number > 0 ({why})"))),
        }
    }
    fn non_negative(&self, key: &str, v: f64) -> Result<f64, MachineError> {
        match super::machine::not_a_quantity(v, true) {
            None => Ok(v),
            Some(why) => Err(self.err(key, format!("must be a finite number >= 0 ({why})"))),
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
        let (node_positions, elements) = shaft::read_shaft(&ctx, &raw)?;
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
        let bases = bearings::read_bases(&ctx, &raw.base)?;
        let mut bearings = Vec::new();
        let mut weight_share: Vec<usize> = Vec::new();
        for (b, rb) in raw.bearings.iter().enumerate() {
            let bearing = bearings::read_bearing(
                &ctx,
                b,
                rb,
                &bearings,
                &node_positions,
                &bases,
                &mut weight_share,
            )?;
            bearings.push(bearing);
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
