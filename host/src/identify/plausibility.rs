//! Plausibility of an identified pedestal where the fit itself can be
//! perfect: numbers no pedestal has, and the unit or scale mismatch between
//! channels that produces them.
//!
//! A scale mismatch between the pedestal pick-ups and the shaft probes
//! (`ped` in µm against `rel` in m) scales k, m and c alike and leaves the
//! fit exact and the natural frequencies unchanged: only the size of the
//! numbers gives it away. The yardstick is the bearing the pedestal
//! carries: a pedestal stiffer or softer than its bearing's direct
//! stiffness by more than [`BEARING_STIFFNESS_RATIO`] is not a machine
//! anybody builds, and when the ratio is near a power of 1000 the unit
//! mistake is named. Independently, masses, stiffnesses and natural
//! frequencies outside wide absolute ranges ([`MASS_RANGE_KG`],
//! [`STIFFNESS_RANGE_N_PER_M`], [`NATURAL_FREQUENCY_RANGE_HZ`]) are never
//! `ok`. A value counts as outside only when its 3σ interval is
//! ([`SIGMAS`]), so a weakly determined mass is left to the other warnings.
//!
//! Gravity gives the one bound on the mass that no reading of the speeds
//! can move: y is vertical (formats.md), so a pedestal of mass m on a
//! vertical stiffness k_y sags at least m·g/k_y = g/ω_y² under its own
//! weight (more with the bearing load on it). The softest supports rotating
//! machines stand on, steel-spring isolators, are made for up to about
//! 0.1 m of static deflection (a 1.6 Hz mount); a support that sags more
//! than [`MAX_SAG_M`] (0.25 m: a vertical natural frequency under 1.0 Hz)
//! cannot hold a shaft line, whatever its k and m are separately. The
//! speeds read in the wrong unit are the case it is for: speeds in rpm read
//! as Hz give the same pedestal with m·3600 and c·60 and an unchanged k
//! (every frequency /60), and where the bearing force is almost all
//! stiffness the two readings fit alike (an 85 kg bracket at 46 Hz reads
//! as 3e5 kg sagging 0.42 m; docs/unseen-train.md, third machine). The
//! convention check ([`super::convention`]) counts a reading with any
//! finding here as not plausible, so it never names such a reading.
//! Velocity declared as displacement and mixed phase conventions do change
//! the fit, and are tried as convention mistakes ([`super::convention`]).

use super::{Identification, PedestalFit, Warning, WarningKind};
use crate::rundir::RunDir;

/// Pedestal masses any machine has [kg].
pub const MASS_RANGE_KG: [f64; 2] = [0.1, 1.0e6];
/// Pedestal stiffnesses any machine has [N/m].
pub const STIFFNESS_RANGE_N_PER_M: [f64; 2] = [1.0e3, 1.0e12];
/// Pedestal natural frequencies sqrt(k/m)/2π any machine has [Hz].
pub const NATURAL_FREQUENCY_RANGE_HZ: [f64; 2] = [0.5, 2.0e4];
/// Largest factor between a pedestal's stiffness and its bearing's direct
/// stiffness, either way [-] (field machines: within about 30).
pub const BEARING_STIFFNESS_RATIO: f64 = 1.0e3;
/// Standard errors a value must lie outside a range by [-].
pub const SIGMAS: f64 = 3.0;
/// Standard gravity [m/s²].
pub const GRAVITY_M_PER_S2: f64 = 9.806_65;
/// Largest static deflection m·g/k_y of a pedestal under its own weight [m]
/// (module docs: 2.5 times the deepest spring isolators'; a vertical
/// natural frequency of 1.0 Hz).
pub const MAX_SAG_M: f64 = 0.25;

/// The static deflection m·g/k_y [m] of `fit`'s pedestal under its own
/// weight with its standard error [m] (`None` when k_y or m is not
/// positive). The relative standard error is bounded by the sum of those
/// of m and k_y (|ρ| ≤ 1), so the bound holds whatever their correlation.
pub fn sag(fit: &PedestalFit) -> Option<(f64, f64)> {
    let (k, m) = (fit.pedestal.k_y, fit.pedestal.m);
    if !(k > 0.0 && m > 0.0) {
        return None;
    }
    let finite = |s: f64| if s.is_finite() { s } else { f64::INFINITY };
    let se = fit.std_err.theta();
    let sag = m * GRAVITY_M_PER_S2 / k;
    Some((sag, sag * (finite(se[2]) / m + finite(se[0]) / k)))
}

