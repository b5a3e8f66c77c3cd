//! Machine-level check (`--machine`): the whole machine re-simulated with the
//! identified pedestals and effects (as in the paper's Fig. 6), compared with
//! every measured channel.
//!
//! The pedestals (k, m, c) replace the machine file's; pedestal effects are
//! handed to the simulator in its own parametrisation (`crate::sim::inject`):
//! cross-coupling as k_yz/√(k_y·k_z), mass anisotropy as m_z/m_y − 1 on
//! m = m_y, the loss factor as is; `foundation_coupling` stands the
//! pedestals on base elements of the simulator with the identified base
//! parameters (`put_bases`); a table's clearance correction
//! (`bearing_coefficients`) simulates that bearing as the oil film its table
//! was written for at the corrected clearance, a table's stiffness ratio
//! simulates it as its table with the stiffness × k_scale. Sensor effects (runout, delays) are applied to the
//! simulated readings here, exactly as identified.
//!
//! What each measured pedestal stands on is the identified model's, not the
//! machine file's: pedestals fitted on rigid ground already hold the motion
//! of whatever they stand on, so the file's base under them is left out (and
//! an identified base put in with `foundation_coupling`). The report says so
//! ([`replaced_bases`]): the machine-level gap is that of the file with its
//! base replaced.

use super::data::Prepared;
use super::foundation::FoundationFit;
use super::model::{Nonlinear, Term};
use super::state::State;
use crate::effects::EffectKind;
use crate::estimate::Pedestal;
use crate::sim::base::Base;
use crate::sim::{unbalance_response, BearingModel, EffectSet, Machine};
use anyhow::{anyhow, Context, Result};
use num_complex::Complex;
use plinth_shared::bearing::BearingCoefficients;

mod change;
mod gap;
pub mod unit_scale;
pub(in crate::diagnose) use gap::flat;
pub use gap::{
    machine_floor, machine_gap, parameter_variance, parameter_variance_of, refitted_base,
    MachineCheck,
};

/// Predicted readings (rel, ped) per bearing and speed index [m].
pub type Readings = Vec<Vec<Option<([Complex<f64>; 2], [Complex<f64>; 2])>>>;

