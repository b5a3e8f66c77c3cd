//! Transducer pairs written at an angle ([`Convention::RelRotated`],
//! [`Convention::PedRotated`]): a bearing's two proximity probes (or its two
//! casing pick-ups) mounted at an angle to y (vertical) and z (horizontal),
//! the usual X-Y pair of API 670 at ±45° from the vertical, and written as
//! they read instead of resolved to y and z. The pair then holds R(a)·q,
//! q the true (y, z) phasors and R(a) the rotation by the mounting angle a:
//! the first channel reads along −a from y (towards −z), the second along
//! 90° − a.
//!
//! Exactly testable: with the pair resolved back (R(−a)) the pedestal
//! equations fit to the noise floor again. The angle is estimated per
//! bearing and per pair ([`angles`]): the OLS screen's relative residual
//! r(a) = Σ|e|²/Σ|F|² ([`super::screen::relative_residual`]) searched over
//! a ∈ (−90°, 90°] (a turn by a + 180° is the same fit with every bearing
//! force, or every pedestal row, negated: the same residual, k, m, c of
//! the other sign, which plausibility tells apart, so both a and a + 180°
//! are tried), on a 2° grid and then by golden section to 0.01°. An angle
//! is tried only when the screen's likelihood ratio for it, ν·ln(r(0)/r(a)),
//! is decisive ([`DECISIVE_DELTA_CHI2`]: one parameter estimated, a chance
//! of about 2e-4 per pair under white noise); it is read as the nearest
//! multiple of 45° (the field's arrangements: ±45°, 90°) when that angle's
//! residual lies within one unit of ν·ln r of the estimate's (the estimate's
//! own one-σ interval), otherwise as estimated to 0.1°. Each angle so found
//! is then a candidate reading like every other mistake (screened, refitted,
//! judged by [`super::decide`]).

use super::judge::Judge;
use super::{Convention, DECISIVE_DELTA_CHI2};
use crate::estimate::Observation;
use crate::field::angle::resolve;
use num_complex::Complex;
use plinth_shared::phasor::Phasor2;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;

/// An angle [deg] in (−180°, 180°], held in tenths of a degree (so that a
/// [`Convention`] stays exact to compare and hash).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Angle(i32);

impl Angle {
    /// `deg` [deg] wrapped to (−180°, 180°] and rounded to 0.1°.
    pub fn from_deg(deg: f64) -> Self {
        let mut tenths = (deg * 10.0).round() as i64 % 3600;
        if tenths > 1800 {
            tenths -= 3600;
        } else if tenths <= -1800 {
            tenths += 3600;
        }
        Angle(tenths as i32)
    }

    /// The angle [deg].
    pub fn deg(self) -> f64 {
        f64::from(self.0) / 10.0
    }

    /// Whether the angle is a multiple of 45° (a field arrangement).
    pub fn is_field_arrangement(self) -> bool {
        self.0 % 450 == 0
    }
}

impl fmt::Display for Angle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}°", self.deg())
    }
}

impl Serialize for Angle {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_f64(self.deg())
    }
}

impl<'de> Deserialize<'de> for Angle {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let deg = f64::deserialize(d)?;
        if !deg.is_finite() {
            return Err(serde::de::Error::custom(
                "an angle in degrees must be finite",
            ));
        }
        Ok(Angle::from_deg(deg))
    }
}

/// The axes [deg from +y towards +z] along which a pair turned by `deg`
/// [deg] reads: −deg and 90° − deg (module docs).
fn turned_axes(deg: f64) -> [f64; 2] {
    [-deg, 90.0 - deg]
}

/// `v`, a pair written as it read when turned by `deg` [deg], resolved to
/// (y, z): the import's resolution of transducers at known angles
/// ([`crate::field::angle::resolve`]), here at [`turned_axes`].
pub fn resolve_turned(v: &mut Phasor2<f64>, deg: f64) {
    *v = resolve(&turned_axes(deg), v, None).0;
}

/// The noise sds `sd` [m] of such a pair (each channel's noise
/// independent) resolved with it ([`resolve_turned`]):
/// √(cos²·σ₁² + sin²·σ₂²) and √(sin²·σ₁² + cos²·σ₂²).
pub fn resolve_turned_sd(sd: &mut [f64], deg: f64) {
    let zero = [Complex::new(0.0, 0.0); 2];
    if let (_, Some(resolved)) = resolve(&turned_axes(deg), &zero, Some(sd)) {
        sd[..2].copy_from_slice(&resolved);
    }
}

/// Which pair of a bearing is turned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pair {
    /// The proximity probes (`rel`).
    Rel,
    /// The casing pick-ups (`ped`).
    Ped,
}

impl Pair {
    /// The mistake "this pair written turned by `angle`".
    pub fn convention(self, angle: Angle) -> Convention {
        match self {
            Pair::Rel => Convention::RelRotated(angle),
            Pair::Ped => Convention::PedRotated(angle),
        }
    }
}