/// Why `fit` is implausible, one sentence each; `bearing_stiffness` is the
/// geometric mean of the bearing's direct stiffnesses |k_yy|, |k_zz| over the
/// measured speeds [N/m] (`None`: unknown).
pub fn findings(fit: &PedestalFit, bearing_stiffness: Option<f64>) -> Vec<String> {
    let mut out = Vec::new();
    let se = fit.std_err.theta();
    let outside = |v: f64, s: f64, [lo, hi]: [f64; 2]| {
        let s = if s.is_finite() { s } else { 0.0 };
        v + SIGMAS * s < lo || v - SIGMAS * s > hi
    };
    for (name, v, s, range, unit) in [
        (
            "k_y",
            fit.pedestal.k_y,
            se[0],
            STIFFNESS_RANGE_N_PER_M,
            "N/m",
        ),
        (
            "k_z",
            fit.pedestal.k_z,
            se[1],
            STIFFNESS_RANGE_N_PER_M,
            "N/m",
        ),
        ("m", fit.pedestal.m, se[2], MASS_RANGE_KG, "kg"),
    ] {
        if v > 0.0 && outside(v, s, range) {
            out.push(format!(
                "{name} = {v:.3e} ± {s:.1e} {unit} is outside anything a pedestal can be ({:.0e} to {:.0e} {unit})",
                range[0], range[1]
            ));
        }
    }
    if fit.pedestal.m > 0.0 && fit.pedestal.k_y > 0.0 && fit.pedestal.k_z > 0.0 {
        for (axis, k) in [("y", fit.pedestal.k_y), ("z", fit.pedestal.k_z)] {
            let f = (k / fit.pedestal.m).sqrt() / (2.0 * std::f64::consts::PI);
            let [lo, hi] = NATURAL_FREQUENCY_RANGE_HZ;
            if !(lo..=hi).contains(&f) {
                out.push(format!(
                    "its natural frequency in {axis}, sqrt(k_{axis}/m)/2π = {f:.3e} Hz, is outside anything a pedestal can have ({lo} to {hi:.0e} Hz)"
                ));
            }
        }
    }
    if let Some((sag, se)) = sag(fit) {
        if sag - SIGMAS * se > MAX_SAG_M {
            out.push(format!(
                "it would sag m·g/k_y = {sag:.3} ± {se:.1e} m under its own weight (vertical natural frequency {:.3} Hz), more than any support of a shaft line ({MAX_SAG_M} m): speeds in the wrong unit (rpm for Hz) give such a mass",
                (GRAVITY_M_PER_S2 / sag).sqrt() / (2.0 * std::f64::consts::PI)
            ));
        }
    }
    if let Some(ratio) = stiffness_ratio(fit, bearing_stiffness) {
        if !within_ratio(ratio) {
            out.push(format!(
                "its stiffness is {ratio:.1e} times its bearing's ({:.2e} N/m): {}",
                (fit.pedestal.k_y * fit.pedestal.k_z).sqrt() / ratio,
                unit_mismatch(ratio)
            ));
        }
    }
    out
}

/// The pedestal's stiffness √(k_y·k_z) over its bearing's `bearing_stiffness`
/// [N/m] ([`bearing_stiffness`]), [-]; `None` when either is unknown or not
/// positive.
fn stiffness_ratio(fit: &PedestalFit, bearing_stiffness: Option<f64>) -> Option<f64> {
    let kb = bearing_stiffness.filter(|k| *k > 0.0 && k.is_finite())?;
    (fit.pedestal.k_y > 0.0 && fit.pedestal.k_z > 0.0)
        .then(|| (fit.pedestal.k_y * fit.pedestal.k_z).sqrt() / kb)
        .filter(|r| r.is_finite())
}

/// Whether a pedestal/bearing stiffness ratio [-] is one machines are built
/// with ([`BEARING_STIFFNESS_RATIO`] either way).
fn within_ratio(ratio: f64) -> bool {
    (1.0 / BEARING_STIFFNESS_RATIO..=BEARING_STIFFNESS_RATIO).contains(&ratio)
}

