//! Effects the simulator can put into a machine beyond the paper's pedestal
//! model (names, physics and parameters as defined in `crate::effects`), with
//! the default sizes the tests use.
//!
//! An effect is requested as `NAME[:BEARING][=SIZE]` (the `--effect` option).
//! Without a bearing it acts on every bearing. SIZE and its default, per effect:
//!
//! | name | SIZE means | default | resulting parameters |
//! | --- | --- | --- | --- |
//! | `pedestal_damping` | damping ratio ζ of each pedestal direction | 0.02 | c_y = 2ζ·sqrt(k_y·m), c_z = 2ζ·sqrt(k_z·m) [N·s/m] |
//! | `structural_damping` | loss factor η | 0.06 | `eta`; K → K·(1 + iη) on the pedestal |
//! | `pedestal_cross_coupling` | fraction of sqrt(k_y·k_z) | 0.25 | k_yz = k_zy = SIZE·sqrt(k_y·k_z) [N/m] |
//! | `pedestal_mass_anisotropy` | relative extra horizontal mass | 0.30 | m_y = m, m_z = (1 + SIZE)·m [kg] |
//! | `probe_runout` | fraction of the median \|rel\| of that bearing | 0.25 | r = a·(e^{i30°}, e^{−i60°}), a = SIZE·median over speeds and y, z of \|rel\| [m] |
//! | `sensor_delay` | delay τ [s] | 0.35e-3 | ped channels × e^{−iΩτ} |
//! | `foundation_coupling` | compliance of the base relative to the pedestals it carries (in parallel) | 0.20 | a base element (`super::base`) under every bearing with a pedestal (with a bearing: it and its neighbour, the next bearing with a pedestal in file order, the previous one for the last): K_B = Σk / SIZE per direction [N/m], M_B = 2·Σm [kg], C_B = 0.1·sqrt(K_B·M_B) [N·s/m] (5 % damping ratio); the pedestals' k, c then act between pedestal and base; not measured (no `base.csv`) |
//! | `pedestal_sub_base` | compliance of the sub-base relative to its pedestal (in series) | 0.50 | a sub-base element (`super::base`, carrying that pedestal only) under the bearing (without a bearing: under every pedestal, each its own): K_S = k / SIZE per direction [N/m], M_S = m (the pedestal's mass per direction) [kg], C_S = 0.1·sqrt(K_S·M_S) [N·s/m] (5 % damping ratio); the pedestal's k, c then act between pedestal and sub-base; not measured. The same element as a machine file's `sub_base` |
//! | `bearing_coefficients` | relative error of the written table | 0.15 | the simulation uses the machine's bearing, `bearings.csv` another one (without a bearing: every bearing): an oil film's table is computed for the radial clearance (1 − SIZE)·c (SIZE < 1); a speed table is written with K and C both × (1 + SIZE). `truth.json` records the correction (written → true): `clearance_ratio` = 1/(1 − SIZE), `clearance_true`, `clearance_written` [m], or `k_scale` = `c_scale` = 1/(1 + SIZE); `plinth simulate` writes the simulated table as `bearings_true.csv` |

use super::base::Base;
use super::machine::{BearingModel, Machine};
use super::pedestal::PedestalDynamics;
use super::SimError;
use crate::effects::EffectKind;
use crate::rundir::EffectTruth;
use std::collections::BTreeMap;
use std::str::FromStr;

/// One requested effect: kind, optional bearing, optional size (see the module table).
#[derive(Clone, Debug, PartialEq)]
pub struct EffectRequest {
    /// Which effect.
    pub kind: EffectKind,
    /// Bearing it acts on; `None` = every bearing (see module docs).
    pub bearing: Option<String>,
    /// Size in the effect's own unit (module table); `None` = default.
    pub size: Option<f64>,
}

/// The effects to inject into one simulation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EffectSet {
    /// Requests, applied in order.
    pub requests: Vec<EffectRequest>,
}