/// Re-simulates `machine` with the pedestals and effects of `state`, and
/// with the bases of `foundation` when given (module docs).
pub fn resimulate(
    machine: &Machine,
    prep: &Prepared,
    state: &State,
    foundation: Option<&FoundationFit>,
) -> Result<Readings> {
    let mut machine = machine.clone();
    let nb = prep.bearings.len();
    let value = |t: Term| -> Option<f64> {
        state
            .model
            .terms
            .iter()
            .position(|u| *u == t)
            .map(|i| state.params.beta[i])
    };
    let mut effects = EffectSet::none();
    for (b, name) in prep.bearings.iter().enumerate() {
        // A pedestal on an identified base is set with its base (`put_bases`);
        // its cross-coupling (relative to the base, as the simulator's
        // pedestal has it) in the simulator's parametrisation on that fit.
        if let Some((theta, _)) = foundation.and_then(|f| f.pedestal(b)) {
            if let Some(k_yz) = value(Term::CrossStiffness { bearing: b }) {
                effects = effects.with(
                    EffectKind::PedestalCrossCoupling,
                    Some(name),
                    Some(k_yz / (theta[0] * theta[1]).abs().sqrt()),
                );
            }
            continue;
        }
        let k_y = value(Term::Stiffness { bearing: b, dir: 0 }).unwrap_or(0.0);
        let k_z = value(Term::Stiffness { bearing: b, dir: 1 }).unwrap_or(0.0);
        let (m_y, m_z) = match value(Term::Mass {
            bearing: b,
            dir: None,
        }) {
            Some(m) => (m, m),
            None => (
                value(Term::Mass {
                    bearing: b,
                    dir: Some(0),
                })
                .unwrap_or(0.0),
                value(Term::Mass {
                    bearing: b,
                    dir: Some(1),
                })
                .unwrap_or(0.0),
            ),
        };
        // The simulator takes damping >= 0: an identified value below zero
        // (noise around an undamped pedestal) is simulated as zero.
        let c_y = value(Term::Damping { bearing: b, dir: 0 })
            .unwrap_or(0.0)
            .max(0.0);
        let c_z = value(Term::Damping { bearing: b, dir: 1 })
            .unwrap_or(0.0)
            .max(0.0);
        machine
            .set_pedestal(
                name,
                Some(Pedestal {
                    m: m_y,
                    k_y,
                    k_z,
                    c_y,
                    c_z,
                }),
            )
            .with_context(|| format!("setting the identified pedestal of bearing {name}"))?;
        if m_z != m_y {
            effects = effects.with(
                EffectKind::PedestalMassAnisotropy,
                Some(name),
                Some(m_z / m_y - 1.0),
            );
        }
        if let Some(k_yz) = value(Term::CrossStiffness { bearing: b }) {
            effects = effects.with(
                EffectKind::PedestalCrossCoupling,
                Some(name),
                Some(k_yz / (k_y * k_z).sqrt()),
            );
        }
        for (k, p) in state.model.nonlinear.iter().enumerate() {
            if *p == (Nonlinear::LossFactor { bearing: b }) {
                effects = effects.with(
                    EffectKind::StructuralDamping,
                    Some(name),
                    Some(state.params.nl[k]),
                );
            }
        }
    }
    // A table's clearance correction: the bearing simulated as the oil film
    // the table was written for, at the corrected clearance c_w·(1 + δ).
    for (k, p) in state.model.nonlinear.iter().enumerate() {
        if let Nonlinear::Clearance { bearing } = *p {
            let Some(table) = state.model.tables.get(bearing).copied().flatten() else {
                continue;
            };
            let mut film = table.film;
            film.clearance *= 1.0 + state.params.nl[k];
            let i = machine.bearing_index(&prep.bearings[bearing])?;
            machine.bearings[i].model = BearingModel::OilFilm(film);
        }
    }
    // A table's stiffness ratio: the bearing simulated as the table the data
    // were fitted with (`bearings.csv` at the measured speeds), its
    // stiffness × k_scale, its damping as written.
    for (k, p) in state.model.nonlinear.iter().enumerate() {
        if let Nonlinear::StiffnessRatio { bearing } = *p {
            let delta = state.params.nl[k];
            let rows: Vec<(f64, BearingCoefficients<f64>)> = prep.points[bearing]
                .iter()
                .flatten()
                .map(|o| {
                    let corr = super::bearing_table::scale::correction(&o.kstar, delta);
                    let coefficients = BearingCoefficients {
                        k: std::array::from_fn(|r| {
                            std::array::from_fn(|c| o.kstar[r][c].re + corr[r][c].re)
                        }),
                        c: std::array::from_fn(|r| {
                            std::array::from_fn(|c| o.kstar[r][c].im / o.omega())
                        }),
                    };
                    (o.speed_hz, coefficients)
                })
                .collect();
            let i = machine.bearing_index(&prep.bearings[bearing])?;
            machine.bearings[i].model = BearingModel::Table(rows);
        }
    }
    // The identified model decides what each measured pedestal stands on:
    // rigid ground, or an identified base.
    for name in &prep.bearings {
        let i = machine.bearing_index(name)?;
        machine.bearings[i].base = None;
    }
    if let Some(f) = foundation {
        put_bases(&mut machine, prep, f)?;
    }
    let omega: Vec<f64> = prep
        .speeds_hz
        .iter()
        .map(|f| std::f64::consts::TAU * f)
        .collect();
    for (b, name) in prep.bearings.iter().enumerate() {
        let q: [Option<f64>; 2] =
            std::array::from_fn(|dir| value(Term::Quartic { bearing: b, dir }));
        if q.iter().all(Option::is_none) || foundation.is_some_and(|f| f.pedestal(b).is_some()) {
            continue;
        }
        let i = machine.bearing_index(name)?;
        let Some(p) = machine.bearings[i].pedestal else {
            continue;
        };
        put_support(&mut machine, i, &p, q.map(|v| v.unwrap_or(0.0)), &omega)
            .with_context(|| format!("the Ω⁴ support identified under bearing {name}"))?;
    }
    let response = unbalance_response(&machine, &prep.speeds_hz, &effects)
        .map_err(|e| anyhow!("re-simulating the machine: {e}"))?;
    let mut out: Readings = vec![vec![None; prep.speeds_hz.len()]; nb];
    for (b, name) in prep.bearings.iter().enumerate() {
        let mb = response
            .bearing_names
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| anyhow!("the machine file has no bearing {name}"))?;
        // Sensor effects of this bearing, as identified.
        let mut runout = [Complex::new(0.0, 0.0); 2];
        for (t, v) in state.model.terms.iter().zip(&state.params.beta) {
            if let Term::Runout { bearing, dir, imag } = *t {
                if bearing == b {
                    runout[dir] += if imag {
                        Complex::new(0.0, *v)
                    } else {
                        Complex::new(*v, 0.0)
                    };
                }
            }
        }
        for (j, row) in response.bearings.iter().enumerate() {
            if prep.points[b][j].is_none() {
                continue;
            }
            let omega = std::f64::consts::TAU * prep.speeds_hz[j];
            let r = &row[mb];
            let mut rel = [r.rel[0] + runout[0], r.rel[1] + runout[1]];
            let mut ped = r.ped;
            for (k, p) in state.model.nonlinear.iter().enumerate() {
                if let Nonlinear::Delay { bearing, channels } = *p {
                    if bearing == b {
                        let f = Complex::from_polar(1.0, -omega * state.params.nl[k]);
                        for d in 0..2 {
                            if channels.rel[d] {
                                rel[d] *= f;
                            }
                            if channels.ped[d] {
                                ped[d] *= f;
                            }
                        }
                    }
                }
            }
            out[b][j] = Some((rel, ped));
        }
    }
    Ok(out)
}

