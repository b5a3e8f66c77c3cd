//! The bearings of a machine file (speed tables or oil films, pedestals,
//! sub-bases) and the bases they stand on, each checked at its key.

use super::{locate, Ctx, RawBearing, RawBody, RawLoad};
use crate::estimate::Pedestal;
use crate::sim::base::Base;
use crate::sim::machine::{Bearing, BearingModel, MachineError};
use crate::sim::oil_film::OilFilmBearing;
use plinth_shared::bearing::BearingCoefficients;

/// The `[[base]]` tables, checked (names unique and CSV-safe).
pub(super) fn read_bases(ctx: &Ctx, raw: &[RawBody]) -> Result<Vec<Base>, MachineError> {
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

/// Bearing `b` of the file (`rb`), checked against the bearings read before
/// it (`earlier`: names and nodes unique); an oil film loaded by the rotor's
/// weight is left at NaN load and its index pushed onto `weight_share`.
pub(super) fn read_bearing(
    ctx: &Ctx,
    b: usize,
    rb: &RawBearing,
    earlier: &[Bearing],
    node_positions: &[f64],
    bases: &[Base],
    weight_share: &mut Vec<usize>,
) -> Result<Bearing, MachineError> {
    let key = format!("bearings[{b}]");
    crate::names::check("bearing", &rb.name).map_err(|m| ctx.err(format!("{key}.name"), m))?;
    if let Some(other) = earlier.iter().position(|x: &Bearing| x.name == rb.name) {
        return Err(ctx.err(
            format!("{key}.name"),
            format!("{:?} is already the name of bearings[{other}]", rb.name),
        ));
    }
    let node = locate(ctx, &key, rb.node, rb.position, node_positions)?;
    if let Some(other) = earlier.iter().position(|x: &Bearing| x.node == node) {
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
        (None, None) => return Err(ctx.err(key, "needs coefficients (a speed table) or oil_film")),
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
        Some(name) => Some(base_of(ctx, &key, name, pedestal.is_some(), bases)?),
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
            Some(read_body(ctx, &sk, &format!("{}.sub_base", rb.name), body)?)
        }
        None => None,
    };
    Ok(Bearing {
        name: rb.name.clone(),
        node,
        model,
        pedestal,
        base,
        sub_base,
    })
}
