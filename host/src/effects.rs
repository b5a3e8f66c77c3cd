//! The effects a real machine may have beyond the paper's pedestal model
//! (formats.md, "Effect names"), shared by the simulator (which injects them)
//! and the model-discrepancy workflow (which names them).
//!
//! Physics and parameters of each, as Plinth defines them:
//!
//! | name | physics | parameters (SI) |
//! | --- | --- | --- |
//! | `pedestal_damping` | viscous pedestal damping C = diag(c_y, c_z) | `c_y`, `c_z` [N·s/m] |
//! | `structural_damping` | hysteretic pedestal damping: K → K·(1 + iη) | `eta` [-] |
//! | `pedestal_cross_coupling` | pedestal stiffness k_yz = k_zy off the diagonal | `k_yz` [N/m] |
//! | `pedestal_mass_anisotropy` | M = diag(m_y, m_z), m_y ≠ m_z | `m_y`, `m_z` [kg] |
//! | `probe_runout` | a constant (speed-independent) 1X vector r added to the `rel` readings of one bearing | `r_y_re`, `r_y_im`, `r_z_re`, `r_z_im` [m] |
//! | `sensor_delay` | a time delay τ on the pedestal (seismic) channels of one bearing: ped_meas = ped·e^{−iΩτ} | `tau` [s] |
//! | `foundation_coupling` | the pedestals stand on a flexible base (a body of mass M_B on springs K_B and dampers C_B to ground, per direction, `sim::base`); the pedestals' k, c act between pedestal and base, so one pedestal moves under the others' forces, through a speed-dependent complex coupling (`estimate::base`) | `base_k_y`, `base_k_z` [N/m], `base_m_y`, `base_m_z` [kg], `base_c_y`, `base_c_z` [N·s/m] |
//! | `pedestal_sub_base` | one pedestal stands on its own flexible sub-base (a body of mass M_S on springs K_S and dampers C_S to ground, per direction, `sim::base`): the pedestal's k, c act between pedestal and sub-base, a two-degree-of-freedom pedestal per direction; the sub-base is not measured. When its mode lies above the speed range (variant `above_range`) only the first terms of its dynamic stiffness per direction, K − Ω²M − Ω⁴Q − …, are seen, and the effect is the Ω⁴ coefficient per direction on top of the pedestal's apparent k, m | `sub_k_y`, `sub_k_z` [N/m], `sub_m_y`, `sub_m_z` [kg], `sub_c_y`, `sub_c_z` [N·s/m]; above the range [`SUB_BASE_ABOVE_RANGE`]: `q_y`, `q_z` [N·s⁴/m] |
//! | `bearing_coefficients` | the bearing table in `bearings.csv` does not describe the bearing in the machine. For an oil-film bearing (geometry in the machine file) the table is computed for another radial clearance; otherwise the table's K and C are scaled. The correction takes the written table to the true one | `clearance_ratio` = c_true / c_written [-] (oil film, which also records `clearance_true`, `clearance_written` [m]); `k_scale` = K_true / K_written, `c_scale` = C_true / C_written [-] (tables; for oil films the same ratios at the first speed, for reference) |

/// Parameters of `pedestal_sub_base` when its mode lies above the speed
/// range: the Ω⁴ coefficients q_y, q_z [N·s⁴/m] of the support's dynamic
/// stiffness (module table).
pub const SUB_BASE_ABOVE_RANGE: [&str; 2] = ["q_y", "q_z"];

/// An effect the pedestal model may be missing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum EffectKind {
    /// Viscous pedestal damping.
    PedestalDamping,
    /// Hysteretic (loss-factor) pedestal damping.
    StructuralDamping,
    /// Off-diagonal pedestal stiffness.
    PedestalCrossCoupling,
    /// Different pedestal masses in y and z.
    PedestalMassAnisotropy,
    /// Constant vector added to a proximity probe's 1X reading.
    ProbeRunout,
    /// Time delay in the pedestal channels.
    SensorDelay,
    /// Pedestals coupled through a flexible base.
    FoundationCoupling,
    /// One pedestal on its own flexible sub-base (a 2-DOF pedestal).
    PedestalSubBase,
    /// The bearing table does not describe the machine's bearing.
    BearingCoefficients,
}

impl EffectKind {
    /// Every effect Plinth knows, in the order of formats.md's table.
    pub const ALL: [EffectKind; 9] = [
        EffectKind::PedestalDamping,
        EffectKind::StructuralDamping,
        EffectKind::PedestalCrossCoupling,
        EffectKind::PedestalMassAnisotropy,
        EffectKind::ProbeRunout,
        EffectKind::SensorDelay,
        EffectKind::FoundationCoupling,
        EffectKind::PedestalSubBase,
        EffectKind::BearingCoefficients,
    ];

    /// The identifier used in files and on the command line (formats.md).
    pub const fn name(self) -> &'static str {
        match self {
            EffectKind::PedestalDamping => "pedestal_damping",
            EffectKind::StructuralDamping => "structural_damping",
            EffectKind::PedestalCrossCoupling => "pedestal_cross_coupling",
            EffectKind::PedestalMassAnisotropy => "pedestal_mass_anisotropy",
            EffectKind::ProbeRunout => "probe_runout",
            EffectKind::SensorDelay => "sensor_delay",
            EffectKind::FoundationCoupling => "foundation_coupling",
            EffectKind::PedestalSubBase => "pedestal_sub_base",
            EffectKind::BearingCoefficients => "bearing_coefficients",
        }
    }

    /// Parses an identifier.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|e| e.name() == name)
    }

    /// Names of the effect's own parameters, SI units as in the module table.
    pub const fn parameter_names(self) -> &'static [&'static str] {
        match self {
            EffectKind::PedestalDamping => &["c_y", "c_z"],
            EffectKind::StructuralDamping => &["eta"],
            EffectKind::PedestalCrossCoupling => &["k_yz"],
            EffectKind::PedestalMassAnisotropy => &["m_y", "m_z"],
            EffectKind::ProbeRunout => &["r_y_re", "r_y_im", "r_z_re", "r_z_im"],
            EffectKind::SensorDelay => &["tau"],
            EffectKind::FoundationCoupling => &[
                "base_k_y", "base_k_z", "base_m_y", "base_m_z", "base_c_y", "base_c_z",
            ],
            EffectKind::PedestalSubBase => &[
                "sub_k_y", "sub_k_z", "sub_m_y", "sub_m_z", "sub_c_y", "sub_c_z",
            ],
            EffectKind::BearingCoefficients => &[
                "k_scale",
                "c_scale",
                "clearance_ratio",
                "clearance_true",
                "clearance_written",
            ],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for e in EffectKind::ALL {
            assert_eq!(EffectKind::from_name(e.name()), Some(e));
        }
        assert_eq!(EffectKind::from_name("gremlins"), None);
    }
}