impl EffectSet {
    /// No effects: the paper's model.
    pub fn none() -> Self {
        Self::default()
    }

    /// The effects of the command line's `--effect NAME[:BEARING][=SIZE]`
    /// options, in order; an error names the option and its value.
    pub fn from_options(texts: &[String]) -> Result<Self, String> {
        let requests = texts
            .iter()
            .map(|t| t.parse().map_err(|m| format!("--effect {t:?}: {m}")))
            .collect::<Result<Vec<EffectRequest>, String>>()?;
        Ok(Self { requests })
    }

    /// Adds a request (builder style).
    pub fn with(mut self, kind: EffectKind, bearing: Option<&str>, size: Option<f64>) -> Self {
        self.requests.push(EffectRequest {
            kind,
            bearing: bearing.map(str::to_string),
            size,
        });
        self
    }
}

/// Default SIZE of each effect (module table).
pub fn default_size(kind: EffectKind) -> f64 {
    match kind {
        EffectKind::PedestalDamping => 0.02,
        EffectKind::StructuralDamping => 0.06,
        EffectKind::PedestalCrossCoupling => 0.25,
        EffectKind::PedestalMassAnisotropy => 0.30,
        EffectKind::ProbeRunout => 0.25,
        EffectKind::SensorDelay => 0.35e-3,
        EffectKind::FoundationCoupling => 0.20,
        EffectKind::PedestalSubBase => 0.50,
        EffectKind::BearingCoefficients => 0.15,
    }
}

impl FromStr for EffectRequest {
    type Err = String;

    /// Parses `NAME[:BEARING][=SIZE]`.
    fn from_str(s: &str) -> Result<Self, String> {
        let (head, size) = match s.split_once('=') {
            Some((h, v)) => {
                let v: f64 = v
                    .trim()
                    .parse()
                    .map_err(|_| format!("effect {s:?}: SIZE {v:?} is not a number"))?;
                if !(v.is_finite() && v >= 0.0) {
                    return Err(format!("effect {s:?}: SIZE must be finite and >= 0"));
                }
                (h, Some(v))
            }
            None => (s, None),
        };
        let (name, bearing) = match head.split_once(':') {
            Some((n, b)) if !b.is_empty() => (n, Some(b.to_string())),
            Some((_, _)) => return Err(format!("effect {s:?}: empty bearing name after ':'")),
            None => (head, None),
        };
        let kind = EffectKind::from_name(name.trim()).ok_or_else(|| {
            let known: Vec<&str> = EffectKind::ALL.iter().map(|e| e.name()).collect();
            format!("unknown effect {name:?} (known: {})", known.join(", "))
        })?;
        Ok(EffectRequest {
            kind,
            bearing,
            size,
        })
    }
}

/// An error of effect `kind`.
pub(crate) fn effect_err(kind: EffectKind, message: impl Into<String>) -> SimError {
    SimError::Effect {
        effect: kind.name().to_string(),
        message: message.into(),
    }
}

/// A machine with its structural effects resolved: what is simulated.
pub(crate) struct Resolved {
    /// The machine actually simulated (bases and sub-bases of effects added).
    pub machine: Machine,
    /// Pedestal dynamics per bearing (effects applied).
    pub pedestals: Vec<Option<PedestalDynamics>>,
    /// The structural effects for `truth.json` (sub-bases of the machine
    /// file included, as `pedestal_sub_base`).
    pub details: Vec<EffectTruth>,
    /// Sensor effects (kind, bearings, size), recorded once the response is known.
    pub sensor_requests: Vec<(EffectKind, Vec<usize>, f64)>,
    /// Per bearing, the model `bearings.csv` is written from when it is not
    /// the machine's (`bearing_coefficients`).
    pub written: Vec<Option<BearingModel>>,
}