/// The run-level suspicion a named unit mismatch casts on the run's other
/// pedestals: `ratios` holds each pedestal's bearing name and stiffness
/// ratio ([`stiffness_ratio`]). A pedestal whose ratio points to a power of
/// 1000 names a unit mistake between the probes and the pick-ups; the same
/// mistake made on every probe (one instrument, one unit setting) scales
/// another pedestal's k, m, c alike with its fit still exact, and only its
/// ratio can argue against it. So a pedestal whose ratio is plausible as
/// read AND would still be plausible with the named mistake undone is
/// suspect too (one with its undone ratio outside the band is cleared by
/// its bearing). Returns, per pedestal, the sentence saying so (`None`:
/// not suspect). On a run with no named mistake nothing is said: clean
/// runs cannot trip it unless they trip the per-pedestal rule.
fn shared_unit_suspicion(ratios: &[(String, Option<f64>)]) -> Vec<Option<String>> {
    let named: Vec<(&str, i32)> = ratios
        .iter()
        .filter_map(|(b, r)| {
            let r = (*r)?;
            (!within_ratio(r))
                .then(|| thousands_off(r))
                .flatten()
                .map(|t| (b.as_str(), t))
        })
        .collect();
    ratios
        .iter()
        .map(|(bearing, r)| {
            let r = (*r).filter(|r| within_ratio(*r))?;
            let (others, undone): (Vec<&str>, Vec<f64>) = named
                .iter()
                .filter(|(b, _)| b != bearing)
                .filter_map(|(b, t)| {
                    let undone = r * 10f64.powi(3 * t);
                    within_ratio(undone).then_some((*b, undone))
                })
                .unzip();
            let first = *undone.first()?;
            Some(format!(
                "the pedestal{} at {} of this run read{} as a unit mismatch between channels; with the same mistake on this bearing's channels its k, m, c would be off by the same factor with the fit still exact, and its stiffness ({r:.1e} times its bearing's as read, {first:.1e} with the mistake undone) is plausible either way: check the units of every channel",
                if others.len() > 1 { "s" } else { "" },
                others.join(", "),
                if others.len() > 1 { "" } else { "s" },
            ))
        })
        .collect()
}

/// The power of 1000 a pedestal/bearing stiffness ratio [-] points to: `t`
/// when the ratio lies within 1.5 decades of 1000^(−t), t ≠ 0 (t > 0: the
/// pedestal readings 1000^t too large against the probes; t < 0: the
/// probes too large), else `None`.
fn thousands_off(ratio: f64) -> Option<i32> {
    // ped too large by F makes k, m, c too small by F.
    let decades = -ratio.log10();
    let thousands = (decades / 3.0).round() as i32;
    (thousands != 0 && (decades - 3.0 * thousands as f64).abs() <= 1.5).then_some(thousands)
}

/// The unit mistake a pedestal/bearing stiffness ratio points to.
fn unit_mismatch(ratio: f64) -> String {
    let name = |e: i32| match e {
        1 => "mm",
        2 => "µm",
        3 => "nm",
        _ => "another unit",
    };
    if let Some(thousands) = thousands_off(ratio) {
        let factor = format!("1e{}", 3 * thousands.abs());
        if thousands > 0 {
            format!(
                "suspected unit mismatch between channels: the pedestal readings look {factor} too large against the shaft probes (ped in {}, rel in m?); formats.md wants both in m",
                name(thousands)
            )
        } else {
            format!(
                "suspected unit mismatch between channels: the shaft probe readings look {factor} too large against the pedestal pick-ups (rel in {}, ped in m?); formats.md wants both in m",
                name(-thousands)
            )
        }
    } else {
        "a scale mismatch between the ped and rel channels (units, gains) or a wrong bearing table is the likely cause".to_string()
    }
}

/// Geometric mean of the bearing's direct stiffnesses |k_yy|·|k_zz| over
/// the speeds `bearing` was measured at [N/m].
pub(crate) fn bearing_stiffness(run: &RunDir, bearing: &str) -> Option<f64> {
    let schedules = run.bearing_schedules();
    let schedule = schedules.get(bearing)?;
    let logs: Vec<f64> = run
        .measurements
        .iter()
        .filter(|m| m.bearing == bearing)
        .filter_map(|m| schedule.at(m.speed_hz).ok())
        .map(|c| 0.5 * (c.k[0][0].abs() * c.k[1][1].abs()).ln())
        .filter(|v| v.is_finite())
        .collect();
    (!logs.is_empty()).then(|| (logs.iter().sum::<f64>() / logs.len() as f64).exp())
}

