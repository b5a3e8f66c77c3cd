//! Whether a number of `measurements.csv` or `bearings.csv` can be real: a
//! phasor component or a bearing coefficient past any machine's by orders
//! of magnitude (a `1.8e308` typo, an overflowed export) is refused at its
//! line and column before anything is fitted, where the fit would overflow
//! later with a message about units, or take it silently (`plot`). The
//! bounds leave room for the idealisations of simulated runs: a "rigid"
//! support written as a bearing of 1e14-1e16 N/m, an undamped resonance.

use super::{RunDirError, BEARING_COLUMNS, MEASUREMENT_COLUMNS};
use std::path::Path;

/// The largest bearing stiffness coefficient |k_ij| taken [N/m]: 1e8 times
/// the stiffest journal or rolling-element bearing (about 1e10 N/m), 100
/// times a "rigid" support of a test machine (1e16 N/m).
pub const MAX_STIFFNESS: f64 = 1e18;

/// The largest bearing damping coefficient |c_ij| taken [N·s/m]: 1e8 times
/// a large turbine journal bearing's (about 1e8 N·s/m).
pub const MAX_DAMPING: f64 = 1e16;

/// The largest phasor component taken [m]: a metre of vibration, which no
/// bearing survives; 20 times the bound of a measured 1X vector table
/// (`field::plausible::max_amplitude_si`), as a simulated run may hold an
/// undamped resonance.
pub const MAX_DISPLACEMENT: f64 = 1.0;

/// Phasor components above [`MAX_DISPLACEMENT`] up to this are read as a
/// unit mix-up rather than a typo: a metre of vibration written in µm is
/// 1e6 [m as written].
const MAX_UNIT_MIX_UP: f64 = 1e7;

/// The usual units a displacement channel is exported in by mistake, with
/// the factor [m as written per m] each makes of a phasor in metres.
const UNIT_MIX_UPS: [(&str, f64); 3] = [("mm", 1e3), ("mils", 1.0 / 25.4e-6), ("µm", 1e6)];

/// The range of |ped|/|rel| at one speed (both phasor pairs' norms) that
/// machines give [-]: |ped|/|rel| ≈ |K_b|/|Z_ped|, largest at a lightly
/// damped pedestal resonance, smallest where the pedestal is far stiffer
/// than its bearing. The bundled machines (examples/, tests/machines/,
/// simulated at 12 digits) span 0.065 to 163 (the paper's undamped
/// pedestals at resonance). A row outside is read as two channel groups in
/// different units, and the units whose factor brings it inside are named.
const PED_TO_REL_RANGE: [f64; 2] = [1e-2, 1e3];