/// Applies `effects` to `machine` (see the module table).
pub(crate) fn resolve(machine: &Machine, effects: &EffectSet) -> Result<Resolved, SimError> {
    machine.validate()?;
    // `foundation_coupling` and `pedestal_sub_base` stand pedestals on new
    // base elements: the machine actually simulated.
    let mut effective = machine.clone();
    let mut pedestals: Vec<Option<PedestalDynamics>> = machine
        .bearings
        .iter()
        .map(|b| b.pedestal.map(PedestalDynamics::from))
        .collect();
    let mut details = Vec::new();
    let mut sensor_requests = Vec::new();
    let mut written = vec![None; machine.bearings.len()];
    for req in &effects.requests {
        let kind = req.kind;
        let size = req.size.unwrap_or_else(|| default_size(kind));
        let targets: Vec<usize> = match &req.bearing {
            Some(name) => vec![machine.bearing_index(name)?],
            None => match kind {
                EffectKind::FoundationCoupling => {
                    vec![pedestals
                        .iter()
                        .position(Option::is_some)
                        .ok_or_else(|| effect_err(kind, "the machine has no pedestals"))?]
                }
                EffectKind::ProbeRunout
                | EffectKind::SensorDelay
                | EffectKind::BearingCoefficients => (0..machine.bearings.len()).collect(),
                _ => (0..machine.bearings.len())
                    .filter(|&b| pedestals[b].is_some())
                    .collect(),
            },
        };
        for b in targets {
            let name = machine.bearings[b].name.clone();
            let mut params = BTreeMap::new();
            match kind {
                EffectKind::ProbeRunout | EffectKind::SensorDelay => {
                    sensor_requests.push((kind, vec![b], size));
                    continue; // recorded once the response is known
                }
                EffectKind::BearingCoefficients => {
                    let (model, params) = written_bearing(&machine.bearings[b].model, size)?;
                    written[b] = Some(model);
                    details.push(EffectTruth {
                        name: kind.name().into(),
                        bearing: name,
                        parameters: params,
                    });
                    continue;
                }
                _ => {}
            }
            let p = pedestals[b]
                .as_mut()
                .ok_or_else(|| effect_err(kind, format!("bearing {name:?} has no pedestal")))?;
            match kind {
                EffectKind::PedestalDamping => {
                    p.c[0][0] = 2.0 * size * (p.k[0][0] * p.m[0]).sqrt();
                    p.c[1][1] = 2.0 * size * (p.k[1][1] * p.m[1]).sqrt();
                    params.insert("c_y".into(), p.c[0][0]);
                    params.insert("c_z".into(), p.c[1][1]);
                }
                EffectKind::StructuralDamping => {
                    p.eta = size;
                    params.insert("eta".into(), size);
                }
                EffectKind::PedestalCrossCoupling => {
                    let kyz = size * (p.k[0][0] * p.k[1][1]).sqrt();
                    p.k[0][1] = kyz;
                    p.k[1][0] = kyz;
                    params.insert("k_yz".into(), kyz);
                }
                EffectKind::PedestalMassAnisotropy => {
                    p.m[1] = (1.0 + size) * p.m[0];
                    params.insert("m_y".into(), p.m[0]);
                    params.insert("m_z".into(), p.m[1]);
                }
                EffectKind::FoundationCoupling => {
                    let group = foundation_group(&effective, b, req.bearing.is_some())?;
                    let mut base = foundation_base(&pedestals, &group, size)?;
                    let mut n = 1;
                    while effective.bases.iter().any(|x| x.name == base.name) {
                        n += 1;
                        base.name = format!("foundation{n}");
                    }
                    for (key, v) in [
                        ("base_k_y", base.k[0]),
                        ("base_k_z", base.k[1]),
                        ("base_m_y", base.m[0]),
                        ("base_m_z", base.m[1]),
                        ("base_c_y", base.c[0]),
                        ("base_c_z", base.c[1]),
                    ] {
                        params.insert(key.into(), v);
                    }
                    let index = effective.bases.len();
                    effective.bases.push(base);
                    for &g in &group {
                        effective.bearings[g].base = Some(index);
                    }
                }
                EffectKind::PedestalSubBase => {
                    let brg = &mut effective.bearings[b];
                    if brg.base.is_some() || brg.sub_base.is_some() {
                        return Err(effect_err(
                            kind,
                            format!("the pedestal of bearing {name:?} already stands on a base or sub-base"),
                        ));
                    }
                    brg.sub_base = Some(sub_base(&name, p, size)?);
                    continue; // recorded with the machine file's sub-bases
                }
                EffectKind::ProbeRunout
                | EffectKind::SensorDelay
                | EffectKind::BearingCoefficients => {}
            }
            details.push(EffectTruth {
                name: kind.name().into(),
                bearing: name,
                parameters: params,
            });
        }
    }
    for brg in &effective.bearings {
        if let Some(sb) = &brg.sub_base {
            details.push(sub_base_truth(&brg.name, sb));
        }
    }
    effective.validate()?;
    Ok(Resolved {
        machine: effective,
        pedestals,
        details,
        sensor_requests,
        written,
    })
}