/// The machine file's bases under measured pedestals that the re-simulation
/// replaces (module docs), as a sentence for the report; `None` when every
/// measured pedestal of the file stands on rigid ground. `foundation` says
/// whether the final model stands pedestals on identified bases.
pub fn replaced_bases(machine: &Machine, bearings: &[String], foundation: bool) -> Option<String> {
    // (file base, the measured bearings on it), in the file's base order.
    let mut on: Vec<(usize, Vec<&str>)> = Vec::new();
    for b in machine.bearings.iter() {
        let Some(i) = b.base.filter(|_| bearings.contains(&b.name)) else {
            continue;
        };
        match on.iter_mut().find(|(j, _)| *j == i) {
            Some((_, names)) => names.push(&b.name),
            None => on.push((i, vec![&b.name])),
        }
    }
    if on.is_empty() {
        return None;
    }
    let list = |v: &[&str]| {
        v.iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let bases: Vec<String> = on
        .iter()
        .map(|(i, names)| {
            let name = machine.bases.get(*i).map_or("?", |b| b.name.as_str());
            format!("base `{name}` under {}", list(names))
        })
        .collect();
    Some(format!(
        "the machine-level check replaces the machine file's {} by the identified model's support (rigid ground for the base model{}): pedestals identified on rigid ground already hold the base's motion, so the file's base is not simulated under them",
        bases.join("; "),
        if foundation {
            ", the identified bases for the final model"
        } else {
            ""
        }
    ))
}

/// Stands bearing `i`'s pedestal `p` (its apparent k, m, c, as identified
/// with the Ω⁴ terms q) on a sub-base of the simulator
/// (`crate::sim::Bearing::sub_base`) whose chain has the same dynamic
/// stiffness to order Ω⁴, K − Ω²M − Ω⁴q + iΩc per direction
/// (`pedestal_sub_base` above the range, `super::candidates::ABOVE_RANGE`).
/// The data fix only those three numbers per direction, so one chain of
/// the family is chosen ([`support_chain`]): the share f of the apparent
/// mass on the pedestal (m₁ = f·M) that keeps the chain closest to
/// K − Ω²M − Ω⁴q over the speeds `omega` [rad/s] (the largest deviation
/// relative to K, f on a grid of 0.02-0.90).
fn put_support(
    machine: &mut Machine,
    i: usize,
    p: &Pedestal,
    q: [f64; 2],
    omega: &[f64],
) -> Result<()> {
    let k = [p.k_y, p.k_z];
    let c = [p.c_y.max(0.0), p.c_z.max(0.0)];
    let deviation = |f: f64| -> Option<f64> {
        let mut worst = 0.0f64;
        for d in 0..2 {
            let (k1, c1, k2, c2, m2) = support_chain(k[d], p.m, q[d], c[d], f)?;
            for &w in omega {
                let zp = Complex::new(k1, w * c1);
                let zs = Complex::new(k2, w * c2);
                let chain = zp - w * w * f * p.m - zp * zp / (zp + zs - w * w * m2);
                let poly = Complex::new(k[d] - w * w * p.m - w.powi(4) * q[d], w * c[d]);
                worst = worst.max((chain - poly).norm() / k[d]);
            }
        }
        worst.is_finite().then_some(worst)
    };
    let f = (1..=45)
        .map(|j| 0.02 * j as f64)
        .filter_map(|f| deviation(f).map(|v| (f, v)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(f, _)| f)
        .ok_or_else(|| anyhow!("apparent stiffness or mass not positive"))?;
    let mut ped = *p;
    let mut base = Base {
        name: format!("{}.identified_support", machine.bearings[i].name),
        m: [0.0; 2],
        k: [0.0; 2],
        c: [0.0; 2],
        eta: 0.0,
    };
    for d in 0..2 {
        let (k1, c1, k2, c2, m2) = support_chain(k[d], p.m, q[d], c[d], f)
            .ok_or_else(|| anyhow!("apparent stiffness or mass not positive"))?;
        if d == 0 {
            (ped.k_y, ped.c_y) = (k1, c1);
        } else {
            (ped.k_z, ped.c_z) = (k1, c1);
        }
        (base.k[d], base.c[d], base.m[d]) = (k2, c2, m2);
    }
    ped.m = f * p.m;
    base.check().map_err(|e| anyhow!("{e}"))?;
    let name = machine.bearings[i].name.clone();
    machine.set_pedestal(&name, Some(ped))?;
    machine.bearings[i].base = None;
    machine.bearings[i].sub_base = Some(base);
    Ok(())
}

/// The chain (k₁ [N/m], c₁ [N·s/m], k₂ [N/m], c₂ [N·s/m], M_S [kg]) of a
/// pedestal of mass f·M on a sub-base whose dynamic stiffness is
/// K − Ω²M − Ω⁴q + iΩc to order Ω⁴ (K [N/m], M [kg], q [N·s⁴/m],
/// c [N·s/m]): with A = (1 − f)·M the mass seen through the sub-base,
/// r = 1/(1 + Kq/A²), S = k₁ + k₂ = A²/(q·r²), k₁ = r·S, k₂ = (1 − r)·S,
/// M_S = A/r², so that K = r(1 − r)S, M = f·M + M_S·r² and
/// q = M_S²r²/S; damping proportional to stiffness (c_i = c·k_i/K, the
/// series c at low speed). A q not above 10⁻⁶·A²/K (none, or negative)
/// is taken as that: a sub-base spring 10⁶ times stiffer than K. `None`
/// when K or A is not positive.
fn support_chain(k: f64, m: f64, q: f64, c: f64, f: f64) -> Option<(f64, f64, f64, f64, f64)> {
    let a = (1.0 - f) * m;
    if !(k > 0.0 && a > 0.0) {
        return None;
    }
    let q = q.max(1e-6 * a * a / k);
    let r = 1.0 / (1.0 + k * q / (a * a));
    let s = a * a / (q * r * r);
    let (k1, k2) = (r * s, (1.0 - r) * s);
    Some((k1, c * k1 / k, k2, c * k2 / k, a / (r * r)))
}

/// Stands the pedestals of each identified base on a base element of the
/// simulator (`crate::sim::base`), with their pedestals as identified on it.
/// A direction where no base motion was detected gets a base 10⁸ times
/// stiffer than its pedestals (rigid to < 1e-6, README "Bases"); a base
/// whose identified mass is not positive (only its compliance determined)
/// gets 10⁻⁶ of its pedestals' mass; damping below zero is simulated as 0.
fn put_bases(machine: &mut Machine, prep: &Prepared, f: &FoundationFit) -> Result<()> {
    for (gi, (group, fit)) in f.grouping.groups.iter().zip(&f.grouping.fits).enumerate() {
        let k_ped: f64 = fit
            .pedestals
            .iter()
            .map(|t| t[0].abs().max(t[1].abs()))
            .fold(0.0, f64::max);
        let m_ped: f64 = fit.pedestals.iter().map(|t| t[2].abs()).sum();
        let base = Base {
            name: format!("identified_base_{}", gi + 1),
            m: std::array::from_fn(|d| {
                let m = fit.base.m[d];
                if m.is_finite() && m > 0.0 {
                    m
                } else {
                    1e-6 * m_ped.max(1.0)
                }
            }),
            k: std::array::from_fn(|d| {
                let k = fit.base.k[d];
                if k.is_finite() {
                    k
                } else {
                    1e8 * k_ped.max(1.0)
                }
            }),
            c: std::array::from_fn(|d| {
                let c = fit.base.c[d];
                if c.is_finite() {
                    c.max(0.0)
                } else {
                    0.0
                }
            }),
            eta: 0.0,
        };
        base.check().map_err(|e| {
            anyhow!(
                "the identified base under {} cannot be simulated: {e}",
                group
                    .iter()
                    .map(|&b| prep.bearings[b].as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })?;
        let index = machine.bases.len();
        machine.bases.push(base);
        for (i, &b) in group.iter().enumerate() {
            let name = &prep.bearings[b];
            let t = fit.pedestals[i];
            machine
                .set_pedestal(
                    name,
                    Some(Pedestal {
                        m: t[2],
                        k_y: t[0],
                        k_z: t[1],
                        c_y: t[3].max(0.0),
                        c_z: t[4].max(0.0),
                    }),
                )
                .with_context(|| format!("setting the identified pedestal of bearing {name}"))?;
            let bi = machine.bearing_index(name)?;
            machine.bearings[bi].base = Some(index);
        }
    }
    Ok(())
}
