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

use super::machine::Machine;
use super::pedestal::PedestalDynamics;
use super::SimError;
use crate::effects::EffectKind;
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
        if let Some(j) = machine.bearings[g].base {
            return Err(effect_err(
                kind,
                format!(
                    "bearing {:?} already stands on base {:?} of the machine file",
                    machine.bearings[g].name, machine.bases[j].name
                ),
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
