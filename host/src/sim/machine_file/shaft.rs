//! The shaft of a machine file: materials, sections split into Timoshenko
//! elements, and the memory check of the mesh before it is built.

use super::{Ctx, RawMachine, RawMaterial};
use crate::sim::machine::MachineError;
use crate::sim::timoshenko::ShaftElement;

/// A shaft material: Young's modulus [Pa], shear modulus [Pa], density [kg/m³].
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

/// Refuses, before the shaft is built, a mesh whose model would not fit in
/// the memory this machine has (`crate::sim::budget::machine_bytes`): the number
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
    let needed = crate::sim::budget::machine_bytes(total, raw.bearings.len() as u64);
    crate::sim::budget::check(
        &format!("a shaft of {total} elements"),
        needed,
        crate::sim::budget::available_bytes(),
    )
    .map_err(|m| ctx.err(format!("shaft.sections[{}].elements", largest.0), m))
}

/// The shaft's node positions [m] (from `shaft.start`) and its elements,
/// every section checked at its key.
pub(super) fn read_shaft(
    ctx: &Ctx,
    raw: &RawMachine,
) -> Result<(Vec<f64>, Vec<ShaftElement>), MachineError> {
    if raw.shaft.sections.is_empty() {
        return Err(ctx.err("shaft.sections", "needs at least one section"));
    }
    let default_material = match &raw.shaft.material {
        Some(m) => Some(material(ctx, "shaft.material", m)?),
        None => None,
    };
    let start = ctx.finite("shaft.start", raw.shaft.start.unwrap_or(0.0))?;
    element_budget(ctx, raw)?;
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
                own = material(ctx, &format!("{key}.material"), m)?;
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
    Ok((node_positions, elements))
}