/// The screen's relative residual [-] and degrees of freedom of `points`
/// with pair `pair` resolved back from a turn by `deg` [deg].
fn residual_at(
    judge: &Judge,
    points: &[Observation],
    pair: Pair,
    deg: f64,
    bearing: &str,
) -> Option<(f64, usize)> {
    let turned: Vec<Observation> = points
        .iter()
        .map(|&o| {
            let mut o = o;
            match pair {
                Pair::Rel => resolve_turned(&mut o.rel, deg),
                Pair::Ped => resolve_turned(&mut o.ped, deg),
            }
            o
        })
        .collect();
    super::screen::relative_residual(&turned, judge.options, judge.pedestals, bearing)
}

/// The angle [deg] in (−90°, 90°] that minimises `f` (a relative residual):
/// a 2° grid, then golden section over the grid step either side.
fn minimise(f: &mut dyn FnMut(f64) -> f64) -> Option<f64> {
    let mut best: Option<(f64, f64)> = None;
    for k in -44..=45 {
        let a = 2.0 * f64::from(k);
        let v = f(a);
        if v.is_finite() && best.is_none_or(|(_, b)| v < b) {
            best = Some((a, v));
        }
    }
    let (a0, _) = best?;
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut lo, mut hi) = (a0 - 2.0, a0 + 2.0);
    let (mut x1, mut x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
    let (mut f1, mut f2) = (f(x1), f(x2));
    while hi - lo > 0.01 {
        if f1 <= f2 || f2.is_nan() {
            hi = x2;
            (x2, f2) = (x1, f1);
            x1 = hi - g * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            (x1, f1) = (x2, f2);
            x2 = lo + g * (hi - lo);
            f2 = f(x2);
        }
    }
    Some(0.5 * (lo + hi))
}

/// The angle of `pair` at the bearing of `points` (module docs), or `None`
/// when no turn fits decisively better than none.
fn angle_of(judge: &Judge, points: &[Observation], pair: Pair, bearing: &str) -> Option<Angle> {
    let r = |deg: f64| residual_at(judge, points, pair, deg, bearing);
    let (r0, dof) = r(0.0)?;
    let nu = dof as f64;
    let a_hat = minimise(&mut |deg| r(deg).map_or(f64::NAN, |(v, _)| v))?;
    let (r_hat, _) = r(a_hat)?;
    if !(r0 > 0.0 && r_hat > 0.0) || nu * (r0 / r_hat).ln() < DECISIVE_DELTA_CHI2 {
        return None;
    }
    // The field's arrangement nearest the estimate, when the data allow it.
    let field = 45.0 * (a_hat / 45.0).round();
    let angle = match r(field) {
        Some((r_field, _)) if nu * (r_field / r_hat).ln() <= 1.0 => Angle::from_deg(field),
        _ => Angle::from_deg(a_hat),
    };
    (angle.deg().abs() >= MIN_MOUNTING_ANGLE_DEG).then_some(angle)
}

/// Smallest turn [deg] of a pair tried as a mounting mistake. A small turn
/// δ changes the bearing force K*·R(δ)·rel by about δ·|F| across it, the
/// form a bearing cross-coupling of δ·k, a pedestal cross-coupling or a
/// phase error also has: over a band the turn absorbs part of any such
/// model error (and of correlated noise) and comes out "decisive". On the
/// stored ROSS runs of tests/data (docs/trust.md, Session 48 (mount17)) it
/// named turns of 0.1° (correlated noise), 0.8° (a probe delay) and 7.7°
/// (pedestal cross-coupling k_yz = 0.2·√(k_y·k_z)); a probe pair mounted
/// on purpose at an angle is at 30°, 45°, 60° or 90°. 20° lies between,
/// chosen after seeing those runs (2.6 times the largest absorbed turn);
/// the fresh seeds of that section measure it.
pub const MIN_MOUNTING_ANGLE_DEG: f64 = 20.0;

/// The turned-pair mistakes to try in `judge`'s run, each with the
/// bearings it is read at: for every bearing whose rows are all in its
/// table and each pair, the angle found ([`angle_of`]) and the same angle
/// + 180°, one entry per mistake listing every bearing that found it.
pub(super) fn candidates(judge: &Judge) -> Vec<(Convention, Vec<String>)> {
    let mut out: Vec<(Convention, Vec<String>)> = Vec::new();
    for rows in &judge.found_rows {
        let Some(points) = rows.in_range() else {
            continue;
        };
        for pair in [Pair::Rel, Pair::Ped] {
            let Some(a) = angle_of(judge, points, pair, &rows.bearing) else {
                continue;
            };
            for c in [a, Angle::from_deg(a.deg() + 180.0)].map(|a| pair.convention(a)) {
                match out.iter_mut().find(|(k, _)| *k == c) {
                    Some((_, at)) => at.push(rows.bearing.clone()),
                    None => out.push((c, vec![rows.bearing.clone()])),
                }
            }
        }
    }
    out
}