/// The sub-base of `pedestal_sub_base` of size `size` under bearing `name`'s
/// pedestal `p` (module table): K_S = k / size [N/m], M_S = m [kg] per
/// direction, C_S = 0.1·sqrt(K_S·M_S) [N·s/m].
pub(crate) fn sub_base(name: &str, p: &PedestalDynamics, size: f64) -> Result<Base, SimError> {
    let kind = EffectKind::PedestalSubBase;
    if !(size.is_finite() && size > 0.0) {
        return Err(effect_err(
            kind,
            format!("SIZE (sub-base compliance relative to the pedestal) must be > 0 (got {size})"),
        ));
    }
    let k: [f64; 2] = std::array::from_fn(|d| p.k[d][d] / size);
    let base = Base {
        name: format!("{name}.sub_base"),
        m: p.m,
        k,
        c: std::array::from_fn(|d| 0.1 * (k[d] * p.m[d]).sqrt()),
        eta: 0.0,
    };
    base.check().map_err(|e| effect_err(kind, e))?;
    Ok(base)
}

/// The `truth.json` record of the sub-base `sb` under bearing `bearing`.
fn sub_base_truth(bearing: &str, sb: &Base) -> EffectTruth {
    let names = EffectKind::PedestalSubBase.parameter_names();
    let values = [sb.k[0], sb.k[1], sb.m[0], sb.m[1], sb.c[0], sb.c[1]];
    EffectTruth {
        name: EffectKind::PedestalSubBase.name().into(),
        bearing: bearing.to_string(),
        parameters: names.iter().map(|n| n.to_string()).zip(values).collect(),
    }
}

/// The bearing `bearings.csv` is written for under `bearing_coefficients`
/// of size `size` (module table), with the correction for `truth.json`.
fn written_bearing(
    model: &BearingModel,
    size: f64,
) -> Result<(BearingModel, BTreeMap<String, f64>), SimError> {
    let kind = EffectKind::BearingCoefficients;
    let mut params = BTreeMap::new();
    let model = match model {
        BearingModel::OilFilm(of) => {
            if !(0.0..1.0).contains(&size) {
                return Err(effect_err(
                    kind,
                    format!("SIZE (relative clearance error of the table) must be in [0, 1) for an oil film (got {size})"),
                ));
            }
            let mut wrong = *of;
            wrong.clearance = of.clearance * (1.0 - size);
            params.insert("clearance_true".into(), of.clearance);
            params.insert("clearance_written".into(), wrong.clearance);
            params.insert("clearance_ratio".into(), of.clearance / wrong.clearance);
            BearingModel::OilFilm(wrong)
        }
        BearingModel::Table(rows) => {
            let f = 1.0 + size;
            let scale = |m: [[f64; 2]; 2]| m.map(|r| r.map(|v| v * f));
            params.insert("k_scale".into(), 1.0 / f);
            params.insert("c_scale".into(), 1.0 / f);
            BearingModel::Table(
                rows.iter()
                    .map(|(s, c)| {
                        let mut w = *c;
                        w.k = scale(c.k);
                        w.c = scale(c.c);
                        (*s, w)
                    })
                    .collect(),
            )
        }
    };
    Ok((model, params))
}