/// The bound of the eight numbers of a row of the table with `columns`
/// (measurements: displacement phasor components [m]; bearings: four
/// stiffness [N/m] then four damping coefficients [N·s/m]), with their
/// unit; `None` for another table.
fn bounds(columns: &[&str; 10]) -> Option<[(f64, &'static str); 8]> {
    if *columns == MEASUREMENT_COLUMNS {
        Some([(MAX_DISPLACEMENT, "m"); 8])
    } else if *columns == BEARING_COLUMNS {
        Some(std::array::from_fn(|k| {
            if k < 4 {
                (MAX_STIFFNESS, "N/m")
            } else {
                (MAX_DAMPING, "N·s/m")
            }
        }))
    } else {
        None
    }
}

/// Checks the eight numbers `values` of one data row (file `path`, 1-based
/// `line`; `index[k]` is the 0-based field of `columns[k]`) against their
/// bounds: the first beyond its bound is an error naming its line and
/// column.
pub fn check(
    path: &Path,
    line: u64,
    columns: &[&'static str; 10],
    index: &[usize; 10],
    values: &[f64; 8],
) -> Result<(), RunDirError> {
    let Some(bounds) = bounds(columns) else {
        return Ok(());
    };
    for (k, (&v, (bound, unit))) in values.iter().zip(bounds).enumerate() {
        if v.abs() > bound {
            // A phasor of metres to kilometres is a number written in a
            // smaller unit (µm, mils, mm): the commonest mix-up between a
            // proximity probe and a pedestal pick-up's instrument.
            let cause = if unit == "m" && v.abs() <= MAX_UNIT_MIX_UP {
                channel_mix_up(values, k).unwrap_or_else(|| {
                    "a unit mix-up (this column written in µm, mils or mm, where every phasor is in metres)?".to_string()
                })
            } else {
                "a typo, or an overflowed export?".to_string()
            };
            return Err(RunDirError::Csv {
                file: path.to_path_buf(),
                line,
                message: format!(
                    "column {} (`{}`): {} {unit} is beyond any machine's (at most {bound:e} {unit} is taken): {cause}",
                    index[k + 2] + 1,
                    columns[k + 2],
                    super::format_number(v)
                ),
            });
        }
    }
    Ok(())
}

/// The unit mix-up between channels that a displacement row's values
/// (`values`: rel y, z then ped y, z, real and imaginary parts [m as
/// written]) point to when its component `k` is past its bound: the ratio
/// |ped|/|rel| outside what machines give ([`PED_TO_REL_RANGE`]) on the
/// side of `k`'s group, with the units ([`UNIT_MIX_UPS`]) whose factor
/// brings it back inside, nearest the range's middle (in decades) first.
/// `None` when the groups are in proportion (the whole row in another
/// unit) or no usual unit explains the ratio.
fn channel_mix_up(values: &[f64; 8], k: usize) -> Option<String> {
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let r = norm(&values[4..]) / norm(&values[..4]);
    let [lo, hi] = PED_TO_REL_RANGE;
    let ped = k >= 4;
    if !(r.is_finite() && r > 0.0) || (ped && r <= hi) || (!ped && r >= lo) {
        return None;
    }
    // |ped|/|rel| with the group of `k` read in unit factor f.
    let undone = |f: f64| if ped { r / f } else { r * f };
    let middle = (lo * hi).sqrt().log10();
    let off = |f: f64| (undone(f).log10() - middle).abs();
    let mut units: Vec<(&str, f64)> = UNIT_MIX_UPS
        .iter()
        .copied()
        .filter(|&(_, f)| (lo..=hi).contains(&undone(f)))
        .collect();
    units.sort_by(|a, b| off(a.1).total_cmp(&off(b.1)));
    let names: Vec<String> = units
        .iter()
        .map(|(u, f)| format!("{u} ({f:.1e})"))
        .collect();
    let (group, rest, said) = if ped {
        (
            "ped",
            "rel",
            format!(
                "the pedestal readings (ped) of this row are {r:.1e} times the shaft probes' (rel)"
            ),
        )
    } else {
        ("rel", "ped", format!("the shaft probe readings (rel) of this row are {:.1e} times the pedestal pick-ups' (ped)", 1.0 / r))
    };
    (!names.is_empty()).then(|| {
        format!(
            "suspected unit mismatch between channels: {said}, beyond the {lo:.0e} to {hi:.0e} machines give: {group} written in {} while {rest} is in m? formats.md wants every phasor in m",
            names.join(" or ")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_past_their_bound_are_named_by_column() {
        let index = std::array::from_fn(|k| k);
        let p = Path::new("bearings.csv");
        let mut v = [1e16, -2e7, 3e6, 1e9, 1e5, 0.0, -1e4, 1e6];
        assert!(check(p, 2, &BEARING_COLUMNS, &index, &v).is_ok());
        v[3] = 1.7976931348623157e308;
        let e = check(p, 7, &BEARING_COLUMNS, &index, &v)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bearings.csv:7:") && e.contains("column 6 (`kzz`)"),
            "{e}"
        );
        v[3] = 1e9;
        v[7] = -2e16;
        let e = check(p, 3, &BEARING_COLUMNS, &index, &v)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("column 10 (`czz`)") && e.contains("N·s/m"),
            "{e}"
        );
        let m = [1e-5, -2e-6, 0.0, 3e-5, 1e-7, 1e-7, 0.9, -0.9];
        let p = Path::new("measurements.csv");
        assert!(check(p, 2, &MEASUREMENT_COLUMNS, &index, &m).is_ok());
        let mut m2 = m;
        m2[4] = 1e300;
        let e = check(p, 9, &MEASUREMENT_COLUMNS, &index, &m2)
            .unwrap_err()
            .to_string();
        assert!(e.contains("column 7 (`ped_y_re`)"), "{e}");
        assert!(e.contains("overflowed export"), "{e}");
        // Pick-ups written in µm against probes in m: named as a unit mix-up.
        m2[4] = 1.07;
        let e = check(p, 9, &MEASUREMENT_COLUMNS, &index, &m2)
            .unwrap_err()
            .to_string();
        // (this row's ped are 5e4 times its rel: a mix-up between channels)
        assert!(e.contains("unit mismatch") && e.contains("µm"), "{e}");
        // Pick-ups written in µm against probes in m (every ped ×1e6): the
        // row's two groups 1e6 apart, named as such.
        let mut mixed = m;
        for v in &mut mixed[4..] {
            *v = 3e-6 * 1e6;
        }
        for v in &mut mixed[..4] {
            *v = 1e-6;
        }
        let e = check(p, 9, &MEASUREMENT_COLUMNS, &index, &mixed)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("ped written in µm (1.0e6)") && e.contains("column 7 (`ped_y_re`)"),
            "{e}"
        );
        // The probes in mm against pick-ups in m.
        let mut mixed = m;
        for v in &mut mixed[..4] {
            *v = 2e-3 * 1e3;
        }
        for v in &mut mixed[4..] {
            *v = 1e-2;
        }
        let e = check(p, 9, &MEASUREMENT_COLUMNS, &index, &mixed)
            .unwrap_err()
            .to_string();
        assert!(e.contains("rel written in mm (1.0e3)"), "{e}");
        // The whole row in µm: no mix-up between channels to name.
        let e = check(p, 9, &MEASUREMENT_COLUMNS, &index, &[2.0; 8])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("every phasor is in metres") && !e.contains("between channels"),
            "{e}"
        );
    }
}