/// Adds a [`WarningKind::Implausible`] warning to every implausible pedestal
/// of `identification` (identified from `run`) and updates `trusted`.
/// A pedestal plausible on its own is marked too when another pedestal of
/// the run names a unit mismatch its numbers could share
/// ([`shared_unit_suspicion`]).
pub fn mark(run: &RunDir, identification: &mut Identification) {
    let stiffness: Vec<Option<f64>> = identification
        .pedestals
        .iter()
        .map(|p| bearing_stiffness(run, &p.bearing))
        .collect();
    let ratios: Vec<(String, Option<f64>)> = identification
        .pedestals
        .iter()
        .zip(&stiffness)
        .map(|(p, kb)| (p.bearing.clone(), stiffness_ratio(p, *kb)))
        .collect();
    let shared = shared_unit_suspicion(&ratios);
    for ((p, kb), shared) in identification
        .pedestals
        .iter_mut()
        .zip(stiffness)
        .zip(shared)
    {
        let mut found = findings(p, kb);
        found.extend(shared);
        if found.is_empty() {
            continue;
        }
        p.warnings.push(Warning {
            kind: WarningKind::Implausible,
            message: format!("implausible pedestal: {}", found.join("; ")),
        });
        p.trusted = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::Pedestal;

    fn fit(k: f64, m: f64) -> PedestalFit {
        PedestalFit {
            bearing: "left".into(),
            pedestal: Pedestal {
                k_y: k,
                k_z: 0.8 * k,
                m,
                c_y: 0.0,
                c_z: 0.0,
            },
            std_err: Pedestal {
                k_y: 1e-3 * k,
                k_z: 1e-3 * k,
                m: 1e-3 * m,
                c_y: 1.0,
                c_z: 1.0,
            },
            residual_rms: 0.0,
            condition_number: 2.0,
            fixed: Vec::new(),
            trusted: true,
            speeds: 50,
            equations: 200,
            speed_range_hz: [5.0, 200.0],
            warnings: Vec::new(),
            ols: None,
            suspected_convention_error: None,
            base: None,
            base_measured: None,
            covariance: None,
            modal: None,
        }
    }

    #[test]
    fn ordinary_pedestals_pass() {
        assert!(findings(&fit(1e7, 80.0), Some(2e7)).is_empty());
        assert!(findings(&fit(3e9, 5000.0), Some(1e8)).is_empty());
    }

    #[test]
    fn micrometres_against_metres_are_named() {
        // ped in µm: k = 1e7·1e-6 = 10 N/m, m = 80e-6 kg, f_n unchanged.
        let f = findings(&fit(10.0, 8e-5), Some(2e7));
        let all = f.join(" | ");
        assert!(all.contains("1e6 too large") && all.contains("µm"), "{all}");
        assert!(all.contains("m = 8.000e-5"), "{all}");
        // rel in µm instead: the pedestal looks 1e6 too stiff.
        let f = findings(&fit(1e13, 8e7), Some(2e7)).join(" | ");
        assert!(f.contains("rel in µm"), "{f}");
    }

    #[test]
    fn a_unit_mismatch_named_at_one_bearing_is_suspected_at_the_others() {
        let r = |b: &str, x: f64| (b.to_string(), Some(x));
        // Every probe in mm for µm-sized numbers (rel 1e3 too large): B1 and
        // B2 show it, B3 (truly 0.02 of its bearing) reads 20 and would be
        // 0.02 undone: suspect. B4 (truly 2) reads 2 here: undone 2e-3 is
        // still plausible, so it is suspect too; B5 at 0.5 would be 5e-4
        // undone, which no machine has: cleared.
        let said = shared_unit_suspicion(&[
            r("B1", 1.2e4),
            r("B2", 2.0e3),
            r("B3", 20.0),
            r("B4", 2.0),
            r("B5", 0.5),
            ("B6".to_string(), None),
        ]);
        assert!(said[0].is_none() && said[1].is_none(), "{said:?}");
        let b3 = said[2].as_deref().unwrap_or_default();
        assert!(
            b3.contains("pedestals at B1, B2") && b3.contains("2.0e-2"),
            "{b3}"
        );
        assert!(said[3].is_some() && said[4].is_none() && said[5].is_none());
        // No named mistake, nothing said.
        assert!(shared_unit_suspicion(&[r("B1", 5.0), r("B2", 0.01)])
            .iter()
            .all(Option::is_none));
    }

    #[test]
    fn absurd_magnitudes_are_never_ok() {
        let f = findings(&fit(1e151, 80.0), None).join(" | ");
        assert!(f.contains("k_y") && f.contains("natural frequency"), "{f}");
        assert!(!findings(&fit(1e7, 1e-4), None).is_empty());
    }

    #[test]
    fn a_pedestal_that_would_sag_a_quarter_metre_is_never_ok() {
        // An 85 kg bracket on 22 MN/m (f_y 81 Hz) read with its speeds in
        // rpm: m·3600, the same k, f_y/60 = 1.35 Hz, sag 0.136 m: within
        // what spring isolators allow, so not named here.
        assert!(findings(&fit(2.2e7, 85.0 * 3600.0), Some(1.5e8)).is_empty());
        // At 46 Hz (k 7.1 MN/m): 0.77 Hz, sag 0.42 m: named.
        let f = findings(&fit(7.1e6, 85.0 * 3600.0), Some(1.5e8)).join(" | ");
        assert!(f.contains("sag") && f.contains("rpm"), "{f}");
        // A weakly determined mass (± 50 %) is left alone.
        let mut weak = fit(7.1e6, 85.0 * 3600.0);
        weak.std_err.m = 0.5 * weak.pedestal.m;
        assert!(findings(&weak, Some(1.5e8)).is_empty());
        // A spring-isolated pedestal at 1.6 Hz (0.1 m) is a machine.
        let k = 1000.0 * (2.0 * std::f64::consts::PI * 1.6f64).powi(2);
        assert!(findings(&fit(k, 1000.0), Some(10.0 * k)).is_empty());
    }
}