/// The bearings `foundation_coupling` stands on one new base: with a named
/// bearing `b`, it and its neighbour (the next bearing with a pedestal in
/// file order, the previous one for the last); otherwise every bearing with
/// a pedestal. None of them may already stand on a base.
pub(crate) fn foundation_group(
    machine: &Machine,
    b: usize,
    named: bool,
) -> Result<Vec<usize>, SimError> {
    let kind = EffectKind::FoundationCoupling;
    let with_ped: Vec<usize> = (0..machine.bearings.len())
        .filter(|&i| machine.bearings[i].pedestal.is_some())
        .collect();
    let group = if named {
        let pos = with_ped.iter().position(|&i| i == b).unwrap_or(0);
        let other = if pos + 1 < with_ped.len() {
            with_ped[pos + 1]
        } else if pos > 0 {
            with_ped[pos - 1]
        } else {
            return Err(effect_err(kind, "needs two bearings with pedestals"));
        };
        vec![b.min(other), b.max(other)]
    } else {
        with_ped
    };
    if group.len() < 2 {
        return Err(effect_err(kind, "needs two bearings with pedestals"));
    }
    for &g in &group {
        let brg = &machine.bearings[g];
        if let Some(j) = brg.base {
            return Err(effect_err(
                kind,
                format!(
                    "bearing {:?} already stands on base {:?}",
                    brg.name, machine.bases[j].name
                ),
            ));
        }
        if brg.sub_base.is_some() {
            return Err(effect_err(
                kind,
                format!("bearing {:?} already stands on a sub-base", brg.name),
            ));
        }
    }
    Ok(group)
}

/// The base of `foundation_coupling` of size `size` under `group` (see
/// `inject`'s table): per direction d, K_B = Σ k_d / size [N/m] (size is the
/// base's compliance relative to the pedestals in parallel), M_B = 2·Σ m_d
/// [kg], damping ratio 5 % on its own springs, C_B = 0.1·sqrt(K_B·M_B)
/// [N·s/m].
pub(crate) fn foundation_base(
    pedestals: &[Option<PedestalDynamics>],
    group: &[usize],
    size: f64,
) -> Result<super::base::Base, SimError> {
    let kind = EffectKind::FoundationCoupling;
    if !(size.is_finite() && size > 0.0) {
        return Err(effect_err(
            kind,
            format!("SIZE (base compliance relative to the pedestals) must be > 0 (got {size})"),
        ));
    }
    let mut k = [0.0; 2];
    let mut m = [0.0; 2];
    for &g in group {
        let p = pedestals[g]
            .as_ref()
            .ok_or_else(|| effect_err(kind, "a bearing of the group has no pedestal"))?;
        for d in 0..2 {
            k[d] += p.k[d][d];
            m[d] += p.m[d];
        }
    }
    let k = k.map(|v| v / size);
    let m = m.map(|v| 2.0 * v);
    let base = super::base::Base {
        name: "foundation".to_string(),
        m,
        k,
        c: std::array::from_fn(|d| 0.1 * (k[d] * m[d]).sqrt()),
        eta: 0.0,
    };
    base.check().map_err(|e| effect_err(kind, e))?;
    Ok(base)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_name_bearing_and_size() {
        let r: EffectRequest = "sensor_delay:left=0.001".parse().unwrap();
        assert_eq!(r.kind, EffectKind::SensorDelay);
        assert_eq!(r.bearing.as_deref(), Some("left"));
        assert_eq!(r.size, Some(0.001));
        let r: EffectRequest = "probe_runout".parse().unwrap();
        assert_eq!((r.bearing, r.size), (None, None));
        assert!("gremlins:left".parse::<EffectRequest>().is_err());
        assert!("sensor_delay=abc".parse::<EffectRequest>().is_err());
    }
}
